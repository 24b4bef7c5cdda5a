"""Reproduce the four lab reports (``shared/seeds``): one command, one report, every result checked.

* ``claims.toml`` — the seeds' claims as data, each with its place in the seed;
* :mod:`.data` — :class:`Claim`, :class:`Verdict`, :func:`load_claims` (light);
* :mod:`.compare` — parsing the seeds' expressions and the comparison rules;
* :mod:`.checks` — one check per claim kind against hexapod_kin's values (:class:`Context`);
* :mod:`.cache` — the disk cache of the symbolic verdicts and derivation texts;
* :mod:`.figures` — the seed-like figures (a render cache: the same data is not drawn twice)
  and the animations;
* :mod:`.build` — :func:`reproduce`: Markdown + standalone HTML + ``verdicts.json`` (the
  symbolic side runs in a forked process while the experiments run);
* :mod:`.replay` — the run cache: a run with the same source, claims, options and library
  versions as an earlier successful build copies its files (no experiment is redone).

Importing this package is light (no sympy, matplotlib, Pinocchio, numba, scipy or meshcat):
they are imported when a report is built, not when one is replayed.

``hexapod-kin reproduce --out DIR`` is the command line.
"""

from __future__ import annotations

from .build import Report, reproduce
from .data import CLAIMS_FILE, Claim, Verdict, load_claims

__all__ = ["CLAIMS_FILE", "Claim", "Report", "Verdict", "load_claims", "reproduce"]
