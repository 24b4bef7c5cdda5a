"""The same Khalil–Kleinfinger table, derived with sympy: transforms, Jacobians, det J, families.

The folder reads in the order the data flows:

* :mod:`~hexapod_kin.symbolic.sources` — a source (chain, preset, mounted leg, table file,
  URDF) turned into the chain to derive and the frame it is expressed in;
* :mod:`~hexapod_kin.symbolic.core` — the sympy stages (transforms, Jacobian, factored
  ``det J`` or Gram determinant), no caching, no budget;
* :mod:`~hexapod_kin.symbolic.families` — singular families read off the factors, checked
  against the numeric σ_min, and their numpy residuals for scans;
* :mod:`~hexapod_kin.symbolic.cache` — the disk cache keyed by the table and the time budget
  (stages run in a forked child; :func:`run_in_process` for a process that is itself bounded);
* :mod:`~hexapod_kin.symbolic.derivation` — the public face: :func:`derive`,
  :class:`Derivation`, :func:`cached`, :func:`family_residuals`.

Importing this package imports sympy (about 0.5 s): the rest of hexapod_kin imports it only
inside the functions that derive (``singularity`` families on request, the ``derive`` command).
"""

from __future__ import annotations

from .cache import in_process, run_in_process
from .core import ROW_NAMES, khalil_matrix
from .derivation import (
    _MEMO,  # noqa: F401 - the in-process memo (tests clear it)
    DEFAULT_BUDGET,
    Derivation,
    cached,
    clear_memory,
    default_rows,
    derive,
    family_residuals,
    row_indices,
)
from .families import FamilyResiduals, SingularFamily

__all__ = [
    "ROW_NAMES",
    "DEFAULT_BUDGET",
    "Derivation",
    "FamilyResiduals",
    "SingularFamily",
    "derive",
    "family_residuals",
    "cached",
    "clear_memory",
    "khalil_matrix",
    "default_rows",
    "row_indices",
    "in_process",
    "run_in_process",
]
