"""The resumable chunks of a sweep: written atomically, checked against what they claim.

A sweep writing ``x.csv`` keeps each finished chunk in the hidden ``.x.csv.sweep-parts/``
(``chunk_NNNNN.npz`` and a ``manifest.json``). A stored chunk is used only when it is a bounded
plain ``.npz`` (never unpickled) naming this sweep's key and its number, sealed
(:func:`hexapod_kin._cache.mac`), with plausible scores, and one of its designs scored again
gives the same bits; the others are scored again (one ``CacheWarning``).
"""

from __future__ import annotations

import hashlib
import hmac
import io
import json
import zipfile
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .. import _cache as _disk
from .._io import atomic_write, read_regular
from ..exceptions import ConfigurationError, HexapodKinError
from .scores import SCORES

__all__ = ["ChunkStore", "check_scores"]

_SLACK = 1 << 16  # bytes of a chunk file beside its scores (zip headers, key, digest)
_FLAGS = ("feasible", "volume_exact")
_NON_NEGATIVE = ("volume", "volume_se", "volume_mc", "volume_mc_se")


def check_scores(scores: np.ndarray) -> str | None:
    """Why ``scores`` (n, len(SCORES)) cannot be a chunk's scores, or None when plausible."""
    if scores.ndim != 2 or scores.shape[1] != len(SCORES):
        return f"scores of shape {scores.shape}"
    bad = ~np.isfinite(scores)
    if bad.any():
        i, j = np.argwhere(bad)[0]
        return f"{list(SCORES)[j]} = {scores[i, j]} (design {i} of the chunk)"
    names = list(SCORES)
    for name in _FLAGS:
        col = scores[:, names.index(name)]
        if not np.all((col == 0) | (col == 1)):
            return f"{name} not 0 or 1"
    for name in _NON_NEGATIVE:
        if np.any(scores[:, names.index(name)] < 0):
            return f"{name} < 0"
    return None


class ChunkStore:
    """The sidecar folder of one sweep (see the module docstring)."""

    def __init__(self, parts: Path, key: str, spec: Mapping[str, Any], chunks: int) -> None:
        self.parts = parts
        self.key = key
        self.manifest = json.dumps({"key": key, "spec": spec, "chunks": chunks}, indent=1) + "\n"
        self._ready = False

    def _digest(self, k: int, scores: np.ndarray) -> str:
        """The keyed seal of chunk ``k`` (:func:`hexapod_kin._cache.mac`; "" without a secret)."""
        data = np.ascontiguousarray(scores, dtype=float).tobytes()
        return _disk.mac(b"sweep", f"{self.key}:{k}".encode(), data) or ""

    def path(self, k: int) -> Path:
        """The file of chunk ``k``."""
        return self.parts / f"chunk_{k:05d}.npz"

    def resume(
        self, bounds: Sequence[tuple[int, int]], designs: np.ndarray,
        rescore: Callable[[np.ndarray], np.ndarray], out: str,
    ) -> dict[int, np.ndarray]:  # fmt: skip
        """The stored chunks that pass every check, by number (the others: one warning).

        Raises ConfigurationError when the folder holds chunks of another sweep (its readable
        manifest names another key): an interrupted sweep is never overwritten.
        """
        if not self.parts.is_dir():
            return {}
        files = sorted(self.parts.glob("chunk_*.npz"))
        try:
            old = json.loads(read_regular(self.parts / "manifest.json", 1 << 20))
            old_key = old.get("key") if isinstance(old, dict) else None
        except (HexapodKinError, ValueError):
            old_key = None
        if old_key is not None and old_key != self.key and files:
            msg = (
                f"out={out!r}: {str(self.parts)!r} holds chunks of a different sweep "
                f"(key {str(old_key)[:12]} != {self.key[:12]}), interrupted; re-run that "
                "sweep to finish it, use another --out, or remove that folder"
            )
            raise ConfigurationError(msg, parameter="out", value=out)
        results: dict[int, np.ndarray] = {}
        bad: list[str] = []
        for k, (a, b) in enumerate(bounds):
            f = self.path(k)
            if f.exists():
                got = self._load(f, k, designs[a:b], rescore)
                if got is None:
                    bad.append(f.name)
                else:
                    results[k] = got
        if bad:
            names = ", ".join(bad[:3]) + (f" and {len(bad) - 3} more" if len(bad) > 3 else "")
            who = ("they do not", "they claim") if bad[1:] else ("it does not", "it claims")
            verb = f"{who[0]} hold what {who[1]}"
            where = f"{names} in {self.parts.name}"
            _disk.damaged("sweep", where, verb, "scoring again", stacklevel=3)
        return results

    def _load(
        self, path: Path, k: int, designs: np.ndarray, rescore: Callable[[np.ndarray], np.ndarray]
    ) -> np.ndarray | None:
        n = designs.shape[0]
        room = n * len(SCORES) * 8 + _SLACK  # the scores' bytes and the small arrays
        try:
            data = read_regular(path, room)  # a regular file only (a pipe would block np.load)
            with zipfile.ZipFile(io.BytesIO(data)) as zf:  # the members' sizes, before inflating
                if sum(info.file_size for info in zf.infolist()) > room:
                    return None
            with np.load(io.BytesIO(data), allow_pickle=False) as z:
                scores = np.array(z["scores"], dtype=float)
                ok = (
                    str(z["key"]) == self.key
                    and int(z["chunk"]) == k
                    and scores.shape == (n, len(SCORES))
                    and hmac.compare_digest(str(z["digest"]), self._digest(k, scores) or "-")
                    and check_scores(scores) is None
                )
        except Exception:  # noqa: BLE001 - a damaged file (bad zip, truncated, pickled, ...)
            return None
        if not ok:
            return None
        r = int(hashlib.sha256(f"{self.key}:{k}".encode()).hexdigest(), 16) % n
        if not np.array_equal(rescore(designs[r : r + 1])[0], scores[r]):
            return None
        return scores

    def save(self, k: int, scores: np.ndarray) -> None:
        """Write chunk ``k`` atomically (the folder and its manifest with the first one)."""
        if not self._ready:
            self.parts.mkdir(exist_ok=True)
            atomic_write(self.parts / "manifest.json", self.manifest)
            self._ready = True
        buf = io.BytesIO()
        arrays: dict[str, Any] = dict(key=np.array(self.key), chunk=np.array(k))
        arrays |= dict(scores=np.ascontiguousarray(scores, dtype=float))
        np.savez(buf, **arrays, digest=np.array(self._digest(k, scores)))
        atomic_write(self.path(k), buf.getvalue())
