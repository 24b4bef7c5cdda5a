"""The package's disk caches (symbolic, families, report, sweep): one folder, one key, one seal.

The root is ``$HEXAPOD_KIN_CACHE_DIR``, else the user cache folder. Entries are sealed by an
HMAC-SHA256 keyed by a per-user secret in the root's ``seal.key`` (no secret, no cache); an
entry that is not the sealed one of its key is no entry, with one
:class:`~hexapod_kin.exceptions.CacheWarning`. Each cache also checks an entry's claims
against the robot.
"""

from __future__ import annotations

import contextlib
import hashlib
import hmac
import json
import os
import re
import secrets
import threading
import warnings
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

from ._io import atomic_write
from .exceptions import CacheWarning, HexapodKinError

__all__ = ["FOLDER_SEAL", "check_folder", "damaged", "folder", "key", "load", "mac", "seal",
           "seal_folder", "store", "user_secret"]  # fmt: skip

_SECRET_BYTES = 32
_SECRETS: dict[str, bytes | None] = {}
_LOCK = threading.Lock()


def root() -> Path:
    """The cache root (not created here); see the module docstring."""
    env = os.environ.get("HEXAPOD_KIN_CACHE_DIR")
    return Path(env) if env else _default_root()


def _default_root() -> Path:
    """The user's own cache root (``HEXAPOD_KIN_CACHE_DIR`` aside)."""
    try:
        import platformdirs

        return Path(platformdirs.user_cache_dir("hexapod_kin"))
    except ImportError:
        return Path.home() / ".cache" / "hexapod_kin"


def folder(kind: str) -> Path:
    """The cache folder of ``kind`` (``"symbolic"``, ``"families"``, ``"report"``, ...)."""
    return root() / kind


def _canonical(obj: Any) -> bytes:
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), default=repr).encode()


def key(parts: Any) -> str:
    """SHA-256 (hex) of the canonical JSON of ``parts`` (anything else by ``repr``)."""
    return hashlib.sha256(_canonical(parts)).hexdigest()


def _secret(base: Path | None = None, *, quiet: bool = False) -> bytes | None:
    """The seals' secret in ``base`` (default :func:`root`), created once; None: unusable root.

    Race-free (a private temporary file hard-linked to the name: the first run wins); one of
    the wrong length is replaced; a root that is a file is said once unless ``quiet``.
    """
    base = root() if base is None else base
    with _LOCK:
        if str(base) in _SECRETS:
            return _SECRETS[str(base)]
        path = base / "seal.key"
        found: bytes | None = None
        for _ in range(2):
            with contextlib.suppress(OSError):
                found = path.read_bytes()
            if found is not None and len(found) == _SECRET_BYTES:
                break
            found = None
            tmp = base / f".seal.key.{secrets.token_hex(8)}.tmp"
            try:
                base.mkdir(parents=True, exist_ok=True)
                fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
                with os.fdopen(fd, "wb") as fh:
                    fh.write(secrets.token_bytes(_SECRET_BYTES))
                with contextlib.suppress(FileExistsError):  # another process made it first
                    os.replace(tmp, path) if path.exists() else os.link(tmp, path)
            except OSError as exc:
                file = base.exists() and not base.is_dir() or isinstance(exc, NotADirectoryError)
                if file and not quiet:
                    where = f"cache folder {str(base)!r} is not a folder (a regular file?)"
                    warnings.warn(f"{where}; nothing is cached", CacheWarning, stacklevel=4)
                break
            finally:
                with contextlib.suppress(OSError):
                    tmp.unlink()
        _SECRETS[str(base)] = found
        return found


def mac(*chunks: bytes) -> str | None:
    """HMAC-SHA256 (hex) of ``chunks`` (each length-prefixed) with the secret; ``None``: none."""
    secret = _secret()
    return None if secret is None else _hmac(secret, chunks)


def _hmac(secret: bytes, chunks: Iterable[bytes]) -> str:
    """HMAC-SHA256 (hex) of ``chunks``, each prefixed by its length (8 bytes, big-endian)."""
    h = hmac.new(secret, digestmod=hashlib.sha256)
    for chunk in chunks:
        h.update(len(chunk).to_bytes(8, "big"))
        h.update(chunk)
    return h.hexdigest()


def seal(kind: str, digest: str, body: Any) -> str | None:
    """The keyed seal binding ``body`` (JSON data) to ``kind`` and the key ``digest``."""
    return mac(kind.encode(), digest.encode(), _canonical(body))


def damaged(kind: str, name: str, why: BaseException | str, then: str, stacklevel: int = 3) -> None:
    """The one warning of a cache entry ``name`` that is not what it claims.

    ``why``: what is wrong (an exception: its type and message); ``then``: what happens
    instead ("recomputing it"); ``stacklevel`` from the caller's caller.
    """
    short = name[:12] if re.fullmatch(r"[0-9a-f]{16,}", name) else name
    if isinstance(why, BaseException):
        why = f"{type(why).__name__}: {' '.join(str(why).split())[:80]}"
    message = f"{kind} cache entry {short} is damaged or was edited ({why}); {then}"
    warnings.warn(message, CacheWarning, stacklevel=stacklevel)


def store(kind: str, digest: str, body: Any, fmt: int, *, sync: bool = True) -> Path | None:
    """Write ``body`` (JSON data) as the sealed entry ``digest`` of ``kind``, atomically.

    Returns the file, or ``None`` when nothing is cached (no secret, unwritable, disk full).
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

    Quietly when missing, of another format or without a secret; else (unreadable, torn,
    edited, another key's) with one warning (:func:`damaged`, ``then``: what happens).
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


# ------------------------------------------------------------ folders of opaque files
#: The seal file of a folder sealed by :func:`seal_folder`.
FOLDER_SEAL = "hexapod_kin.seal"
_FOLDER_FORMAT = 1


def user_secret() -> bytes | None:
    """The secret of shared folders (numba's): the default root's, else :func:`root`'s."""
    return _secret(_default_root(), quiet=True) or _secret()


def _file_mac(secret: bytes, name: str, data: bytes) -> str:
    return _hmac(secret, (b"folder-file", name.encode(), data))


def _sealed_files(folder: Path, suffixes: tuple[str, ...]) -> list[Path]:
    try:
        return sorted(p for p in folder.iterdir() if p.suffix in suffixes and p.is_file())
    except OSError:
        return []


@contextlib.contextmanager
def _folder_lock(folder: Path) -> Iterator[None]:
    """An exclusive lock on ``folder`` (``flock`` of the folder itself; none where refused)."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        yield
        return
    try:
        with contextlib.suppress(ImportError, OSError):  # no flock: the last writer wins
            import fcntl

            fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)  # releases the lock


def seal_folder(folder: str | os.PathLike[str], suffixes: tuple[str, ...]) -> bool:
    """Seal the files of ``folder`` ending in ``suffixes``; whether it was written (no error).

    :data:`FOLDER_SEAL` holds the keyed MAC of each file's name and bytes, written atomically
    under a lock of the folder (the last of two concurrent seals covers both).
    """
    path = Path(folder)
    secret = user_secret()
    if secret is None:
        return False
    try:
        with _folder_lock(path):
            macs = {}
            for p in _sealed_files(path, suffixes):
                try:
                    macs[p.name] = _file_mac(secret, p.name, p.read_bytes())
                except FileNotFoundError:  # removed meanwhile: nothing to seal
                    continue
            text = json.dumps({"format": _FOLDER_FORMAT, "files": macs}, sort_keys=True)
            atomic_write(path / FOLDER_SEAL, text, sync=False)
        return True
    except (OSError, HexapodKinError):
        return False


def check_folder(folder: str | os.PathLike[str], suffixes: tuple[str, ...]) -> dict[str, str]:
    """The files of ``folder`` ending in ``suffixes`` that its seal does not vouch for.

    Returns:
        File name → ``"not sealed"`` (foreign, or written after the seal), ``"edited or
        swapped"``, ``"no seal"`` or ``"no secret"``; empty when every file is sealed.

    """
    path = Path(folder)
    files = _sealed_files(path, suffixes)
    if not files:
        return {}
    secret = user_secret()
    if secret is None:
        return dict.fromkeys((p.name for p in files), "no secret")
    try:
        data = json.loads((path / FOLDER_SEAL).read_text(encoding="utf-8"))
        sealed = data["files"] if data.get("format") == _FOLDER_FORMAT else {}
        if not isinstance(sealed, dict):
            sealed = {}
    except (OSError, ValueError, TypeError, AttributeError, KeyError):
        return dict.fromkeys((p.name for p in files), "no seal")
    bad = {}
    for p in files:
        expected = sealed.get(p.name)
        if not isinstance(expected, str):
            bad[p.name] = "not sealed"
            continue
        try:
            ok = hmac.compare_digest(expected, _file_mac(secret, p.name, p.read_bytes()))
        except OSError:
            continue  # removed meanwhile: not there to be loaded
        if not ok:
            bad[p.name] = "edited or swapped"
    return bad
