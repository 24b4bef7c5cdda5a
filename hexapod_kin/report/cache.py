"""Disk cache of the symbolic verdicts: a second ``reproduce`` reads them instead of redoing sympy.

One JSON file per verdict under :func:`hexapod_kin._io.cache_root` ``("report")``
(``$HEXAPOD_KIN_CACHE_DIR/report`` when set), named by a SHA-256 of everything the verdict
depends on:

* the claim's own data (the seed's text as written in ``claims.toml``) and the data of the
  claims its check reads (the seed's own factors of a product, the ``p`` a ``J`` should be the
  derivative of);
* hexapod_kin's expressions the check compares against (``srepr`` of the derived matrices,
  det J, the families, the lengths, the preset's table rows);
* the package version, the sympy version, this cache's :data:`FORMAT` and the package's source
  (:func:`package_digest`, kept in :mod:`.replay`), so an edited rule never reads an old verdict.

Only the symbolic kinds are cached (:data:`KINDS`); the numeric checks (FK, IK, schedule,
measured bounds) always run. A verdict with status ``"error"`` is never stored. The plain-text
derivations printed in the report (:func:`derivation_text`) are kept the same way, keyed by
every field of the derivation but its timing. Files are written atomically
(:func:`hexapod_kin._io.atomic_write`); a missing, corrupt or foreign file is ignored (the
verdict is recomputed and the file rewritten).
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import fields
from functools import lru_cache
from pathlib import Path
from typing import Any

import sympy as sp

from .._io import atomic_write, cache_root
from .compare import Claim, Verdict
from .replay import package_digest

__all__ = [
    "FORMAT",
    "KINDS",
    "cache_dir",
    "derivation_text",
    "key",
    "load",
    "package_digest",
    "store",
]

#: Version of the file layout and of the key's parts.
FORMAT = 1
#: Claim kinds whose verdicts are cached (the ones that run sympy).
KINDS = frozenset({"matrix", "generic", "det", "table", "families"})
_STATUSES = ("agrees", "wrong", "differs")
_FIELDS = tuple(f.name for f in fields(Verdict))


def cache_dir() -> Path:
    """The cache folder (not created here): :func:`hexapod_kin._io.cache_root` ``("report")``."""
    return cache_root("report")


def _sre(obj: Any) -> str:
    return _srepr(sp.ImmutableMatrix(obj) if isinstance(obj, sp.MatrixBase) else obj)


@lru_cache(maxsize=1024)
def _srepr(obj: Any) -> str:
    """``sympy.srepr``, remembered (the claims of one model share its matrices)."""
    return str(sp.srepr(obj))


def _factor_claims(c: Claim, ctx: Any) -> list[Any]:
    """The data of the seed's own ``^{k-1}T_k`` claims a ``^0T_j`` check multiplies."""
    j = int(c.data["item"][3:])
    return [
        x.data
        for x in ctx.claims.values()
        if x.seed == c.seed
        and x.kind == "matrix"
        and x.data.get("model") == c.data["model"]
        and x.data.get("item") in {f"T {k}" for k in range(1, j + 1)}
    ]


def _ours(c: Claim, ctx: Any) -> dict[str, Any]:
    """hexapod_kin's side of a symbolic check (what its verdict depends on), as text."""
    from .checks import _OTHER, MODELS, _det_truth

    kind, data = c.kind, c.data
    if kind == "matrix":
        key, item = data["model"], data["item"]
        out: dict[str, Any] = {"truth": _sre(ctx.item(key, item))}
        if key in _OTHER:
            out["other"] = _sre(ctx.item(_OTHER[key][0], item))
        if item.startswith("0T "):
            out["factors"] = _factor_claims(c, ctx)
        if "derivative_of" in data:
            out["derivative_of"] = ctx.claims[data["derivative_of"]].data
        return out
    if kind == "generic":
        from ..symbolic import khalil_matrix

        s = sp.symbols("alpha d theta r", real=True)
        return {"truth": _sre(sp.Matrix(khalil_matrix(*s)))}
    if kind == "det":
        return {"truth": _sre(_det_truth(c, ctx))}
    if kind == "table":
        key = data["model"]
        return {
            "preset": repr(MODELS[key]),
            "rows": repr(ctx.chain(key).rows),
            "lengths": repr(sorted(ctx.lengths(key).items(), key=str)),
            "p": [_sre(ctx.item(k, "p")) for k in ("leg", "leg+")],
        }
    if kind == "families":
        d = ctx.derivation(data["model"])
        return {
            "det": _sre(d.det),
            "numeric": _sre(d.numeric(d.det)),
            "families": [repr(f) for f in d.families],
            "lengths": repr(sorted(ctx.lengths(data["model"]).items(), key=str)),
            "nq": d.chain.nq,
        }
    raise KeyError(kind)


def key(c: Claim, ctx: Any) -> str | None:
    """The cache key of ``c``'s verdict against ``ctx``, or ``None`` (kind not cached)."""
    if c.kind not in KINDS:
        return None
    from .. import __version__

    parts = {
        "format": FORMAT,
        "version": __version__,
        "sympy": sp.__version__,
        "code": package_digest(),
        "claim": c.data,
        "ours": _ours(c, ctx),
    }
    text = json.dumps(parts, sort_keys=True, default=repr)
    return hashlib.sha256(text.encode()).hexdigest()


def load(digest: str, claim: Claim) -> Verdict | None:
    """The verdict stored under ``digest`` for ``claim``, or ``None`` (missing or unusable)."""
    try:
        data = json.loads((cache_dir() / f"{digest}.json").read_text(encoding="utf-8"))
        v = data["verdict"]
        ok = (
            data.get("format") == FORMAT
            and data.get("key") == digest
            and set(v) == set(_FIELDS)
            and all(isinstance(v[f], str) for f in _FIELDS)
            and v["claim"] == claim.id
            and v["kind"] == claim.kind
            and v["status"] in _STATUSES
        )
        return Verdict(**{f: v[f] for f in _FIELDS}) if ok else None
    except Exception:  # noqa: BLE001 - any damage to the file means "not cached"
        return None


def store(digest: str, verdict: Verdict) -> Path | None:
    """Write ``verdict`` atomically; the path, or ``None`` (error verdict, unwritable folder)."""
    if verdict.status not in _STATUSES:
        return None
    try:
        folder = cache_dir()
        folder.mkdir(parents=True, exist_ok=True)
        v = {f: getattr(verdict, f) for f in _FIELDS}
        text = json.dumps({"format": FORMAT, "key": digest, "verdict": v}, ensure_ascii=False)
        return atomic_write(folder / f"{digest}.json", text)
    except Exception:  # noqa: BLE001 - a cache that cannot be written is only slower
        return None


def _text_key(d: Any) -> str:
    parts: dict[str, Any] = {
        "format": FORMAT,
        "sympy": sp.__version__,
        "code": package_digest(),
    }
    for f in fields(d):
        if f.name in ("seconds", "cached"):
            continue
        value = getattr(d, f.name)
        if isinstance(value, (list, tuple)):
            parts[f.name] = [_sre(v) if isinstance(v, sp.Basic) else repr(v) for v in value]
        else:
            parts[f.name] = _sre(value) if isinstance(value, sp.Basic) else repr(value)
    text = json.dumps(parts, sort_keys=True, default=repr)
    return hashlib.sha256(text.encode()).hexdigest()


def derivation_text(d: Any, cache: bool = True) -> str:
    """``d.text()`` (a :class:`~hexapod_kin.symbolic.Derivation`), read from the cache when kept.

    The key is every field of ``d`` but ``seconds`` and ``cached`` (``srepr`` of the sympy
    ones), the sympy version and the package source. ``cache=False``: printed, not kept.
    """
    if not cache:
        return str(d.text())
    try:
        digest = _text_key(d)
    except Exception:  # noqa: BLE001 - no key: print it
        return str(d.text())
    path = cache_dir() / f"text-{digest}.json"
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        if data.get("format") == FORMAT and data.get("key") == digest:
            if isinstance(data.get("text"), str):
                return str(data["text"])
    except Exception:  # noqa: BLE001 - missing or damaged: print it again
        pass
    text = str(d.text())
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        payload = {"format": FORMAT, "key": digest, "text": text}
        atomic_write(path, json.dumps(payload, ensure_ascii=False))
    except Exception:  # noqa: BLE001 - a cache that cannot be written is only slower
        pass
    return text
