"""Reproduce the four lab reports (``shared/seeds``): one command, one report, every result checked.

* ``claims.toml`` — the seeds' claims as data, each with its place in the seed;
* :mod:`.compare` — parsing the claims and the comparison rules (:class:`Verdict`);
* :mod:`.checks` — one check per claim kind against hexapod_kin's values (:class:`Context`);
* :mod:`.cache` — the disk cache of the symbolic verdicts and derivation texts;
* :mod:`.figures` — the seed-like figures (a render cache: the same data is not drawn twice)
  and the animations;
* :mod:`.build` — :func:`reproduce`: Markdown + standalone HTML + ``verdicts.json`` (the
  symbolic side runs in a forked process while the experiments run).

``hexapod-kin reproduce --out DIR`` is the command line.
"""

from __future__ import annotations

from .build import Report, reproduce
from .compare import CLAIMS_FILE, Claim, Verdict, load_claims

__all__ = ["CLAIMS_FILE", "Claim", "Report", "Verdict", "load_claims", "reproduce"]
