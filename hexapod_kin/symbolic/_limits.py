"""The default CPU budget of a derivation (no sympy here: the command line reads it first)."""

from __future__ import annotations

__all__ = ["DEFAULT_BUDGET"]

#: Default time budget of :func:`~hexapod_kin.symbolic.derive` in [s] of CPU time.
DEFAULT_BUDGET = 10.0
