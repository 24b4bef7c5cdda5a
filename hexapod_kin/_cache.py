"""The package's disk caches: one folder, one key, one keyed seal, one warning.

Every cache of the package (symbolic derivations, singular families, printed derivations,
report replays, sweep chunks) goes through this module:

* :func:`folder` — ``$HEXAPOD_KIN_CACHE_DIR/<kind>``, else
  ``platformdirs.user_cache_dir("hexapod_kin")/<kind>`` when platformdirs is installed, else
  ``~/.cache/hexapod_kin/<kind>``.
* :func:`key` — SHA-256 of the canonical JSON of what an entry depends on.
* :func:`mac` / :func:`seal` — HMAC-SHA256 keyed by a per-user secret (32 random bytes in
  ``seal.key`` of the cache root, mode 0600, created once, race-free). A plain hash guards
  against accidents only: anyone can recompute it after an edit. A seal needs the secret, so
  an edited entry resealed by someone without it is detected. Without a readable or
  writable secret (a read-only or unusable cache root) nothing is cached.
* :func:`store` / :func:`load` — one JSON envelope per entry (``format``, ``key``, ``body``,
  ``seal``), written atomically (:func:`hexapod_kin._io.atomic_write`: no temporary file left
  on any failure). A missing entry, or one of another format, is no entry (quietly);
  anything else that is not the sealed entry of its key is no entry with one
  :class:`~hexapod_kin.exceptions.CacheWarning` (:func:`damaged`, the one text).

The seal is not what protects the answers: every cache also checks what an entry claims
against the robot (its caller's content checks), so even an entry sealed with a stolen secret
is not used when it is wrong.
"""

from __future__ import annotations

import hashlib
import hmac
import json
import os
import re
import secrets
import threading
import warnings
from pathlib import Path
from typing import Any

from ._io import atomic_write
from .exceptions import CacheWarning, HexapodKinError

__all__ = ["damaged", "folder", "key", "load", "mac", "seal", "store"]

_SECRET_BYTES = 32
_SECRETS: dict[str, bytes | None] = {}
_LOCK = threading.Lock()


def root() -> Path:
    """The cache root (not created here); see the module docstring."""
    env = os.environ.get("HEXAPOD_KIN_CACHE_DIR")
    if env:
        return Path(env)
    try:
        import platformdirs

        return Path(platformdirs.user_cache_dir("hexapod_kin"))
    except ImportError:
        return Path.home() / ".cache" / "hexapod_kin"


def folder(kind: str) -> Path:
    """The cache folder of ``kind`` (``"symbolic"``, ``"families"``, ``"report"``, ...)."""
    return root() / kind


def _canonical(obj: Any) -> bytes:
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), ensure_ascii=True).encode()


def key(parts: Any) -> str:
    """SHA-256 (hex) of the canonical JSON of ``parts`` (anything else by ``repr``)."""
    text = json.dumps(parts, sort_keys=True, separators=(",", ":"), default=repr)
    return hashlib.sha256(text.encode()).hexdigest()


def _secret() -> bytes | None:
    """The per-user secret of the seals, created once; ``None`` when the root is unusable.

    Created race-free: a private temporary file is hard-linked to the name, so of concurrent
    first runs one wins and the others read its secret. A secret of the wrong length is
    replaced (entries sealed with the old one are then recomputed). A cache root that is a
    regular file is said once (one :class:`CacheWarning`).
    """
    base = root()
    with _LOCK:
        if str(base) in _SECRETS:
            return _SECRETS[str(base)]
        path = base / "seal.key"
        found: bytes | None = None
        for _ in range(2):
            try:
                data = path.read_bytes()
                if len(data) == _SECRET_BYTES:
                    found = data
                    break
            except OSError:
                pass
            tmp = base / f".seal.key.{secrets.token_hex(8)}.tmp"
            try:
                base.mkdir(parents=True, exist_ok=True)
                fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
                with os.fdopen(fd, "wb") as fh:
                    fh.write(secrets.token_bytes(_SECRET_BYTES))
                try:
                    if path.exists():
                        os.replace(tmp, path)
                    else:
                        os.link(tmp, path)
                except FileExistsError:
                    pass  # another process made it first: read its secret
            except OSError as exc:
                if base.exists() and not base.is_dir() or isinstance(exc, NotADirectoryError):
                    warnings.warn(
                        f"cache folder {str(base)!r} is not a folder (a regular file?); "
                        "nothing is cached",
                        CacheWarning,
                        stacklevel=4,
                    )
                break
            finally:
                try:
                    tmp.unlink()
                except OSError:
                    pass
        _SECRETS[str(base)] = found
        return found


def mac(*chunks: bytes) -> str | None:
    """HMAC-SHA256 (hex) of ``chunks`` (each length-prefixed) with the secret; ``None``: none."""
    secret = _secret()
    if secret is None:
        return None
    h = hmac.new(secret, digestmod=hashlib.sha256)
    for chunk in chunks:
        h.update(len(chunk).to_bytes(8, "big"))
        h.update(chunk)
    return h.hexdigest()


def seal(kind: str, digest: str, body: Any) -> str | None:
    """The keyed seal binding ``body`` (JSON data) to ``kind`` and the key ``digest``."""
    return mac(kind.encode(), digest.encode(), _canonical(body))


def damaged(kind: str, name: str, why: BaseException | str, then: str, stacklevel: int = 3) -> None:
    """The one warning of a cache entry that is not what it claims (see the module docstring).

    Args:
        kind: The cache (``"symbolic"``, ``"families"``, ...).
        name: The entry (a key, shown by its first 12 characters, or file names).
        why: What is wrong (an exception: its type and message).
        then: What happens instead (``"recomputing it"``).
        stacklevel: As for :func:`warnings.warn`, from the caller's caller.

    """
    short = name[:12] if re.fullmatch(r"[0-9a-f]{16,}", name) else name
    if isinstance(why, BaseException):
        why = f"{type(why).__name__}: {' '.join(str(why).split())[:80]}"
    warnings.warn(
        f"{kind} cache entry {short} is damaged or was edited ({why}); {then}",
        CacheWarning,
        stacklevel=stacklevel,
    )


def store(kind: str, digest: str, body: Any, fmt: int, *, sync: bool = True) -> Path | None:
    """Write ``body`` (JSON data) as the sealed entry ``digest`` of ``kind``, atomically.

    Returns:
        The file, or ``None`` when nothing is cached (no secret, unwritable, disk full: a
        cache that cannot be written is only slower). No temporary file is left behind.

    """
    stamp = seal(kind, digest, body)
    if stamp is None:
        return None
    text = json.dumps({"format": fmt, "key": digest, "body": body, "seal": stamp})
    path = folder(kind) / f"{digest}.json"
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        return atomic_write(path, text, sync=sync)
    except (OSError, HexapodKinError):
        return None


def load(kind: str, digest: str, fmt: int, then: str) -> Any | None:
    """The body of the sealed entry ``digest`` of ``kind``, or ``None``.

    Missing, of another format, or no secret: ``None`` quietly. Unreadable, torn, edited
    (seal broken), resealed without the secret, or another key's (a swapped or copied
    file): ``None`` with one warning (:func:`damaged`, ``then`` saying what happens).
    """
    if _secret() is None:
        return None
    path = folder(kind) / f"{digest}.json"
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        return None
    except (OSError, UnicodeDecodeError) as exc:
        damaged(kind, digest, exc, then)
        return None
    try:
        data = json.loads(text)
        if isinstance(data, dict) and "format" in data and data["format"] != fmt:
            return None  # an older (or newer) package's entry: rewritten quietly
        if not isinstance(data, dict) or data.get("key") != digest:
            raise ValueError("not the entry of its key")
        expected = seal(kind, digest, data.get("body")) or ""
        if not isinstance(data.get("seal"), str) or not hmac.compare_digest(data["seal"], expected):
            raise ValueError("its seal does not match its content")
        return data["body"]
    except Exception as exc:  # noqa: BLE001 - any damage means "no entry"
        damaged(kind, digest, exc, then)
        return None
