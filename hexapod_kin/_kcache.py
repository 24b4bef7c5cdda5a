"""numba's disk cache of the package's kernels: stamps, and a manifest checked before loading.

numba's cache files are pickles (loading one can run code) holding machine code (an edited
byte runs as is). Beside the stamps (:mod:`._kernels`), a manifest
``hexapod_kin-<stamp key>.manifest.json`` (sealed by its own SHA-256) lists the SHA-256 of
every cache file of the package's modules, rewritten after each area's first completed call
(:func:`write_manifest`). Before anything is loaded in a process (:func:`verify`), every
listed file is checked: one that is truncated, emptied, overwritten, swapped with another or
edited is removed before numba opens it (one :class:`~hexapod_kin.exceptions.CacheWarning`),
and numba compiles that function again; a damaged manifest disowns every file. Files written
since the manifest (another process compiling) are numba's own. Only numba's documented
cache location (``NUMBA_CACHE_DIR``, else ``__pycache__`` beside the sources) is read.
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
import sys
import threading
import warnings
from pathlib import Path
from typing import Any

import numba

from ._io import atomic_write
from .exceptions import CacheWarning

__all__ = ["cache_files", "remove_file", "stamp", "verify", "write_manifest"]


@functools.cache
def _stamp_key() -> str:
    """Package version, numba's, Python's and the CPU name (see the module docstring)."""
    import importlib.metadata

    import llvmlite.binding

    try:
        version = importlib.metadata.version("hexapod-kin")
    except importlib.metadata.PackageNotFoundError:  # pragma: no cover - run from a checkout
        version = "dev"
    py = f"{sys.version_info[0]}{sys.version_info[1]}"
    return f"{version}-numba{numba.__version__}-py{py}-{llvmlite.binding.get_host_cpu_name()}"


def _stamp_root() -> Path:
    """The cache directory: numba's (``NUMBA_CACHE_DIR``), else ``hexapod_kin/__pycache__``."""
    return Path(numba.config.CACHE_DIR or Path(__file__).resolve().parent / "__pycache__")


def stamp(area: str) -> Path:
    """The stamp file of ``area`` (see the module docstring)."""
    return _stamp_root() / f"hexapod_kin-{area}-{_stamp_key()}.stamp"


def _manifest() -> Path:
    """The manifest of the package's cache files (see the module docstring)."""
    return _stamp_root() / f"hexapod_kin-{_stamp_key()}.manifest.json"


def _cache_folders() -> list[Path]:
    """The cache folders of the package's modules, as numba names them.

    With ``NUMBA_CACHE_DIR``: ``<dir>/<folder name>_<SHA-1 of the folder's absolute path>``
    per source folder; else ``__pycache__`` beside the sources.
    """
    pkg = os.path.dirname(os.path.abspath(__file__))
    dirs = sorted({os.path.dirname(os.path.join(pkg, p)) for p in _sources()})
    if numba.config.CACHE_DIR:
        root = os.path.abspath(numba.config.CACHE_DIR)
        return [
            Path(root, f"{os.path.basename(d)}_{hashlib.sha1(d.encode()).hexdigest()}")  # noqa: S324
            for d in dirs
        ]
    return [Path(d, "__pycache__") for d in dirs]


@functools.cache
def _sources() -> tuple[str, ...]:
    """The package's Python files, relative to it."""
    pkg = Path(__file__).resolve().parent
    return tuple(str(p.relative_to(pkg)) for p in sorted(pkg.rglob("*.py")))


def cache_files() -> list[Path]:
    """Every numba cache file (index ``.nbi``, data ``.nbc``) of the package's modules."""
    out: list[Path] = []
    for folder in _cache_folders():
        try:
            out += [p for p in folder.iterdir() if p.suffix in (".nbi", ".nbc")]
        except OSError:
            pass
    return sorted(out)


#: Path → (size, mtime in ns, SHA-256) of the cache files this process hashed.
_HASHED: dict[str, tuple[int, int, str]] = {}
_VERIFIED = [False]
_VERIFY_LOCK = threading.Lock()


def _sha(path: Path) -> str | None:
    """SHA-256 of a cache file (re-read unless this process hashed it unchanged), or None."""
    try:
        st = path.stat()
        hit = _HASHED.get(str(path))
        if hit is not None and hit[:2] == (st.st_size, st.st_mtime_ns):
            return hit[2]
        digest = hashlib.sha256(path.read_bytes()).hexdigest()
    except OSError:
        return None
    _HASHED[str(path)] = (st.st_size, st.st_mtime_ns, digest)
    return digest


def _rel(path: Path) -> str:
    """A cache file's name in the manifest: its path from the stamps' folder."""
    return os.path.relpath(path, _stamp_root())


def _seal(listed: Any) -> str:
    return hashlib.sha256(json.dumps(listed, sort_keys=True).encode()).hexdigest()


def verify() -> None:
    """Once per process, before numba loads anything: remove the files the manifest disowns.

    A listed file whose SHA-256 differs from its line is removed (numba then compiles that
    function again); a damaged manifest disowns every file. One warning when anything is
    removed. No manifest (a cache being filled for the first time): nothing to check.
    """
    with _VERIFY_LOCK:
        if _VERIFIED[0]:
            return
        _VERIFIED[0] = True
        manifest = _manifest()
        try:
            text = manifest.read_text(encoding="utf-8")
        except FileNotFoundError:
            return
        except OSError:
            text = ""
        files = cache_files()
        try:
            data = json.loads(text)
            listed = data["files"]
            if not isinstance(listed, dict) or data.get("seal") != _seal(listed):
                raise ValueError("seal")
            bad = [f for f in files if _rel(f) in listed and _sha(f) != listed[_rel(f)]]
            why = "differ from the manifest"
        except Exception:  # noqa: BLE001 - the manifest itself is damaged: trust nothing
            bad, why = files, "cannot be checked: its manifest is damaged"
            manifest.unlink(missing_ok=True)
        if not bad:
            return
        names = ", ".join(f.name for f in bad[:2]) + (", ..." if len(bad) > 2 else "")
        warnings.warn(
            f"the compiled-code cache is damaged or was edited ({len(bad)} file(s) {why}: "
            f"{names}); they are removed and compiled again",
            CacheWarning,
            stacklevel=5,
        )
        for f in bad:
            remove_file(f)


def remove_file(path: Path) -> None:
    try:
        path.unlink()
    except OSError:
        pass
    _HASHED.pop(str(path), None)


def write_manifest() -> None:
    """List the SHA-256 of every cache file of the package now (best effort, atomic)."""
    listed = {_rel(f): h for f in cache_files() if (h := _sha(f)) is not None}
    try:
        atomic_write(_manifest(), json.dumps({"files": listed, "seal": _seal(listed)}))
    except OSError:
        pass
