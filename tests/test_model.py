"""Loading: sources, example-robot-data lookup, sub-chain reduction, geometry, exceptions."""

from __future__ import annotations

import inspect
import json

import numpy as np
import pinocchio as pin
import pytest

import hexapod_kin as hk
from hexapod_kin import exceptions
from hexapod_kin.exceptions import FrameNotFoundError, SourceError
from hexapod_kin.sources import erd_names, erd_path, resolve_source


def test_every_exception_is_in_the_family():
    classes = [
        c
        for _, c in inspect.getmembers(exceptions, inspect.isclass)
        if issubclass(c, Exception)
        and not issubclass(c, Warning)
        and c.__module__ == exceptions.__name__
    ]
    assert len(classes) >= 8
    for cls in classes:
        assert issubclass(cls, hk.HexapodKinError), cls
    assert issubclass(exceptions.OptionalDependencyError, ImportError)


def test_erd_data_package_found_without_python_module():
    names = erd_names()
    assert "solo12" in names and "ur5_robot" in names and names == sorted(names)
    path = erd_path("solo12")
    assert path.is_file() and path.name == "solo12.urdf"
    assert "cmeel.prefix" in str(path)
    with pytest.raises(SourceError, match="example-robot-data has"):
        erd_path("solo13")


@pytest.mark.parametrize("source", ["hexabot_leg", "erd:solo12", "<robot", "urdf/scara.urdf"])
def test_resolve_source_kinds(source):
    if source == "<robot":
        source = hk.to_urdf(hk.robots.pendulum())
    res = resolve_source(source)
    assert res.text.lstrip().startswith("<?xml") or res.text.lstrip().startswith("<robot")
    if source == "erd:solo12":
        assert res.package_dirs and res.mesh_root


def test_preset_parameters_reach_the_model():
    model = hk.load("hexabot_leg", l1=0.07)
    np.testing.assert_allclose(model.fk([0, 0, 0])[:3, 3], [0.27, 0, 0], atol=1e-15)
    with pytest.raises(SourceError, match="non-preset"):
        hk.load("erd:solo12", l1=0.07)


def test_subchain_reduction_locks_the_other_joints():
    full = hk.load("hexapod")
    leg3 = hk.load("hexapod", tip="leg3_foot")
    assert full.nq == 18 and leg3.nq == 3
    assert leg3.joint_names == ("leg3_hip", "leg3_knee", "leg3_ankle")
    assert len(leg3.locked_joints) == 15
    q = np.array([0.2, -0.4, 0.9])
    q18 = np.zeros(18)
    q18[6:9] = q
    np.testing.assert_allclose(leg3.fk(q), full.placement(q18, "leg3_foot"), atol=1e-15)
    unreduced = hk.load("hexapod", tip="leg3_foot", reduce=False)
    assert unreduced.nq == 18


def test_base_must_be_an_ancestor_of_the_tip():
    with pytest.raises(FrameNotFoundError, match="ancestor"):
        hk.load("hexapod", base="leg1_coxa", tip="leg2_foot")
    with pytest.raises(FrameNotFoundError, match="must be fixed"):
        hk.load("hexapod", base="leg1_femur", tip="leg1_foot", reduce=False)


@pytest.mark.parametrize(
    "source,kw,count", [("hexabot_leg", {}, None), ("erd:solo12", {"tip": "FL_FOOT"}, None)]
)
def test_geometry_model_matches_the_reduced_model(source, kw, count):
    model = hk.load(source, **kw)
    geom = model.geometry_model("visual")
    # one geometry per <visual> of the URDF's links that the model keeps (counted in the text)
    import xml.etree.ElementTree as ET

    from hexapod_kin import sources

    text = (
        hk.to_urdf(hk.robots.hexabot_leg())
        if source == "hexabot_leg"
        else sources.erd_path(source.removeprefix("erd:")).read_text(encoding="utf-8")
    )
    bodies = {f.name for f in model.model.frames if f.type == pin.FrameType.BODY}
    visuals = sum(
        len(link.findall("visual"))
        for link in ET.fromstring(text).iter("link")
        if link.get("name") in bodies
    )
    assert geom.ngeoms == visuals and visuals >= 5
    for obj in geom.geometryObjects:
        assert obj.parentJoint < model.model.njoints
    data = geom.createData()
    q = model.random_q(seed=0)
    pin.updateGeometryPlacements(model.model, model.data, geom, data, q)
    assert all(np.all(np.isfinite(p.homogeneous)) for p in data.oMg)
    with pytest.raises(hk.ParameterError, match="kind='mesh'"):
        model.geometry_model("mesh")


# ------------------------------------------------------------------ exceptions with fields
def test_exceptions_keep_message_and_carry_fields():
    err = exceptions.ParameterError(
        "l1='abc' is not a number", parameter="l1", value="abc", allowed="a length > 0 in [m]"
    )
    assert str(err) == "l1='abc' is not a number"
    assert (err.parameter, err.value, err.allowed) == ("l1", "abc", "a length > 0 in [m]")
    assert err.to_dict() == {
        "type": "ParameterError",
        "message": "l1='abc' is not a number",
        "parameter": "l1",
        "value": "abc",
        "allowed": "a length > 0 in [m]",
    }
    plain = exceptions.SourceError("just a message")
    assert str(plain) == "just a message" and plain.parameter is None
    assert plain.value is None and plain.allowed is None
    opt = exceptions.OptionalDependencyError("pip install x", parameter="viewer")
    assert isinstance(opt, ImportError) and opt.parameter == "viewer"
    with pytest.raises(TypeError):  # extras are keyword-only
        exceptions.HexapodKinError("m", "p")  # type: ignore[misc]


def test_did_you_mean():
    names = ["hexabot_leg", "scara", "ur5_robot", "ur10_robot"]
    assert "'hexabot_leg'" in exceptions.did_you_mean("hexabot_lge", names)
    assert "'ur5_robot'" in exceptions.did_you_mean("ur5", names)
    assert exceptions.did_you_mean("zzzzzz", names) == ""


# ------------------------------------------------------------------ the per-model cache
def test_cached_builds_once_per_model_and_key():
    m1, m2 = hk.load("hexabot_leg"), hk.load("hexabot_leg")
    calls = []

    def factory():
        calls.append(1)
        return object()

    a = m1.cached("test.k", factory)
    assert m1.cached("test.k", factory) is a and len(calls) == 1
    assert m2.cached("test.k", factory) is not a and len(calls) == 2
    with pytest.raises(ZeroDivisionError):
        m1.cached("test.bad", lambda: 1 / 0)
    assert m1.cached("test.bad", lambda: 7) == 7  # a failed factory stores nothing
    # reentrant: a factory may use another cached key
    assert m1.cached("test.outer", lambda: m1.cached("test.inner", lambda: 3) + 1) == 4


def test_cached_is_thread_safe_single_build():
    import threading
    import time

    model = hk.load("hexabot_leg")
    calls = []

    def slow():
        calls.append(1)
        time.sleep(0.05)
        return len(calls)

    out = []
    threads = [
        threading.Thread(target=lambda: out.append(model.cached("test.slow", slow)))
        for _ in range(8)
    ]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert calls == [1] and out == [1] * 8


def test_arrays_extracted_once_and_match_pinocchio():
    from hexapod_kin import _kernels

    model = hk.load("hexabot_leg")
    assert model.arrays is model.arrays
    q = np.array([0.3, -0.4, 0.9])
    arrays, pos = model.arrays, np.empty(3)
    rot = np.empty((3, 3))
    args = (pos, np.empty((3, 3)), arrays.scratch(), False, arrays.tip_rot, rot)
    _kernels.fk_jac_into(*arrays.packed, q, *args)
    np.testing.assert_allclose(rot, model.fk(q)[:3, :3], atol=1e-14)
    np.testing.assert_allclose(pos, model.fk(q)[:3, 3], atol=1e-14)


# ------------------------------------------------------------------ sources
def test_sources_module_owns_resolution():
    from hexapod_kin import model as model_mod
    from hexapod_kin import sources

    assert not hasattr(model_mod, "erd_path")  # one home: no second import path
    import ast
    from pathlib import Path

    tree = ast.parse(Path(sources.__file__).read_text())
    imported = {a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
    imported |= {n.module or "" for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)}
    assert "pinocchio" not in imported  # what a source means needs no Pinocchio


def test_kinematics_imports_no_private_name_of_model():
    import ast
    from pathlib import Path

    from hexapod_kin import kinematics

    tree = ast.parse(Path(kinematics.__file__).read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module == "model":
            assert all(not a.name.startswith("_") for a in node.names), ast.dump(node)


def test_erd_alias_and_did_you_mean():
    assert erd_path("ur5") == erd_path("ur5_robot")
    assert hk.load("erd:ur5").nq == hk.load("erd:ur5_robot").nq == 6
    with pytest.raises(SourceError, match="did you mean") as info:
        erd_path("ur")  # ambiguous prefix: ur3, ur5, ur10 ...
    assert info.value.parameter == "source" and "ur5_robot" in info.value.allowed
    with pytest.raises(SourceError, match=r"did you mean 'hexabot_leg'") as info2:
        hk.load("hexabot_lge")
    assert info2.value.value == "hexabot_lge"
    with pytest.raises(SourceError, match=r"did you mean 'erd:panda'"):
        hk.load("pandaa")


def test_erd_names_lists_every_urdf_file():
    from hexapod_kin.sources import erd_share

    robots_dir = erd_share() / "example-robot-data" / "robots"
    files = set(robots_dir.rglob("*.urdf"))
    assert {erd_path(n) for n in erd_names()} == files and len(files) > 60
    assert {p.stem for p in files} <= set(erd_names())
    b, c = (
        erd_path("anymal_b_simple_description/anymal"),
        erd_path("anymal_c_simple_description/anymal"),
    )
    assert b != c and hk.load(f"erd:{c.parent.parent.name}/anymal").nq == 12


# ------------------------------------------------------------------ import cost (modules, not time)
def _modules_after(code: str) -> set[str]:
    import json
    import subprocess
    import sys

    out = subprocess.run(
        [sys.executable, "-c", code + "\nimport sys, json; print(json.dumps(sorted(sys.modules)))"],
        capture_output=True,
        text=True,
        check=True,
        timeout=600,
    )
    return set(json.loads(out.stdout.strip().splitlines()[-1]))


def test_import_pulls_no_heavy_module():
    mods = _modules_after("import hexapod_kin")
    heavy = {"pinocchio", "sympy", "numba", "scipy", "matplotlib", "yourdfpy", "meshcat", "lxml"}
    assert not heavy & {m.split(".")[0] for m in mods}
    loaded = {m for m in mods if m.startswith("hexapod_kin.")}
    assert "hexapod_kin.singularity" not in loaded and "hexapod_kin.ik" not in loaded


def test_submodules_are_lazy_attributes():
    mods = _modules_after(
        "import hexapod_kin as hk\n"
        "assert hk.kinematics.load is not None and hk.sources.erd_names\n"
        "assert 'kinematics' in dir(hk)\n"
        "try:\n    hk.no_such_module\nexcept AttributeError:\n    pass\n"
        "else:\n    raise SystemExit(3)"
    )
    assert "hexapod_kin.kinematics" in mods and "pinocchio" in mods
    import hexapod_kin as hkm

    for name in hkm._LAZY_SUBMODULES:
        import importlib.util

        exists = importlib.util.find_spec(f"hexapod_kin.{name}") is not None
        assert hasattr(hkm, name) == exists, name


# ------------------------------------------------------------------ real URDFs as they are
def _load_warned(source, **kw):
    import warnings

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        model = hk.load(source, **kw)
    return model, [w for w in caught if issubclass(w.category, exceptions.UrdfWarning)]


@pytest.mark.parametrize(
    ("name", "link", "defect"),
    [
        ("human", "left_upperleg_virtual", "has no mass"),
        ("romeo", "LFinger11Link", "has no mass"),
        ("icub", "head", "not positive definite"),
        ("romeo_small", "RShoulderYawLink", "triangle inequality"),
    ],
)
def test_implausible_inertials_warn_for_kinematics_and_refuse_for_dynamics(name, link, defect):
    from hexapod_kin.model import check_inertials

    path = erd_path(name)
    model, warned = _load_warned(path)
    assert len(warned) == 1
    text = str(warned[0].message)
    kind = {"has no mass": "have no mass"}.get(defect, defect)  # one line per kind
    line = next(ln for ln in text.splitlines() if kind in ln)
    assert link in line and "inertia='collision' or 'point'" in line
    assert any(lk == link and defect in why for lk, why in model.inertia_defects)
    raw = pin.buildModelFromUrdf(str(path))
    q = model.random_q(seed=1)
    d = raw.createData()
    pin.framesForwardKinematics(raw, d, q)
    np.testing.assert_allclose(
        model.fk(q), d.oMf[raw.getFrameId(model.tip)].homogeneous, atol=1e-12
    )
    with pytest.raises(exceptions.UrdfError, match=f"link {link!r}") as info:
        check_inertials(model)
    assert info.value.parameter == "inertial"
    with pytest.raises(exceptions.UrdfError, match="physically implausible"):
        hk.load(path, strict_inertia=True)


def test_plausible_robot_passes_check_inertials():
    from hexapod_kin.model import check_inertials

    model, warned = _load_warned("erd:solo12")
    assert warned == [] and model.inertia_defects == ()
    check_inertials(model)


def _ros_tree(tmp_path, mesh_name="a.stl", with_manifest=True):
    """A ROS-like workspace: ws/src/my_robot_description/{package.xml, urdf/r.urdf, meshes}."""
    pkg = tmp_path / "ws" / "src" / "my_robot_description"
    (pkg / "urdf").mkdir(parents=True)
    (pkg / "meshes").mkdir()
    (pkg / "meshes" / "a.stl").write_text("solid a\nendsolid a\n")
    if with_manifest:
        (pkg / "package.xml").write_text("<package><name>my_robot_description</name></package>")
    text = hk.to_urdf(hk.robots.pendulum()).replace(
        "<visual>",
        f'<visual><geometry><mesh filename="package://my_robot_description/meshes/{mesh_name}"/>'
        "</geometry></visual><visual>",
        1,
    )
    path = pkg / "urdf" / "r.urdf"
    path.write_text(text)
    return pkg, path


def test_package_uri_resolves_from_the_folders_above(tmp_path):
    pkg, path = _ros_tree(tmp_path)
    model, warned = _load_warned(path)
    assert warned == []
    assert str(pkg.parent.resolve()) in model.source.package_dirs


def test_package_uri_resolves_through_ros_package_path_and_package_dirs(tmp_path, monkeypatch):
    pkg, path = _ros_tree(tmp_path)
    elsewhere = tmp_path / "elsewhere.urdf"  # no package folder above this file
    elsewhere.write_text(path.read_text())
    _, warned = _load_warned(elsewhere)
    assert len(warned) == 1 and "package://my_robot_description/meshes/a.stl" in str(
        warned[0].message
    )
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(tmp_path / "ws"))  # found 2 levels below
    model, warned = _load_warned(elsewhere)
    assert warned == [] and str(pkg.parent) in model.source.package_dirs
    monkeypatch.delenv("ROS_PACKAGE_PATH")
    model, warned = _load_warned(elsewhere, package_dirs=[pkg.parent])
    assert warned == [] and model.source.package_dirs[0] == str(pkg.parent)


def test_missing_mesh_costs_its_visual_not_the_kinematics(tmp_path):
    _, path = _ros_tree(tmp_path, mesh_name="gone.stl")
    model, warned = _load_warned(path)
    assert len(warned) == 1
    assert "package://my_robot_description/meshes/gone.stl" in str(warned[0].message)
    assert "does not exist" in str(warned[0].message)
    reference = hk.load(hk.robots.pendulum())
    q = reference.random_q(seed=2)
    np.testing.assert_allclose(model.fk(q), reference.fk(q), atol=0)
    geom = model.geometry_model("visual")
    full = reference.geometry_model("visual")
    assert geom.ngeoms == full.ngeoms  # the dropped visual only; the other one remains


def test_hostile_mesh_uris_stay_refused(tmp_path):
    _, path = _ros_tree(tmp_path, mesh_name="../../../../../etc/passwd")
    with pytest.raises(exceptions.UrdfError, match="outside the allowed root"):
        hk.load(path)


def test_continuous_joints_take_one_angle():
    path = erd_path("double_pendulum_continuous")
    model = hk.load(path)
    assert model.nq == 2 and model.model.nq == 4  # Pinocchio: (cos, sin) per joint
    np.testing.assert_array_equal(model.lower, [-np.pi, -np.pi])
    np.testing.assert_array_equal(model.upper, [np.pi, np.pi])
    np.testing.assert_array_equal(model.neutral(), [0.0, 0.0])
    q = np.array([0.4, -1.1])
    np.testing.assert_allclose(
        model.pinocchio_q(q), [np.cos(0.4), np.sin(0.4), np.cos(-1.1), np.sin(-1.1)]
    )
    # a full turn is the same pose; FK by finite differences agrees with the Jacobian
    np.testing.assert_allclose(model.fk(q + 2 * np.pi), model.fk(q), atol=1e-12)
    jac = model.jacobian(q)
    for k in range(2):
        dq = np.zeros(2)
        dq[k] = 1e-6
        num = (model.fk(q + dq)[:3, 3] - model.fk(q - dq)[:3, 3]) / 2e-6
        np.testing.assert_allclose(jac[:3, k], num, atol=1e-8)


def test_duplicate_frame_names_prefer_the_link():
    # a link named like its joint (as anymal's URDF does): Pinocchio's getFrameId raises
    text = hk.to_urdf(hk.robots.pendulum())
    text = text.replace('name="rod"', 'name="swing"').replace('link="rod"', 'link="swing"')
    model = hk.load(text, tip="swing")
    fid = model.frame_id("swing")
    assert model.model.frames[fid].type == pin.FrameType.BODY
    assert model.tip_id == fid
    q = np.array([0.7])
    d = model.model.createData()
    pin.framesForwardKinematics(model.model, d, model.pinocchio_q(q))
    np.testing.assert_allclose(model.fk(q), (model.baseMo * d.oMf[fid]).homogeneous, atol=0)


def test_resolved_source_and_gate_result_to_dict():
    import json

    from hexapod_kin._gate import check_urdf

    resolved = resolve_source("hexabot_leg")
    d = json.loads(json.dumps(resolved.to_dict()))
    assert d["name"] == "hexabot_leg" and d["params"] == resolved.params.name
    gate = json.loads(json.dumps(check_urdf(resolved.text).to_dict()))
    assert gate["root_link"] == resolved.params.base and len(gate["joints"]) >= 3


# --------------------------------------------------------------------- default tips of URDFs
def test_default_tips_a_user_would_pick() -> None:
    """A URDF loaded without ``tip``: the arm's TCP with the gripper locked, every limb's end
    of a legged robot, a chain's last frame — each checked against raw Pinocchio's tree."""
    import pinocchio as pin

    panda = hk.load("erd:panda")
    assert panda.default_tips.kind == "gripper" and panda.tip == "panda_hand_tcp"
    assert panda.nq == 7 and set(panda.default_tips.locked) == {
        "panda_finger_joint1",
        "panda_finger_joint2",
    }
    # the TCP pose equals raw Pinocchio's on the full model with the fingers anywhere
    full = panda.full_model
    data = full.createData()
    q7 = panda.random_q(1, seed=4)[0]
    qf = pin.neutral(full)
    qf[:7] = q7
    qf[7:] = 0.02
    pin.framesForwardKinematics(full, data, qf)
    ref = data.oMf[full.getFrameId("panda_hand_tcp")].homogeneous
    assert np.abs(panda.fk(q7) - ref).max() <= 1e-12
    anymal = hk.load("erd:anymal")
    assert anymal.default_tips.kind == "limbs"
    assert sorted(anymal.default_tips.tips) == ["LF_FOOT", "LH_FOOT", "RF_FOOT", "RH_FOOT"]
    assert anymal.nq == 12  # nothing locked: fk prints every foot
    ur5 = hk.load("erd:ur5_robot")
    assert ur5.default_tips.kind == "chain" and ur5.tip == "tool0" and ur5.nq == 6
    assert hk.load("hexabot_leg").default_tips is None  # a table's own tip


def test_fk_prints_every_limb_end(capsys) -> None:
    from hexapod_kin.cli import main

    q = [str(v) for v in np.linspace(-0.3, 0.3, 12)]
    assert main(["fk", "erd:solo12", "--q", *q, "--json"]) == 0
    cap = capsys.readouterr()
    out = json.loads(cap.out)
    assert sorted(out["ends"]) == ["FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT"]
    assert "every limb's end" in cap.err  # said on one line
    raw = pin.buildModelFromUrdf(str(erd_path("solo12")))  # raw Pinocchio, no toolkit code
    data = raw.createData()
    pin.framesForwardKinematics(raw, data, np.array(q, dtype=float))
    for name, T in out["ends"].items():
        ref = data.oMf[raw.getFrameId(name)].homogeneous
        assert np.abs(np.array(T) - ref).max() <= 1e-12


# ------------------------------------------------------------------ joint kinds, floating twin
def test_joint_kinds_are_told_apart_in_one_place():
    from hexapod_kin.frames import joint_kind

    m = pin.Model()
    axis = np.array([0.0, 0.6, 0.8])
    cases = [
        (pin.JointModelRX(), "revolute", [1, 0, 0]),
        (pin.JointModelRY(), "revolute", [0, 1, 0]),
        (pin.JointModelRUBZ(), "continuous", [0, 0, 1]),
        (pin.JointModelPY(), "prismatic", [0, 1, 0]),
        (pin.JointModelRevoluteUnaligned(*axis), "revolute", axis),
        (pin.JointModelPrismaticUnaligned(*axis), "prismatic", axis),
    ]
    for k, (jm, kind, ax) in enumerate(cases):
        j = m.addJoint(0, jm, pin.SE3.Identity(), f"j{k}")
        got = joint_kind(m.joints[j])
        assert got is not None and got[0] == kind and np.array_equal(got[1], ax)
    for jm in (pin.JointModelFreeFlyer(), pin.JointModelSpherical(), pin.JointModelPlanar()):
        assert joint_kind(jm) is None
    # the loader, the batch arrays and the reference Jacobian read the same kinds
    km = hk.load(erd_path("double_pendulum_continuous"))
    assert not km.is_prismatic.any() and km.arrays.kind.tolist() == [0] * km.nq


@pytest.mark.parametrize(
    "source", ["hexapod", "erd:solo12", "erd:a1", "erd:anymal_c", "erd:double_pendulum_continuous"]
)
def test_the_floating_model_is_the_urdf_parsed_with_a_free_flyer(source):
    """Built from the loaded model (no second parse), equal (``==``: joints, limits,
    inertias, frames) to Pinocchio's own parse of the URDF with a free-flyer root."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        km = hk.load(source)
    ref = pin.buildModelFromXML(km.urdf, pin.JointModelFreeFlyer())
    ff = km.floating_model
    assert ff == ref and ff is km.floating_model  # built once, kept in the model's cache
    assert ff.nq == km.full_model.nq + 7 and ff.nv == km.full_model.nv + 6
    q = pin.integrate(ref, pin.neutral(ref), np.random.default_rng(2).normal(size=ref.nv))
    d1, d2 = ff.createData(), ref.createData()
    assert np.array_equal(pin.centerOfMass(ff, d1, q), pin.centerOfMass(ref, d2, q))
