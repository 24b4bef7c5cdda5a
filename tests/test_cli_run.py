"""``python -m hexapod_kin`` as a whole process: the output is whole, the exit status kept."""

from __future__ import annotations

import os
import subprocess
import sys

from hexapod_kin.cli import main


def _cli(args: list[str], tmp_path) -> subprocess.CompletedProcess:
    env = dict(os.environ, HEXAPOD_KIN_CACHE_DIR=str(tmp_path / "hk"))
    return subprocess.run(
        [sys.executable, "-m", "hexapod_kin", *args],
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )


def test_output_is_whole_and_the_same_as_in_process(tmp_path, capsys):
    args = ["fk", "hexabot_leg", "--q", "0", "0.5", "-1"]
    assert main(args) == 0
    expected = capsys.readouterr().out
    res = _cli(args, tmp_path)
    assert res.returncode == 0 and res.stdout == expected and len(expected) > 200


def test_error_status_is_kept(tmp_path):
    res = _cli(["fk", "no_such_robot"], tmp_path)
    assert res.returncode == 2
    assert res.stderr.count("\n") == 1 and "no_such_robot" in res.stderr
