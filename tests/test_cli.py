"""The hexapod-kin command line (in process and as the installed console script)."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys

import numpy as np
import pytest

import hexapod_kin as hk
from hexapod_kin.cli import main


def run(capsys, *argv):
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err


def test_list(capsys):
    code, out, _ = run(capsys, "list", "--json")
    assert code == 0
    names = [p["name"] for p in json.loads(out)["presets"]]
    assert names == hk.robots.names()


def test_fk_json_matches_api(capsys):
    code, out, _ = run(capsys, "fk", "hexabot_leg", "--q", "10", "20", "-30", "--deg", "--json")
    assert code == 0
    obj = json.loads(out)
    q = np.radians([10, 20, -30])
    np.testing.assert_allclose(obj["T_tip"], hk.table_fk(hk.robots.hexabot_leg(), q), atol=1e-12)
    assert len(obj["transforms"]) == 4 and obj["joint_names"] == ["hip", "knee", "ankle"]


def test_fk_text_prints_every_transform(capsys):
    code, out, _ = run(
        capsys,
        "fk",
        "coxa_tibia_leg",
        "--set",
        "l1=10",
        "--set",
        "l2=5",
        "--q",
        "0",
        "-30",
        "--deg",
    )
    assert code == 0
    assert "^0T_1" in out and "^2T_3" in out and "14.330127" in out and "-2.500000" in out


def test_jacobian_json(capsys):
    code, out, _ = run(
        capsys,
        "jacobian",
        "scara",
        "--q",
        "0.1",
        "0.2",
        "0.3",
        "0.05",
        "--reference",
        "world",
        "--json",
    )
    assert code == 0
    obj = json.loads(out)
    model = hk.load("scara")
    np.testing.assert_allclose(obj["jacobian"], model.jacobian([0.1, 0.2, 0.3, 0.05], "world"))


def test_jacobian_erd_leg(capsys):
    code, out, _ = run(
        capsys, "jacobian", "erd:solo12", "--tip", "FL_FOOT", "--q", "0", "0.5", "-1", "--json"
    )
    assert code == 0 and len(json.loads(out)["jacobian"][0]) == 3


def test_urdf_export_atomic(tmp_path, capsys):
    dest = tmp_path / "leg.urdf"
    code, _, err = run(capsys, "urdf", "hexabot_leg", "--set", "l1=0.06", "-o", str(dest))
    assert code == 0 and "wrote" in err
    text = dest.read_text()
    assert "made by: hexapod-kin urdf hexabot_leg -s l1=0.06" in text
    model = hk.load(dest)
    np.testing.assert_allclose(model.fk([0, 0, 0])[:3, 3], [0.26, 0, 0], atol=1e-15)


@pytest.mark.parametrize(
    "argv,fragment",
    [
        (["fk", "nope"], "presets are"),
        (["fk", "hexabot_leg", "--q", "1", "2"], "has 3 joints"),
        (["fk", "hexabot_leg", "--tip", "toe"], "frames are"),
        (["urdf", "hexabot_leg", "--set", "l1"], "NAME=VALUE"),
        (["urdf", "hexabot_leg", "--set", "l1=-2"], "l1=-2"),
        (["fk", "erd:nope"], "example-robot-data has"),
        (["fk", ""], "is empty"),
    ],
)
def test_errors_are_one_line_and_exit_2(capsys, argv, fragment):
    code, out, err = run(capsys, *argv)
    assert code == 2 and out == ""
    assert err.startswith("hexapod-kin: error:") and fragment in err


def test_console_script_demo(tmp_path):
    exe = shutil.which("hexapod-kin") or str(
        __import__("pathlib").Path(sys.executable).with_name("hexapod-kin")
    )
    res = subprocess.run([exe, "demo", "--out", str(tmp_path)], capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    assert (tmp_path / "hexabot_leg.urdf").exists() and "det(J_position)" in res.stdout
