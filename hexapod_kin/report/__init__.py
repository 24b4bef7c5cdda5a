"""Reproduce the four lab reports: one command, one report, every result checked.

In data-flow order:

* ``seeds/`` — the four lab reports' texts, unchanged, shipped as package data (a wheel has
  them; the report quotes them and links every claim to its lines);
* ``claims.toml`` — the seeds' claims as data, each with its place (and lines) in the seed;
* :mod:`.data` — :class:`Claim`, :class:`Verdict`, :func:`load_claims` (light);
* :mod:`.compare` — parsing the seeds' expressions and the comparison rules (sympy, numpy);
* :mod:`.replay` — the run cache: a run with the same source, claims, options and library
  versions as an earlier successful build copies its files (light);
* :mod:`.cache` — the disk cache of the printed derivations (``hexapod-kin derive``);
* :mod:`.checks` — :class:`~.checks.Context` (hexapod_kin's values) and one check per claim kind;
* :mod:`.figures` — the seed-like figures, the animations and their still frames;
* :mod:`.html` — the page's pieces (matrices as tables, the no-WebGL fallback, the seed texts);
* :mod:`.build` — :func:`reproduce`: Markdown + standalone HTML + ``verdicts.json``.

Importing this package is light (no sympy, matplotlib, Pinocchio, numba, scipy or meshcat).
``hexapod-kin reproduce --out DIR`` is the command line.
"""

from __future__ import annotations

from .build import Report, reproduce
from .data import CLAIMS_FILE, Claim, Verdict, load_claims

__all__ = ["CLAIMS_FILE", "Claim", "Report", "Verdict", "load_claims", "reproduce"]
