"""``hexapod-kin``'s fast exit (``cli.run``): the output is whole, the status kept, and the
``atexit`` work (the tier ledger) done, though the interpreter is not torn down."""

from __future__ import annotations

import os
import subprocess
import sys

from hexapod_kin.cli import main


def _cli(args: list[str], tmp_path, **env: str) -> subprocess.CompletedProcess:
    full = dict(os.environ, HEXAPOD_KIN_CACHE_DIR=str(tmp_path / "hk"), **env)
    full["NUMBA_CACHE_DIR"] = str(tmp_path / "numba")
    return subprocess.run(
        [sys.executable, "-m", "hexapod_kin", *args],
        env=full,
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


def test_atexit_work_is_done(tmp_path):
    """The tier ledger (written by an atexit handler) holds the interpreted seconds."""
    res = _cli(["ik", "hexabot_leg", "--target", "0.25", "0.05", "-0.1"], tmp_path)
    assert res.returncode == 0, res.stderr
    ledgers = list((tmp_path / "hk" / "tier").glob("interpreted-seconds-*.json"))
    assert ledgers and ledgers[0].stat().st_size > 2
