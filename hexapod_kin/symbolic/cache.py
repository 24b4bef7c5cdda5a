"""The disk cache of :func:`hexapod_kin.symbolic.derive`: one sealed entry per derivation.

Entries (:mod:`hexapod_kin._cache`, kind ``"symbolic"``) are keyed by the table, the row
selection, the length names and :data:`FORMAT`, and hold the stages reached (and, when
unfinished, why and with which budget; :class:`Writer` writes stage by stage). Sympy objects
are stored as ``srepr`` text, rebuilt by a restricted reader (:mod:`._reader`, no ``eval``); a
damaged or foreign entry is ignored with one ``CacheWarning``.
"""

from __future__ import annotations

from contextlib import suppress
from dataclasses import fields
from pathlib import Path
from typing import Any

import sympy as sp

from .. import _cache as _disk
from .._io import atomic_write
from ..exceptions import HexapodKinError
from ._reader import read_srepr
from .families import SingularFamily

FORMAT = 6
KIND = "symbolic"
THEN = "recomputing it"


def cache_dir() -> Path:
    """The cache folder (not created here): :func:`hexapod_kin._cache.folder` ``("symbolic")``."""
    return _disk.folder(KIND)


def key(parts: Any) -> str:
    """The key of a derivation: :func:`hexapod_kin._cache.key` of ``parts`` and the format."""
    return _disk.key({"format": FORMAT, "parts": parts})


def _encode(obj: Any) -> Any:
    if isinstance(obj, SingularFamily):
        return {"__family__": {f.name: _encode(getattr(obj, f.name)) for f in fields(obj)}}
    if isinstance(obj, sp.MatrixBase):
        return {"__matrix__": sp.srepr(sp.ImmutableMatrix(obj))}
    if isinstance(obj, sp.Basic):
        return {"__sympy__": sp.srepr(obj)}
    if isinstance(obj, dict):
        return {"__dict__": [[_encode(k), _encode(v)] for k, v in obj.items()]}
    if isinstance(obj, (list, tuple)):
        return {"__tuple__": [_encode(x) for x in obj]}
    if obj is None or isinstance(obj, (bool, int, float, str)):
        return obj
    raise TypeError(f"cannot cache {type(obj).__name__}")


def _decode(obj: Any) -> Any:
    if isinstance(obj, dict):
        if "__family__" in obj:
            return SingularFamily(**{k: _decode(v) for k, v in obj["__family__"].items()})
        if "__matrix__" in obj:
            return sp.Matrix(read_srepr(obj["__matrix__"]))
        if "__sympy__" in obj:
            return read_srepr(obj["__sympy__"])
        if "__dict__" in obj:
            return {_decode(k): _decode(v) for k, v in obj["__dict__"]}
        if "__tuple__" in obj:
            return tuple(_decode(x) for x in obj["__tuple__"])
        raise ValueError("unknown cache entry")
    return obj


def load(digest: str) -> dict[str, Any] | None:
    """Stages stored under ``digest`` (rebuilt by the restricted reader), or ``None``.

    ``None`` when missing, or damaged or refused by the reader (one warning).
    """
    body = _disk.load(KIND, digest, FORMAT, THEN)
    if body is None:
        return None
    try:
        stages = _decode(body)
        if not isinstance(stages, dict):
            raise ValueError("no stages")
        return stages
    except Exception as exc:  # noqa: BLE001 - any damage to the file means "not cached"
        _disk.damaged(KIND, digest, exc, THEN)
        return None


def store(digest: str, stages: dict[str, Any]) -> Path | None:
    """Write ``stages`` atomically; returns the path, or ``None`` when it cannot be written."""
    try:
        body = _encode(stages)
    except TypeError:
        return None
    return _disk.store(KIND, digest, body, FORMAT)


class Writer:
    """Writes the stages of one derivation as they come (atomic, no ``fsync``), each encoded once.

    After every stage the file holds the stages reached so far and ``attempt`` (why it is
    unfinished, and with which budget): a run stopped at its budget leaves what it reached.
    """

    def __init__(self, digest: str, have: dict[str, Any]) -> None:
        """Start from the stages ``have`` (of an earlier, unfinished run)."""
        self.digest = digest
        self.parts = {name: _encode(value) for name, value in have.items()}

    def add(self, name: str, value: Any, attempt: Any, key: str) -> None:
        """Add a stage and write the file; ``attempt`` (stored under ``key``) None: complete."""
        self.parts[name] = _encode(value)
        items = [[k, v] for k, v in self.parts.items()]
        if attempt is not None:
            items.append([key, _encode(attempt)])
        _disk.store(KIND, self.digest, {"__dict__": items}, FORMAT, sync=False)


def snapshot(digest: str) -> bytes | None:
    """The entry file of ``digest`` as it is now (None: there is none), for :func:`restore`."""
    try:
        return (cache_dir() / f"{digest}.json").read_bytes()
    except OSError:
        return None


def restore(digest: str, data: bytes | None) -> None:
    """Put the entry of ``digest`` back as :func:`snapshot` found it (after a Ctrl-C)."""
    path = cache_dir() / f"{digest}.json"
    with suppress(OSError, HexapodKinError):
        if data is None:
            path.unlink(missing_ok=True)
        else:
            atomic_write(path, data, sync=False)
    sweep(digest)


def sweep(digest: str) -> None:
    """Remove the temporary files a killed derivation of ``digest`` may have left."""
    for tmp in cache_dir().glob(f".{digest}.json.*.tmp"):
        with suppress(OSError):
            tmp.unlink()
