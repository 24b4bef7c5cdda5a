"""Files: atomic writing (never a half-written file) and regular files read with a byte cap."""

from __future__ import annotations

import contextlib
import os
import secrets
import stat
from pathlib import Path

from .exceptions import HexapodKinError, ParameterError, SourceError

__all__ = ["atomic_write", "read_regular"]


def atomic_write(path: str | os.PathLike[str], data: str | bytes, *, sync: bool = True) -> Path:
    """Write ``data`` (text as UTF-8, or bytes) to ``path`` atomically; return it as a Path.

    A temporary file in the same directory, fsync'ed (and the folder, unless not ``sync``),
    renamed over ``path``; any failure before (even ``KeyboardInterrupt``) removes it.

    Raises:
        ParameterError: No such directory, ``path`` a directory, or the write failed.

    """
    dest = Path(path)
    parent = dest.parent if str(dest.parent) else Path(".")
    if not parent.is_dir():
        raise ParameterError(f"path={str(dest)!r}: directory {str(parent)!r} does not exist")
    if dest.is_dir():
        raise ParameterError(f"path={str(dest)!r} is a directory; expected a file path")
    payload = data.encode("utf-8") if isinstance(data, str) else bytes(data)
    # the name first, then the file, inside the clean-up: a Ctrl-C at any point leaves nothing
    tmp = str(parent / f".{dest.name}.{secrets.token_hex(8)}.tmp")
    try:
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
        with os.fdopen(fd, "wb") as fh:
            fh.write(payload)
            if sync:
                fh.flush()
                os.fsync(fh.fileno())
        if not dest.exists():
            os.chmod(tmp, 0o644)
        with contextlib.suppress(OSError):  # the mode of the file replaced, when there is one
            os.chmod(tmp, dest.stat().st_mode & 0o777)
        os.replace(tmp, dest)
    except BaseException as exc:
        with contextlib.suppress(FileNotFoundError):
            if not isinstance(exc, FileExistsError):  # else the name was another's: keep it
                os.unlink(tmp)
        if isinstance(exc, OSError):  # named by the destination, never the temporary file
            raise ParameterError(
                f"path={str(dest)!r}: cannot write it ({exc.strerror or exc}); the previous "
                "content, if any, is unchanged",
                parameter="path",
                value=str(dest),
                allowed="a file in a writable directory",
            ) from None
        raise
    if sync:  # the rename made durable (best effort: some file systems refuse it)
        with contextlib.suppress(OSError):
            fd = os.open(parent, os.O_RDONLY)
            try:
                os.fsync(fd)
            finally:
                os.close(fd)
    return dest


def read_regular(
    path: str | os.PathLike[str],
    max_bytes: int,
    what: str = "source",
    too_big: type[HexapodKinError] | None = None,
) -> bytes:
    """The bytes of a regular file, refused beyond ``max_bytes`` (counted while reading).

    A device (``/dev/zero``), named pipe, socket or folder is refused unread (opened
    non-blocking: a pipe with no writer does not hang; ``fstat`` of the open descriptor).

    Raises:
        SourceError: Not a regular file, unreadable, or larger than ``max_bytes`` (then
            ``too_big`` when given, e.g. :class:`~.exceptions.UrdfError`); ``parameter``: ``what``.

    """
    name, fd = str(path), -1

    def refused(why: str, allowed: str, cls: type[HexapodKinError] = SourceError) -> Exception:
        return cls(f"{what}={name!r}{why}", parameter=what, value=name, allowed=allowed)

    try:
        fd = os.open(name, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
        mode = os.fstat(fd).st_mode
        if not stat.S_ISREG(mode):
            kind = (
                "a folder" if stat.S_ISDIR(mode)
                else "a named pipe" if stat.S_ISFIFO(mode)
                else "a device" if stat.S_ISCHR(mode) or stat.S_ISBLK(mode)
                else "a socket" if stat.S_ISSOCK(mode)
                else "not a regular file"
            )  # fmt: skip
            raise refused(f" is {kind}; only regular files are read", "a regular file")
        chunks: list[bytes] = []
        total = 0
        while True:
            block = os.read(fd, min(1 << 20, max_bytes + 1 - total))
            if not block:
                break
            chunks.append(block)
            total += len(block)
            if total > max_bytes:
                why = f": more than {max_bytes} bytes (exceeds the cap of {max_bytes} bytes)"
                raise refused(why, f"at most {max_bytes} bytes", too_big or SourceError)
        return b"".join(chunks)
    except OSError as exc:
        why = f": cannot read it ({exc.strerror or exc})"
        raise refused(why, "a readable regular file") from None
    finally:
        if fd >= 0:
            os.close(fd)
