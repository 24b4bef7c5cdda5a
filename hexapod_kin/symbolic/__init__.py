"""The same Khalil–Kleinfinger table, derived with sympy: transforms, Jacobians, det J, families.

The folder reads in the order the data flows:

* :mod:`~hexapod_kin.symbolic.sources` — a source (chain, preset, mounted leg, table file,
  URDF) turned into the chain to derive and the base it is expressed in;
* :mod:`~hexapod_kin.symbolic.core` — the sympy stages (transforms, Jacobian, factored
  ``det J`` or Gram determinant), no caching, no budget;
* :mod:`~hexapod_kin.symbolic.families` — singular families read off the factors, checked
  against the numeric σ_min;
* :mod:`~hexapod_kin.symbolic.cache` — the disk cache keyed by the table (the budget, in CPU
  time, is :mod:`hexapod_kin._budget`'s: one child process, never a fork);
* :mod:`~hexapod_kin.symbolic.derivation` — the public face: :func:`derive`,
  :class:`Derivation`, :func:`cached`.

The families as numbers for scans (residuals, exact distances) are
:mod:`hexapod_kin.singularity.families`. Importing this package imports sympy (slow to import):
the rest of hexapod_kin imports it only inside the functions that derive.
"""

from __future__ import annotations

from .core import ROW_NAMES, khalil_matrix
from .derivation import (
    DEFAULT_BUDGET,
    Derivation,
    cached,
    clear_memory,
    derive,
    row_indices,
)
from .families import SingularFamily

__all__ = [
    "ROW_NAMES",
    "DEFAULT_BUDGET",
    "Derivation",
    "SingularFamily",
    "derive",
    "cached",
    "clear_memory",
    "khalil_matrix",
    "row_indices",
]
