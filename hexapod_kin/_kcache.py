"""numba's disk cache of the package's kernels: stamps, and a manifest checked before loading.

numba's cache files are pickles (loading one can run code) holding machine code (an edited
byte runs as is). Beside the stamps (:mod:`._kernels`), a manifest
``hexapod_kin-<stamp key>.manifest.json`` (sealed by its own SHA-256) lists the SHA-256 of
every cache file of the package's modules, rewritten after each area's first completed call
(:func:`write_manifest`). Before anything is loaded in a process (:func:`verify`), every
data file (``.nbc``) listed must match its line, and every index (``.nbi``) must match its
line or read, through an unpickler that admits only numba's types, as an index numba writes
for that very function (numba rewrites an index when it adds an overload). A file that is
truncated, emptied, overwritten, swapped with another, edited or planted is removed before
numba opens it (one :class:`~hexapod_kin.exceptions.CacheWarning`), and numba compiles that
function again; a damaged manifest disowns every file. Data files written since the manifest
(another process compiling) are numba's own. Only numba's documented cache location
(``NUMBA_CACHE_DIR``, else ``__pycache__`` beside the sources) is read, and no numba API
but the dispatchers' public ones is called.
"""

from __future__ import annotations

import functools
import hashlib
import io
import json
import os
import pickle
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


class _IndexReader(pickle.Unpickler):
    """Reads a numba index (``.nbi``) allowing only the classes a real one holds.

    numba's types (classes of ``numba.core.types``), their reconstructor, ``object`` and
    ``copyreg._reconstructor``: a pickle that names anything else (a function that runs a
    command, opens a file...) is refused before it is called.
    """

    SAFE = frozenset(
        (
            ("builtins", "object"),
            ("copyreg", "_reconstructor"),
            ("numba.core.types.abstract", "_type_reconstructor"),
        )
    )

    def find_class(self, module: str, name: str) -> Any:
        if (module, name) in self.SAFE:
            return super().find_class(module, name)
        if module.startswith("numba.core.types.") and "." not in name:
            found = super().find_class(module, name)
            if isinstance(found, type) and issubclass(found, numba.types.Type):
                return found
        raise pickle.UnpicklingError(f"{module}.{name} is not allowed in a numba index")


def _index_ok(path: Path) -> bool:
    """Whether ``path`` reads as an index numba itself writes for this function.

    The layout numba reads: a pickled version string, then a pickled ``(stamp, overloads)``
    whose values name this function's own data files (``<stem>.<n>.nbc``). Read with
    :class:`_IndexReader` (nothing outside numba's types is ever called).
    """
    stem = path.name[: -len(".nbi")]
    try:
        with path.open("rb") as f:
            version = _IndexReader(f).load()
            stamp, overloads = _IndexReader(io.BytesIO(f.read())).load()
    except Exception:  # noqa: BLE001 - anything unreadable is no index
        return False
    return (
        version == numba.__version__
        and isinstance(stamp, (bytes, tuple))
        and isinstance(overloads, dict)
        and all(
            isinstance(name, str)
            and name.startswith(f"{stem}.")
            and name.endswith(".nbc")
            and os.sep not in name
            for name in overloads.values()
        )
    )


def verify() -> None:
    """Once per process, before numba loads anything: remove the files that are not vouched for.

    A data file (``.nbc``, machine code) listed in the manifest must match its SHA-256; an
    index (``.nbi``) must match its line or read as an index numba writes for that function
    (:func:`_index_ok`: numba adds overloads to an index, rewriting it). A file that fails is
    removed (numba then compiles that function again), with one warning for all of them; a
    damaged manifest disowns every file. Unlisted data files (written since the manifest,
    e.g. by another process) are numba's own; without a manifest only the indexes are checked.
    """
    with _VERIFY_LOCK:
        if _VERIFIED[0]:
            return
        _VERIFIED[0] = True
        manifest = _manifest()
        files = cache_files()
        try:
            text = manifest.read_text(encoding="utf-8")
        except FileNotFoundError:
            text = None
        except OSError:
            text = ""
        why = "do not match the manifest"
        try:
            listed: dict[str, str] = {}
            if text is not None:
                data = json.loads(text)
                listed = data["files"]
                if not isinstance(listed, dict) or data.get("seal") != _seal(listed):
                    raise ValueError("seal")
            bad = [f for f in files if not _vouched(f, listed)]
        except Exception:  # noqa: BLE001 - the manifest itself is damaged: trust nothing
            bad, why = files, "cannot be checked: the manifest is damaged"
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


def _vouched(path: Path, listed: dict[str, str]) -> bool:
    """A data file matching its line (or unlisted); an index matching it or numba's own."""
    line = listed.get(_rel(path))
    if path.suffix == ".nbc":
        return line is None or _sha(path) == line
    return (line is not None and _sha(path) == line) or _index_ok(path)


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
