"""The same Khalil–Kleinfinger table, derived with sympy: transforms, Jacobians, det J, families.

:mod:`.sources` (a source → the chain to derive), :mod:`.core` (the sympy stages),
:mod:`.families` (families off the factors, checked against σ_min), :mod:`.cache` (the disk
cache), :mod:`.derivation` (:func:`derive`, :class:`Derivation`, :func:`cached`). Importing
this package imports sympy: the rest of hexapod_kin imports it only inside functions.
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
