"""Reproduce the four lab reports: one command, one report, every result checked.

``seeds/`` (the texts, package data) and ``claims.toml`` (their claims as data) feed
:mod:`.data` (claims, verdicts), :mod:`.compare` (the rules), :mod:`.checks` (one check per
kind), :mod:`.experiments` (the models and experiments, no sympy), :mod:`.figures`,
:mod:`.html` and :mod:`.build` (:func:`reproduce`; its numeric half runs beside it,
:mod:`._worker`); :mod:`.replay` is its cache. Importing it is light: the names below are
imported from their module on first access (PEP 562). Command line: ``hexapod-kin reproduce``.
"""

from __future__ import annotations

TYPE_CHECKING = False
if TYPE_CHECKING:  # pragma: no cover - the names below are imported on first access
    from typing import Any

    from .build import Report, reproduce
    from .data import CLAIMS_FILE, Claim, Verdict, load_claims

#: Name → the submodule that defines it (imported on first access).
_LAZY_NAMES = {
    "Report": "build",
    "reproduce": "build",
    "CLAIMS_FILE": "data",
    "Claim": "data",
    "Verdict": "data",
    "load_claims": "data",
}


def __getattr__(name: str) -> Any:
    """Import ``name`` from its submodule on first access (PEP 562).

    Raises:
        AttributeError: If ``name`` is none of the package's names.

    """
    if name not in _LAZY_NAMES:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(f"{__name__}.{_LAZY_NAMES[name]}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY_NAMES))


__all__ = ["CLAIMS_FILE", "Claim", "Report", "Verdict", "load_claims", "reproduce"]
