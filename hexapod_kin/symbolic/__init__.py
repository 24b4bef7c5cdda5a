"""The same Khalil–Kleinfinger table, derived with sympy: transforms, Jacobians, det J, families.

:mod:`.sources` (a source → the chain to derive), :mod:`.core` (the sympy stages),
:mod:`.families` (families off the factors, checked against σ_min), :mod:`.cache` (the disk
cache), :mod:`.derivation` (:func:`derive`, :class:`Derivation`, :func:`cached`). The names
below are imported from their module on first access (PEP 562): importing this package (or
its sympy-free :mod:`.sources`) imports no sympy; the first of those names does.
"""

from __future__ import annotations

from .._lazy import lazy_names
from ._limits import DEFAULT_BUDGET

TYPE_CHECKING = False
if TYPE_CHECKING:  # pragma: no cover - the names below are imported on first access
    from .core import ROW_NAMES, khalil_matrix
    from .derivation import Derivation, cached, clear_memory, derive, row_indices
    from .families import SingularFamily

#: Name → the submodule that defines it (imported on first access).
_LAZY_NAMES = dict.fromkeys(("ROW_NAMES", "khalil_matrix"), ".core")
_LAZY_NAMES |= dict.fromkeys(("Derivation", "cached", "clear_memory", "derive"), ".derivation")
_LAZY_NAMES |= {"row_indices": ".derivation", "SingularFamily": ".families"}


__getattr__, __dir__ = lazy_names(__name__, _LAZY_NAMES, globals())


__all__ = ["ROW_NAMES", "DEFAULT_BUDGET", "Derivation", "SingularFamily", "derive", "cached",
           "clear_memory", "khalil_matrix", "row_indices"]  # fmt: skip
