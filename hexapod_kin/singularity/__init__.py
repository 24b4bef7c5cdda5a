"""Singularity measures, scans of joint space, singular families.

:mod:`.measure` (:func:`measures`, :func:`measures_batch`), :mod:`.scans` (:func:`scan`),
:mod:`.families` (families as numbers, cached on disk), :mod:`._zeroset` (exact distances to
a family), :mod:`._kernel` / :mod:`._plan` (the compiled batch kernel and its Python side).
Row names come from :mod:`hexapod_kin.jacobian_rows`; the workspace is
:mod:`hexapod_kin.workspace`. Names load on first use (PEP 562): importing the package imports
neither numba nor sympy.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import lazy_names
from ..jacobian_rows import ROW_NAMES, row_indices, row_names

if TYPE_CHECKING:  # pragma: no cover
    from ..workspace import WorkspaceResult, cross_section, workspace
    from .families import Families, Family, families_for
    from .measure import Measures, MeasuresBatch, default_rows, measures, measures_batch, reach
    from .scans import ScanResult, default_joints, default_q_fixed, scan


__all__ = ["ROW_NAMES", "Families", "Family", "Measures", "MeasuresBatch", "ScanResult",
           "WorkspaceResult", "cross_section", "default_joints", "default_q_fixed", "default_rows",
           "families_for", "measures", "measures_batch", "reach", "row_indices", "row_names",
           "scan", "workspace"]  # fmt: skip

_WHERE = {
    name: where
    for where, names in (
        (".families", ("Families", "Family", "families_for")),
        (".measure", ("Measures", "MeasuresBatch", "default_rows", "measures", "measures_batch")),
        (".measure", ("reach",)),
        (".scans", ("ScanResult", "default_joints", "default_q_fixed", "scan")),
        ("..workspace", ("WorkspaceResult", "cross_section", "workspace")),
    )
    for name in names
}


__getattr__, __dir__ = lazy_names(__name__, _WHERE, globals())
