"""The README's promises: its first commands, .ci/run calling the same test command, and every
Python example running as written."""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

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


@pytest.mark.parametrize("index", range(len(BLOCKS)))
def test_readme_python_examples_run(index, tmp_path):
    os.symlink(ROOT / "examples", tmp_path / "examples")
    run = subprocess.run(
        [sys.executable, "-c", BLOCKS[index]],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stderr[-2000:]


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
def test_readme_command_line_runs(line, tmp_path):
    """Each command line of the README, as written, in a fresh folder: exit status 0.

    ``view`` serves until interrupted: it must come up (its address printed) and end with
    status 130 and one line on Ctrl-C.
    """
    import shlex
    import signal
    import time

    for name in ("examples", "tests"):
        os.symlink(ROOT / name, tmp_path / name)
    argv = [sys.executable, "-m", "hexapod_kin", *shlex.split(line)[1:]]
    env = dict(os.environ, MPLBACKEND="Agg")
    if argv[3] == "view":
        proc = subprocess.Popen(
            argv, cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env
        )
        deadline = time.monotonic() + 60
        out = ""
        while time.monotonic() < deadline and "127.0.0.1" not in out:
            out += proc.stdout.readline()
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=30)
        assert "127.0.0.1" in out, (out, err)
        assert proc.returncode in (130, -signal.SIGINT), err  # a shell reports both as 130
        assert err.strip().splitlines()[-1] == "hexapod-kin: interrupted", err
        return
    run = subprocess.run(argv, cwd=tmp_path, capture_output=True, text=True, timeout=300, env=env)
    assert run.returncode == 0, (line, run.stdout[-1000:], run.stderr[-2000:])
