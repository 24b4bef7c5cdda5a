"""Ctrl-C ends every long command with one line and exit status 130, leaving no partial file.

SIGINT is sent at random times (from just after Python's own start-up, whose handling is the
interpreter's, to the end of the work) to commands that run longer than a second. Each try
must end either interrupted (status 130, the one line ``hexapod-kin: interrupted``, no
traceback, no temporary or half-written file) or, when the signal came after the work was
done, as a normal success.
"""

from __future__ import annotations

import random
import signal
import subprocess
import sys
import time
from pathlib import Path
from xml.etree import ElementTree

import pytest

TRIES = 5

COMMANDS = {
    "gait": ["gait", "--duration", "10", "--json"],
    "mjcf": ["mjcf", "hexapod", "--meshes", "-o", "{out}/robot.xml"],
    "export-package": ["export-package", "hexabot_leg", "-o", "{out}/pkg", "-f"],
    "reproduce": ["reproduce", "--quick", "--no-animations", "--out", "{out}/report"],
}


def _no_partial_files(out: Path) -> None:
    leftovers = [p for p in out.rglob("*") if p.name.endswith(".tmp") or p.name.startswith(".")]
    assert not leftovers, leftovers
    for xml in out.rglob("*.xml"):
        ElementTree.parse(xml)  # every file written is whole (atomic writes)


@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_ctrl_c(tmp_path: Path, name: str) -> None:
    rng = random.Random(name)
    for attempt in range(TRIES):
        out = tmp_path / f"try{attempt}"
        out.mkdir()
        argv = [a.replace("{out}", str(out)) for a in COMMANDS[name]]
        proc = subprocess.Popen(
            [sys.executable, "-m", "hexapod_kin", *argv],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
        )
        time.sleep(rng.uniform(0.3, 1.5))  # after Python's own start-up (its own handling)
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=60)
        assert "Traceback" not in err, err
        if proc.returncode in (130, -signal.SIGINT):  # a shell reports both as 130
            assert err.strip().splitlines()[-1] == "hexapod-kin: interrupted", err
            assert len(err.strip().splitlines()) <= 2, err  # a notice line may precede it
        else:
            assert proc.returncode == 0, (proc.returncode, err)  # done before the signal
        _no_partial_files(out)
