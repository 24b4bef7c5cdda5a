"""The hexapod-kin command line (in process and as the installed console script)."""

from __future__ import annotations

import json
import re
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
    assert "det(J_position)" in res.stdout
    # the demo's URDF is the seeds' leg: the same foot as the preset's, by FK
    import numpy as np

    import hexapod_kin as hk

    written, preset = hk.load(str(tmp_path / "hexabot_leg.urdf")), hk.load("hexabot_leg")
    for q in preset.random_q(5, seed=4):
        np.testing.assert_allclose(written.fk(q), preset.fk(q), atol=1e-12)


# --------------------------------------------------------------------- one robot argument
def test_one_message_per_misuse_of_set(capsys):
    """-s given for a source that takes no parameters: the same one line from every command."""
    said = set()
    for argv in (
        ["fk", "erd:solo12"],
        ["mjcf", "erd:solo12"],
        ["stand", "erd:solo12"],
        ["gait", "erd:solo12"],
        ["simulate", "erd:solo12"],
        ["timeline", "gait", "erd:solo12", "-o", "x.csv"],
    ):
        assert main([*argv, "-s", "l1=0.05"]) == 2, argv
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1, err
        said.add(err[0])
    assert len(said) == 1, said
    assert "non-preset 'erd:solo12'" in said.pop()


def test_foot_is_appended_on_every_legged_command():
    """--foot given once per leg reaches the robot whole (simulate kept only the last one)."""
    from hexapod_kin.cli import build_parser
    from hexapod_kin.cli.common import robot_of

    feet = ["a:0,0,0.1", "b:0,0,0.2"]
    for cmd in (["stand"], ["gait"], ["simulate"], ["timeline", "gait", "-o", "x.csv"]):
        argv = [*cmd, "x.urdf", "--foot", feet[0], "--foot", feet[1], "--foot-radius", "0.01"]
        robot = robot_of(build_parser().parse_args(argv))
        # parsed before the robot loads: one spec per --foot, in order
        assert [(f.frame, f.offset) for f in robot.feet] == [
            ("a", (0.0, 0.0, 0.1)),
            ("b", (0.0, 0.0, 0.2)),
        ], cmd
        assert robot.foot_radius == 0.01, cmd
        assert robot.source == "x.urdf"


def test_tool_is_one_option_in_degrees_with_deg(capsys):
    """--tool reads its rpy in degrees with --deg, on fk as on ik: the same tip."""
    q = ["10", "20", "-30"]
    tool = ["0.01", "0.02", "0.03"]
    code, out, _ = run(capsys, "fk", "hexabot_leg", "--q", *q, "--deg", "--json",
                       "--tool", *tool, "90", "0", "45")  # fmt: skip
    assert code == 0
    deg = np.array(json.loads(out)["T_tip"])
    code, out, _ = run(capsys, "fk", "hexabot_leg", "--q", *np.radians([10, 20, -30]).astype(str),
                       "--json", "--tool", *tool, str(np.pi / 2), "0", str(np.pi / 4))  # fmt: skip
    assert code == 0
    np.testing.assert_allclose(deg, np.array(json.loads(out)["T_tip"]), atol=1e-12)
    model = hk.load("hexabot_leg", tool=((0.01, 0.02, 0.03), (np.pi / 2, 0.0, np.pi / 4)))
    np.testing.assert_allclose(deg, model.fk(np.radians([10, 20, -30])), atol=1e-12)


def test_gait_html_of_a_urdf_in_another_folder(tmp_path, monkeypatch, capsys):
    """The page is of the robot given (a relative path from elsewhere), not of a namesake."""
    pytest.importorskip("umsgpack")
    robots_dir = tmp_path / "robots"
    robots_dir.mkdir()
    import hexapod_kin.viewer.walk as walk_pages

    drawn_joints: list[tuple[str, ...]] = []
    real = walk_pages.render_html

    def spy(model, *args, **kwargs):
        drawn_joints.append(tuple(model.joint_names))
        return real(model, *args, **kwargs)

    monkeypatch.setattr(walk_pages, "render_html", spy)
    text = hk.to_urdf("hexapod")
    assert text.count('"leg1_hip"') == 1
    # the file's robot differs from the preset by one joint's name
    (robots_dir / "hexapod.urdf").write_text(text.replace('"leg1_hip"', '"leg1_hip_there"'))
    here = tmp_path / "here"
    here.mkdir()
    monkeypatch.chdir(here)
    page = here / "walk.html"
    code = main(["gait", "../robots/hexapod.urdf", "--duration", "0.5", "--html", str(page)])
    assert code == 0, capsys.readouterr().err
    ((*joints,),) = drawn_joints
    assert "leg1_hip_there" in joints and "leg1_hip" not in joints  # that file's robot
    data = json.loads(re.search(r"var DATA = (\{.*?\});\n", page.read_text()).group(1))
    assert data["animation"] is True and data["duration"] == pytest.approx(0.5, abs=0.05)


def test_to_urdf_takes_what_load_takes(tmp_path):
    """A source means the same in every export: a preset name or a table file, as load reads."""
    from hexapod_kin.exceptions import ParameterError
    from hexapod_kin.export import to_xacro

    leg = hk.robots.hexabot_leg()
    assert hk.to_urdf("hexabot_leg") == hk.to_urdf(leg)
    table = "examples/leg4.toml"
    assert hk.to_urdf(table) == hk.to_urdf(hk.load(table).params)
    with pytest.raises(ParameterError, match="URDF without a parameter table"):
        hk.to_urdf("erd:ur5")
    with pytest.raises(ParameterError, match="URDF without a parameter table"):
        to_xacro("erd:ur5")  # the same refusal on every export of a table
    with pytest.raises(hk.SourceError, match="did you mean 'hexabot_leg'"):
        hk.to_urdf("hexabot_le")


def test_mjcf_of_a_urdf_with_package_meshes():
    """`mjcf erd:ur5`: offered by --help, and exported (without its meshes): 6 joints kept."""
    mujoco = pytest.importorskip("mujoco")
    from hexapod_kin.export.mjcf import to_mjcf

    xml = to_mjcf("erd:ur5", floor=False).xml
    assert "<mesh" not in xml
    model = mujoco.MjModel.from_xml_string(xml)
    assert model.njnt == hk.load("erd:ur5").nq == 6
