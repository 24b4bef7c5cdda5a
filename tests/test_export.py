"""Exports checked by the tools that consume them.

* xacro: the real ``xacro`` package expands our document; the result loads (Pinocchio) to the
  same model as ``to_urdf``: FK of every frame at random q to 1e-12, masses, inertias, limits,
  damping, friction. Editing one property equals rebuilding the preset with that dimension.
* ROS 2 package: ``package.xml`` parsed and validated by catkin_pkg (the library colcon/ament
  use) plus the format-3 rules; CMakeLists configured and installed by CMake with a stub
  ament_cmake; the launch file compiled and run against stub launch modules (it names files
  that exist); the URDF passes urdfdom's ``check_urdf``; every preset.
* MJCF: MuJoCo's FK (body xpos/xmat) equals Pinocchio's to 1e-12 at random configurations
  (joints mapped by name), every preset; damping/limits/inertials carried over; the pendulum
  swings the same in MuJoCo (RK4) and in hexapod_kin.dynamics.simulate (RK4) to 1e-9 rad.
* Meshes: STL bytes deterministic, read back by trimesh with the expected bounds.
* Every export: same input → same bytes; header records the command; no ``--`` in comments.
"""

from __future__ import annotations

import ast
import importlib.metadata
import math
import os
import re
import shutil
import subprocess
import sys
import types
from pathlib import Path

import numpy as np
import pytest

import hexapod_kin as hk
from hexapod_kin import robots
from hexapod_kin.exceptions import ParameterError
from hexapod_kin.params import Chain, Hexapod, Inertial, JointLimits, KhalilRow, LegMount

xacro = pytest.importorskip("xacro")
mujoco = pytest.importorskip("mujoco")
trimesh = pytest.importorskip("trimesh")
pin = pytest.importorskip("pinocchio")
etree = pytest.importorskip("lxml.etree")

from hexapod_kin.export import (  # noqa: E402
    add_collisions,
    expand_xacro,
    export_package,
    mesh_visuals,
    package_files,
    to_mjcf,
    to_xacro,
    write_mjcf,
)

PRESETS = robots.names()


# ------------------------------------------------------------------------ helpers
def _odd_chain() -> Chain:
    """Prismatic joint, theta/r offsets, a gimbal-lock row, explicit inertial, damping."""
    return Chain(
        rows=(
            KhalilRow("revolute", 0.3, 0.02, 0.4, 0.05),
            KhalilRow("prismatic", math.pi / 2, 0.1, math.pi / 2, 0.03),
            KhalilRow("revolute", -0.7, 0.08, -1.1, -0.02),
            KhalilRow("fixed", 0.2, 0.05, 0.3, 0.01),
        ),
        joint_names=("a-1", "a.2", "a3"),
        limits=(
            JointLimits(-1.0, 2.0, 3.0, 4.0),
            JointLimits(-0.05, 0.1, 0.5, 60.0),
            JointLimits(-2.5, 0.5, 7.0, 8.0),
        ),
        inertials=(
            None,
            Inertial(0.3, (0.01, 0.02, -0.03), (2e-3, 3e-3, 4e-3, 1e-4, -2e-4, 3e-4)),
            None,
            None,
        ),
        name="odd",
        link_mass=0.2,
        link_radius=0.01,
        damping=(0.1, 0.2, 0.3),
        friction=(0.01, 0.0, 0.02),
    )


def _two_family_robot() -> Hexapod:
    leg = robots.hexabot_leg()
    other = robots.coxa_tibia_leg(0.08, 0.12)
    return Hexapod(
        legs=(
            LegMount("front", leg, (0.1, 0.05, 0.01), 0.3),
            LegMount("back", other, (-0.1, -0.05, 0.0), 2.5),
            LegMount("side", leg, (0.0, 0.12, -0.02), 1.4),
        ),
        name="mixed",
    )


def _sources() -> dict[str, Chain | Hexapod]:
    out: dict[str, Chain | Hexapod] = {name: robots.get(name) for name in PRESETS}
    out["odd"] = _odd_chain()
    out["mixed"] = _two_family_robot()
    if "tool" in Chain.__dataclass_fields__:  # base/tool poses (being added to Chain)
        out["tooled"] = robots.hexabot_leg().replace(
            base=((0.01, 0.02, 0.03), (0.1, -0.2, 0.3)),
            tool=((0.02, 0.0, -0.01), (0.0, 0.4, 0.0)),
            tip="tool",
        )
    return out


SOURCES = _sources()


def _random_q(model, rng) -> np.ndarray:
    lo = np.maximum(model.lowerPositionLimit, -np.pi)
    hi = np.minimum(model.upperPositionLimit, np.pi)
    return rng.uniform(lo, hi)


def assert_same_model(text_a: str, text_b: str, n_q: int = 25) -> None:
    """Both URDF texts load (through hexapod_kin.load) to the same model."""
    ma, mb = hk.load(text_a).full_model, hk.load(text_b).full_model
    assert [f.name for f in ma.frames] == [f.name for f in mb.frames]
    assert list(ma.names) == list(mb.names)
    assert ma.nq == mb.nq
    for arr in (
        "lowerPositionLimit",
        "upperPositionLimit",
        "velocityLimit",
        "effortLimit",
        "damping",
        "friction",
    ):
        np.testing.assert_allclose(
            getattr(ma, arr), getattr(mb, arr), rtol=1e-14, atol=0, err_msg=arr
        )
    for ia, ib in zip(ma.inertias, mb.inertias):
        assert abs(ia.mass - ib.mass) <= 1e-14 * max(1.0, ia.mass)
        np.testing.assert_allclose(ia.lever, ib.lever, rtol=0, atol=1e-14)
        np.testing.assert_allclose(ia.inertia, ib.inertia, rtol=0, atol=1e-14 * max(1.0, ia.mass))
    for fa, fb in zip(ma.frames, mb.frames):
        assert abs(fa.inertia.mass - fb.inertia.mass) <= 1e-14
    da, db = ma.createData(), mb.createData()
    rng = np.random.default_rng(7)
    for _ in range(n_q):
        q = _random_q(ma, rng)
        pin.framesForwardKinematics(ma, da, q)
        pin.framesForwardKinematics(mb, db, q)
        for k in range(ma.nframes):
            np.testing.assert_allclose(
                da.oMf[k].homogeneous, db.oMf[k].homogeneous, rtol=0, atol=1e-12
            )


def _comments_ok(text: str) -> list[str]:
    comments = re.findall(r"<!--(.*?)-->", text, re.S)
    for c in comments:
        assert "--" not in c, c
    return comments


def check_urdf_binary() -> str:
    """urdfdom's check_urdf, shipped by the cmeel-urdfdom wheel (a Pinocchio dependency)."""
    candidates = [shutil.which("check_urdf", path=os.path.dirname(sys.executable))]
    try:
        dist = importlib.metadata.distribution("cmeel-urdfdom")
        candidates.append(str(dist.locate_file("cmeel.prefix/bin/check_urdf")))
    except importlib.metadata.PackageNotFoundError:
        pass
    for c in candidates:
        if c and os.path.isfile(c) and os.access(c, os.X_OK):
            return c
    pytest.skip("urdfdom check_urdf not found (cmeel-urdfdom)")


def run_check_urdf(path: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [check_urdf_binary(), str(path)], capture_output=True, text=True, timeout=600
    )


# ------------------------------------------------------------------------ xacro
@pytest.mark.parametrize("name", sorted(SOURCES))
def test_xacro_expands_to_the_same_model(name):
    src = SOURCES[name]
    text = to_xacro(src, header="made by: hexapod-kin xacro test")
    assert text == to_xacro(src, header="made by: hexapod-kin xacro test")  # same bytes
    _comments_ok(text)
    urdf = expand_xacro(text)
    assert "<xacro:" not in urdf and "${" not in urdf
    assert_same_model(hk.to_urdf(src), urdf)


def test_xacro_has_one_macro_per_family_and_six_instances():
    text = to_xacro(robots.hexapod())
    root = etree.fromstring(text.encode())
    ns = {"xacro": "http://www.ros.org/wiki/xacro"}
    families = [
        m.get("name")
        for m in root.findall("xacro:macro", ns)
        if not m.get("name").startswith("hk_")
    ]
    assert families == ["hexabot_leg"]
    calls = root.findall("xacro:hexabot_leg", ns)
    assert [c.get("prefix") for c in calls] == [f"leg{i}_" for i in range(1, 7)]
    props = {p.get("name"): p.get("value") for p in root.findall("xacro:property", ns)}
    for key in (
        "d2",
        "d3",
        "d4",
        "alpha2",
        "hip_lower",
        "knee_effort",
        "ankle_damping",
        "coxa_mass",
        "link_radius",
        "body_length",
        "body_mass",
        "mount_radius",
        "leg1_yaw",
    ):
        assert key in props, key
    assert float(props["d3"]) == 0.10 and float(props["mount_radius"]) == pytest.approx(0.12)
    mixed = etree.fromstring(to_xacro(_two_family_robot()).encode())
    fams = [
        m.get("name")
        for m in mixed.findall("xacro:macro", ns)
        if not m.get("name").startswith("hk_")
    ]
    assert fams == ["hexabot_leg", "coxa_tibia_leg"]


@pytest.mark.parametrize(
    ("prop", "value", "preset", "params"),
    [
        ("d3", "0.13", "hexabot_leg", {"l2": 0.13}),
        ("d2", "0.07", "hexapod", {"l1": 0.07}),
        ("mount_radius", "0.15", "hexapod", {"body_radius": 0.15, "body_height": 0.05}),
        ("r1", "0.5", "scara", {"r1": 0.5}),
    ],
)
def test_xacro_one_property_edits_the_model(prop, value, preset, params):
    text = to_xacro(robots.get(preset))
    edited = re.sub(rf'(<xacro:property name="{prop}" value=")[^"]*"', rf'\g<1>{value}"', text)
    assert edited != text
    expected = robots.get(preset, **params)
    if prop == "mount_radius":  # the body box follows body_radius in the preset, not the mounts
        size = robots.hexapod().body_size
        expected = Hexapod(
            legs=expected.legs,
            name=expected.name,
            body_size=size,
            body_mass=expected.body_mass,
            description=expected.description,
        )
    assert_same_model(hk.to_urdf(expected), expand_xacro(edited), n_q=5)


def test_xacro_single_leg_and_errors():
    robot = robots.hexapod()
    assert_same_model(hk.to_urdf(robot, leg="leg3"), expand_xacro(to_xacro(robot, leg="leg3")))
    with pytest.raises(ParameterError, match="leg='leg9'"):
        to_xacro(robot, leg="leg9")
    with pytest.raises(ParameterError, match="without a parameter table"):
        to_xacro(hk.to_urdf(robots.hexabot_leg()))


def test_a_source_string_means_the_same_to_every_exporter(tmp_path):
    """A preset name is the preset for load, to_xacro, package_files and to_mjcf alike."""
    leg = robots.hexabot_leg()
    assert to_xacro("hexabot_leg") == to_xacro(leg)
    assert package_files("hexabot_leg") == package_files(leg)
    assert to_mjcf("hexabot_leg").xml == to_mjcf(leg).xml
    text = hk.to_urdf(leg)
    (tmp_path / "leg.urdf").write_text(text)
    from_text, from_file = to_mjcf(text), to_mjcf(tmp_path / "leg.urdf")
    assert from_text.xml.split("\n", 2)[2] == from_file.xml.split("\n", 2)[2]
    with pytest.raises(hk.SourceError, match="hexabot_le"):
        to_mjcf("hexabot_le")


def test_body_collision_box_leaves_the_leg_mounts_outside():
    """The body's collision box is the visual box trimmed so no leg mount lies inside it.

    ``hexapod()``'s box (2.2 x 1.6 x the mount radius) holds the front and rear mounts; the
    legs' first links start there and would collide with the body they hang from.
    """
    src = robots.hexapod()
    root = etree.fromstring(add_collisions(hk.to_urdf(src)).encode())
    body = next(link for link in root.iter("link") if link.get("name") == src.body)
    visual = [float(v) for v in body.find("visual/geometry/box").get("size").split()]
    coll = [float(v) for v in body.find("collision/geometry/box").get("size").split()]
    assert visual == pytest.approx(src.body_size)  # the drawing and the inertia keep it
    half = 0.5 * np.array(coll)
    mounts = np.array([m.xyz for m in src.legs])
    assert not np.any(np.all(np.abs(mounts) < half - 1e-9, axis=1))  # none inside
    assert np.any(np.all(np.abs(mounts) <= half + 1e-6, axis=1))  # some on its faces
    assert sum(np.all(np.abs(mounts) < 0.5 * np.array(visual), axis=1)) == 4  # the old box
    assert coll[1:] == pytest.approx(visual[1:])  # trimmed along x only: it keeps more
    assert coll[0] == pytest.approx(2 * abs(mounts[0, 0]), rel=1e-5)


# ------------------------------------------------------------------------ check_urdf
@pytest.mark.parametrize("name", PRESETS)
def test_check_urdf_accepts_every_exported_urdf(name, tmp_path):
    src = robots.get(name)
    texts = {
        "plain": hk.to_urdf(src),
        "collisions": add_collisions(hk.to_urdf(src)),
        "xacro": expand_xacro(to_xacro(src)),
        "meshes": mesh_visuals(hk.to_urdf(src), "package://p/meshes/").urdf,
    }
    for label, text in texts.items():
        path = tmp_path / f"{label}.urdf"
        path.write_text(text)
        res = run_check_urdf(path)
        assert res.returncode == 0, (label, res.stdout, res.stderr)
        assert "Successfully Parsed XML" in res.stdout, label


def test_check_urdf_is_a_real_check(tmp_path):
    bad = hk.to_urdf(robots.hexabot_leg()).replace('<parent link="coxa"/>', '<parent link="nope"/>')
    path = tmp_path / "bad.urdf"
    path.write_text(bad)
    assert run_check_urdf(path).returncode != 0


# ------------------------------------------------------------------------ ROS 2 package
FORMAT3_ORDER = ("name", "version", "description", "maintainer", "license", "url", "author")


def _check_package_xml(path: Path, pkg: str) -> None:
    from catkin_pkg.package import parse_package_string

    text = path.read_text()
    parsed = parse_package_string(text)
    parsed.validate()  # catkin_pkg's own rules (names, version, maintainers, licenses)
    assert parsed.package_format == 3 and parsed.name == pkg
    assert [d.name for d in parsed.buildtool_depends] == ["ament_cmake"]
    exec_deps = {d.name for d in parsed.exec_depends}
    assert {"robot_state_publisher", "joint_state_publisher_gui", "rviz2", "xacro"} <= exec_deps
    assert all(m.email and "@" in m.email for m in parsed.maintainers)
    assert [e.content for e in parsed.exports if e.tagname == "build_type"] == ["ament_cmake"]
    # format-3 schema rules catkin_pkg does not enforce: element order and required ones.
    root = etree.fromstring(text.encode())
    assert root.tag == "package" and root.get("format") == "3"
    tags = [c.tag for c in root if isinstance(c.tag, str)]
    head = [t for t in tags if t in FORMAT3_ORDER]
    assert head == sorted(head, key=FORMAT3_ORDER.index)
    for required in ("name", "version", "description", "maintainer", "license"):
        assert required in tags
    assert re.fullmatch(r"\d+\.\d+\.\d+", root.findtext("version"))
    assert re.fullmatch(r"[a-z][a-z0-9_]*", root.findtext("name"))
    assert tags[-1] == "export"


class _Rec:
    """Records its constructor arguments (stands in for launch / launch_ros classes)."""

    def __init__(self, *args, **kwargs):
        self.args, self.kwargs = args, kwargs


def _stub_launch_modules(monkeypatch) -> None:
    names = {
        "launch": ["LaunchDescription"],
        "launch.actions": ["DeclareLaunchArgument"],
        "launch.conditions": ["IfCondition", "UnlessCondition"],
        "launch.substitutions": ["Command", "LaunchConfiguration", "PathJoinSubstitution"],
        "launch_ros": [],
        "launch_ros.actions": ["Node"],
        "launch_ros.parameter_descriptions": ["ParameterValue"],
        "launch_ros.substitutions": ["FindPackageShare"],
    }
    for mod, classes in names.items():
        m = types.ModuleType(mod)
        for c in classes:
            setattr(m, c, type(c, (_Rec,), {}))
        monkeypatch.setitem(sys.modules, mod, m)


def _check_launch(pkg_dir: Path, pkg: str, robot: str, monkeypatch) -> None:
    path = pkg_dir / "launch" / "display.launch.py"
    source = path.read_text()
    code = compile(source, str(path), "exec")  # valid Python
    consts = {}
    for node in ast.parse(source).body:
        if isinstance(node, ast.Assign) and isinstance(node.targets[0], ast.Name):
            consts[node.targets[0].id] = ast.literal_eval(node.value)
    assert consts["PACKAGE"] == pkg
    assert (pkg_dir.joinpath(*consts["MODEL_FILE"])).is_file()
    assert consts["MODEL_FILE"] == ("urdf", f"{robot}.urdf.xacro")
    assert (pkg_dir.joinpath(*consts["RVIZ_FILE"])).is_file()
    _stub_launch_modules(monkeypatch)
    env: dict = {}
    exec(code, env)
    desc = env["generate_launch_description"]()
    actions = desc.args[0]
    nodes = [a for a in actions if type(a).__name__ == "Node"]
    executables = [(n.kwargs["package"], n.kwargs["executable"]) for n in nodes]
    for needed in (
        ("robot_state_publisher", "robot_state_publisher"),
        ("joint_state_publisher_gui", "joint_state_publisher_gui"),
        ("rviz2", "rviz2"),
    ):
        assert needed in executables
    from catkin_pkg.package import parse_package_string

    parsed = parse_package_string((pkg_dir / "package.xml").read_text())
    exec_deps = {d.name for d in parsed.exec_depends}
    assert {n.kwargs["package"] for n in nodes} <= exec_deps  # every node's package declared
    imported = {
        node.module.split(".")[0]
        for node in ast.walk(ast.parse(source))
        if isinstance(node, ast.ImportFrom) and node.module
    }
    assert imported <= exec_deps  # launch, launch_ros
    rviz = next(n for n in nodes if n.kwargs["executable"] == "rviz2")
    rviz_path = rviz.kwargs["arguments"][1].args[0]
    assert rviz_path[0].args == (pkg,) and tuple(rviz_path[1:]) == ("rviz", "display.rviz")
    model_arg = next(
        a for a in actions if type(a).__name__ == "DeclareLaunchArgument" and a.args[0] == "model"
    )
    default = model_arg.kwargs["default_value"].args[0]
    assert default[0].args == (pkg,) and pkg_dir.joinpath(*default[1:]).is_file()


def _check_cmake(pkg_dir: Path, pkg: str, tmp_path: Path) -> None:
    text = (pkg_dir / "CMakeLists.txt").read_text()
    assert re.search(rf"project\({pkg}\)", text)
    dirs = re.search(r"DIRECTORY ([^\n]+)", text).group(1).split()
    assert dirs == ["urdf", "launch", "rviz", "meshes"]
    for d in dirs:
        assert (pkg_dir / d).is_dir(), d
    if not (shutil.which("cmake") and shutil.which("cc") and shutil.which("c++")):
        return
    # Configure and install with a stub ament_cmake: proves the CMake syntax and install rules.
    stub = tmp_path / "stub"
    stub.mkdir()
    (stub / "ament_cmakeConfig.cmake").write_text("macro(ament_package)\nendmacro()\n")
    build, prefix = tmp_path / "build", tmp_path / "install"
    for cmd in (
        ["cmake", "-S", str(pkg_dir), "-B", str(build), f"-DCMAKE_PREFIX_PATH={stub}"],
        ["cmake", "--install", str(build), "--prefix", str(prefix)],
    ):
        res = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
        assert res.returncode == 0, res.stdout + res.stderr
    share = prefix / "share" / pkg
    for rel in ("urdf", "launch/display.launch.py", "rviz/display.rviz", "meshes"):
        assert (share / rel).exists(), rel


@pytest.mark.parametrize("name", PRESETS)
def test_ros2_package_is_consistent(name, tmp_path, monkeypatch):
    yaml = pytest.importorskip("yaml")
    src = robots.get(name)
    pkg = f"{name}_description"
    out = tmp_path / pkg
    res = export_package(src, out, header="made by: hexapod-kin export-package test")
    assert res.name == pkg and res.path == out
    for rel in (
        "package.xml",
        "CMakeLists.txt",
        f"urdf/{name}.urdf",
        f"urdf/{name}.urdf.xacro",
        "launch/display.launch.py",
        "rviz/display.rviz",
        "README.md",
    ):
        assert (out / rel).is_file(), rel
    assert sorted(res.files) == sorted(
        str(p.relative_to(out)) for p in out.rglob("*") if p.is_file()
    )
    _check_package_xml(out / "package.xml", pkg)
    _check_launch(out, pkg, name, monkeypatch)
    check = run_check_urdf(out / "urdf" / f"{name}.urdf")
    assert check.returncode == 0, check.stderr
    assert_same_model(hk.to_urdf(src), (out / "urdf" / f"{name}.urdf").read_text(), n_q=3)
    rviz = yaml.safe_load((out / "rviz" / "display.rviz").read_text())
    fixed = rviz["Visualization Manager"]["Global Options"]["Fixed Frame"]
    links = {e.get("name") for e in etree.parse(str(out / "urdf" / f"{name}.urdf")).iter("link")}
    assert fixed in links
    classes = [d["Class"] for d in rviz["Visualization Manager"]["Displays"]]
    assert "rviz_default_plugins/RobotModel" in classes
    for rel in ("package.xml", f"urdf/{name}.urdf", f"urdf/{name}.urdf.xacro"):
        comments = _comments_ok((out / rel).read_text())
        assert any("made by: hexapod-kin export-package test" in c for c in comments), rel
    if name == "hexabot_leg":
        _check_cmake(out, pkg, tmp_path)


@pytest.mark.filterwarnings("ignore:.*mesh file:UserWarning")
def test_ros2_package_with_meshes_resolves_and_is_deterministic(tmp_path):
    src = robots.hexabot_leg()
    a, b = tmp_path / "a" / "leg_description", tmp_path / "b" / "leg_description"
    a.parent.mkdir()
    b.parent.mkdir()
    ra = export_package(src, a, name="leg_description", meshes=True, header="made by: x")
    rb = export_package(src, b, name="leg_description", meshes=True, header="made by: x")
    assert ra.files == rb.files
    for rel in ra.files:
        assert (a / rel).read_bytes() == (b / rel).read_bytes(), rel
    urdf = (a / "urdf" / "hexabot_leg.urdf").read_text()
    uris = re.findall(r'filename="([^"]+)"', urdf)
    assert uris and all(u.startswith("package://leg_description/meshes/") for u in uris)
    for u in uris:
        assert (a / "meshes" / u.rsplit("/", 1)[1]).is_file()
    root = etree.fromstring(urdf.encode())
    for coll in root.iter("collision"):  # collisions stay primitive
        assert coll.find("geometry/mesh") is None
    # the loader gate resolves package:// against the folder holding the package
    model = hk.load(str(a / "urdf" / "hexabot_leg.urdf"), package_dirs=[str(a.parent)])
    assert model.nq == 3
    assert_same_model(hk.to_urdf(src), urdf, n_q=3)


def test_ros2_package_atomic_and_refuses_to_overwrite(tmp_path, monkeypatch):
    src = robots.pendulum()
    out = tmp_path / "pend"
    export_package(src, out)
    before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    with pytest.raises(ParameterError, match="not empty"):
        export_package(src, out)
    import hexapod_kin.export.ros2 as ros2

    calls = {"n": 0}
    real = ros2.atomic_write

    def failing(path, data):
        calls["n"] += 1
        if calls["n"] == 4:
            raise OSError("disk full")
        return real(path, data)

    monkeypatch.setattr(ros2, "atomic_write", failing)
    with pytest.raises(OSError, match="disk full"):
        export_package(robots.scara(), out, force=True)
    after = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    assert after == before  # the old package is intact
    assert sorted(p.name for p in tmp_path.iterdir()) == ["pend"]  # no temp folders left
    monkeypatch.setattr(ros2, "atomic_write", real)
    export_package(robots.scara(), out, force=True)
    assert (out / "urdf" / "scara.urdf").is_file() and not (out / "urdf" / "pendulum.urdf").exists()
    with pytest.raises(ParameterError, match="ROS package name"):
        export_package(src, tmp_path / "x", name="Bad-Name")
    with pytest.raises(ParameterError, match="e-mail"):
        export_package(src, tmp_path / "x", email="nobody")


# ------------------------------------------------------------------------ MJCF
def _mj_model(out) -> object:
    return mujoco.MjModel.from_xml_string(out.xml, out.assets)


def _mj_vs_pinocchio(mj, src, n_q: int = 30) -> float:
    pm = hk.load(hk.to_urdf(src)).full_model
    pd, md = pm.createData(), mujoco.MjData(mj)
    rng = np.random.default_rng(3)
    worst = 0.0
    joint = mujoco.mjtObj.mjOBJ_JOINT
    adr = {}
    for i in range(1, pm.njoints):
        j = mujoco.mj_name2id(mj, joint, pm.names[i])
        assert j >= 0, pm.names[i]
        adr[pm.joints[i].idx_q] = mj.jnt_qposadr[j]
    assert mj.nq == pm.nq
    checked = 0
    for _ in range(n_q):
        q = _random_q(pm, rng)
        md.qpos[:] = 0.0
        for iq, jq in adr.items():
            md.qpos[jq] = q[iq]
        mujoco.mj_kinematics(mj, md)
        pin.framesForwardKinematics(pm, pd, q)
        for b in range(1, mj.nbody):
            name = mujoco.mj_id2name(mj, mujoco.mjtObj.mjOBJ_BODY, b)
            f = pm.getFrameId(name, pin.BODY)
            assert f < pm.nframes, name
            oMf = pd.oMf[f]
            worst = max(
                worst,
                float(np.abs(md.xpos[b] - oMf.translation).max()),
                float(np.abs(md.xmat[b].reshape(3, 3) - oMf.rotation).max()),
            )
            checked += 1
    assert checked == n_q * (mj.nbody - 1)
    return worst


@pytest.mark.parametrize("name", sorted(SOURCES))
def test_mjcf_fk_equals_pinocchio(name):
    src = SOURCES[name]
    out = to_mjcf(src, header="made by: hexapod-kin mjcf test")
    assert out.xml == to_mjcf(src, header="made by: hexapod-kin mjcf test").xml
    _comments_ok(out.xml)
    mj = _mj_model(out)
    assert _mj_vs_pinocchio(mj, src) <= 1e-12
    # damping, friction, limits, effort, inertials carried over (by joint / body name)
    pm = hk.load(hk.to_urdf(src)).full_model
    for i in range(1, pm.njoints):
        j = mujoco.mj_name2id(mj, mujoco.mjtObj.mjOBJ_JOINT, pm.names[i])
        v = pm.joints[i].idx_v
        dof = mj.jnt_dofadr[j]
        assert mj.dof_damping[dof] == pytest.approx(pm.damping[v], rel=1e-15, abs=0)
        assert mj.dof_frictionloss[dof] == pytest.approx(pm.friction[v], rel=1e-15, abs=0)
        np.testing.assert_allclose(
            mj.jnt_range[j], [pm.lowerPositionLimit[v], pm.upperPositionLimit[v]], rtol=1e-15
        )
        np.testing.assert_allclose(
            mj.jnt_actfrcrange[j], [-pm.effortLimit[v], pm.effortLimit[v]], rtol=1e-15
        )
    total = sum(pm.inertias[i].mass for i in range(pm.njoints))
    assert float(np.sum(mj.body_mass)) == pytest.approx(total, rel=1e-13)
    for b in range(1, mj.nbody):
        name_b = mujoco.mj_id2name(mj, mujoco.mjtObj.mjOBJ_BODY, b)
        frame = pm.frames[pm.getFrameId(name_b, pin.BODY)]
        inertia = frame.inertia if frame.inertia.mass > 0 else None
        if inertia is None or mj.body_dofnum[b] == 0 and mj.body_mass[b] == 0:
            continue
        rot = np.empty(9)
        mujoco.mju_quat2Mat(rot, mj.body_iquat[b])
        rot = rot.reshape(3, 3)
        full = rot @ np.diag(mj.body_inertia[b]) @ rot.T
        assert mj.body_mass[b] == pytest.approx(inertia.mass, rel=1e-14)
        np.testing.assert_allclose(mj.body_ipos[b], inertia.lever, atol=1e-14)
        np.testing.assert_allclose(full, inertia.inertia, atol=1e-14 * max(1.0, inertia.mass))
    floor = mj.geom("floor")
    assert floor.type[0] == mujoco.mjtGeom.mjGEOM_PLANE


def test_mjcf_with_meshes_and_files(tmp_path):
    src = robots.hexapod()
    path = tmp_path / "hexapod.xml"
    out = write_mjcf(src, path, meshes=True, header="made by: x")
    mesh_dir = tmp_path / "hexapod_meshes"
    assert sorted(p.name for p in mesh_dir.iterdir()) == sorted(
        k.split("/", 1)[1] for k in out.assets
    )
    mj = mujoco.MjModel.from_xml_path(str(path))  # meshes read from disk beside the file
    assert mj.nmesh == len(out.assets) > 0
    assert _mj_vs_pinocchio(mj, src, n_q=5) <= 1e-12
    meshes = [g for g in range(mj.ngeom) if mj.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH]
    assert meshes and all(mj.geom_contype[g] == 0 and mj.geom_conaffinity[g] == 0 for g in meshes)
    again = to_mjcf(src, meshes=True, mesh_prefix="hexapod_meshes/", header="made by: x")
    assert again.xml == path.read_text() and again.assets == out.assets


def test_pendulum_swings_the_same_in_mujoco_and_pinocchio():
    from hexapod_kin.dynamics import simulate

    src = robots.pendulum()
    dt, duration = 1e-3, 5.0
    out = to_mjcf(src, timestep=dt, integrator="RK4")
    mj = _mj_model(out)
    assert mj.opt.integrator == mujoco.mjtIntegrator.mjINT_RK4 and mj.opt.timestep == dt
    md = mujoco.MjData(mj)
    q0 = -math.pi / 2 + math.pi / 6  # seed 001: 30 degrees from the vertical
    md.qpos[0] = q0
    n = int(round(duration / dt))
    q_mj = np.empty(n + 1)
    q_mj[0] = q0
    for k in range(n):
        mujoco.mj_step(mj, md)
        q_mj[k + 1] = md.qpos[0]
    run = simulate(hk.load(src), [q0], duration=duration, dt=dt, method="rk4")
    assert run.q.shape == (n + 1, 1)
    diff = float(np.abs(run.q[:, 0] - q_mj).max())
    assert diff <= 1e-9, diff
    # it really swings: several periods, decaying amplitude (damping 0.01 carried over)
    assert np.ptp(q_mj) > 0.9 and np.sum(np.diff(np.sign(q_mj - (-math.pi / 2))) != 0) >= 6


# ------------------------------------------------------------------------ meshes
def test_mesh_files_are_deterministic_and_match_the_primitives():
    leg = robots.hexabot_leg()
    a = mesh_visuals(hk.to_urdf(leg), "meshes/")
    b = mesh_visuals(hk.to_urdf(leg), "meshes/")
    assert a.files == b.files and a.urdf == b.urdf
    import io

    femur = trimesh.load(io.BytesIO(a.files["femur_link.stl"]), file_type="stl")
    r = leg.link_radius
    # a capsule along x from the femur frame to the next joint (l2 = 0.10 m), radius r
    np.testing.assert_allclose(femur.bounds, [[-r, -r, -r], [0.10 + r, r, r]], atol=1e-9)
    foot = trimesh.load(io.BytesIO(a.files["foot_foot.stl"]), file_type="stl")
    np.testing.assert_allclose(foot.bounds, [[-1.5 * r] * 3, [1.5 * r] * 3], atol=1e-9)
    assert femur.is_watertight


# ------------------------------------------------------------------------ CLI
def test_cli_writes_every_format(tmp_path, capsys):
    from hexapod_kin.cli import main

    xacro_path = tmp_path / "leg.urdf.xacro"
    assert main(["xacro", "hexabot_leg", "-s", "l2=0.12", "-o", str(xacro_path)]) == 0
    text = xacro_path.read_text()
    assert "made by: hexapod-kin xacro hexabot_leg -s l2=0.12" in text
    assert_same_model(hk.to_urdf(robots.hexabot_leg(l2=0.12)), expand_xacro(text), n_q=3)
    assert main(["export-package", "hexapod", "--out", str(tmp_path / "pkg"), "-m"]) == 0
    assert (tmp_path / "pkg" / "package.xml").is_file()
    assert any((tmp_path / "pkg" / "meshes").glob("*.stl"))
    assert main(["mjcf", "pendulum", "-o", str(tmp_path / "p.xml"), "--timestep", "0.001"]) == 0
    xml = (tmp_path / "p.xml").read_text()
    assert "made by: hexapod-kin mjcf pendulum (timestep 0.001)" in xml
    _comments_ok(xml)
    capsys.readouterr()
    assert main(["export-package", "hexapod", "--out", str(tmp_path / "pkg")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("hexapod-kin: error:") and "not empty" in err and "\n" not in err
    assert main(["mjcf", "pendulum", "--integrator", "leapfrog"]) == 2
    assert "RK4" in capsys.readouterr().err


def test_mjcf_floating_robot_fk_and_it_lands_on_the_floor():
    src = robots.hexapod()
    out = to_mjcf(src, floating=True, timestep=1e-3)
    mj = _mj_model(out)
    assert mj.nq == 7 + 18 and mj.jnt_type[0] == mujoco.mjtJoint.mjJNT_FREE
    pm = pin.buildModelFromXML(hk.to_urdf(src), pin.JointModelFreeFlyer())
    pd, md = pm.createData(), mujoco.MjData(mj)
    np.random.seed(11)  # pin.randomConfiguration draws from numpy's global generator
    for _ in range(10):
        q = pin.randomConfiguration(pm, -np.ones(pm.nq), np.ones(pm.nq))
        md.qpos[:3] = q[:3]
        md.qpos[3:7] = [q[6], q[3], q[4], q[5]]  # MuJoCo w x y z, Pinocchio x y z w
        for i in range(2, pm.njoints):
            j = mujoco.mj_name2id(mj, mujoco.mjtObj.mjOBJ_JOINT, pm.names[i])
            md.qpos[mj.jnt_qposadr[j]] = q[pm.joints[i].idx_q]
        mujoco.mj_kinematics(mj, md)
        pin.framesForwardKinematics(pm, pd, q)
        for b in range(1, mj.nbody):
            f = pm.getFrameId(mujoco.mj_id2name(mj, mujoco.mjtObj.mjOBJ_BODY, b), pin.BODY)
            np.testing.assert_allclose(md.xpos[b], pd.oMf[f].translation, atol=1e-12)
            np.testing.assert_allclose(md.xmat[b].reshape(3, 3), pd.oMf[f].rotation, atol=1e-12)
    # dropped from q = 0, the robot falls and comes to rest on the floor (contacts work)
    mujoco.mj_resetData(mj, md)
    floor_z = float(mj.geom("floor").pos[2])
    for _ in range(3000):
        mujoco.mj_step(mj, md)
    assert np.all(np.isfinite(md.qpos))
    assert md.ncon > 0 and abs(md.qvel[2]) < 0.05
    assert floor_z < md.qpos[2] < 0.0  # fell from 0, stopped above the floor
    with pytest.raises(ParameterError, match="floating"):
        to_mjcf(robots.hexabot_leg(), floating=True)


def test_rounded_zero_inertias_of_a_real_urdf_are_lifted_only_when_asked():
    """erd:anymal's dummy ``base`` link gives ixx = iyy = 0 (eigenvalues ±2e-22): MuJoCo refuses
    it; ``balance_inertia`` raises only such moments, to 1e-6 of the link's largest (then
    MuJoCo's ``balanceinertia`` averages moments that break A + B >= C), and every other
    body's inertia in the compiled MJCF is the URDF's (MuJoCo's own principal axes)."""
    mujoco = pytest.importorskip("mujoco")
    from hexapod_kin.exceptions import UrdfError
    from hexapod_kin.export.mjcf import to_mjcf
    from hexapod_kin.sources import resolve_source

    with pytest.raises(UrdfError, match="positive eigenvalues"):
        to_mjcf("erd:anymal", floor=False)
    xml = to_mjcf("erd:anymal", floor=False, balance_inertia=True).xml
    model = mujoco.MjModel.from_xml_string(xml)
    import xml.etree.ElementTree as ET

    root = ET.fromstring(resolve_source("erd:anymal").text)
    checked = 0
    for link in root.iter("link"):
        node = link.find("inertial/inertia")
        if node is None or float(link.find("inertial/mass").get("value")) == 0:
            continue
        a = {k: float(v) for k, v in node.attrib.items()}
        tensor = np.array(
            [
                [a["ixx"], a["ixy"], a["ixz"]],
                [a["ixy"], a["iyy"], a["iyz"]],
                [a["ixz"], a["iyz"], a["izz"]],
            ]
        )
        lam = np.linalg.eigvalsh(tensor)
        body = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, link.get("name"))
        got = np.sort(model.body_inertia[body])
        want = np.maximum(lam, 1e-6 * lam[-1])
        if want[0] + want[1] < want[2]:  # MuJoCo's balanceinertia: the three set to their mean
            want = np.full(3, want.mean())
        assert np.allclose(got, want, rtol=1e-9, atol=1e-15), link.get("name")
        checked += 1
    assert checked >= 10
