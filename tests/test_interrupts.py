"""Ctrl-C ends every long command with one line and exit status 130, leaving nothing behind.

Every command form below runs longer than a second on the 2-core reference machine with
fresh caches (numba compiling, sympy deriving, trimesh/MuJoCo/matplotlib loading). For each:

1. a **reference run**, uninterrupted, with fresh caches: its wall time ``D``, exit status
   and files;
2. ``TRIES`` **interrupted runs**, each with fresh caches: SIGINT at a uniformly random time
   between the end of start-up (measured in each try by a concurrent ``python -c "import
   hexapod_kin"``: before that, Ctrl-C is the interpreter's to handle) and ``D``, sent
   either to the process group (what a terminal's Ctrl-C does: forked workers and servers
   get it too) or to the command's process alone (``kill -INT``). Each try ends either
   interrupted — status 130, last stderr line ``hexapod-kin: interrupted``, at most one
   line before it and only one that the complete run prints too (a notice such as numba's
   "compiling"), no traceback — or, when the signal came after the work, with the
   reference run's status. Either way: no temporary file (``*.tmp*``) in the output folder
   or the caches, no process of the run left alive, and every output file is whole:
   byte-identical to the reference run's file (every run writes to the same paths, so even
   the paths inside the files agree);
3. a **next run**, uninterrupted, on the output folder and caches of the interrupted try
   whose signal came last (the most state written): the same status and the same files as
   the reference run. Nothing an interrupt leaves blocks or changes the next run.

These runs are marked ``soak``: the default run leaves them out (pyproject's addopts) and the
``soak`` step of ``.ci/run`` runs them. ``TRIES`` is ``HEXAPOD_KIN_CTRL_C_TRIES``: unset
(``pytest -m soak``), 2 tries of the commands in :data:`REGULAR`; set (``.ci/run`` sets 20),
every command.
``HEXAPOD_KIN_CTRL_C_REPORT=FILE`` appends one JSON line per command with its outcome counts.
"""

from __future__ import annotations

import json
import os
import random
import signal
import subprocess
import sys
import time
import uuid
from pathlib import Path
from typing import Any

import pytest

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals and sessions")

ROOT = Path(__file__).resolve().parent.parent
TRIES = int(os.environ.get("HEXAPOD_KIN_CTRL_C_TRIES", "2"))
SOAK = "HEXAPOD_KIN_CTRL_C_TRIES" in os.environ

#: name -> arguments; ``{out}`` is the output folder. One form per command that runs longer
#: than a second (its heavier typical options), cold caches in every run.
COMMANDS: dict[str, list[str]] = {
    "derive-5dof": ["derive", str(ROOT / "examples" / "leg5.yaml")],
    "derive-7dof": ["derive", "erd:panda"],
    "scan-ur5": ["scan", "erd:ur5_robot", "--plot", "{out}/scan.png"],
    "step-twist-ur5": ["step", "erd:ur5_robot", "--twist", "0", "0", "0.01", "0", "0", "0.1"],
    "step-plot": ["step", "hexabot_leg", "--plot", "{out}/step.png"],
    "pendulum": ["pendulum", "--plot", "{out}/p.png", "--html", "{out}/p.html"],
    "gait": ["gait", "--duration", "10", "--html", "{out}/walk.html", "--plot", "{out}/w.png"],
    "timeline": ["timeline", "gait", "--duration", "60", "-o", "{out}/walk.csv"],
    "animate": ["animate", "erd:ur5_robot", "--html", "{out}/anim.html"],
    "view": ["view", "hexapod", "--serve-for", "1"],
    "drive": ["drive", "hexapod", "--no-open", "--serve-for", "1"],
    "mjcf": ["mjcf", "hexapod", "--meshes", "-o", "{out}/robot.xml"],
    "export-package": ["export-package", "hexapod", "--meshes", "-o", "{out}/pkg", "-f"],
    "sweep": [
        *("sweep", "--height", "0.1", "--l1", "0.03:0.05:3", "--l2", "0.08:0.12:10"),
        *("--l3", "0.1:0.14:10", "--mc-samples", "2000", "--no-progress"),
        *("--out", "{out}/sweep.csv"),
    ],
    "simulate": ["simulate", "hexapod", "--duration", "10", "--json"],
    "reproduce-quick": ["reproduce", "--quick", "--no-animations", "--out", "{out}/report"],
    "reproduce": ["reproduce", "--out", "{out}/report"],
    # numba compiling (tens of seconds cold; precompile's other areas compile the same way,
    # 3 to 5 times longer)
    "scan-compiled": ["scan", "hexabot_leg", "--samples", "6000"],
    "precompile": ["precompile", "--only", "batch"],
}
#: The regular suite's share (a few seconds each: the sympy worker, trimesh and MuJoCo
#: imports, matplotlib, the resumable sweep, the viewer's server); the soak runs them all.
REGULAR = ("derive-5dof", "export-package", "gait", "mjcf", "sweep", "view")
#: Hidden files that are resumable state by design (``sweep``: its chunks' sidecar, removed
#: once the table is written).
RESUMABLE = (".sweep.csv.sweep-parts",)
INTERRUPTED = "hexapod-kin: interrupted"


def _params() -> list[object]:
    soak_only = pytest.mark.skipif(not SOAK, reason="soak only (HEXAPOD_KIN_CTRL_C_TRIES)")
    return [pytest.param(n, marks=() if n in REGULAR else soak_only) for n in sorted(COMMANDS)]


class Run:
    """One process of a command in ``work`` (output ``work/out``, caches ``work/cache``)."""

    def __init__(self, name: str, work: Path) -> None:
        self.work = work
        (work / "out").mkdir(parents=True, exist_ok=True)
        self.marker = uuid.uuid4().hex
        env = dict(os.environ, MPLBACKEND="Agg", HEXAPOD_KIN_CTRL_C_MARK=self.marker)
        env.update(
            NUMBA_CACHE_DIR=str(work / "cache" / "numba"),
            HEXAPOD_KIN_CACHE_DIR=str(work / "cache" / "hexapod_kin"),
        )
        env.pop("HEXAPOD_KIN_DEBUG", None)
        argv = [a.replace("{out}", str(work / "out")) for a in COMMANDS[name]]
        self.start = time.perf_counter()
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "hexapod_kin", *argv],
            cwd=work / "out",
            env=env,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
            start_new_session=True,  # its own process group, as a shell's foreground job
        )
        self.signalled: str | None = None

    def interrupt_at(self, fraction: float, duration: float, group: bool) -> float:
        """Send SIGINT ``fraction`` of the way from the end of start-up to ``duration`` [s].

        The end of start-up is measured now, under the machine's present load: a probe
        ``python -c "import hexapod_kin"`` started with the command ends about when the
        command's own interpreter has started and imported the package (before that, Ctrl-C
        is the interpreter's to handle). Returns the time sent, in seconds from the start.
        """
        subprocess.run([sys.executable, "-c", "import hexapod_kin"], cwd=ROOT, check=True)
        ready = 1.2 * (time.perf_counter() - self.start)
        at = ready + fraction * max(duration - ready, 0.05)
        time.sleep(max(0.0, self.start + at - time.perf_counter()))
        if self.proc.poll() is None:
            try:
                if group:
                    os.killpg(self.proc.pid, signal.SIGINT)
                else:
                    self.proc.send_signal(signal.SIGINT)
                self.signalled = "group" if group else "process"
            except ProcessLookupError:
                pass
        return at

    def finish(self, timeout: float) -> tuple[int, str, float]:
        """Exit status, stderr and wall seconds (a run over ``timeout`` fails the test)."""
        try:
            _, err = self.proc.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            os.killpg(self.proc.pid, signal.SIGKILL)
            _, err = self.proc.communicate()
            pytest.fail(f"no exit within {timeout:.0f} s after the signal: {err[-2000:]}")
        wall = time.perf_counter() - self.start
        rc = self.proc.returncode
        return (130 if rc == -signal.SIGINT else rc), err, wall  # a shell's $? for both

    def survivors(self) -> list[int]:
        """Processes still alive that this run started (its environment mark), after ≤ 60 s."""
        deadline = time.monotonic() + 60.0  # a guard: returns as soon as none is left
        while True:
            alive = []
            for env in Path("/proc").glob("[0-9]*/environ"):
                try:
                    if f"HEXAPOD_KIN_CTRL_C_MARK={self.marker}".encode() in env.read_bytes():
                        status = (env.parent / "stat").read_text().split(")")[-1].split()
                        if status[0] != "Z":  # a zombie is already dead (its parent reaps it)
                            alive.append(int(env.parent.name))
                except OSError:
                    pass
            if not alive or time.monotonic() > deadline:
                return alive
            time.sleep(0.1)


#: ``reproduce``'s verdicts: the fields that describe the run itself (its time, whether it
#: was replayed from the cache), not the report.
RUN_FIELDS = ("seconds", "build_seconds", "replayed_from")


def _content(path: Path) -> bytes:
    data = path.read_bytes()
    if path.name == "verdicts.json":
        try:
            doc = json.loads(data)
        except ValueError:
            return data  # not whole: unlike the reference
        return json.dumps({k: v for k, v in doc.items() if k not in RUN_FIELDS}).encode()
    return data


def _files(folder: Path) -> dict[str, bytes]:
    return {
        str(p.relative_to(folder)): _content(p)
        for p in sorted(folder.rglob("*"))
        if p.is_file() and not p.is_symlink()
    }


def _problems(work: Path, reference: dict[str, bytes]) -> list[str]:
    """Temporary files, unexpected hidden files and files unlike the reference run's."""
    found = []
    for p in sorted(work.rglob("*")):
        if ".tmp" in p.name:
            found.append(f"temporary file left: {p.relative_to(work)}")
        elif p.name.startswith(".") and p.name not in RESUMABLE and "cache" not in p.parts:
            found.append(f"hidden file left: {p.relative_to(work)}")
    for rel, data in _files(work / "out").items():
        if rel.split("/")[0] in RESUMABLE:
            continue
        if rel not in reference:
            found.append(f"a file the complete run does not write: {rel}")
        elif data != reference[rel]:
            found.append(f"a file unlike the complete run's (partial?): {rel}")
    return found


def _stderr_problems(status: int, err: str, ref_status: int, ref_err: str) -> list[str]:
    """The interrupt adds one line; any line before it is one the complete run prints too."""
    lines = err.strip().splitlines()
    if "Traceback" in err or "Exception ignored" in err:
        return [f"a traceback: {err[-3000:]}"]
    if status == 130:
        notices = set(ref_err.strip().splitlines())
        if not lines or lines[-1] != INTERRUPTED or len(lines) > 2:
            return [f"status 130 but stderr is not the one line: {err[-1000:]!r}"]
        if any(line not in notices for line in lines[:-1]):
            return [f"status 130 after a line the complete run does not print: {err[-1000:]!r}"]
        return []
    if status != ref_status:
        return [f"status {status} (reference {ref_status}): {err[-1000:]!r}"]
    return []


@pytest.mark.soak
@pytest.mark.parametrize("name", _params())
def test_ctrl_c(tmp_path: Path, name: str) -> None:
    timeout = 300.0
    work = tmp_path / "work"
    # 1. the reference run
    ref = Run(name, work)
    ref_status, ref_err, duration = ref.finish(timeout)
    assert ref_status in (0, 1), (ref_status, ref_err[-2000:])
    reference = _files(work / "out")
    assert bool(reference) == any("{out}" in a for a in COMMANDS[name]), sorted(reference)
    assert not ref.survivors()
    work.rename(tmp_path / "reference")

    # 2. interrupted tries, fresh caches each
    rng = random.Random(f"{name}:{os.environ.get('HEXAPOD_KIN_CTRL_C_SEED', '0')}")
    counts = {"130": 0, "finished": 0, "failed": 0}
    failures: list[str] = []
    latest: tuple[float, Path] | None = None
    for attempt in range(TRIES):
        fraction, group = rng.random(), rng.random() < 0.5
        run = Run(name, work)
        at = run.interrupt_at(fraction, duration, group)
        status, err, _ = run.finish(timeout)
        where = f"try {attempt}: SIGINT to the {run.signalled} at {at:.3f} s of {duration:.2f} s"
        problems = _stderr_problems(status, err, ref_status, ref_err)
        if run.signalled is None and status == 130:
            problems.append("status 130 without a signal")
        problems += _problems(work, reference)
        if alive := run.survivors():
            problems.append(f"processes left alive: {alive}")
        if problems:
            counts["failed"] += 1
            failures += [f"{where}: status {status}: {p}" for p in problems]
            if status != 130:
                failures.append(f"{where}: its stderr: {err[-1500:]!r}")
        else:
            counts["130" if status == 130 else "finished"] += 1
        kept = tmp_path / f"try{attempt}"
        work.rename(kept)
        if status == 130 and (latest is None or at > latest[0]):
            latest = (at, kept)

    # 3. the next run, on the state the latest interrupt left
    if latest is None:
        latest = (0.0, kept)
    latest[1].rename(work)
    after = Run(name, work)
    status, err, _ = after.finish(timeout)
    if status != ref_status or "Traceback" in err:
        failures.append(
            f"next run (after the {latest[0]:.3f} s try): status {status}: {err[-2000:]}"
        )
    failures += [f"next run: {p}" for p in _problems(work, reference)]
    missing = sorted(set(reference) - set(_files(work / "out")))
    if missing:
        failures.append(f"next run: files missing {missing}")
    if alive := after.survivors():
        failures.append(f"next run: processes left alive: {alive}")

    summary = {"command": name, "duration_s": round(duration, 2), "tries": TRIES, **counts}
    if path := os.environ.get("HEXAPOD_KIN_CTRL_C_REPORT"):
        with open(path, "a", encoding="utf-8") as fh:
            fh.write(json.dumps({**summary, "failures": failures[:20]}) + "\n")
    assert not failures, "\n".join([json.dumps(summary), *failures[:10]])


class _OneCommand:
    """A parser stand-in whose only command is ``func`` (for :func:`hexapod_kin.cli.main`)."""

    def __init__(self, func: object) -> None:
        self.func = func

    def parse_args(self, argv: object) -> object:
        import argparse

        return argparse.Namespace(func=self.func)


def test_swallowed_interrupt_stops_the_work(monkeypatch: pytest.MonkeyPatch, capsys) -> None:
    """A Ctrl-C that a finalizer or callback swallows ("Exception ignored") still stops it.

    The command's own code keeps running after the swallowed interrupt (a 20 s sleep here);
    ``main`` delivers the interrupt again, so the sleep never completes: one line and 130.
    """
    import threading

    from hexapod_kin import cli

    if threading.current_thread() is not threading.main_thread():
        pytest.skip("signals are handled in the main thread only")

    class Finalized:
        def __del__(self) -> None:
            raise KeyboardInterrupt  # reported as unraisable, not raised

    slept: list[bool] = []

    def command(args: object) -> int:
        Finalized()
        time.sleep(20)
        slept.append(True)  # reached only if the interrupt was not delivered again
        return 0

    monkeypatch.setattr(cli, "build_parser", lambda: _OneCommand(command))
    status = cli.main([])
    assert status == 130
    assert slept == []  # the sleep was cut short (no clock read: a busy machine changes none)
    assert capsys.readouterr().err.strip().splitlines()[-1] == INTERRUPTED


def test_interrupt_escaping_pyrun_code_exits_130(tmp_path: Path) -> None:
    """An interrupt raised through CPython's ``PyRun_*`` API (as in Boost.Python's ``exec``
    during Pinocchio's import) and caught by ``main`` ends the process with the one line and
    by its own SIGINT (a shell's status 130), like every interrupted command. Run with ``-m`` as
    ``python -m hexapod_kin`` is: ``-c`` exits from inside its own ``PyRun`` call instead."""
    script = """if True:
        import argparse, ctypes
        from hexapod_kin import cli

        def command(args):
            run = ctypes.pythonapi.PyRun_String
            run.argtypes = [ctypes.c_char_p, ctypes.c_int, ctypes.py_object, ctypes.py_object]
            run.restype = ctypes.py_object
            run(b"raise KeyboardInterrupt", 257, {}, {})  # 257: Py_file_input
            return 0

        class Parser:
            def parse_args(self, argv):
                return argparse.Namespace(func=command)

        cli.build_parser = Parser
        cli.run()
    """
    (tmp_path / "pyrun_probe.py").write_text(script, encoding="utf-8")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), str(tmp_path)]))
    res = subprocess.run(
        [sys.executable, "-m", "pyrun_probe"], capture_output=True, text=True, timeout=600, env=env
    )
    assert res.returncode in (130, -signal.SIGINT), (res.returncode, res.stderr)  # $? = 130
    assert res.stderr.strip().splitlines() == [INTERRUPTED], res.stderr


def test_error_made_of_an_interrupt_is_the_one_line(
    monkeypatch: pytest.MonkeyPatch, capsys
) -> None:
    """A library that turns Ctrl-C into an error (pybind11: ``ImportError`` "initialization
    failed", then "mujoco is not installed") gives the one line of the interrupt only."""
    import threading

    from hexapod_kin import cli
    from hexapod_kin.exceptions import OptionalDependencyError

    if threading.current_thread() is not threading.main_thread():
        pytest.skip("signals are handled in the main thread only")

    def command(args: object) -> int:
        try:
            signal.raise_signal(signal.SIGINT)
        except KeyboardInterrupt:
            raise OptionalDependencyError("mujoco is not installed") from None
        return 0

    monkeypatch.setattr(cli, "build_parser", lambda: _OneCommand(command))
    assert cli.main([]) == 130
    assert capsys.readouterr().err.strip().splitlines() == [INTERRUPTED]


def test_atomic_write_interrupted_as_its_file_is_created(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A Ctrl-C that arrives just as the temporary file is created leaves no file behind (the
    soak found ``.chunk_00016.npz.*.tmp`` in an interrupted sweep's sidecar)."""
    from hexapod_kin._io import atomic_write

    real_open = os.open

    def open_then_interrupt(path: str, flags: int, *args: object) -> int:
        fd = real_open(path, flags, *args)
        if path.endswith(".tmp"):
            os.close(fd)
            raise KeyboardInterrupt
        return fd

    monkeypatch.setattr(os, "open", open_then_interrupt)
    with pytest.raises(KeyboardInterrupt):
        atomic_write(tmp_path / "x.txt", "whole")
    assert sorted(p.name for p in tmp_path.iterdir()) == []


def test_interrupted_derivation_leaves_its_entry_as_it_was(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The worker writes its stages as they finish, marked as a budget stop; after a Ctrl-C
    the entry is put back as it was (here: none), so the next run with the same budget
    carries on instead of stopping at NOT DONE (the soak found exit 1 after an interrupt)."""
    from hexapod_kin import _budget
    from hexapod_kin.symbolic import cache, derive

    monkeypatch.setenv("HEXAPOD_KIN_CACHE_DIR", str(tmp_path))
    written: list[Path] = []

    def interrupted_run(job: Any, args: Any, budget: object) -> object:
        for _stage in job(*args):  # the worker's first stages reach the disk, then Ctrl-C
            written.extend(cache.cache_dir().glob("*.json"))
            if written:
                raise KeyboardInterrupt
        raise KeyboardInterrupt

    monkeypatch.setattr(_budget, "run", interrupted_run)
    with pytest.raises(KeyboardInterrupt):
        derive(str(ROOT / "examples" / "leg5.yaml"))
    assert written, "the stages were not written as they finished"
    assert sorted(cache.cache_dir().glob("*.json")) == []


_CHILD_SCRIPT = """
import sys, time
from hexapod_kin import _budget
import slowjob  # the job pickles by reference: the child imports slowjob again to read it
child = _budget.Child(slowjob.job, (), None)
time.sleep(0.5)
child.close()  # the caller ends the child (SIGTERM) while it imports the job (2 s)
print("closed")
"""


def test_a_budget_child_stopped_while_it_reads_its_job_prints_nothing(tmp_path: Path) -> None:
    """A budgeted job's child ended while unpickling its job (which imports the job's module:
    a 2 s import planted here) ends without a word. Before the fix it printed its own
    ``KeyboardInterrupt`` traceback (found by the Ctrl-C soak in ``derive``; this test fails
    on that code)."""
    (tmp_path / "slowjob.py").write_text(
        "import time\ntime.sleep(2.0)\n\n\ndef job():\n    yield 'a', 1\n"
    )
    paths = [str(tmp_path), str(ROOT), os.environ.get("PYTHONPATH", "")]
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in paths if p))
    run = subprocess.run(
        [sys.executable, "-c", _CHILD_SCRIPT], cwd=tmp_path, env=env, capture_output=True,
        text=True, timeout=120,
    )  # fmt: skip
    assert (run.returncode, run.stdout.strip(), run.stderr) == (0, "closed", ""), run
