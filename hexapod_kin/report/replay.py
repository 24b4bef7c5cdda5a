"""Replay of whole reports: a second ``reproduce`` with the same inputs copies the first's files.

The key (:func:`key_parts`, :func:`run_key`): the package's source, ``claims.toml``, the seed
texts, the options, the installed versions (from metadata, never imported) and the platform.
An entry ``_cache.folder("report")/runs/<key>/`` holds ``files/`` (all the build wrote but
``verdicts.json``) and ``manifest.json`` (each file's SHA-256 and size, the verdicts, facts and
wall time) under the package's keyed seal (:func:`seal`), written last. :func:`lookup` checks
the seal, every file, the verdicts against ``report.md`` and every PNG against ``report.html``
before copying anything; a damaged entry is no entry, with one
:class:`~hexapod_kin.exceptions.CacheWarning`. Files are copied as bytes, never run, only inside
the report folder. Only complete builds are stored; :data:`KEEP` entries are kept. Light.
"""

from __future__ import annotations

import base64
import contextlib
import hashlib
import json
import os
import platform
import shutil
import sys
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path, PurePosixPath
from typing import Any

from .. import _cache as _disk
from .._io import atomic_write
from .data import CLAIMS_FILE, LABELS, SEEDS_DIR, Verdict

__all__ = [
    "DISTRIBUTIONS",
    "FORMAT",
    "KEEP",
    "Entry",
    "key_parts",
    "lookup",
    "prune",
    "restore",
    "run_key",
    "runs_dir",
    "save",
    "seal",
    "source_digest",
]

#: Version of the entry layout (part of the key).
FORMAT = 4
#: Number of run entries kept (the most recently built or replayed).
KEEP = 4
#: Distributions whose installed versions are part of the key.
DISTRIBUTIONS = ("numpy", "scipy", "pin", "sympy", "matplotlib", "numba", "meshcat")
MANIFEST = "manifest.json"
_PACKAGE = Path(__file__).resolve().parents[1]
#: An entry without a manifest older than this [s] is a crashed store (removed by prune).
_STALE = 3600.0


def runs_dir() -> Path:
    """The entries' folder (not created here): ``_cache.folder("report") / "runs"``."""
    return _disk.folder("report") / "runs"


def source_digest() -> str:
    """SHA-256 of the package's Python source (every ``.py`` file of ``hexapod_kin``), read now."""
    return _digest(_PACKAGE, _PACKAGE.rglob("*.py"))


def _digest(root: Path, files: Any) -> str:
    """SHA-256 of ``files`` (their paths relative to ``root`` and bytes), in sorted order."""
    h = hashlib.sha256()
    for f in sorted(files):
        h.update(str(f.relative_to(root)).encode())
        h.update(f.read_bytes())
    return h.hexdigest()


def versions() -> dict[str, str]:
    """Installed versions of Python, hexapod_kin and :data:`DISTRIBUTIONS` (none imported)."""
    from importlib.metadata import PackageNotFoundError, version

    from .. import __version__

    python = f"{platform.python_implementation()} {platform.python_version()}"
    out = {"python": python, "hexapod_kin": __version__}
    for name in DISTRIBUTIONS:
        try:
            out[name] = version(name)
        except PackageNotFoundError:
            out[name] = "absent"
    return out


def key_parts(*, quick: bool, animations: bool, digest: str) -> dict[str, Any]:
    """Everything a report of these options depends on, JSON-ready (``digest``: the source's).

    Raises:
        OSError: The package's source or ``claims.toml`` cannot be read.

    """
    return {
        "format": FORMAT,
        "code": digest,
        "claims": hashlib.sha256(CLAIMS_FILE.read_bytes()).hexdigest(),
        "seeds": _digest(SEEDS_DIR, SEEDS_DIR.glob("*.txt")),
        "options": {"quick": bool(quick), "animations": bool(animations)},
        "versions": versions(),
        "platform": f"{sys.platform}-{platform.machine()}",
    }


def run_key(parts: Mapping[str, Any]) -> str:
    """The cache key (:func:`hexapod_kin._cache.key`) of ``parts`` (:func:`key_parts`)."""
    return _disk.key(parts)


@dataclass(frozen=True)
class Entry:
    """A complete, verified run entry: key, folder, manifest and files (POSIX path → bytes).

    The manifest (``record``) holds ``built`` (UTC time of the build), ``seconds`` (its wall
    time [s]), ``verdicts``, ``facts``, ``files``, ``parts``...
    """

    key: str
    folder: Path
    record: dict[str, Any]
    files: dict[str, bytes]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: key, folder, the manifest and the files' sizes."""
        sizes = {rel: len(data) for rel, data in self.files.items()}
        return {"key": self.key, "folder": str(self.folder), "record": self.record, "files": sizes}


def _safe(rel: Any) -> bool:
    """A relative path inside the report folder (no absolute path, no ``..``)."""
    if not isinstance(rel, str) or not rel or "\\" in rel or "\0" in rel:
        return False
    p = PurePosixPath(rel)
    return not p.is_absolute() and all(part not in ("", ".", "..") for part in p.parts)


def seal(record: Mapping[str, Any]) -> str | None:
    """The keyed seal (:func:`hexapod_kin._cache.seal`) of a manifest (None: no secret)."""
    body = {k: v for k, v in record.items() if k != "seal"}
    body = json.loads(json.dumps(body, default=str))
    return _disk.seal("replay", str(record.get("key")), body)


class _Damaged(ValueError):
    """An entry that is there but is not the sealed, complete entry of its key."""


def lookup(key: str) -> Entry | None:
    """The complete entry of ``key`` with every file matching its manifest, else ``None``.

    Never raises; a damaged, edited or foreign entry warns once (``CacheWarning``).
    """
    folder = runs_dir() / key
    try:
        text = (folder / MANIFEST).read_text(encoding="utf-8")
    except FileNotFoundError:
        return None
    except Exception as exc:  # noqa: BLE001 - unreadable: no entry
        _warn(key, exc)
        return None
    try:
        return _checked(key, folder, text)
    except Exception as exc:  # noqa: BLE001 - any damage means "no entry"
        _warn(key, exc)
        return None


def _warn(key: str, exc: BaseException) -> None:
    what = " ".join(str(exc).split())[:100] if isinstance(exc, _Damaged) else type(exc).__name__
    _disk.damaged("report", key, what, "building again", stacklevel=4)


def _checked(key: str, folder: Path, text: str) -> Entry:
    """The entry of ``key`` read from its manifest ``text``, every check passed (else _Damaged)."""
    record = json.loads(text)
    if not isinstance(record, dict) or record.get("format") != FORMAT:
        raise _Damaged("not a manifest of this format")
    if record.get("key") != key:
        raise _Damaged("the manifest of another key")
    if record.get("seal") != seal(record) or record.get("seal") is None:
        raise _Damaged("its manifest does not match its seal")
    listed = record.get("files")
    kinds: dict[str, Any] = dict(built=str, seconds=(int, float), verdicts=list, facts=dict)
    complete = all(isinstance(record.get(k), t) for k, t in kinds.items())
    if not (complete and isinstance(listed, dict) and listed):
        raise _Damaged("an incomplete manifest")
    for v in record["verdicts"]:
        if not isinstance(v, dict) or Verdict.from_fields(v).status == "error":
            raise _Damaged("a verdict that is not a computed verdict")
    files: dict[str, bytes] = {}
    for rel, meta in listed.items():
        if not _safe(rel) or rel == "verdicts.json":
            raise _Damaged(f"a file name outside the report folder: {str(rel)[:40]!r}")
        try:
            data = (folder / "files" / rel).read_bytes()
        except OSError:
            raise _Damaged(f"{rel} is missing") from None
        if len(data) != meta["size"] or hashlib.sha256(data).hexdigest() != meta["sha256"]:
            raise _Damaged(f"{rel} does not match its manifest line")
        files[rel] = data
    if not verdicts_match(record["verdicts"], files):
        raise _Damaged("its manifest's verdicts are not the report's")
    html = files.get("report.html", b"")
    for rel, data in files.items():
        if rel.endswith(".png") and not _shown(html, PurePosixPath(rel).stem, data):
            raise _Damaged(f"{rel} is not the figure report.html shows under its name")
    return Entry(key, folder, record, files)


def _shown(html: bytes, stem: str, png: bytes) -> bool:
    """Whether ``report.html`` inlines ``png`` in an image whose ``alt`` names ``stem``."""
    at = html.find(b'src="data:image/png;base64,' + base64.b64encode(png) + b'"')
    if at < 0:
        return False
    tag = html[html.rfind(b"<img", 0, at) : at]
    names = [f'alt="{stem}"']
    if stem.endswith("_still"):
        names.append(f'alt="still frame of {stem[: -len("_still")]} (')
    return any(n.encode() in tag for n in names)


def verdicts_match(verdicts: list[dict[str, Any]], files: Mapping[str, bytes]) -> bool:
    """Whether each claim's row of ``report.md`` starts its verdict with the manifest's status."""
    md = files.get("report.md")
    if md is None:
        return False
    text = md.decode("utf-8")
    for v in verdicts:
        row = f"| {v['claim']} | {v['seed']} |"
        i = text.find(row)
        if i < 0:
            return False
        line = text[i : text.find("\n", i) if "\n" in text[i:] else len(text)]
        cols = line.split(" | ")
        status = str(v["status"])
        if len(cols) < 4 or not cols[3].startswith(LABELS.get(status, status)[:6]):
            return False
    return True


def restore(entry: Entry, out: Path) -> list[Path]:
    """Write the entry's files into ``out`` (atomically; ParameterError); mark it used."""
    written = []
    for rel, data in entry.files.items():
        dest = out.joinpath(*PurePosixPath(rel).parts)
        dest.parent.mkdir(parents=True, exist_ok=True)
        written.append(atomic_write(dest, data))
    with contextlib.suppress(OSError):
        os.utime(entry.folder / MANIFEST)  # last use: what prune keeps
    return written


def save(
    key: str,
    parts: Mapping[str, Any],
    out: Path,
    files: Sequence[Path],
    record: Mapping[str, Any],
    keep: int = KEEP,
) -> Path | None:
    """Keep a successful build's ``files`` (written into ``out``) under ``runs/<key>/``.

    ``record``: the build's verdicts (:meth:`~.data.Verdict.fields`), facts, summary, counts
    and seconds. Returns the entry's folder, or ``None`` (never raises); prunes to ``keep``.
    """
    folder = runs_dir() / key
    try:
        if any(v.get("status") == "error" for v in record["verdicts"]):
            return None
        rels = [p.resolve().relative_to(out.resolve()).as_posix() for p in files]
        if not rels or len(set(rels)) != len(rels) or not all(map(_safe, rels)):
            return None
        folder.mkdir(parents=True, exist_ok=True)
        (folder / MANIFEST).unlink(missing_ok=True)  # incomplete until the manifest is back
        listed: dict[str, dict[str, Any]] = {}
        for rel in sorted(rels):
            data = out.joinpath(*PurePosixPath(rel).parts).read_bytes()
            dest = folder.joinpath("files", *PurePosixPath(rel).parts)
            dest.parent.mkdir(parents=True, exist_ok=True)
            atomic_write(dest, data)
            listed[rel] = {"sha256": hashlib.sha256(data).hexdigest(), "size": len(data)}
        manifest = {
            **record,
            "format": FORMAT,
            "key": key,
            "parts": dict(parts),
            "built": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
            "files": listed,
        }
        manifest["seal"] = seal(manifest)
        if manifest["seal"] is None:
            return None
        atomic_write(folder / MANIFEST, json.dumps(manifest, indent=1, default=str))
    except Exception:  # noqa: BLE001 - a cache that cannot be written is only slower
        return None
    prune(keep)
    return folder


def prune(keep: int = KEEP) -> list[Path]:
    """Remove all but the ``keep`` most recently used entries (never raises); return them.

    An entry without a manifest is removed after an hour (it may be being stored).
    """
    removed: list[Path] = []
    try:
        folders = [d for d in runs_dir().iterdir() if d.is_dir()]
    except OSError:
        return removed
    complete: list[tuple[float, Path]] = []
    now = time.time()
    for d in folders:
        try:
            complete.append(((d / MANIFEST).stat().st_mtime, d))
        except OSError:
            with contextlib.suppress(OSError):
                if now - d.stat().st_mtime > _STALE:
                    shutil.rmtree(d, ignore_errors=True)
                    removed.append(d)
    complete.sort(key=lambda t: (t[0], t[1].name), reverse=True)
    for _, d in complete[max(keep, 0) :]:
        shutil.rmtree(d, ignore_errors=True)
        removed.append(d)
    return removed
