"""One exit-status rule for every command, through the command line's entry ``main(argv)``.

Every row runs in this process (``main`` returns the status); rows of each status also run
as a user runs them, a child process each, whose exit status must be the same.

0 achieved; 1 answered but not achieved (a check of the plan fails, infeasible, a limit
reached: one ``hexapod-kin: not achieved: ...`` line or the answer's own words); 2 bad input
(one ``error`` line on stderr); 130 interrupted. The table lists every command of
``hexapod-kin`` (a test checks none is missing) with its failure modes. ``--help`` offers no
source kind that the command then refuses (in-process: each kind, each command).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from hexapod_kin.cli import build_parser, main
from hexapod_kin.cli.common import SOURCE_KINDS

ROOT = Path(__file__).resolve().parents[1]
TABLE = str(ROOT / "examples" / "leg4.toml")
URDF_LEG = str(ROOT / "urdf" / "hexabot_leg.urdf")
URDF_HEXAPOD = str(ROOT / "urdf" / "hexapod.urdf")

#: Every command (``timeline`` by its plans) -> (argv after the command, status) rows.
#: ``{tmp}`` is a fresh folder of the test. Each row is a failure mode (or success).
TABLE_ROWS: dict[str, list[tuple[list[str], int]]] = {
    "list": [([], 0), (["--bogus"], 2)],
    "urdf": [
        (["hexabot_leg"], 0),
        (["erd:ur5"], 2),  # a URDF is already a URDF
        (["hexabot_leg", "-s", "l1"], 2),  # -s NAME=VALUE
    ],
    "fk": [(["hexabot_leg", "--q", "0", "0", "0"], 0), (["hexabot_leg", "--q", "0"], 2)],
    "jacobian": [([TABLE], 0), (["no_such_robot"], 2)],
    "demo": [(["--out", "{tmp}/demo"], 0), (["--out", "/proc/no/such"], 2)],
    "derive": [
        (["hexabot_leg", "--budget", "120"], 0),
        (["hexabot_leg", "--budget", "0.01"], 1),  # the budget ran out: NOT DONE lines
        (["hexabot_leg", "--budget", "-1"], 2),
    ],
    "scan": [
        (["hexabot_leg", "--grid", "5", "--families", "off"], 0),
        (["hexabot_leg", "--rows", "q"], 2),
    ],
    "view": [(["hexabot_leg", "--no-wait"], 0), (["hexabot_leg", "--serve-for", "-1"], 2)],
    "drive": [
        (["hexabot_leg", "--no-open", "--serve-for", "0"], 0),
        (["hexabot_leg", "--no-open", "--serve-for", "-1"], 2),
        (["hexabot_leg", "--no-open", "--port", "70000"], 2),
    ],
    "animate": [
        (["hexabot_leg", "--samples", "5", "--html", "{tmp}/a.html"], 0),
        (["hexabot_leg", "--html", "{tmp}/a.txt"], 2),
    ],
    "ik": [
        (["hexabot_leg", "--target", "0.15", "0.05", "-0.1"], 0),
        (["hexabot_leg", "--target", "1", "0", "0"], 1),  # unreachable: nearest printed
        (["hexabot_leg", "--target", "1", "0"], 2),
    ],
    "step": [
        (["hexabot_leg", "--duration", "0.3", "--no-baseline"], 0),
        (["hexabot_leg", "--velocity", "0.5", "0", "0", "--duration", "1"], 1),  # limits
        (["hexabot_leg", "--velocity", "0.5", "0"], 2),
    ],
    "pendulum": [(["--duration", "1"], 0), (["--theta0-deg", "200"], 2)],
    "torques": [(["hexabot_leg"], 0), (["hexabot_leg", "--inertia", "bogus"], 2)],
    "stand": [
        ([], 0),
        (["--legs", "1", "2", "4", "--shift", "0.06", "0"], 1),  # a foot pulls: infeasible
        (["--shift", "0.2", "0"], 1),  # a leg cannot reach its foot point
        (["--legs", "1", "2", "4", "--shift", "0.06", "0", "--method", "friction"], 2),  # no mu
        ([*"--legs 1 2 4 --shift 0.06 0 --method friction --mu 0.5".split()], 1),  # no forces
        (["--legs", "1", "2"], 2),  # two feet cannot hold a body: ask for three
        (["erd:solo12", "-s", "l1=3"], 2),  # -s for a non-preset: one message
    ],
    "xacro": [(["hexabot_leg"], 0), (["erd:ur5"], 2)],
    "export-package": [(["hexabot_leg", "-o", "{tmp}/pkg"], 0), (["hexabot_leg"], 2)],
    "mjcf": [(["erd:ur5"], 0), (["pendulum", "--integrator", "leapfrog"], 2)],
    "sweep": [
        (["--l1", "0.05", "--mc-samples", "100", "--out", "{tmp}/s.csv", "--no-progress"], 0),
        (["--l1", "a:b"], 2),
    ],
    "gait": [
        (["--duration", "1"], 0),
        (["--stride", "0.4", "--duration", "1"], 1),  # a check fails: out of reach
        # every check passes but the CoM and the ZMP leave the support polygon
        (["erd:anymal", "--pattern", "trot", "--velocity", "0.3", "0", "0", "--duration", "2"], 1),
        (["--pattern", "gallop"], 2),
        (["--duration", "0.5", "--view", "--no-wait"], 0),
        (["erd:solo12", "--view"], 2),  # --view plays the hexapod preset only
    ],
    "simulate": [
        (["--duration", "1", "--no-stand"], 0),
        (["--stride", "0.4", "--duration", "1"], 1),  # the plan fails, as gait's
        (["erd:anymal", "--period", "0.4", "--duration", "2"], 1),  # ZMP margin -0.13 m
        (["--terrain", "mud"], 2),
        (["--control", "--robust"], 2),  # one verdict per run
        (["--control", "--mjcf", "x.xml"], 2),
        # the closed loop's disturbances: on both grounds (bumps), on the closed loop (push)
        (["--control", "--duration", "1", "--bumps", "0.005", "--push", "5@0.2,0.1"], 0),
        (["--bumps", "0.01"], 2),  # bumps and pushes need --control
        (["--push", "20@1,0.2"], 2),
        (["--control", "--push", "20@x"], 2),
        (["--control", "--bumps", "0.1"], 2),  # at most 0.05 m
        (["--payload", "1"], 2),  # a payload needs --control
        (["--control", "--payload", "-1"], 2),
    ],
    "control": [
        (["--duration", "1"], 0),
        (["--duration", "1.5", "--push", "60@0.2,0.5"], 1),  # 3x its weight: it falls
        (["--push", "20@x"], 2),
        (["--duration", "1", "--payload", "1@0.05,0,0.02"], 0),  # half its weight, off centre
        (["--payload", "1@0,0"], 2),
    ],
    "reproduce": [(["--out", "/proc/no/such"], 2)],  # a full run takes minutes: test_report
    "precompile": [(["--only", "bogus"], 2)],  # compiling takes minutes: test_precompile
    "timeline gait": [
        (["--duration", "1", "-o", "{tmp}/w.csv"], 0),
        (["--duration", "1", "--calibration", "{tmp}/cal.yaml", "-o", "{tmp}/x.csv"], 1),
        (["--duration", "1", "-o", "{tmp}/w.txt"], 2),
    ],
    "timeline step": [
        (["--duration", "0.5", "-o", "{tmp}/s.json"], 0),
        (["--duration", "0.5", "--calibration", "{tmp}/cal1.yaml", "-o", "{tmp}/s.csv"], 1),
        (["no_such_leg", "-o", "{tmp}/s.csv"], 2),
    ],
    "timeline path": [
        (["{tmp}/path.csv", "-o", "{tmp}/p.yaml"], 0),
        (["{tmp}/path.csv", "--calibration", "{tmp}/cal1.yaml", "-o", "{tmp}/p.csv"], 1),
        (["{tmp}/no_such.csv", "-o", "{tmp}/p.csv"], 2),
    ],
}

ROWS = [(cmd, argv, status) for cmd, rows in TABLE_ROWS.items() for argv, status in rows]


def _commands() -> set[str]:
    """Every command of the parser (``timeline`` as ``timeline <plan>``)."""
    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    names = set()
    for name, p in sub.choices.items():
        plans = [a for a in p._actions if a.dest == "plan"]
        names |= {f"{name} {plan}" for plan in plans[0].choices} if plans else {name}
    return names


def test_the_table_lists_every_command() -> None:
    assert set(TABLE_ROWS) == _commands()
    for cmd, rows in TABLE_ROWS.items():  # each command's bad input is in the table
        assert 2 in [status for _, status in rows], cmd


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    tmp = tmp_path_factory.mktemp("exit")
    ankle = "joints:\n  leg1_ankle: {limits: [-0.5, 0.5]}\n"
    (tmp / "cal.yaml").write_text("defaults: {units: rad}\n" + ankle)
    (tmp / "cal1.yaml").write_text("defaults: {limits: [-0.1, 0.1]}\n")
    (tmp / "path.csv").write_text("t,j1,j2\n0,0,0\n0.5,0.25,-0.5\n1,1,-1\n")
    return tmp


def _run(argv: list[str], cwd: Path, **kw: object) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if k != "HEXAPOD_KIN_DEBUG"}
    return subprocess.run(
        [sys.executable, "-m", "hexapod_kin", *argv],
        capture_output=True,
        text=True,
        cwd=cwd,
        env=env,
        timeout=600,
        **kw,  # type: ignore[arg-type]
    )


def _check(args: list[str], status: int, done: subprocess.CompletedProcess[str]) -> None:
    """``done`` ended with ``status``, and said so as the rule asks (one line, no traceback)."""
    said = done.stderr.strip().splitlines()
    assert done.returncode == status, (args, done.stderr[-2000:])
    assert "Traceback" not in done.stderr
    lines = [ln for ln in said if ln.startswith("hexapod-kin") and "warning" not in ln]
    if status == 2:  # one line says why
        assert len([ln for ln in lines if "error" in ln]) == 1, done.stderr
    elif status == 1:  # the answer says what was not achieved
        text = (done.stdout + done.stderr).lower()
        assert any(w in text for w in ("not achieved", "unreachable", "not done")), text[-2000:]
    else:
        assert not [ln for ln in lines if "error" in ln or "not achieved" in ln], done.stderr


def _args(cmd: str, argv: list[str], folder: Path) -> list[str]:
    return [*cmd.split(), *(a.replace("{tmp}", str(folder)) for a in argv)]


@pytest.mark.parametrize(("cmd", "argv", "status"), ROWS, ids=lambda v: str(v))
def test_exit_status(
    folder: Path,
    cmd: str,
    argv: list[str],
    status: int,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Every row through the command line's own entry, ``main(argv)``, in this process.

    :func:`test_exit_status_of_the_process` runs rows of each status as a child and checks
    that the process ends with the status ``main`` returns.
    """
    args = _args(cmd, argv, folder)
    monkeypatch.chdir(folder)
    monkeypatch.delenv("HEXAPOD_KIN_DEBUG", raising=False)
    code = main(args)
    out, err = capsys.readouterr()
    _check(args, status, subprocess.CompletedProcess(args, code, out, err))


#: Rows also run as a user runs them, a child ``python -m hexapod_kin`` each: every status,
#: a refusal by argparse and one by the package, a command that imports MuJoCo.
PROCESS_ROWS = [
    ("list", ["--bogus"], 2),
    ("fk", ["hexabot_leg", "--q", "0", "0", "0"], 0),
    ("fk", ["hexabot_leg", "--q", "0"], 2),
    ("stand", ["--shift", "0.2", "0"], 1),
    (
        "timeline path",
        ["{tmp}/path.csv", "--calibration", "{tmp}/cal1.yaml", "-o", "{tmp}/p.csv"],
        1,
    ),
    ("simulate", ["--duration", "1", "--no-stand"], 0),
    ("simulate", ["--terrain", "mud"], 2),
]


@pytest.mark.parametrize(("cmd", "argv", "status"), PROCESS_ROWS, ids=lambda v: str(v))
def test_exit_status_of_the_process(folder: Path, cmd: str, argv: list[str], status: int) -> None:
    assert (cmd, argv, status) in ROWS
    args = _args(cmd, argv, folder)
    _check(args, status, _run(args, folder))


def test_interrupted_is_130(folder: Path) -> None:
    """Ctrl-C while a command serves: status 130 (the process ends by its own SIGINT)."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "hexapod_kin", "view", "hexabot_leg"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=folder,
    )
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline()  # the viewer's URL: the command is serving
        assert "meshcat viewer" in line, line
        time.sleep(0.5)
        proc.send_signal(signal.SIGINT)
        proc.wait(timeout=600)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode in (130, -signal.SIGINT)
    assert proc.stderr is not None and "interrupted" in proc.stderr.read()


# ------------------------------------------------------------------------ --help
#: One source of each kind that ``--help`` may offer (a preset, a table, a URDF, erd:NAME).
KIND_EXAMPLES = {
    "any": ["hexabot_leg", TABLE, URDF_LEG, "erd:ur5"],
    "table": ["hexabot_leg", TABLE],
    "legged": ["hexapod", URDF_HEXAPOD, "erd:solo12"],
}

#: A cheap command line per robot command, SOURCE where ``{src}`` is.
CHEAP = {
    "urdf": ["urdf", "{src}"],
    "fk": ["fk", "{src}"],
    "jacobian": ["jacobian", "{src}"],
    "derive": ["derive", "{src}", "--budget", "0.01"],
    "scan": ["scan", "{src}", "--grid", "3", "--families", "off", "--json"],
    "view": ["view", "{src}", "--no-wait"],
    "drive": ["drive", "{src}", "--no-open", "--serve-for", "0"],
    "animate": ["animate", "{src}", "--samples", "3", "--html", "{tmp}/a.html", "--json"],
    "ik": ["ik", "{src}", "--target", "0.1", "0.1", "0.1", "--restarts", "0"],
    "step": ["step", "{src}", "--duration", "0.01", "--no-baseline", "--json"],
    "torques": ["torques", "{src}", "--json"],
    "stand": ["stand", "{src}", "--json"],
    "xacro": ["xacro", "{src}"],
    "export-package": ["export-package", "{src}", "-o", "{tmp}/pkg", "-f", "--json"],
    "mjcf": ["mjcf", "{src}"],
    "gait": ["gait", "{src}", "--duration", "0.5", "--json"],
    "simulate": ["simulate", "{src}", "--duration", "0.5", "--no-stand", "--json"],
    "control": ["control", "{src}", "--duration", "0.5", "--json"],
    "timeline gait": ["timeline", "gait", "{src}", "--duration", "0.5", "-o", "{tmp}/t.csv"],
    "timeline step": ["timeline", "step", "{src}", "--duration", "0.05", "-o", "{tmp}/t.csv"],
    "timeline path": ["timeline", "path", "{tmp}/path.csv", "{src}", "-o", "{tmp}/t.csv"],
}


def _source_kind(cmd: str) -> str | None:
    """The kind a command's ``--help`` offers for SOURCE (None: it takes no robot)."""
    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    p = sub.choices[cmd.split()[0]]
    if " " in cmd:
        p = next(a for a in p._actions if a.dest == "plan").choices[cmd.split()[1]]
    action = next((a for a in p._actions if a.dest == "source"), None)
    if action is None:
        return None
    kinds = [k for k, text in SOURCE_KINDS.items() if (action.help or "").startswith(text)]
    assert len(kinds) == 1, (cmd, action.help)  # declared in one place: cli.common
    return kinds[0]


def test_every_robot_command_declares_its_source_in_one_place() -> None:
    taking = {cmd for cmd in _commands() if _source_kind(cmd) is not None}
    assert taking == set(CHEAP)


CASES = [
    (cmd, src)
    for cmd in sorted(CHEAP)
    for src in KIND_EXAMPLES[_source_kind(cmd) or "any"]
    if not (cmd in ("simulate", "control") and src != "hexapod")  # MuJoCo: one kind is enough
]


@pytest.mark.parametrize(("cmd", "src"), CASES, ids=lambda v: str(v).rsplit("/", 1)[-1])
def test_help_offers_nothing_that_is_refused(
    folder: Path, cmd: str, src: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """Each source kind ``--help`` names is taken: the answer comes (status 0 or 1)."""
    if cmd in ("simulate", "control"):
        pytest.importorskip("mujoco")
    argv = [a.replace("{src}", src).replace("{tmp}", str(folder)) for a in CHEAP[cmd]]
    if cmd == "timeline path":  # a plan for this robot: its own joints, at rest
        import hexapod_kin as hk

        plan = folder / f"path-{abs(hash(src))}.csv"
        names = hk.load(src).joint_names
        plan.write_text(
            "t," + ",".join(names) + "\n0" + ",0" * len(names) + "\n1" + ",0" * len(names) + "\n"
        )
        argv[2] = str(plan)
    status = main(argv)
    err = capsys.readouterr().err
    assert status in (0, 1), (argv, err)
