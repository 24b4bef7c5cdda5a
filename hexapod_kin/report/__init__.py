"""Reproduce the four lab reports: one command, one report, every result checked.

``seeds/`` (the texts, package data) and ``claims.toml`` (their claims as data) feed
:mod:`.data` (claims, verdicts), :mod:`.compare` (the rules), :mod:`.checks` (one check per
kind), :mod:`.experiments` (the models and experiments, no sympy), :mod:`.figures`,
:mod:`.html` and :mod:`.build` (:func:`reproduce`; its numeric half runs beside it,
:mod:`._worker`); :mod:`.replay` is its cache. Importing it is light: the names below are
imported from their module on first access (PEP 562). Command line: ``hexapod-kin reproduce``.
"""

from __future__ import annotations

from .._lazy import lazy_names

TYPE_CHECKING = False
if TYPE_CHECKING:  # pragma: no cover - the names below are imported on first access
    from .build import Report, reproduce
    from .data import CLAIMS_FILE, Claim, Verdict, load_claims

#: Name → the submodule that defines it (imported on first access).
_LAZY_NAMES = dict.fromkeys(("Report", "reproduce"), ".build")
_LAZY_NAMES.update(dict.fromkeys(("CLAIMS_FILE", "Claim", "Verdict", "load_claims"), ".data"))


__getattr__, __dir__ = lazy_names(__name__, _LAZY_NAMES, globals())


__all__ = ["CLAIMS_FILE", "Claim", "Report", "Verdict", "load_claims", "reproduce"]
