"""The size rule: command-line-sized work never imports numba (Pinocchio and numpy only).

Each command runs in a fresh interpreter through ``hexapod_kin.cli.main``; afterwards
``numba`` must not be in ``sys.modules`` (importing it costs 0.3–0.7 s). Batch APIs and the
one IK loop (``ik.solve``; ``ik`` when the closed form does not answer) are the only users of
the compiled layer (:mod:`hexapod_kin._kernels`).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent

COMMANDS = [
    ["fk", "hexabot_leg", "--q", "0.1", "0.2", "0.3"],
    ["jacobian", "hexabot_leg", "--q", "0.1", "0.2", "0.3"],
    ["ik", "hexabot_leg", "--target", "0.15", "0.05", "-0.05"],
    ["scan", "hexabot_leg"],
    ["step", "hexabot_leg", "--duration", "1"],
    ["gait", "--duration", "2"],
    ["stand"],
    ["simulate", "hexapod", "--duration", "1", "--no-stand"],
    ["derive", "hexabot_leg"],
]

_CHILD = """
import sys
from hexapod_kin.cli import main
rc = main(sys.argv[1:])
assert rc == 0, rc
loaded = sorted(m for m in ("numba", "llvmlite") if m in sys.modules)
assert not loaded, f"imported {loaded}"
"""


@pytest.mark.slow
@pytest.mark.parametrize("argv", COMMANDS, ids=lambda a: a[0])
def test_command_line_work_does_not_import_numba(argv: list[str], tmp_path: Path) -> None:
    env = dict(os.environ, PYTHONPATH=str(ROOT), HEXAPOD_KIN_CACHE_DIR=str(tmp_path))
    out = subprocess.run(
        [sys.executable, "-c", _CHILD, *argv], env=env, capture_output=True, text=True
    )
    assert out.returncode == 0, out.stderr[-2000:]


def test_per_call_kinematics_does_not_import_numba() -> None:
    code = (
        "import sys, hexapod_kin as hk\n"
        "m = hk.load('hexabot_leg'); q = [0.1, 0.2, 0.3]\n"
        "m.fk(q); m.jacobian(q, 'local'); m.fk_jacobian(q); m.frame_placements(q)\n"
        "m.transforms(q); m.position_jacobian(q)\n"
        "import hexapod_kin._numerics\n"
        "assert 'numba' not in sys.modules\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], env=dict(os.environ, PYTHONPATH=str(ROOT)),
        capture_output=True, text=True,
    )  # fmt: skip
    assert out.returncode == 0, out.stderr[-2000:]
