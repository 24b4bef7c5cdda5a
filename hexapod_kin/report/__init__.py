"""Reproduce the four lab reports: one command, one report, every result checked.

``seeds/`` (the texts, package data) and ``claims.toml`` (their claims as data) feed
:mod:`.data` (claims, verdicts), :mod:`.compare` (the rules), :mod:`.checks` (one check per
kind), :mod:`.figures`, :mod:`.html` and :mod:`.build` (:func:`reproduce`); :mod:`.replay` is its
cache. Importing it is light. Command line: ``hexapod-kin reproduce``.
"""

from __future__ import annotations

from .build import Report, reproduce
from .data import CLAIMS_FILE, Claim, Verdict, load_claims

__all__ = ["CLAIMS_FILE", "Claim", "Report", "Verdict", "load_claims", "reproduce"]
