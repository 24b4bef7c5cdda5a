"""Disk cache of the printed derivations (``sympy.pretty`` of every matrix takes a while).

One JSON file per derivation under :func:`hexapod_kin._io.cache_root` ``("report")``, named by
a SHA-256 of every field of the derivation but its timing (sympy objects by ``srepr``), the
package and sympy versions, :data:`FORMAT` and the package's source
(:func:`.replay.package_digest`). A missing, corrupt or foreign file is ignored (printed again
and rewritten).
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import fields
from typing import Any

import sympy as sp

from .._io import atomic_write, cache_root
from .replay import package_digest

__all__ = ["FORMAT", "derivation_text"]

#: Version of the file layout and of the key's parts.
FORMAT = 2


def _text(obj: Any) -> Any:
    """JSON-ready ``obj``: sympy objects by ``srepr``, sequences walked, the rest by ``repr``."""
    if isinstance(obj, sp.MatrixBase):
        return sp.srepr(sp.ImmutableMatrix(obj))
    if isinstance(obj, sp.Basic):
        return sp.srepr(obj)
    if isinstance(obj, (list, tuple)):
        return [_text(x) for x in obj]
    return repr(obj)


def _key(d: Any) -> str:
    from .. import __version__

    parts = {f.name: _text(getattr(d, f.name)) for f in fields(d)}
    del parts["seconds"], parts["cached"]
    parts.update(format=FORMAT, version=__version__, sympy=sp.__version__, code=package_digest())
    return hashlib.sha256(json.dumps(parts, sort_keys=True).encode()).hexdigest()


def derivation_text(d: Any, cache: bool = True) -> str:
    """``d.text()`` (a :class:`~hexapod_kin.symbolic.Derivation`), read from the cache when kept.

    ``cache=False``: printed, neither read nor kept.
    """
    if not cache:
        return str(d.text())
    try:
        digest = _key(d)
    except Exception:  # noqa: BLE001 - no key: print it
        return str(d.text())
    path = cache_root("report") / f"text-{digest}.json"
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        if data["key"] == digest and isinstance(data["text"], str):
            return str(data["text"])
    except Exception:  # noqa: BLE001 - missing or damaged: print it again
        pass
    text = str(d.text())
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        atomic_write(path, json.dumps({"key": digest, "text": text}, ensure_ascii=False))
    except Exception:  # noqa: BLE001 - a cache that cannot be written is only slower
        pass
    return text
