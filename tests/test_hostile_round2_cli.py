"""Issue 35, round 2 of the reliability probe: the cases still failing in session 4.

Each case runs the command line's entry ``main(argv)`` in this process
(``test_hostile_cli.here``: CPU time by ``getrusage``, peak memory by the rise of the resident
set); the Ctrl-C case is a child. A refusal is exit 2 and one line
``hexapod-kin: error: ...`` naming the file or the parameter, within a second of CPU beyond
the command's own start (its imports and the robot's load, measured by a refusal of the
same command that stops before any work) and 1 GB, with no catch-all nor traceback.

* Servo calibrations whose map leaves the joint's range outside the servo's: refused before
  the walk is planned (was 9 s of CPU), naming the key (``limits``, ``resolution``); a speed
  limit of 1e-320 rad/s refused.
* Path files with a 1e308 rad sample: no JSON/CSV/ROS 2 file is written; a 1e300 rad path
  (finite) is no servo's command either; a JSON plan's numbers written as texts or booleans,
  names that are numbers and unknown keys are refused (they were converted or ignored).
* Feet files: a number written as text or a boolean, an entry with a misspelt key (its offset
  silently 0), a frame that is not a text; ``control --foot`` honoured (it was ignored).
* Command timelines of ``control``: numbers only, a pattern that is a text, the file named.
* Bounded work: ``animate --samples 1e9`` (was 12 GB), ``ik --target 1e308`` (3 overflow
  warnings and ``inf``) and ``ik --target 1000 0 0`` for a 25 cm leg.
* Pages of the robot given: ``gait ../robots/hexapod.urdf --html`` writes the same page in
  a folder holding another ``hexapod.urdf`` as anywhere else.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from test_hostile_cli import PHANTOMX, SIDES35, Run, _clean_phantomx, _feet_args, here, refused

#: CPU a refusal may take beyond the same command's start [s] (the issue's "under a second").
REFUSAL_S = 1.0
PLAN = "t,j1,j2\n0,0,0\n0.5,0.2,0.1\n1,0.4,0.2\n"


def _start_cpu(args: list[str], cwd: Path) -> float:
    """CPU [s] of ``args`` refused at once (an unknown pattern: after imports and the load)."""
    run = here(*args, cwd=cwd)
    assert run.status == 2, run.stderr
    return run.cpu


def fast_refusal(run: Run, phrase: str, start: float = 0.0) -> str:
    line = refused(run, phrase)
    assert run.cpu < start + REFUSAL_S, f"{run.cpu:.2f} s CPU (start {start:.2f} s): {line}"
    return line


# ------------------------------------------------------------------ calibrations for a robot
ROBOT_CALIBRATIONS = {
    # centre 5000 us: the joint's [-2.6, 2.6] rad maps to [3691, 6309] us, outside [500, 2500]
    "centre": (
        "defaults: {units: us, us_per_rad: 500, centre: 5000, limits: [500, 2500]}\n",
        "limits [500.0, 2500.0] us reach the joint only at",
    ),
    # 3000 us steps: the commands are 0 or 3000 us, none within the servo's [1000, 2000]
    "resolution": (
        "defaults: {units: us, us_per_rad: 500, centre: 1500, limits: [1000, 2000], "
        "resolution: 3000}\n",
        "resolution 3000 us has no step within [1000, 2000] us",
    ),
    # 1e6 us/rad (per degree?): the servo's [500, 2500] sweeps 0.002 rad of the joint's 5.2
    "us_per_rad": (
        "defaults: {units: us, us_per_rad: 1e6, centre: 1500, limits: [500, 2500]}\n",
        "us_per_rad 1000000.0 lets the servo's limits [500.0, 2500.0] us sweep only 0.002 of",
    ),
}


@pytest.mark.parametrize("key", sorted(ROBOT_CALIBRATIONS))
def test_calibration_refused_before_the_walk(tmp_path: Path, key: str) -> None:
    text, phrase = ROBOT_CALIBRATIONS[key]
    urdf = _clean_phantomx(tmp_path)
    (tmp_path / "cal.yaml").write_text(text)
    args = ["timeline", "gait", str(urdf), *_feet_args(), "-o", "out.csv"]
    start = _start_cpu([*args, "--pattern", "no-such-pattern"], tmp_path)
    run = here(*args, "--calibration", "cal.yaml", cwd=tmp_path)
    line = fast_refusal(run, phrase, start)
    assert "cal.yaml': calibration of j_c1_lf: " in line, line
    assert not (tmp_path / "out.csv").exists()


def test_calibration_speed_limit_of_1e_320_refused(tmp_path: Path) -> None:
    (tmp_path / "plan.csv").write_text(PLAN)
    (tmp_path / "cal.yaml").write_text("defaults: {units: rad, velocity_limit: 1e-320}\n")
    run = here(
        "timeline", "path", "plan.csv", "--calibration", "cal.yaml", "-o", "o.csv", cwd=tmp_path
    )
    fast_refusal(run, "velocity_limit 1e-320 rad/s is not a servo's speed")
    assert not (tmp_path / "o.csv").exists()


@pytest.mark.parametrize(
    "entry, phrase",
    [
        # scale 5e-324 / 2 pi = 0: a ZeroDivisionError, the catch-all's "(a bug ...)"
        ("{units: ticks, ticks_per_revolution: 5e-324}", "need ticks_per_revolution >= 1"),
        ("{units: us, us_per_rad: 1e-300, centre: 1500}", "need us_per_rad >= 1"),
    ],
    ids=["ticks-5e-324", "us-1e-300"],
)
def test_calibration_scale_of_nothing_refused(tmp_path: Path, entry: str, phrase: str) -> None:
    (tmp_path / "plan.csv").write_text(PLAN)
    (tmp_path / "cal.yaml").write_text(f"defaults: {entry}\n")
    args = ("timeline", "path", "plan.csv", "--calibration", "cal.yaml", "-o", "o.csv")
    fast_refusal(here(*args, cwd=tmp_path), phrase)


def test_path_of_1e300_rad_is_no_servo_command(tmp_path: Path) -> None:
    """No robot, no calibration (rad, unlimited): a finite 1e300 rad is still not sent."""
    (tmp_path / "plan.csv").write_text("t,j1\n0,0\n1,1e300\n")
    run = here("timeline", "path", "plan.csv", "-o", "o.json", cwd=tmp_path)
    fast_refusal(run, "beyond ±1e+09 (no servo's)")
    assert not (tmp_path / "o.json").exists()


@pytest.mark.parametrize("out", ["o.json", "o.csv", "o.yaml"])
def test_path_with_a_1e308_sample_writes_nothing(tmp_path: Path, out: str) -> None:
    (tmp_path / "plan.csv").write_text("t,j1\n0,0\n0.5,1e308\n1,0\n")
    run = here("timeline", "path", "plan.csv", "-o", out, cwd=tmp_path)
    fast_refusal(run, "joint j1 at t=0.0000 s: ")
    assert not (tmp_path / out).exists()


PLAN_FILES = {
    "text-number": ('{"t": [0, 1], "q": [[0], ["0.5"]]}', "q[1][0]='0.5' is not a finite number"),
    "boolean": ('{"t": [0, true], "q": [[0], [0.5]]}', "t[1]=True is not a finite number"),
    "name-number": (
        '{"t": [0, 1], "q": [[0], [0.5]], "joint_names": [5]}',
        "joint_names[0]=5 must be a string",
    ),
    "unknown-key": ('{"t": [0, 1], "q": [[0], [0.5]], "qq": 1}', "unknown key 'qq'"),
}


@pytest.mark.parametrize("case", sorted(PLAN_FILES))
def test_plan_file_values_are_checked(tmp_path: Path, case: str) -> None:
    text, phrase = PLAN_FILES[case]
    (tmp_path / "p.json").write_text(text)
    line = fast_refusal(here("timeline", "path", "p.json", "-o", "o.csv", cwd=tmp_path), phrase)
    assert "plan='p.json'" in line, line
    assert not (tmp_path / "o.csv").exists()


# ------------------------------------------------------------------------------ feet files
FEET_FILES = {
    "text-number": ("tibia_lf: ['0', 0, 0]\n", "offset[0]='0' is not a finite number"),
    "boolean": ("tibia_lf: [true, 0, 0]\n", "offset[0]=True is not a finite number"),
    "misspelt-key": (
        "feet: [{frame: tibia_lf, offst: [0, 0.16, 0.029]}]\n",
        "unknown key 'offst'",
    ),
    "frame-not-text": ("feet: [{frame: 5, offset: [0, 0, 0]}]\n", "frame=5 must be a string"),
}


@pytest.mark.parametrize("command", ["stand", "gait", "simulate", "control"])
@pytest.mark.parametrize("case", sorted(FEET_FILES))
def test_feet_file_values_are_checked(tmp_path: Path, command: str, case: str) -> None:
    text, phrase = FEET_FILES[case]
    urdf = _clean_phantomx(tmp_path)
    (tmp_path / "feet.yaml").write_text(text)
    run = here(command, str(urdf), "--foot", "feet.yaml", cwd=tmp_path)
    line = fast_refusal(run, phrase)
    assert "feet='feet.yaml'" in line, line


def test_control_honours_the_feet(tmp_path: Path) -> None:
    """``control --foot`` was ignored ('no foot link'): a foot beyond the robot is refused."""
    urdf = _clean_phantomx(tmp_path)
    run = here("control", str(urdf), *_feet_args(lf="1000,0,0"), cwd=tmp_path)
    fast_refusal(run, "foot tibia_lf: offset 1000,0,0 m is larger than the robot")


# ---------------------------------------------------------------- control command timelines
COMMANDS = {
    "text-number": ('{"commands": [{"t": 0, "vx": "0.1"}]}', "vx='0.1' is not a finite number"),
    "boolean": ('{"commands": [{"t": 0, "vx": true}]}', "vx=True is not a finite number"),
    "text-time": ('{"commands": [{"t": "0", "vx": 0.1}]}', "t='0' is not a finite number"),
    "pattern-number": ('{"commands": [{"t": 0, "pattern": 5}]}', "pattern=5 must be a string"),
    "infinite": ('{"commands": [{"t": 0, "vx": Infinity}]}', "vx=inf is not a finite number"),
    "huge-speed": ('{"commands": [{"t": 0, "vx": 1e308}]}', "vx=1e+308 m/s: at most 10 m/s"),
    "huge-yaw": ('{"commands": [{"t": 0, "wz": -11}]}', "wz=-11 rad/s: at most 10 rad/s"),
}


@pytest.mark.parametrize("case", sorted(COMMANDS))
def test_command_timeline_values_are_checked(tmp_path: Path, case: str) -> None:
    text, phrase = COMMANDS[case]
    (tmp_path / "c.json").write_text(text)
    run = here("control", "--command", "c.json", "--duration", "0.5", cwd=tmp_path)
    if case == "infinite" and "Infinity" in run.stderr:  # the strict JSON reader's own words
        phrase = "Infinity"
    line = fast_refusal(run, phrase)
    assert "'c.json'" in line, line


# ------------------------------------------------------------------------------ bounded work
@pytest.mark.parametrize(
    "args, phrase",
    [
        (["animate", "hexabot_leg", "--samples", "1000000000"], "samples=1000000000"),
        (["ik", "hexabot_leg", "--target", "1e308", "0", "0"], "larger than the robot"),
        (["ik", "hexabot_leg", "--target", "1000", "0", "0"], "larger than the robot"),
        (["ik", "hexabot_leg", "--pose", "0", "1e300", "0", "0", "0", "0"], "larger than"),
    ],
    ids=["animate-samples", "ik-1e308", "ik-1km", "ik-pose-1e300"],
)
def test_work_beyond_reason_refused_at_once(tmp_path: Path, args: list[str], phrase: str) -> None:
    fast_refusal(here(*args, cwd=tmp_path), phrase)


def test_an_unreachable_target_is_still_answered(tmp_path: Path) -> None:
    """1 m for a 25 cm leg: beyond its reach but not beyond reason (exit 1, nearest point)."""
    run = here("ik", "hexabot_leg", "--target", "1", "0", "0", cwd=tmp_path)
    assert run.status == 1 and run.stderr == "", run.stderr
    assert "nearest reachable point" in run.stdout


# ------------------------------------------------------------------- the page of the robot given
def test_page_of_the_robot_given_not_of_a_namesake(tmp_path: Path) -> None:
    robots, ours, there = tmp_path / "robots", tmp_path / "here", tmp_path / "there"
    for folder in (robots, ours, there):
        folder.mkdir()
    made = here("urdf", "hexapod", "-o", str(robots / "hexapod.urdf"), cwd=tmp_path)
    assert made.status == 0, made.stderr
    shutil.copy(PHANTOMX, ours / "hexapod.urdf")  # another robot of the same file name
    pages = []
    for cwd in (ours, there):
        run = here("gait", "../robots/hexapod.urdf", "--duration", "1", "--html", "p.html", cwd=cwd)
        assert run.status == 0 and run.lines == ["wrote p.html"], run.stderr
        pages.append((cwd / "p.html").read_bytes())
    assert pages[0] == pages[1]
    assert b"tibia_lf" not in pages[0] and len(SIDES35) == 6


# ------------------------------------------------------------ Ctrl-C ignored by its starter
def test_a_command_started_with_ctrl_c_ignored_keeps_ignoring_it(tmp_path: Path) -> None:
    """A script's ``cmd &`` starts it with SIGINT ignored: a Ctrl-C meant for the script
    must not stop it half-way (the command line used to install its own handler over it)."""
    import os
    import signal
    import subprocess
    import sys
    import time

    from test_hostile_cli import _PEAK, _cap, _env, _finish

    def ignoring() -> None:  # pragma: no cover - runs in the child
        _cap()
        signal.signal(signal.SIGINT, signal.SIG_IGN)

    argv = [sys.executable, "-c", _PEAK, str(tmp_path / ".peak"), "urdf", "hexapod", "-o", "h.urdf"]
    out, err = tmp_path / ".stdout", tmp_path / ".stderr"
    with open(out, "wb") as o, open(err, "wb") as e:
        t0 = time.monotonic()
        proc = subprocess.Popen(
            argv, cwd=tmp_path, stdout=o, stderr=e, env=_env(), preexec_fn=ignoring
        )
        for _ in range(20):  # Ctrl-C after Ctrl-C, through its start and its work (a
            time.sleep(0.05)  # finished child is a zombie until _finish reaps it)
            os.kill(proc.pid, signal.SIGINT)
        run = _finish(proc, t0, 120.0, out, err)
    assert run.status == 0 and "interrupted" not in run.stderr, (run.status, run.stderr)
    assert (tmp_path / "h.urdf").stat().st_size > 1000
