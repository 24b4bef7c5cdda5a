"""Nothing lost: every file is written atomically, even when the write is interrupted."""

from __future__ import annotations

import errno
import os
import re
import stat
from pathlib import Path
from typing import Any

import pytest

from hexapod_kin import _io, robots, urdf
from hexapod_kin._io import atomic_write
from hexapod_kin.exceptions import ParameterError

ROOT = Path(__file__).resolve().parent.parent


def _leftovers(directory: Path) -> list[str]:
    return sorted(p.name for p in directory.iterdir() if p.name.endswith(".tmp"))


def test_roundtrip_text_and_bytes(tmp_path: Path) -> None:
    path = tmp_path / "a.json"
    assert atomic_write(path, '{"ü": 1}') == path
    assert path.read_bytes() == '{"ü": 1}'.encode()
    atomic_write(path, b"\x00\x01")
    assert path.read_bytes() == b"\x00\x01"
    assert _leftovers(tmp_path) == []


def test_new_file_gets_0644_and_overwrite_keeps_mode(tmp_path: Path) -> None:
    path = tmp_path / "f.txt"
    atomic_write(path, "x")
    assert stat.S_IMODE(path.stat().st_mode) == 0o644
    path.chmod(0o600)
    atomic_write(path, "y")
    assert stat.S_IMODE(path.stat().st_mode) == 0o600


@pytest.mark.parametrize("exc", [KeyboardInterrupt(), OSError(errno.EIO, "I/O error")])
def test_interrupted_replace_keeps_previous(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, exc: BaseException
) -> None:
    path = tmp_path / "robot.urdf"
    atomic_write(path, "previous content\n")

    def boom(*args: Any, **kwargs: Any) -> None:
        raise exc

    monkeypatch.setattr(_io.os, "replace", boom)
    # an OSError becomes one ParameterError naming the destination, never the temporary file
    expected = ParameterError if isinstance(exc, OSError) else type(exc)
    with pytest.raises(expected) as info:
        atomic_write(path, "new content that must not appear\n")
    if isinstance(exc, OSError):
        assert str(path) in str(info.value) and ".tmp" not in str(info.value)
    assert path.read_text() == "previous content\n"
    assert _leftovers(tmp_path) == []


def test_interrupted_fsync_keeps_previous(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    path = tmp_path / "plot.png"
    atomic_write(path, b"PNG-old")

    def boom(fd: int) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(_io.os, "fsync", boom)
    with pytest.raises(KeyboardInterrupt):
        atomic_write(path, b"PNG-new")
    assert path.read_bytes() == b"PNG-old"
    assert _leftovers(tmp_path) == []


class _HalfWriter:
    """A file object that writes half of the payload, then fails (disk full)."""

    def __init__(self, fh: Any, exc: BaseException) -> None:
        self._fh = fh
        self._exc = exc

    def write(self, data: bytes) -> int:
        self._fh.write(data[: len(data) // 2])
        self._fh.flush()
        raise self._exc

    def __enter__(self) -> _HalfWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self._fh.close()

    def __getattr__(self, name: str) -> Any:
        return getattr(self._fh, name)


@pytest.mark.parametrize(
    "exc", [OSError(errno.ENOSPC, "No space left on device"), KeyboardInterrupt()]
)
def test_half_written_payload_never_replaces(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, exc: BaseException
) -> None:
    path = tmp_path / "page.html"
    atomic_write(path, "<html>old</html>")
    real_fdopen = os.fdopen
    monkeypatch.setattr(
        _io.os, "fdopen", lambda fd, *a, **k: _HalfWriter(real_fdopen(fd, *a, **k), exc)
    )
    with pytest.raises(ParameterError if isinstance(exc, OSError) else type(exc)):
        atomic_write(path, "<html>" + "new " * 10_000 + "</html>")
    assert path.read_text() == "<html>old</html>"
    assert _leftovers(tmp_path) == []


def test_interrupted_first_write_leaves_nothing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    def boom(*args: Any, **kwargs: Any) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(_io.os, "replace", boom)
    with pytest.raises(KeyboardInterrupt):
        atomic_write(tmp_path / "new.json", "{}")
    assert list(tmp_path.iterdir()) == []


def test_write_urdf_interrupted_keeps_previous_urdf(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = tmp_path / "hexabot_leg.urdf"
    urdf.write_urdf(robots.get("hexabot_leg"), path)
    before = path.read_text()

    def boom(*args: Any, **kwargs: Any) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(_io.os, "replace", boom)
    with pytest.raises(KeyboardInterrupt):
        urdf.write_urdf(robots.get("hexabot_leg", l2=0.2), path)
    assert path.read_text() == before
    assert _leftovers(tmp_path) == []


def test_bad_destinations(tmp_path: Path) -> None:
    with pytest.raises(ParameterError, match="does not exist"):
        atomic_write(tmp_path / "missing" / "f.txt", "x")
    with pytest.raises(ParameterError, match="is a directory"):
        atomic_write(tmp_path, "x")


#: Writing calls that bypass atomic_write.
_DIRECT_WRITE = re.compile(
    r"\.write_text\(|\.write_bytes\(|\bopen\([^)]*['\"][wax]b?\+?['\"]|savefig\((?!\s*buf)"
    r"|shutil\.copy|\.tofile\(|np\.save"
)


def test_no_direct_file_writes_in_package_and_tools() -> None:
    """Static check: every file the package or its tools write goes through atomic_write."""
    offenders = []
    for path in sorted([*(ROOT / "hexapod_kin").glob("*.py"), *(ROOT / "tools").glob("*.py")]):
        if path.name == "_io.py":
            continue
        for i, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
            if _DIRECT_WRITE.search(line) and "atomic-ok" not in line:
                offenders.append(f"{path.relative_to(ROOT)}:{i}: {line.strip()}")
    assert offenders == []
