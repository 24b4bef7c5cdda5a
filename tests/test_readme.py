"""The README's promises: its first commands, .ci/run calling the same test command, and every
Python example running as written."""

from __future__ import annotations

import ast
import json
import math
import os
import re
import shlex
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
README = (ROOT / "README.md").read_text()
BLOCKS = re.findall(r"```python\n(.*?)```", README, re.S)


def test_readme_first_block_and_ci_agree():
    block = README.split("```bash\n", 1)[1].split("```", 1)[0].strip().splitlines()
    assert len(block) == 2
    demo, tests = block
    assert "'.[viewer,plots]'" in demo and demo.endswith("hexapod-kin reproduce --out report")
    assert "pytest" in tests
    ci = (ROOT / ".ci" / "run").read_text().splitlines()
    assert tests in ci


#: Runs a README block statement by statement (as the interpreter would) and prints, as one
#: JSON object, the value of every expression statement that carries a comment, keyed by its
#: source text: the README's commented values are then checked against what the code gives.
_SHOW = r"""
import ast, json, sys

import numpy as np

src = sys.stdin.read()
lines = src.splitlines()
ns, shown = {"__name__": "__main__"}, {}

def plain(v):
    if isinstance(v, np.ndarray):
        return v.tolist()
    if isinstance(v, (np.floating, np.integer, np.bool_)):
        return v.item()
    if isinstance(v, (list, tuple)):
        return [plain(x) for x in v]
    if isinstance(v, dict):
        return {str(k): plain(x) for k, x in v.items()}
    if isinstance(v, (bool, int, float, str)) or v is None:
        return v
    return str(v)  # sympy expressions: their printed form

for node in ast.parse(src).body:
    text = ast.get_source_segment(src, node)
    if isinstance(node, ast.Expr) and "#" in lines[node.end_lineno - 1][node.end_col_offset:]:
        shown[text] = plain(eval(compile(ast.Expression(node.value), "<readme>", "eval"), ns))
    else:
        exec(compile(ast.Module([node], []), "<readme>", "exec"), ns)
print(json.dumps(shown, allow_nan=False))
"""


def _comment(expression: str) -> str:
    """The README's comment after ``expression`` (the value it promises)."""
    for line in README.splitlines():
        code, _, comment = line.partition("  #")
        if code.strip() == expression:
            return comment.strip()
    raise AssertionError(f"no commented line {expression!r} in the README")


def _magnitudes(comment: str) -> list[float]:
    """The ``~1e-29``-style values of a comment, in order."""
    return [float(v) for v in re.findall(r"~\s*([0-9.]+e[+-]?\d+)", comment)]


def _same_magnitude(value: float, stated: float) -> bool:
    """``value`` is ``~stated``: the same sign and within a factor of 10."""
    return value * stated > 0 and abs(math.log10(abs(value) / abs(stated))) <= 1.0


def _check_tour(shown: dict[str, Any]) -> None:
    # the foot of the seeds' leg by hand: r = l1 + l2 cos q2 + l3 cos(q2 + q3) from the hip axis
    q1, q2, q3 = 0.1, 0.4, -0.8
    r = 0.05 + 0.1 * math.cos(q2) + 0.1 * math.cos(q2 + q3)
    z = 0.1 * math.sin(q2) + 0.1 * math.sin(q2 + q3)
    pose = np.asarray(shown["model.fk(q)"])
    assert pose.shape == (4, 4) and pose[3] == pytest.approx([0, 0, 0, 1])
    assert pose[:3, 3] == pytest.approx([r * math.cos(q1), r * math.sin(q1), z])  # z = 0 here
    transforms = np.asarray(shown["model.transforms(q)"])
    assert transforms.shape == (4, 4, 4)  # ^0T_1 .. ^3T_4, whose product is the foot's pose
    assert np.linalg.multi_dot(list(transforms)) == pytest.approx(pose, abs=1e-12)
    assert np.asarray(shown['model.jacobian(q, "local_world_aligned")']).shape == (6, 3)
    expr = "model.fk_batch(qs).shape, model.jacobian_batch(qs).shape"
    stated = ast.literal_eval("(" + _comment(expr).split(":")[0] + ")")
    assert [tuple(s) for s in shown[expr]] == list(stated)


def _check_symbolic(shown: dict[str, Any]) -> None:
    import sympy

    det = shown["d.det"]
    assert sympy.simplify(sympy.sympify(det) - sympy.sympify(_comment("d.det"))) == 0
    names = shown["[f.name for f in d.families]"]
    # the README's shorthand leaves out the period the names carry
    short = [name.removesuffix(" (mod 2*pi)") for name in names]
    assert short == _comment("[f.name for f in d.families]").split(", ")
    assert shown["d.methods_agree"] is True
    counts = shown["res.family_counts"]
    assert set(counts) <= set(names) and sum(counts.values()) > 0


def _check_seeds(shown: dict[str, Any]) -> None:
    expr = "run.drift_y, run.drift_z, run.error_x"
    stated = _magnitudes(_comment(expr))
    assert len(stated) == 3
    for name, value, want in zip(expr.split(", "), shown[expr], stated):
        assert _same_magnitude(value, want), (name, value, want)
    (want,) = _magnitudes(_comment('run.baseline["drift_z"]'))
    assert _same_magnitude(shown['run.baseline["drift_z"]'], want)
    expr = "ik.analytic(robots.coxa_tibia_leg(), [14.3301, 0, -2.5], tol=1e-5)[0]"
    solutions = np.atleast_2d(shown[expr])  # every branch found, (q1, q2) each
    assert "θ2 = -30°" in _comment(expr)
    assert len(solutions) >= 1
    assert np.degrees(solutions[:, 1]) == pytest.approx(-30.0, abs=1e-3)


def _check_stance(shown: dict[str, Any]) -> None:
    import hexapod_kin as hk

    forces = np.asarray(shown["stance.forces[:, 2]"])
    # the URDF's masses, the body's (fixed to the universe here) included: 1.96 kg
    weight = sum(inertia.mass for inertia in hk.load("hexapod").model.inertias) * 9.81
    assert forces.shape == (6,) and np.all(forces > 0)  # six feet share the weight
    assert forces.sum() == pytest.approx(weight, rel=1e-3)
    assert "> 0" in _comment("float(walk.margin.min())")
    assert shown["float(walk.margin.min())"] > 0


def _check_legged(shown: dict[str, Any]) -> None:
    assert shown["run.ok, run.min_margin > 0, run.max_slip < 1e-9"] == [True, True, True]


#: Each Python block's values, checked against the README's comments (by the block's index).
CHECKS = [_check_tour, _check_symbolic, _check_seeds, _check_stance, _check_legged]


@pytest.mark.slow
@pytest.mark.parametrize("index", range(len(BLOCKS)))
def test_readme_python_examples_run(index, tmp_path):
    """Each Python block runs as written, and every value its comments state is what it gives."""
    os.symlink(ROOT / "examples", tmp_path / "examples")
    run = subprocess.run(
        [sys.executable, "-c", _SHOW],
        input=BLOCKS[index],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stderr[-2000:]
    shown = json.loads(run.stdout.strip().splitlines()[-1])
    assert len(CHECKS) == len(BLOCKS), "a README block without its check: add one to CHECKS"
    CHECKS[index](shown)


def _command_lines() -> list[str]:
    """Every ``hexapod-kin ...`` line of the README's bash blocks (comments stripped)."""
    lines = []
    for block in re.findall(r"```bash\n(.*?)```", README, re.S):
        for line in block.splitlines():
            line = shlex.join(shlex.split(line, comments=True))  # as bash reads it
            if line.startswith("hexapod-kin "):
                lines.append(line)
    return lines


COMMAND_LINES = _command_lines()


def test_readme_has_command_lines():
    assert len(COMMAND_LINES) >= 15


@pytest.mark.parametrize(
    "line", COMMAND_LINES, ids=[ln.split()[1] + str(i) for i, ln in enumerate(COMMAND_LINES)]
)
@pytest.mark.slow
def test_readme_command_line_runs(
    line: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Each command line of the README, as written, in a fresh folder: exit status 0.

    The first line and ``view`` run as a user runs them (a child ``python -m hexapod_kin``);
    the others through the same entry, ``main(argv)``, in this process. ``view`` serves
    until interrupted: it must come up (its address printed) and end with status 130 and one
    line on Ctrl-C.
    """
    import shlex
    import signal
    import time

    from hexapod_kin.cli import main

    for name in ("examples", "tests"):
        os.symlink(ROOT / name, tmp_path / name)
    argv = [sys.executable, "-m", "hexapod_kin", *shlex.split(line)[1:]]
    env = dict(os.environ, MPLBACKEND="Agg")
    if argv[3] == "view":
        proc = subprocess.Popen(
            argv, cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env
        )
        deadline = time.monotonic() + 600  # guards a hang only (never a speed): generous
        out = ""
        while time.monotonic() < deadline and "127.0.0.1" not in out:
            out += proc.stdout.readline()
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=600)
        assert "127.0.0.1" in out, (out, err)
        assert proc.returncode in (130, -signal.SIGINT), err  # a shell reports both as 130
        assert err.strip().splitlines()[-1] == "hexapod-kin: interrupted", err
        return
    if line == COMMAND_LINES[0]:
        run = subprocess.run(
            argv, cwd=tmp_path, capture_output=True, text=True, timeout=300, env=env
        )
        assert run.returncode == 0, (line, run.stdout[-1000:], run.stderr[-2000:])
        return
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    status = main(argv[3:])
    out, err = capsys.readouterr()
    assert status == 0, (line, out[-1000:], err[-2000:])


@pytest.mark.slow  # a fresh-cache reproduce, ~8 s; the same line runs (status 0) in the default run
def test_readme_first_command_prints_what_the_readme_shows(tmp_path):
    """The first line's ``reproduce --out report`` prints the README's two lines: where the
    report is, and the verdict counts (58 claims: 35 agree, 20 seed is wrong, ...)."""
    shown = README.split("```\nreport: ", 1)[1].split("```", 1)[0]
    where, verdicts = ("report: " + shown).splitlines()[:2]
    env = dict(os.environ, MPLBACKEND="Agg", HEXAPOD_KIN_CACHE_DIR=str(tmp_path / "cache"))
    run = subprocess.run(
        [sys.executable, "-m", "hexapod_kin", "reproduce", "--out", "report"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=600,
        env=env,
    )
    assert run.returncode == 0, run.stderr[-2000:]
    lines = run.stdout.splitlines()
    assert lines[0] == where
    pattern = re.escape(verdicts).replace(re.escape("<seconds>"), r"[0-9.]+")
    assert re.fullmatch(pattern, lines[1]), (lines[1], verdicts)
    first = README.split("```\nreport: ", 1)[1].splitlines()[2].strip()
    # the README's sample verdict line is one of those printed (its ending cut at "...")
    sample = first.removesuffix("...").rstrip()
    assert any(line.strip().startswith(sample) for line in lines[2:]), (sample, lines[2:])
