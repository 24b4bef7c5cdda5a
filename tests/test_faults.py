"""Faults of issue 35, as real child processes: full disks, a cache path that is a file, races.

* ``NUMBA_CACHE_DIR`` on a full file system (a 64 kB tmpfs, filled): ``precompile`` and a
  compiled call work, compiled in memory, with one warning, and give the bits of a working
  cache.
* ``HEXAPOD_KIN_CACHE_DIR`` on a full file system: ``derive`` and ``scan`` answer as with a
  working cache and leave no temporary file.
* ``HEXAPOD_KIN_CACHE_DIR`` naming a regular file: one warning that says so (never "damaged
  cache entry"), the answer unchanged.
* Four concurrent ``scan --grid 101`` on one cold package cache give the same answer.

A full file system is a real one: a tmpfs mounted for the test (root only; elsewhere these
tests skip, saying why: ``tests/test_cache_matrix.py`` simulates the full disk with
``RLIMIT_FSIZE`` everywhere). Each child is measured by ``test_hostile_cli``'s harness: CPU
time, peak RSS < 1 GB, no catch-all nor traceback, at most two stderr lines.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from test_hostile_cli import Run, _cap, _finish, cli, py
from test_hostile_cli import bounded_fault as bounded

pytestmark = pytest.mark.skipif(sys.platform != "linux", reason="tmpfs mounts are Linux's")

FK_BATCH = (
    "import hashlib, hexapod_kin as hk\n"
    "leg = hk.load('hexabot_leg')\n"
    "print(hashlib.sha256(leg.fk_batch(leg.random_q(300, seed=3)).tobytes()).hexdigest())\n"
)


def _fill(mnt: Path) -> None:
    """Write zeros to ``mnt/fill`` until the file system refuses (ENOSPC)."""
    fd = os.open(mnt / "fill", os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o600)
    try:
        while os.write(fd, b"\0" * 512):
            pass
    except OSError:
        pass
    finally:
        os.close(fd)


@pytest.fixture
def full_disk(tmp_path: Path) -> Iterator[Path]:
    """A 64 kB tmpfs, filled to the last block: every write fails with ENOSPC."""
    mnt = tmp_path / "full"
    mnt.mkdir()
    if os.geteuid() != 0 or shutil.which("mount") is None:
        pytest.skip("mounting a small tmpfs needs root (test_cache_matrix simulates it)")
    made = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", "size=64k,mode=0777", "tmpfs", str(mnt)],
        capture_output=True,
        text=True,
    )
    if made.returncode != 0:
        pytest.skip(f"mount -t tmpfs is not permitted here: {made.stderr.strip()[:120]}")
    try:
        (mnt / "cache").mkdir()  # the folders exist: only the writes fail
        (mnt / "numba").mkdir()
        _fill(mnt)
        with pytest.raises(OSError):
            (mnt / "probe").write_bytes(b"\0" * 4096)
        yield mnt
    finally:
        subprocess.run(["umount", "-l", str(mnt)], capture_output=True)


def _python(code: str, cwd: Path, timeout: float = 600) -> Run:
    """``python -c CODE`` measured like :func:`test_hostile_cli.cli`."""
    return py(code, cwd=cwd, timeout=timeout)


@pytest.fixture(scope="module")
def working(tmp_path_factory: pytest.TempPathFactory) -> Callable[..., tuple[Path, Run]]:
    """``working(*args)``: the command run with a fresh package cache, once per module (the
    answer both tests below match): (the cache folder it filled, the run)."""
    made: dict[tuple[str, ...], tuple[Path, Run]] = {}

    def run(*args: str) -> tuple[Path, Run]:
        if args not in made:
            cwd = tmp_path_factory.mktemp("working")
            with pytest.MonkeyPatch.context() as mp:
                mp.setenv("HEXAPOD_KIN_CACHE_DIR", str(cwd / "cache"))
                made[args] = (cwd / "cache", cli(*args, cwd=cwd, timeout=120))
        return made[args]

    return run


def _no_tmp(root: Path) -> None:
    assert not [p for p in root.rglob("*") if ".tmp" in p.name], list(root.rglob("*"))


@pytest.mark.slow
def test_numba_cache_on_a_full_disk_compiles_in_memory(
    full_disk: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("HEXAPOD_KIN_CACHE_DIR", str(tmp_path / "hk"))
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "working"))
    want = _python(FK_BATCH, tmp_path)
    assert want.status == 0, want.stderr
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(full_disk / "numba"))
    pre = cli("precompile", "--only", "batch", cwd=tmp_path, timeout=600)
    # the estimate for the areas being compiled, the one warning, one progress line per area
    bounded(pre, cpu=300.0, lines=3)
    assert pre.status == 0, pre.stderr
    assert pre.lines[0].startswith("compiling batch in 1 process(es): about "), pre.stderr
    assert "cannot be written" in pre.stderr and "compiling in memory" in pre.stderr
    assert re.fullmatch(r"  batch done \([0-9.]+ s\)", pre.lines[-1]), pre.stderr
    got = _python(FK_BATCH, tmp_path)
    bounded(got, cpu=300.0, lines=2, cli=False)  # Python's warning: its line and source
    assert got.status == 0, got.stderr
    said = [ln for ln in got.lines if "CacheWarning" in ln]
    assert len(said) == 1 and "compiling in memory" in said[0], got.stderr
    assert got.stdout == want.stdout  # the same bits as with a working cache
    _no_tmp(full_disk)


@pytest.mark.parametrize(
    "args",
    [("derive", "hexabot_leg"), ("scan", "hexabot_leg", "--families", "derive", "--json")],
    ids=["derive", "scan"],
)
@pytest.mark.slow
def test_package_cache_on_a_full_disk(
    full_disk: Path,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    working: Callable[..., tuple[Path, Run]],
    args: tuple[str, ...],
) -> None:
    """Nothing can be cached: the same answer as with a working cache, no ``.tmp`` left."""
    cache, want = working(*args)
    assert want.status == 0, want.stderr
    assert list(cache.rglob("*.json"))  # it does cache there
    seal = (cache / "seal.key").read_bytes()
    for secret in (False, True):  # no secret yet (none can be made), or one written before
        if secret:
            subprocess.run(["umount", "-l", str(full_disk)], check=True)
            subprocess.run(["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(full_disk)])
            (full_disk / "cache").mkdir()
            (full_disk / "cache" / "seal.key").write_bytes(seal)
            _fill(full_disk)
        monkeypatch.setenv("HEXAPOD_KIN_CACHE_DIR", str(full_disk / "cache"))
        run = cli(*args, cwd=tmp_path, timeout=120)
        bounded(run, lines=0)
        assert run.status == 0, run.stderr
        assert run.stdout == want.stdout
        _no_tmp(full_disk)
        assert not list((full_disk / "cache").rglob("*.json"))


@pytest.mark.slow
@pytest.mark.parametrize("command", ["derive", "scan"])
def test_cache_path_that_is_a_regular_file_says_so(
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    working: Callable[..., tuple[Path, Run]],
    command: str,
) -> None:
    _, want = working(command, "hexabot_leg")
    assert want.status == 0, want.stderr
    plain = tmp_path / "a-file"
    plain.write_text("not a folder")
    monkeypatch.setenv("HEXAPOD_KIN_CACHE_DIR", str(plain))
    run = cli(command, "hexabot_leg", cwd=tmp_path, timeout=120)
    bounded(run, lines=1)
    assert run.status == 0 and run.stdout == want.stdout, run.stderr
    assert len(run.lines) == 1 and "is not a folder" in run.lines[0], run.stderr
    assert "damaged" not in run.stderr
    assert plain.read_text() == "not a folder"


@pytest.mark.slow
def test_four_concurrent_cold_scans_agree(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Four ``scan --grid 101`` started together on one empty package cache: one answer.

    The families are derived within a budget of CPU time (never wall-clock time), so the
    machine's load (the other three) changes nothing. numba's cache is warmed first: the
    race under test is the package cache's (secret, entries), not the compile.
    """
    args = [sys.executable, "-m", "hexapod_kin", "scan", "hexabot_leg", "--grid", "101", "--json"]
    monkeypatch.setenv("HEXAPOD_KIN_CACHE_DIR", str(tmp_path / "warm"))
    warm = cli(*args[3:], cwd=tmp_path, timeout=900)
    assert warm.status == 0, warm.stderr
    monkeypatch.setenv("HEXAPOD_KIN_CACHE_DIR", str(tmp_path / "cold"))
    procs = []
    for k in range(4):
        work = tmp_path / f"w{k}"
        work.mkdir()
        out, err = open(work / ".stdout", "wb"), open(work / ".stderr", "wb")
        t0 = time.monotonic()
        proc = subprocess.Popen(
            args, cwd=work, stdout=out, stderr=err, env=dict(os.environ), preexec_fn=_cap
        )
        procs.append((proc, t0, work, out, err))
    runs = []
    for proc, t0, work, out, err in procs:
        run = _finish(proc, t0, 900, work / ".stdout", work / ".stderr")
        out.close()
        err.close()
        runs.append(run)
    for run in runs:
        bounded(run, cpu=120.0, lines=0)
        assert run.status == 0, run.stderr
    assert {run.stdout for run in runs} == {warm.stdout}
    _no_tmp(tmp_path / "cold")


@pytest.mark.parametrize("fault", [KeyboardInterrupt, OSError], ids=["ctrl-c", "disk-full"])
def test_mjcf_stopped_between_its_files_leaves_none(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, fault: type[BaseException]
) -> None:
    """``write_mjcf`` stopped after some meshes: none of the files it made is left."""
    pytest.importorskip("trimesh")
    pytest.importorskip("mujoco")
    from hexapod_kin.export import mjcf

    real, calls = mjcf.atomic_write, []

    def flaky(path, data, **kwargs):
        calls.append(path)
        if len(calls) == 3:
            raise fault(28, "No space left on device") if fault is OSError else fault()
        return real(path, data, **kwargs)

    (tmp_path / "keep.txt").write_text("mine")
    monkeypatch.setattr(mjcf, "atomic_write", flaky)
    with pytest.raises(fault):
        mjcf.write_mjcf("hexabot_leg", tmp_path / "robot.xml", meshes=True)
    assert len(calls) == 3
    assert sorted(p.name for p in tmp_path.iterdir()) == ["keep.txt"]
