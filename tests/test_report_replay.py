"""The whole-report replay cache (``hexapod_kin.report.replay``).

One computed build per module (quick, no animations, a fresh cache folder); the replays are
checked against that build's files, which were computed independently of the cache.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import shutil
import subprocess
import sys
import time
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

import pytest

from hexapod_kin.report import Report, build, replay, reproduce

HEAVY = ("sympy", "matplotlib", "pinocchio", "numba", "scipy", "meshcat")
#: Fields of verdicts.json that name the report folder or this run.
RUN_FIELDS = ("out", "markdown", "html", "seconds", "replayed_from", "build_seconds")


@dataclasses.dataclass
class First:
    cache: Path
    out: Path
    rep: Report
    key: str
    parts: dict[str, Any]
    started: float  # [s] since the epoch, read before the build (brackets its stamp)


@pytest.fixture(scope="module")
def first(tmp_path_factory: pytest.TempPathFactory) -> First:
    cache = tmp_path_factory.mktemp("cache")
    out = tmp_path_factory.mktemp("first") / "report"
    started = time.time()
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("HEXAPOD_KIN_CACHE_DIR", str(cache))
        rep = reproduce(out, quick=True, animations=False)
        parts = replay.key_parts(quick=True, animations=False, digest=replay.source_digest())
    return First(cache, out, rep, replay.run_key(parts), parts, started)


@pytest.fixture()
def env(first: First, monkeypatch: pytest.MonkeyPatch) -> First:
    """The module's cache folder for one test."""
    monkeypatch.setenv("HEXAPOD_KIN_CACHE_DIR", str(first.cache))
    return first


def _files(folder: Path) -> dict[str, bytes]:
    return {
        p.relative_to(folder).as_posix(): p.read_bytes() for p in folder.rglob("*") if p.is_file()
    }


class Built(Exception):
    """Raised by a stand-in build: the run did not replay."""


def _no_build(calls: list[dict[str, Any]]) -> Any:
    def fake(out: Path, **kw: Any) -> Any:
        calls.append(kw)
        raise Built

    return fake


# ---------------------------------------------------------------------------- replay
def test_first_build_computed_and_stored(env: First) -> None:
    assert env.rep.replayed_from is None and env.rep.counts["error"] == 0
    manifest = json.loads((replay.runs_dir() / env.key / "manifest.json").read_text())
    built = _files(env.out)
    # every file the build wrote is kept, with its own hash; verdicts.json is written per run
    assert set(manifest["files"]) | {"verdicts.json"} == set(built)
    for rel, meta in manifest["files"].items():
        assert meta == {"sha256": hashlib.sha256(built[rel]).hexdigest(), "size": len(built[rel])}
    assert manifest["seconds"] == env.rep.seconds
    assert manifest["counts"] == env.rep.counts and manifest["summary"] == env.rep.summary()
    stamp = datetime.strptime(manifest["built"], "%Y-%m-%dT%H:%M:%SZ")
    # stamped during the build (to the second): between the fixture's start and now, however
    # long the build took on a busy machine
    built_at = stamp.replace(tzinfo=timezone.utc).timestamp()
    assert int(env.started) <= built_at <= time.time()
    assert manifest["parts"] == env.parts


def test_key_parts_read_the_installed_versions(env: First, monkeypatch: pytest.MonkeyPatch) -> None:
    import matplotlib
    import numpy
    import sympy

    v = env.parts["versions"]
    assert (v["numpy"], v["sympy"], v["matplotlib"]) == (
        numpy.__version__,
        sympy.__version__,
        matplotlib.__version__,
    )
    assert v["python"].endswith(".".join(map(str, sys.version_info[:3])))
    assert env.parts["options"] == {"quick": True, "animations": False}
    claims = (Path(replay.__file__).with_name("claims.toml")).read_bytes()
    assert env.parts["claims"] == hashlib.sha256(claims).hexdigest()
    monkeypatch.setattr(replay, "DISTRIBUTIONS", ("numpy", "no-such-distribution-hk"))
    assert replay.versions()["no-such-distribution-hk"] == "absent"


def test_replay_is_byte_identical(
    env: First, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    calls: list[dict[str, Any]] = []
    monkeypatch.setattr(build, "_build", _no_build(calls))
    out = tmp_path / "nested" / "again"
    rep = reproduce(out, quick=True, animations=False)
    assert not calls
    manifest = json.loads((replay.runs_dir() / env.key / "manifest.json").read_text())
    assert rep.replayed_from == manifest["built"]
    assert rep.build_seconds == env.rep.seconds
    assert rep.verdicts == env.rep.verdicts
    built, got = _files(env.out), _files(out)
    assert set(got) == set(built)
    assert all(got[k] == built[k] for k in built if k != "verdicts.json")
    a, b = json.loads(built["verdicts.json"]), json.loads(got["verdicts.json"])
    assert {k: v for k, v in a.items() if k not in RUN_FIELDS} == {
        k: v for k, v in b.items() if k not in RUN_FIELDS
    }
    assert a["replayed_from"] is None and b["replayed_from"] == manifest["built"]
    assert b["out"] == str(out) and b["build_seconds"] == a["seconds"]


def _changes(env: First, tmp_path: Path) -> dict[str, Any]:
    claims = tmp_path / "claims.toml"
    claims.write_bytes(replay.CLAIMS_FILE.read_bytes() + b"\n# one more line\n")
    seeds = tmp_path / "seeds"
    seeds.mkdir()
    for f in replay.SEEDS_DIR.glob("*.txt"):
        (seeds / f.name).write_bytes(f.read_bytes())
    (seeds / f.name).write_bytes(f.read_bytes() + b"\n")  # one seed text one byte longer
    versions = replay.versions()

    def newer() -> dict[str, str]:
        return {**versions, "numpy": versions["numpy"] + ".post1"}

    return {
        "source": lambda mp: mp.setattr(replay, "source_digest", lambda: "0" * 64),
        "claims": lambda mp: mp.setattr(replay, "CLAIMS_FILE", claims),
        "seeds": lambda mp: mp.setattr(replay, "SEEDS_DIR", seeds),
        "library": lambda mp: mp.setattr(replay, "versions", newer),
        "format": lambda mp: mp.setattr(replay, "FORMAT", replay.FORMAT + 1),
        "quick": {"quick": False, "animations": False},
        "animations": {"quick": True, "animations": True},
    }


@pytest.mark.parametrize(
    "change", ["none", "source", "claims", "seeds", "library", "format", "quick", "animations"]
)
def test_any_key_part_changed_rebuilds(
    env: First, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, change: str
) -> None:
    calls: list[dict[str, Any]] = []
    monkeypatch.setattr(build, "_build", _no_build(calls))
    how = _changes(env, tmp_path).get(change)
    options = {"quick": True, "animations": False}
    if isinstance(how, dict):
        options = how
    elif how is not None:
        how(monkeypatch)
    if change == "none":
        assert reproduce(tmp_path / "out", **options).replayed_from is not None
        assert not calls
    else:
        with pytest.raises(Built):
            reproduce(tmp_path / "out", **options)
        assert calls == [{**options, "start": calls[0]["start"]}]


def test_no_cache_neither_reads_nor_replays(
    env: First, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    def boom(key: str) -> None:
        raise AssertionError("cache=False read the run cache")

    calls: list[dict[str, Any]] = []
    monkeypatch.setattr(replay, "lookup", boom)
    monkeypatch.setattr(build, "_build", _no_build(calls))
    with pytest.raises(Built):
        reproduce(tmp_path / "out", quick=True, animations=False, cache=False)
    assert len(calls) == 1  # built, the run cache not read


def _entry_copy(env: First, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A copy of the module's entry in another cache folder (free to damage)."""
    root = tmp_path / "other-cache"
    shutil.copytree(replay.runs_dir() / env.key, root / "report" / "runs" / env.key)
    shutil.copy(env.cache / "seal.key", root / "seal.key")  # the same user's secret
    monkeypatch.setenv("HEXAPOD_KIN_CACHE_DIR", str(root))
    assert replay.lookup(env.key) is not None
    return root / "report" / "runs" / env.key


def _flip(path: Path, at: int = 100) -> None:
    data = bytearray(path.read_bytes())
    data[at] ^= 0x01
    path.write_bytes(bytes(data))


@pytest.mark.parametrize(
    "damage",
    ["flip", "truncate", "missing", "no-manifest", "bad-manifest", "foreign-key", "escape"],
)
def test_damaged_or_incomplete_entry_is_not_replayed(
    env: First, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, damage: str
) -> None:
    entry = _entry_copy(env, tmp_path, monkeypatch)
    png = entry / "files" / "figures" / "step.png"
    manifest = entry / "manifest.json"
    record = json.loads(manifest.read_text())
    if damage == "flip":
        _flip(png)
    elif damage == "truncate":
        png.write_bytes(png.read_bytes()[:-1])
    elif damage == "missing":
        png.unlink()
    elif damage == "no-manifest":
        manifest.unlink()
    elif damage == "bad-manifest":
        manifest.write_text(manifest.read_text()[:-10])
    elif damage == "foreign-key":
        manifest.write_text(json.dumps({**record, "key": "f" * 64}))
    elif damage == "escape":  # a manifest naming a file outside the report folder
        meta = record["files"].pop("report.md")
        record["files"]["../report.md"] = meta
        shutil.copy(entry / "files" / "report.md", entry / "report.md")
        manifest.write_text(json.dumps(record))
    import warnings

    from hexapod_kin.exceptions import CacheWarning

    calls: list[dict[str, Any]] = []
    monkeypatch.setattr(build, "_build", _no_build(calls))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        assert replay.lookup(env.key) is None
        with pytest.raises(Built):
            reproduce(tmp_path / "out", quick=True, animations=False)
    assert len(calls) == 1
    said = [w for w in caught if issubclass(w.category, CacheWarning)]
    # once per look: a damaged entry warns, a missing manifest (nothing stored) does not
    assert len(said) == (0 if damage == "no-manifest" else 2), [str(w.message) for w in said]


@pytest.mark.slow
def test_tampered_entry_is_rebuilt_and_rewritten(env: First, tmp_path: Path) -> None:
    entry = replay.runs_dir() / env.key
    html = entry / "files" / "report.html"
    original = html.read_bytes()
    _flip(html, at=len(original) // 2)
    out = tmp_path / "out"
    from hexapod_kin.exceptions import CacheWarning

    with pytest.warns(CacheWarning, match="report.html does not match its manifest line"):
        rep = reproduce(out, quick=True, animations=False)
    assert rep.replayed_from is None  # computed, not replayed
    assert rep.verdicts == env.rep.verdicts
    # the same bytes as the first build (every figure too), and the entry written again
    rebuilt = {k: v for k, v in _files(out).items() if k != "verdicts.json"}
    assert rebuilt == {k: v for k, v in _files(env.out).items() if k != "verdicts.json"}
    assert _files(entry / "files") == rebuilt
    assert replay.lookup(env.key) is not None


# ---------------------------------------------------------------------------- storing
def _fake_out(tmp_path: Path, text: str) -> tuple[Path, list[Path]]:
    out = tmp_path / f"out-{text}"
    (out / "figures").mkdir(parents=True)
    files = [out / "report.md", out / "figures" / "a.txt"]
    for i, f in enumerate(files):
        f.write_text(f"{text} {i}")
    return out, files


def _record(env: First, status: str = "agrees") -> dict[str, Any]:
    verdicts = [v.fields() for v in env.rep.verdicts]
    verdicts[0] = {**verdicts[0], "status": status}
    return {"verdicts": verdicts, "facts": {}, "seconds": 1.0, "summary": "", "counts": {}}


def test_error_build_is_not_stored(
    env: First, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("HEXAPOD_KIN_CACHE_DIR", str(tmp_path / "cache"))
    out, files = _fake_out(tmp_path, "x")
    assert replay.save("a" * 64, {}, out, files, _record(env, "error")) is None
    assert not (replay.runs_dir() / ("a" * 64)).exists()
    assert replay.save("b" * 64, {}, out, files, _record(env)) is not None
    # through reproduce: a build with an error verdict leaves no entry
    bad = dataclasses.replace(env.rep.verdicts[0], status="error", reason="forced")
    rep = dataclasses.replace(env.rep, out=out, verdicts=(bad, *env.rep.verdicts[1:]))
    monkeypatch.setattr(build, "_build", lambda out, **kw: (rep, files))
    assert reproduce(out, quick=True, animations=False) is rep
    assert [d.name for d in replay.runs_dir().iterdir()] == ["b" * 64]


def test_build_whose_source_changed_meanwhile_is_not_stored(
    env: First, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("HEXAPOD_KIN_CACHE_DIR", str(tmp_path / "cache"))
    out, files = _fake_out(tmp_path, "x")
    rep = dataclasses.replace(env.rep, out=out)
    monkeypatch.setattr(build, "_build", lambda out, **kw: (rep, files))
    digests = iter(["1" * 64, "2" * 64])
    monkeypatch.setattr(replay, "source_digest", lambda: next(digests))
    reproduce(out, quick=True, animations=False)
    assert not replay.runs_dir().exists() or not list(replay.runs_dir().iterdir())
    monkeypatch.setattr(replay, "source_digest", lambda: "3" * 64)
    reproduce(out, quick=True, animations=False)  # unchanged: stored
    assert len(list(replay.runs_dir().iterdir())) == 1


def test_prune_keeps_the_newest_four(
    env: First, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("HEXAPOD_KIN_CACHE_DIR", str(tmp_path / "cache"))
    keys = [f"{i}" * 64 for i in range(7)]
    now = time.time()
    for i, key in enumerate(keys[:6]):
        out, files = _fake_out(tmp_path, key[:4])
        assert replay.save(key, {}, out, files, _record(env)) is not None
        os.utime(replay.runs_dir() / key / "manifest.json", (now - 100 + i, now - 100 + i))
    assert replay.KEEP == 4
    assert sorted(d.name for d in replay.runs_dir().iterdir()) == keys[2:6]
    # a replay marks its entry used: the oldest one, replayed, survives the next store
    monkeypatch.setattr(replay, "verdicts_match", lambda *a: True)  # no real report here
    entry = replay.lookup(keys[2])
    assert entry is not None
    restored = replay.restore(entry, tmp_path / "restored")
    assert sorted(p.read_text() for p in restored) == ["2222 0", "2222 1"]
    stale = replay.runs_dir() / ("e" * 64)  # a crashed store, an hour old: removed
    stale.mkdir()
    young = replay.runs_dir() / ("f" * 64)  # another process storing right now: left alone
    young.mkdir()
    os.utime(stale, (now - 7200, now - 7200))
    out, files = _fake_out(tmp_path, "last")
    replay.save(keys[6], {}, out, files, _record(env))
    left = sorted(d.name for d in replay.runs_dir().iterdir())
    assert left == sorted([keys[2], keys[5], keys[4], keys[6], "f" * 64])


def test_source_digest_follows_every_python_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    (tmp_path / "sub").mkdir()
    (tmp_path / "a.py").write_text("x = 1\n")
    (tmp_path / "sub" / "b.py").write_text("y = 2\n")
    (tmp_path / "data.txt").write_text("not code")
    monkeypatch.setattr(replay, "_PACKAGE", tmp_path)
    before = replay.source_digest()
    h = hashlib.sha256()
    for rel in ("a.py", "sub/b.py"):
        h.update(rel.encode())
        h.update((tmp_path / rel).read_bytes())
    assert before == h.hexdigest()
    (tmp_path / "data.txt").write_text("changed")
    assert replay.source_digest() == before
    (tmp_path / "sub" / "b.py").write_text("y = 3\n")
    assert replay.source_digest() != before


# ---------------------------------------------------------------------------- light replay
def test_replay_imports_nothing_heavy(env: First, tmp_path: Path) -> None:
    """A replayed run (CLI, whole process) never imports the numeric or symbolic stack."""
    out = tmp_path / "out"
    code = (
        "import json, sys\n"
        "from hexapod_kin.cli import main\n"
        f"rc = main(['reproduce', '--out', {str(out)!r}, '--quick', '--no-animations'])\n"
        f"heavy = sorted(m for m in sys.modules if m.split('.')[0] in {HEAVY!r})\n"
        "print(json.dumps({'rc': rc, 'heavy': heavy}))\n"
    )
    proc = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        env={**os.environ, "HEXAPOD_KIN_CACHE_DIR": str(env.cache)},
        timeout=600,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.strip().splitlines()
    assert json.loads(lines[-1]) == {"rc": 0, "heavy": []}
    said = next(line for line in lines if line.startswith("verdicts: "))
    assert "replayed: same code, data and libraries as the build of" in said
    assert "--no-cache recomputes" in said
    assert json.loads((out / "verdicts.json").read_text())["replayed_from"]


@pytest.mark.slow
@pytest.mark.parametrize("resealed", [False, True])
def test_edited_manifest_verdicts_are_not_replayed(
    env: First, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, resealed: bool
) -> None:
    """A manifest whose verdicts were edited (e.g. to count more agreements) is not the
    report it lists: the build runs again with one CacheWarning, never a wrong summary.
    Edited as is, the manifest's seal is broken; resealed (an editor who recomputes it),
    the verdicts no longer match the rows of ``report.md``. The broken seal runs a stand-in
    build (it is called: not replayed; ``test_tampered_entry_is_rebuilt_and_rewritten``
    rebuilds for real after a broken entry); the resealed case builds for real."""
    import shutil
    import warnings

    from hexapod_kin.exceptions import CacheWarning

    copy = tmp_path / "cache"
    shutil.copytree(env.cache, copy)  # the module's cache stays untouched
    monkeypatch.setenv("HEXAPOD_KIN_CACHE_DIR", str(copy))
    entry = replay.lookup(env.key)
    assert entry is not None
    assert replay.verdicts_match(entry.record["verdicts"], entry.files)
    record = json.loads((entry.folder / "manifest.json").read_text())
    wrong = next(i for i, v in enumerate(record["verdicts"]) if v["status"] == "wrong")
    record["verdicts"][wrong]["status"] = "agrees"
    assert not replay.verdicts_match(record["verdicts"], entry.files)
    if resealed:
        record["seal"] = replay.seal(record)
    (entry.folder / "manifest.json").write_text(json.dumps(record))
    calls: list[dict[str, Any]] = []
    if not resealed:
        monkeypatch.setattr(build, "_build", _no_build(calls))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            rep = reproduce(tmp_path / "again", quick=True, animations=False)
        except Built:
            assert not resealed
    said = [str(w.message) for w in caught if issubclass(w.category, CacheWarning)]
    why = "verdicts are not the report's" if resealed else "does not match its seal"
    assert len(said) == 1 and why in said[0], said
    if resealed:
        assert rep.counts == env.rep.counts and rep.replayed_from is None
    else:  # built, not replayed
        assert len(calls) == 1 and calls[0]["quick"] and not calls[0]["animations"], calls
