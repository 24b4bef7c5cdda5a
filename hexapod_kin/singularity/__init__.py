"""Singularity measures, scans of joint space, singular families.

The package, from the kernel up:

* :mod:`._kernel` — the compiled kernel: fused FK + Jacobian rows + measures over blocks of
  configurations, on :mod:`hexapod_kin._numerics`; :mod:`._plan` — its Python side (chain
  with z joint axes, Gram/minor plans, output buffers, kept in ``Model.cached``);
* row names and selections: :mod:`hexapod_kin.jacobian_rows` (a leaf shared with
  :mod:`hexapod_kin.symbolic`; ``ROW_NAMES``, ``row_indices``, ``row_names`` re-exported here);
* :mod:`.measure` — :func:`measures` (Pinocchio + numpy), :func:`measures_batch` (the
  kernel), :func:`default_rows`, :func:`reach`;
* :mod:`._zeroset` — a family's factor compiled to numpy value/gradient/Hessian evaluators,
  and the exact distance to its zero set;
* :mod:`.families` — singular families as numbers, derived only when asked, cached on disk;
* :mod:`.scans` — :func:`scan` / :class:`ScanResult` (Pinocchio + numpy up to
  ``SMALL_SCAN`` configurations, the kernel above), defaults, family labels.

(``measure`` and ``scans`` are named apart from the functions ``measures`` and ``scan``: a
submodule of the same name would replace the function as the package's attribute.)

The reachable workspace is :mod:`hexapod_kin.workspace` (re-exported here). Names load on first
use (PEP 562), so ``import hexapod_kin.singularity`` imports neither numba nor sympy.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from ..jacobian_rows import ROW_NAMES, row_indices, row_names

if TYPE_CHECKING:  # pragma: no cover
    from ..workspace import WorkspaceResult, cross_section, workspace
    from .families import Families, Family, families_for
    from .measure import Measures, MeasuresBatch, default_rows, measures, measures_batch, reach
    from .scans import ScanResult, default_joints, default_q_fixed, scan

__all__ = [
    "ROW_NAMES",
    "Families",
    "Family",
    "Measures",
    "MeasuresBatch",
    "ScanResult",
    "WorkspaceResult",
    "cross_section",
    "default_joints",
    "default_q_fixed",
    "default_rows",
    "families_for",
    "measures",
    "measures_batch",
    "reach",
    "row_indices",
    "row_names",
    "scan",
    "workspace",
]

_WHERE = {
    "Families": ".families",
    "Family": ".families",
    "families_for": ".families",
    "Measures": ".measure",
    "MeasuresBatch": ".measure",
    "default_rows": ".measure",
    "measures": ".measure",
    "measures_batch": ".measure",
    "reach": ".measure",
    "ScanResult": ".scans",
    "default_joints": ".scans",
    "default_q_fixed": ".scans",
    "scan": ".scans",
    "WorkspaceResult": "..workspace",
    "cross_section": "..workspace",
    "workspace": "..workspace",
}


def __getattr__(name: str) -> Any:
    where = _WHERE.get(name)
    if where is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(where, __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
