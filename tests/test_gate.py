"""The loader gate: a corpus of malformed and hostile URDFs, each loaded in a child process.

Every corpus file in ``tests/urdf_corpus`` is listed in :data:`CASES` with the exact error
class, a fragment of the message and (where the error is about one element) a marker whose
line the message must name. All files are loaded by one child process (``_urdf_runner.py``)
that prints one JSON line per case, so a Pinocchio segfault fails the test of the case that
crashed instead of killing the run. The crash-prone generated cases (10,000-link chain, the
1,000-link cap itself, deep nesting, oversize) run in their own child processes.
"""

from __future__ import annotations

import json
import math
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from hexapod_kin import _gate, model, robots, sources, urdf
from hexapod_kin._gate import MAX_DOF, MAX_LINKS, MAX_URDF_BYTES, check_urdf, resolve_mesh
from hexapod_kin.exceptions import HexapodKinError, UrdfError

HERE = Path(__file__).parent
CORPUS = HERE / "urdf_corpus"
RUNNER = HERE / "_urdf_runner.py"

# case -> (error class, None for a valid control, or "warn" for a file that loads for kinematics
# with one UrdfWarning holding the fragment; message fragment; line marker or None)
CASES: dict[str, tuple[str | None, str, str | None]] = {
    # XML
    "xml_truncated_element": ("UrdfError", "not well-formed XML", None),
    "xml_truncated_attribute": ("UrdfError", "not well-formed XML", None),
    "xml_empty": ("UrdfError", "Document is empty", None),
    "xml_billion_laughs": ("UrdfError", "DOCTYPE or ENTITY declaration", None),
    "xml_xxe_file": ("UrdfError", "DOCTYPE or ENTITY declaration", None),
    "xml_xxe_parameter_entity": ("UrdfError", "DOCTYPE or ENTITY declaration", None),
    "xml_doctype_harmless": ("UrdfError", "DOCTYPE", None),
    "xml_undefined_entity": ("UrdfError", "Entity 'corpus' not defined", None),
    "xml_root_not_robot": ("UrdfError", "root element <sdf>; <robot> required", "<sdf name"),
    "xml_junk_after_root": ("UrdfError", "Extra content at the end", None),
    "xml_latin1_encoding": ("UrdfError", "encoding='ISO-8859-1' is not allowed", None),
    "xml_mismatched_tag": ("UrdfError", "tag mismatch", None),
    # structure
    "robot_no_links": ("UrdfError", "at least one link is required", None),
    # harmless defects of real robot files: mended with one warning (lenient loading)
    "robot_no_name": ("warn", "<robot> needs a non-empty name: named 'robot'", "<robot>"),
    "link_duplicate_name": ("UrdfError", "duplicate link name", '<link name="arm">'),
    "link_empty_name": ("UrdfError", "needs a non-empty name", '<link name=" "/>'),
    "link_named_universe": ("UrdfError", "reserved by Pinocchio", '<link name="universe"/>'),
    "joint_duplicate_name": (
        "UrdfError",
        "duplicate joint name (first at line 6)",
        '<joint name="j1" type="fixed">',
    ),
    "joint_parent_missing": ("UrdfError", "link='bsae': parent link does not exist", "bsae"),
    "joint_child_missing": ("UrdfError", "link='amr': child link does not exist", "amr"),
    "joint_no_parent_element": ("UrdfError", "<parent> is required", '<joint name="j1"'),
    "joint_parent_equals_child": (
        "UrdfError",
        "parent and child are the same link 'arm'",
        '<joint name="j1"',
    ),
    "joint_unknown_type": ("UrdfError", "type='ball': joint type must be one of", 'type="ball"'),
    "joint_type_missing": ("UrdfError", "type=None: joint type must be one of", "<joint name"),
    "tree_two_parents": ("UrdfError", "at most one parent joint", '<joint name="j2"'),
    "tree_cycle_with_root": ("UrdfError", "no root link", None),
    "tree_detached_cycle": ("UrdfError", "not reachable from the root 'base'", '<link name="p">'),
    "tree_two_roots": ("UrdfError", "2 root links ['base', 'floating_part']", None),
    "joint_mimic_missing": (
        "warn",
        "joint='j0': mimic must name another existing joint: <mimic> dropped",
        "<mimic",
    ),
    "joint_duplicate_axis": ("UrdfError", "<axis> given more than once", '<axis xyz="1 0 0"'),
    # numbers
    "number_nan_origin": ("UrdfError", "xyz='0 nan 0.1': 'nan' is not a decimal number", "nan"),
    "number_inf_axis": (
        "UrdfError",
        "xyz='0 0 inf': 'inf' is not a decimal number",
        'xyz="0 0 inf"',
    ),
    "number_overflow_limit": ("UrdfError", "upper='1e999': numbers must be finite", "1e999"),
    "number_short_vector": ("UrdfError", "3 number(s) required, found 2", 'xyz="0 0.1"'),
    "number_long_vector": ("UrdfError", "rpy='0 0 0 0': 3 number(s) required, found 4", "0 0 0 0"),
    "number_hex_mass": ("UrdfError", "'0x1' is not a decimal number", "0x1"),
    "number_padded_mass": ("UrdfError", "without surrounding spaces", '" 0.5 "'),
    "number_comma_decimal": ("UrdfError", "'0,5' is not a decimal number", "0,5"),
    "number_underscore": ("UrdfError", "'1_0' is not a decimal number", 'effort="1_0"'),
    "number_negative_box": ("UrdfError", "size='0.1 -0.02 0.02': must be >= 0", "-0.02"),
    "number_nan_rgba": (
        "UrdfError",
        "<material name=\"grey\"> <color> rgba='0.5 NaN 0.5 1'",
        'rgba="0.5 NaN',
    ),
    "number_empty_value": ("UrdfError", "value='': '' is not a decimal number", 'value=""'),
    "number_huge_inertial_origin": ("UrdfError", "|-1e308| exceeds 1e+09", "-1e308"),
    # materials and geometry
    "material_duplicate": (
        "UrdfError",
        "duplicate material name (first at line 4)",
        '<material name="grey"><color rgba="1 1 1 1"/>',
    ),
    "material_rgba_out_of_range": ("UrdfError", "colour components must be in [0, 1]", 'rgba="1.5'),
    "geometry_cylinder_no_length": ("UrdfError", "<cylinder length> is required", "<cylinder"),
    "geometry_two_shapes": ("UrdfError", "exactly one shape", "<geometry>"),
    "robot_bad_version": ("UrdfError", "version must be 1.0, 1.1 or 1.2", "<robot name"),
    # joints
    "joint_zero_axis": (
        "UrdfError",
        "xyz='0 0 0': joint axis has zero length",
        '<axis xyz="0 0 0"',
    ),
    "joint_lower_gt_upper": ("UrdfError", "lower='1': lower > upper='-1'", "<limit"),
    "joint_negative_velocity": ("UrdfError", "velocity='-2': must be >= 0", "<limit"),
    "joint_negative_effort": ("UrdfError", "effort='-10': must be >= 0", "<limit"),
    "joint_revolute_no_limit": ("UrdfError", "needs <limit>", '<joint name="j1"'),
    "joint_limit_no_effort": ("UrdfError", "<limit effort> is required", "<limit lower"),
    "joint_negative_damping": ("UrdfError", "damping='-0.1': must be >= 0", "<dynamics"),
    # mass and inertia
    "mass_negative": ("UrdfError", "value='-0.5': must be >= 0", "<mass"),
    "mass_moving_massless": ("warn", "1 link(s) are moving bodies that have no mass (arm;", None),
    "mass_zero_moving": ("warn", "1 link(s) are moving bodies that have no mass (arm;", None),
    "inertia_indefinite": ("warn", "1 link(s) have an indefinite inertia (arm;", "<inertia "),
    "inertia_triangle": ("warn", "violate the triangle inequality I1 + I2 ≥ I3", "<inertia "),
    "inertia_zero_moving": ("warn", "not positive definite (arm;", "<inertia "),
    "inertia_singular_offdiag": ("warn", "not positive definite", "<inertia "),
    "inertia_gyration": (
        "warn",
        "1 link(s) have a radius of gyration far beyond the robot's size (arm;",
        "<inertia ",
    ),
    "inertia_missing_entry": ("UrdfError", "izz=None: attribute is required", "<inertia "),
    "inertial_no_mass": ("UrdfError", "<mass> is required", "<inertial>"),
    # files (other schemes and absolute paths: never read nor fetched, the visual is dropped)
    "mesh_file_uri": (
        "warn",
        "refused",
        "<mesh",
    ),
    "mesh_absolute_path": (
        "warn",
        "1 file(s) refused, their visual/collision elements dropped (/etc/passwd;",
        "<mesh",
    ),
    "mesh_dotdot_escape": ("UrdfError", "outside the allowed root", "<mesh"),
    "mesh_package_without_dirs": ("warn", "no package directories", "<mesh"),
    "mesh_http_uri": (
        "warn",
        "refused, their visual/collision elements dropped (http://127.0.0.1:9/evil.stl",
        "<mesh",
    ),
    "mesh_missing_file": ("warn", "1 file(s) not found", "<mesh"),
    "mesh_directory": ("UrdfError", "is not a regular file", "<mesh"),
    "mesh_empty_filename": ("UrdfError", "empty file name", "<mesh"),
    "mesh_home_tilde": (
        "warn",
        "'~' is not expanded",
        "<mesh",
    ),
    "texture_escape": ("UrdfError", "<texture> filename='../../../../../etc/hostname'", "<texture"),
    # valid controls
    "ok_minimal": (None, "", None),
    "ok_mesh_relative": (None, "", None),
    "ok_merged_point_mass": (None, "", None),
    "ok_massless_link_with_massive_fixed_child": (None, "", None),
}


_Results = tuple[dict[str, dict], subprocess.CompletedProcess]


def _run(paths: list[Path], timeout: float = 600.0) -> _Results:
    """Load ``paths`` in one child process; map case stem -> result line."""
    proc = subprocess.run(
        [sys.executable, str(RUNNER), *map(str, paths)],
        capture_output=True,
        text=True,
        timeout=timeout,
        cwd=HERE,
    )
    results: dict[str, dict] = {}
    for line in proc.stdout.splitlines():
        rec = json.loads(line)
        if not rec.get("started"):
            results[Path(rec["case"]).stem] = rec
    return results, proc


def _lost(proc: subprocess.CompletedProcess) -> str:
    return f"child exited with {proc.returncode}; stderr tail: {proc.stderr[-600:]}"


@pytest.fixture(scope="module")
def corpus_results() -> _Results:
    return _run(sorted(CORPUS.glob("*.urdf")))


def test_corpus_lists_every_file() -> None:
    files = {p.stem for p in CORPUS.glob("*.urdf")}
    assert files == set(CASES)
    assert sum(1 for v in CASES.values() if v[0] not in (None, "warn")) >= 30


@pytest.mark.parametrize("case", sorted(CASES))
def test_corpus_case(case: str, corpus_results: _Results) -> None:
    results, proc = corpus_results
    assert case in results, f"case {case} lost (crash?): {_lost(proc)}"
    rec = results[case]
    error, fragment, marker = CASES[case]
    if error == "warn":  # loads for kinematics; one warning names the defect and its line
        assert rec["error"] is None and rec["fk_finite"] is True, rec
        assert len(rec["warnings"]) == 1, rec["warnings"]
        message = rec["warnings"][0]
        assert fragment in message, message
        if marker is not None:
            lines = (CORPUS / f"{case}.urdf").read_text(encoding="utf-8").splitlines()
            line = next(i for i, text in enumerate(lines, start=1) if marker in text)
            assert f"line {line}:" in message or f"first at line {line})" in message, message
        return
    assert rec["error"] == error, rec
    if error is None:
        assert rec["fk_finite"] is True
        assert rec["warnings"] == [], rec["warnings"]
        return
    assert fragment in rec["message"], rec["message"]
    if marker is not None:
        lines = (CORPUS / f"{case}.urdf").read_text(encoding="utf-8").splitlines()
        line = next(i for i, text in enumerate(lines, start=1) if marker in text)
        assert f"line {line}:" in rec["message"], (line, rec["message"])


def test_corpus_child_exits_cleanly(corpus_results: _Results) -> None:
    results, proc = corpus_results
    assert proc.returncode == 0, _lost(proc)
    assert len(results) == len(CASES)


# ------------------------------------------------------------------------ generated cases
def _chain_urdf(n_links: int, moving: int | None = None) -> str:
    """A serial chain of ``n_links`` links; the first ``moving`` joints revolute, then fixed."""
    moving = n_links - 1 if moving is None else moving
    parts = ['<?xml version="1.0"?>', f'<robot name="chain{n_links}">', '<link name="l0"/>']
    inertial = (
        '<inertial><mass value="0.1"/><inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" '
        'iyz="0" izz="1e-4"/></inertial>'
    )
    for i in range(1, n_links):
        kind = "revolute" if i <= moving else "fixed"
        parts.append(
            f'<joint name="j{i}" type="{kind}"><parent link="l{i - 1}"/><child link="l{i}"/>'
            f'<origin xyz="0.01 0 0" rpy="0 0 0.1"/><axis xyz="0 0 1"/>'
            f'<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
            f'<link name="l{i}">{inertial}</link>'
        )
    parts.append("</robot>")
    return "\n".join(parts) + "\n"


@pytest.mark.parametrize(
    ("name", "n_links", "moving", "error", "fragment"),
    [
        ("chain_10000", 10_000, None, "UrdfError", "10000 links; the cap is 1000"),
        ("chain_1001", MAX_LINKS + 1, 1, "UrdfError", f"{MAX_LINKS + 1} links; the cap is"),
        ("dof_129", MAX_DOF + 2, None, "UrdfError", f"{MAX_DOF + 1} degrees of freedom; the cap"),
        ("chain_1000_fixed", MAX_LINKS, 3, None, ""),
        ("dof_128", MAX_DOF + 1, None, None, ""),
    ],
)
@pytest.mark.slow
def test_long_chains_in_child(
    tmp_path: Path,
    name: str,
    n_links: int,
    moving: int | None,
    error: str | None,
    fragment: str,
) -> None:
    """Chains at and past the caps, in a child: past them refused, at them loaded, no crash."""
    path = tmp_path / f"{name}.urdf"
    path.write_text(_chain_urdf(n_links, moving))
    results, proc = _run([path], timeout=300)
    assert name in results, _lost(proc)
    rec = results[name]
    assert rec["error"] == error, rec
    assert fragment in rec["message"]
    if error is None:
        assert rec["fk_finite"] is True
        assert rec["nq"] == (n_links - 1 if moving is None else moving)


def test_deep_nesting_in_child(tmp_path: Path) -> None:
    depth = 10_000
    text = '<robot name="deep"><link name="a">' + "<visual>" * depth + "</visual>" * depth
    path = tmp_path / "deep.urdf"
    path.write_text(text + "</link></robot>")
    results, proc = _run([path])
    assert results["deep"]["error"] == "UrdfError", _lost(proc)
    assert "not well-formed XML" in results["deep"]["message"]
    assert "depth" in results["deep"]["message"].lower()


def test_oversize_file_and_text(tmp_path: Path) -> None:
    text = _chain_urdf(3).replace("<robot", "<!--" + "x" * (MAX_URDF_BYTES + 10) + "-->\n<robot")
    path = tmp_path / "big.urdf"
    path.write_text(text)
    results, proc = _run([path])
    assert results["big"]["error"] == "UrdfError", _lost(proc)
    assert f"exceeds the cap of {MAX_URDF_BYTES} bytes" in results["big"]["message"]
    with pytest.raises(UrdfError, match="exceeds the cap"):
        check_urdf(text)


# ------------------------------------------------------------------------ what must pass
PRESET_TEXTS = [(n, urdf.to_urdf(robots.get(n))) for n in robots.names()] + [
    ("hexapod:leg1", urdf.to_urdf(robots.hexapod(), leg="leg1")),
    ("hexapod:leg4", urdf.to_urdf(robots.hexapod(), leg="leg4")),
]


@pytest.mark.parametrize(("name", "text"), PRESET_TEXTS, ids=[n for n, _ in PRESET_TEXTS])
def test_gate_accepts_generated(name: str, text: str) -> None:
    result = check_urdf(text)
    assert result.root.tag == "robot"
    assert result.meshes == ()
    assert len(result.links) == len(result.joints) + 1


#: example-robot-data robots the gate accepts (56 of 66 in ERD 6.0.0; solo12 is required).
ERD_PASS = [
    "solo12",
    "solo",
    "ur5_robot",
    "ur10_robot",
    "panda",
    "go2",
    "a1",
    "kinova",
    "bolt",
    "double_pendulum",
    "z1",
    "xarm7",
    "talos_full_v2",
    "talos_reduced",
    "baxter",
    "anymal",
    "finger_edu",
    "quadruped",
    "so101",
    "allegro_left_hand",
    "pr2",
    "hyq_no_sensors",
]
#: ... and those it refuses, each for a real defect of the file.
ERD_REFUSED = {
    "ur3": "<robot> needs a non-empty name",  # Pinocchio refuses it too
    "alex_psyonic_hands": "joint='index_q1': mimic must name another existing joint",
    "human": "moved by joint 'left_hip_Z' has no mass",  # massless virtual links
    "romeo": "moved by joint 'LHand' has no mass",
    "icub": "moved by joint 'neck_yaw' has an inertia that is not positive definite",
    "romeo_small": "violate the triangle inequality",
    "romeo_laas_small": "inertia is indefinite",
    "tiago": "inertia is indefinite",
}


def _erd_check(name: str) -> _gate.GateResult:
    path = sources.erd_path(name)
    return check_urdf(
        path.read_text(encoding="utf-8"),
        package_dirs=(str(sources.erd_share()),),
        mesh_root=str(path.parent),
    )


@pytest.mark.parametrize("name", ERD_PASS)
def test_gate_accepts_erd(name: str) -> None:
    result = _erd_check(name)
    for _uri, path in result.meshes:
        assert path.is_file()
        assert str(path).startswith(os.path.realpath(sources.erd_share()))


@pytest.mark.parametrize("name", sorted(ERD_REFUSED))
def test_gate_refuses_defective_erd(name: str) -> None:
    with pytest.raises(UrdfError, match="line [0-9]+|URDF") as info:
        _erd_check(name)
    assert ERD_REFUSED[name] in str(info.value)


def test_solo12_loads_with_meshes_checked() -> None:
    from hexapod_kin.kinematics import load

    leg = load("erd:solo12", tip="FL_FOOT")
    assert leg.nq == 3
    meshes = _erd_check("solo12").meshes
    # one per <mesh> of the file, in order, each an existing file under the package's folder
    text = sources.erd_path("solo12").read_text(encoding="utf-8")
    assert [uri for uri, _ in meshes] == re.findall(r'<mesh filename="([^"]+)"', text)
    share = Path(sources.erd_share()).resolve()
    for uri, path in meshes:
        rel = uri.removeprefix("package://").split("/", 1)[1]
        assert Path(path).resolve() == (share / "example-robot-data" / rel).resolve()
        assert Path(path).is_file()
    assert len(meshes) == 34


# ------------------------------------------------------------------------ mesh roots
def _with_mesh(filename: str) -> str:
    text = (CORPUS / "ok_minimal.urdf").read_text(encoding="utf-8")
    return text.replace(
        '<geometry><box size="0.1 0.02 0.02"/></geometry>',
        f'<geometry><mesh filename="{filename}"/></geometry>',
    )


def test_package_uri_resolution_and_escapes(tmp_path: Path) -> None:
    pkg = tmp_path / "share" / "mypkg" / "meshes"
    pkg.mkdir(parents=True)
    (pkg / "a.stl").write_text("solid a\nendsolid a\n")
    (tmp_path / "secret.txt").write_text("secret")
    share = str(tmp_path / "share")
    ok = check_urdf(_with_mesh("package://mypkg/meshes/a.stl"), package_dirs=(share,))
    assert ok.meshes == (("package://mypkg/meshes/a.stl", pkg.resolve() / "a.stl"),)
    # Pinocchio's "package:///pkg/path" form resolves the same way.
    ok3 = check_urdf(_with_mesh("package:///mypkg/meshes/a.stl"), package_dirs=(share,))
    assert ok3.meshes[0][1] == pkg.resolve() / "a.stl"
    for bad, fragment in [
        ("package://mypkg/../../secret.txt", "outside the allowed root"),
        ("package://mypkg/meshes/../../../secret.txt", "outside the allowed root"),
        ("package://../secret.txt", "must be package://<package>/<path>"),
        ("package://mypkg", "must be package://<package>/<path>"),
        ("package://mypkg/meshes/none.stl", "does not exist"),
    ]:
        with pytest.raises(UrdfError, match="line 21: .*<mesh>") as info:
            check_urdf(_with_mesh(bad), package_dirs=(share,))
        assert fragment in str(info.value), (bad, str(info.value))


def test_symlink_and_special_files_refused(tmp_path: Path) -> None:
    (tmp_path / "meshes").mkdir()
    outside = tmp_path.parent / f"{tmp_path.name}_outside.stl"
    outside.write_text("solid o\nendsolid o\n")
    os.symlink(outside, tmp_path / "meshes" / "link.stl")
    with pytest.raises(UrdfError, match="outside the allowed root"):
        check_urdf(_with_mesh("meshes/link.stl"), mesh_root=tmp_path)
    os.mkfifo(tmp_path / "meshes" / "fifo.stl")
    with pytest.raises(UrdfError, match="is not a regular file"):
        check_urdf(_with_mesh("meshes/fifo.stl"), mesh_root=tmp_path)
    # a symlink that stays inside the root is fine
    (tmp_path / "meshes" / "real.stl").write_text("solid r\nendsolid r\n")
    os.symlink(tmp_path / "meshes" / "real.stl", tmp_path / "meshes" / "alias.stl")
    ok = check_urdf(_with_mesh("meshes/alias.stl"), mesh_root=tmp_path)
    assert ok.meshes[0][1] == (tmp_path / "meshes" / "real.stl").resolve()


def test_relative_mesh_in_text_source_refused() -> None:
    with pytest.raises(UrdfError, match="no mesh root"):
        check_urdf(_with_mesh("meshes/ok.stl"))
    result = check_urdf(_with_mesh("meshes/ok.stl"), mesh_root=CORPUS)
    assert result.meshes[0][1] == (CORPUS / "meshes" / "ok.stl").resolve()


def test_resolve_mesh_messages() -> None:
    with pytest.raises(UrdfError, match="refused: only mesh files"):
        resolve_mesh("FILE:///etc/passwd", mesh_root=CORPUS)
    with pytest.raises(UrdfError, match="refused: URI scheme 'c'"):
        resolve_mesh("c:/windows/system.ini", mesh_root=CORPUS)


# ------------------------------------------------------------------------ inertia
def test_principal_moments_of_rotated_diagonal_tensors() -> None:
    # R diag(a, b, c) Rᵀ has principal moments a, b, c (ascending), whatever the rotation R.
    from hexapod_kin.params import rpy_to_matrix

    rng = np.random.default_rng(1)
    for _ in range(200):
        moments = np.sort(rng.uniform(-1.0, 1.0, 3)) * 10.0 ** rng.integers(-8, 3)
        rot = rpy_to_matrix(*rng.uniform(-np.pi, np.pi, 3))
        m = rot @ np.diag(moments) @ rot.T
        ours = _gate.principal_moments(m[0, 0], m[1, 1], m[2, 2], m[0, 1], m[0, 2], m[1, 2])
        assert np.allclose(ours, moments, rtol=0, atol=1e-12 * np.abs(moments).max())


def _merged_body(points: list[tuple[float, float, float]], own_mass: float = 0.0) -> str:
    """A revolute link (mass ``own_mass``, no inertia) with point masses fixed to it."""
    own = (
        f'<inertial><mass value="{own_mass}"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" '
        'iyz="0" izz="0"/></inertial>'
        if own_mass
        else ""
    )
    parts = [
        '<robot name="m">',
        '<link name="base"/>',
        '<joint name="j" type="revolute"><parent link="base"/><child link="arm"/>'
        '<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>',
        f'<link name="arm">{own}</link>',
    ]
    for i, p in enumerate(points):
        parts.append(
            f'<link name="p{i}"><inertial><mass value="0.5"/><inertia ixx="0" ixy="0" ixz="0" '
            f'iyy="0" iyz="0" izz="0"/></inertial></link>'
            f'<joint name="f{i}" type="fixed"><parent link="arm"/><child link="p{i}"/>'
            f'<origin xyz="{p[0]} {p[1]} {p[2]}" rpy="0.3 0.2 0.1"/></joint>'
        )
    return "\n".join(parts + ["</robot>"])


def test_merged_body_inertia_matches_pinocchio() -> None:
    import pinocchio as pin

    # Three non-collinear point masses fixed to a massless moving link: a valid body.
    pts = [(0.1, 0.0, 0.0), (0.0, 0.2, 0.0), (0.0, 0.0, 0.3)]
    text = _merged_body(pts)
    check_urdf(text)
    body = pin.buildModelFromXML(text).inertias[1]
    assert math.isclose(body.mass, 1.5, rel_tol=1e-14)
    # Independent: the inertia of point masses about their centre of mass.
    p = np.array(pts)
    c = p.mean(axis=0)
    ref = sum(0.5 * ((x - c) @ (x - c) * np.eye(3) - np.outer(x - c, x - c)) for x in p)
    assert np.allclose(body.inertia, ref, atol=1e-15)
    # Two point masses on a line: singular about that line, refused.
    with pytest.raises(UrdfError, match="merged with the links fixed to it: 2 inertials"):
        check_urdf(_merged_body(pts[:2]))
    # A single point mass: not positive definite.
    with pytest.raises(UrdfError, match="not positive definite"):
        check_urdf(_merged_body(pts[:1]))


# ------------------------------------------------------------------------ misc behaviour
def test_errors_are_one_family() -> None:
    assert issubclass(UrdfError, HexapodKinError)
    with pytest.raises(HexapodKinError):
        check_urdf("<robot")


def test_bytes_input_and_non_utf8_declared() -> None:
    text = (CORPUS / "ok_minimal.urdf").read_text(encoding="utf-8")
    assert check_urdf(text.encode("utf-8")).links == ("base", "arm")
    utf16 = text.replace('encoding="utf-8"', 'encoding="utf-16"').encode("utf-16")
    with pytest.raises(UrdfError):
        check_urdf(utf16)


def test_cache_only_for_documents_without_files() -> None:
    text = urdf.to_urdf(robots.get("pendulum"))
    assert check_urdf(text) is check_urdf(text)
    with_mesh = _with_mesh("meshes/ok.stl")
    assert check_urdf(with_mesh, mesh_root=CORPUS) is not check_urdf(with_mesh, mesh_root=CORPUS)
    with pytest.raises(UrdfError, match="no mesh root"):
        check_urdf(with_mesh)  # not served from a cache filled with mesh_root given


def test_pinocchio_refusal_is_wrapped(monkeypatch: pytest.MonkeyPatch) -> None:
    from hexapod_kin.kinematics import load

    monkeypatch.setattr(model, "check_urdf", lambda *a, **k: _gate.GateResult(root=None))
    bad = _with_mesh("x").replace('<robot name="corpus">', "<robot>")
    with pytest.raises(UrdfError, match="passed the loader gate but Pinocchio refused it"):
        load(bad)


def test_non_fixed_joint_without_limit_continuous_ok() -> None:
    text = (CORPUS / "ok_minimal.urdf").read_text(encoding="utf-8")
    cont = text.replace('type="revolute"', 'type="continuous"').replace(
        '<limit lower="-1" upper="1" effort="10" velocity="2"/>', ""
    )
    check_urdf(cont)
    # Limits default to 0 as in the URDF spec: lower = upper = 0 is allowed.
    zero = text.replace('lower="-1" upper="1" ', "")
    check_urdf(zero)


# ------------------------------------------------------------------ absolute and file:// meshes
def _box_stl(path: Path, lo: tuple[float, float, float], hi: tuple[float, float, float]) -> None:
    """A binary STL of the box [lo, hi] (12 triangles)."""
    import struct

    c = np.array(
        [[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
    )
    faces = [(0, 1, 3), (0, 3, 2), (4, 6, 7), (4, 7, 5), (0, 4, 5), (0, 5, 1),
             (2, 3, 7), (2, 7, 6), (0, 2, 6), (0, 6, 4), (1, 5, 7), (1, 7, 3)]  # fmt: skip
    out = bytearray(b"\0" * 80 + struct.pack("<I", len(faces)))
    for f in faces:
        out += struct.pack("<3f", 0, 0, 0) + b"".join(struct.pack("<3f", *c[i]) for i in f)
        out += b"\0\0"
    path.write_bytes(bytes(out))


def test_absolute_and_file_uri_meshes_read_for_a_file_loaded_urdf(tmp_path: Path) -> None:
    elsewhere = tmp_path / "elsewhere" / "my pkg"
    elsewhere.mkdir(parents=True)
    mesh = elsewhere / "part.stl"
    _box_stl(mesh, (0, 0, 0), (1, 1, 1))
    (elsewhere / "notes.txt").write_text("not a mesh")
    os.symlink("/etc/hostname", elsewhere / "sneaky.stl")
    (elsewhere / "empty.stl").write_bytes(b"")
    root = tmp_path / "robot"
    root.mkdir()
    uri = "file://" + str(mesh).replace(" ", "%20")
    for name in (str(mesh), uri, "file://localhost" + str(mesh)):
        assert check_urdf(_with_mesh(name), mesh_root=root).meshes[0][1] == mesh.resolve()
    cases = [
        (str(mesh), None, "refused: absolute and file:// paths are read only when the URDF"),
        (str(elsewhere / "notes.txt"), root, "refused: only mesh files (.stl, .dae, .obj, .ply)"),
        (str(elsewhere / "sneaky.stl"), root, "refused: only mesh files"),
        ("file://host" + str(mesh), root, "refused: a file:// URI must name a local absolute"),
        ("~/part.stl", root, "refused: '~' is not expanded"),
        (str(elsewhere / "gone.stl"), root, "not found: file"),
        (str(elsewhere / "empty.stl"), root, "empty: "),
    ]
    for name, mesh_root, fragment in cases:
        with pytest.raises(UrdfError, match="line 21: .*<mesh>") as info:
            check_urdf(_with_mesh(name), mesh_root=mesh_root)
        assert fragment in str(info.value), (name, str(info.value))
        lenient = check_urdf(_with_mesh(name), mesh_root=mesh_root, lenient=True)
        assert [u for u, _ in lenient.missing_meshes] == [name]


def test_warning_says_refused_empty_or_not_found_in_one_line_each(tmp_path: Path) -> None:
    import warnings

    from hexapod_kin.exceptions import UrdfWarning
    from hexapod_kin.kinematics import load

    good, empty = tmp_path / "good.stl", tmp_path / "empty.stl"
    _box_stl(good, (0, 0, 0), (0.01, 0.01, 0.01))
    empty.write_bytes(b"")
    text = (CORPUS / "ok_minimal.urdf").read_text(encoding="utf-8")
    extra = "".join(
        f'<visual><geometry><mesh filename="{n}"/></geometry></visual>'
        for n in ("file://" + str(good), str(empty), "/etc/hostname", str(tmp_path / "no.stl"))
    )
    path = tmp_path / "r.urdf"
    path.write_text(text.replace("<visual>", f"{extra}<visual>", 1))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        model = load(path)
    ours = [w for w in caught if issubclass(w.category, UrdfWarning)]
    assert len(ours) == 1 and ours[0].filename == __file__  # the caller's line, not ours
    lines = str(ours[0].message).splitlines()
    assert [ln.split(": ", 1)[1].split(",")[0] for ln in lines] == [
        "meshes: 1 file(s) empty",
        "meshes: 1 file(s) refused",
        "meshes: 1 file(s) not found",
    ], lines
    assert model.mesh_files["file://" + str(good)] == str(good.resolve())
    geom = model.geometry_model("visual")  # the good mesh drawn, the three others dropped
    meshes = [g for g in geom.geometryObjects if str(g.meshPath).endswith(".stl")]
    assert [str(g.meshPath) for g in meshes] == [str(good.resolve())]
    np.testing.assert_allclose(np.ptp(np.asarray(meshes[0].geometry.vertices()), axis=0), 0.01)


# ------------------------------------------------------------------ inertia repairs
PHANTOMX = HERE / "data" / "phantomx" / "phantomx.urdf"


def _load_quiet(source, **kw):
    import warnings

    from hexapod_kin.kinematics import load

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        m = load(source, **kw)
    return m, [str(w.message) for w in caught]


def _triangle_ok(inertia: np.ndarray) -> bool:
    e = np.linalg.eigvalsh(inertia)
    return bool(e[0] > 0 and e[0] + e[1] >= e[2] * (1 - 1e-9))


def test_phantomx_warning_is_one_short_line_per_kind() -> None:
    _, messages = _load_quiet(PHANTOMX)
    inertia = [m for m in messages if "inertia:" in m]
    assert len(inertia) == 1 and "\n" not in inertia[0] and len(inertia[0]) < 300, inertia
    assert (
        "18 link(s) violate the triangle inequality I1 + I2 ≥ I3 (c1_rf, thigh_rf, tibia_rf, …"
        in (inertia[0])
    )
    assert "inertia='collision' or 'point'" in inertia[0]
    assert all(len(m) < 400 for m in messages)


@pytest.mark.parametrize("mode", ["point", "collision"])
def test_phantomx_repaired_keeps_masses_and_coms_and_passes_dynamics(mode: str) -> None:
    from hexapod_kin.model import check_inertials

    raw = model.pin.buildModelFromUrdf(str(PHANTOMX))  # the file as Pinocchio reads it
    rep, messages = _load_quiet(PHANTOMX, inertia=mode)
    assert rep.inertia_defects == ()
    check_inertials(rep)  # dynamics accepts it
    full = rep.full_model
    assert full.nv == raw.nv == 18
    assert sum(not _triangle_ok(raw.inertias[i].inertia) for i in range(1, raw.njoints)) == 18
    for i in range(1, raw.njoints):
        a, b = full.inertias[i], raw.inertias[i]
        assert a.mass == pytest.approx(b.mass, rel=1e-12)
        np.testing.assert_allclose(a.lever, b.lever, atol=1e-12)
        assert _triangle_ok(a.inertia), (full.names[i], np.linalg.eigvalsh(a.inertia))
    # without the package's meshes "collision" falls back to point masses, and says so
    assert rep.inertia_repair is not None
    assert len(rep.inertia_repair.as_point) == 25 and not rep.inertia_repair.from_collision
    assert any(
        f"inertia={mode!r}: masses and centres of mass kept; 25 link(s)" in m for m in messages
    )
    # a single link: the point repair is a sphere of radius 1 cm about the (unmoved) COM
    tibia = full.inertias[full.getJointId("j_tibia_lf")]
    np.testing.assert_allclose(tibia.inertia, np.eye(3) * 0.4 * tibia.mass * 0.01**2, atol=1e-15)
    m = model.pin.crba(full, full.createData(), model.pin.neutral(full))
    assert np.linalg.eigvalsh((m + m.T) / 2)[0] > 0


def test_collision_repair_matches_closed_forms(tmp_path: Path) -> None:
    """Box, cylinder, sphere and a scaled STL mesh: each link's inertia about its COM."""
    import pinocchio as pin

    _box_stl(tmp_path / "m.stl", (0.0, -0.01, 0.0), (0.04, 0.01, 0.02))  # box 0.04×0.02×0.02
    xyz, rpy = np.array([0.05, 0.01, -0.02]), (0.3, -0.2, 0.7)
    org = f'<origin xyz="{xyz[0]} {xyz[1]} {xyz[2]}" rpy="{rpy[0]} {rpy[1]} {rpy[2]}"/>'
    bad = '<inertia ixx="1" iyy="1" izz="3" ixy="0" ixz="0" iyz="0"/>'
    links = {
        "box": (f'{org}<geometry><box size="0.1 0.04 0.02"/></geometry>', org),
        "cyl": ('<origin xyz="0 0 0.1"/><geometry><cylinder radius="0.02" length="0.2"/>'
                "</geometry>", '<origin xyz="0 0 0.05"/>'),
        "ball": ('<geometry><sphere radius="0.03"/></geometry>', ""),
        "mesh": ('<origin rpy="0 0 1.5707963267948966"/><geometry>'
                 '<mesh filename="m.stl" scale="2 1 1"/></geometry>', ""),
    }  # fmt: skip
    parts = ['<robot name="r"><link name="base"/>']
    for k, (name, (coll, iorg)) in enumerate(links.items()):
        parts.append(
            f'<link name="{name}"><inertial>{iorg}<mass value="{k + 1.5}"/>{bad}</inertial>'
            f"<collision>{coll}</collision></link>"
            f'<joint name="j{name}" type="revolute"><parent link="base"/><child link="{name}"/>'
            f'<origin xyz="{k} 0 0"/><axis xyz="0 0 1"/>'
            '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
        )
    path = tmp_path / "r.urdf"
    path.write_text("".join(parts) + "</robot>")
    rep, _ = _load_quiet(path, inertia="collision")
    assert rep.inertia_repair.from_collision == list(links) and rep.inertia_defects == ()
    got = {n: rep.full_model.inertias[rep.full_model.getJointId(f"j{n}")] for n in links}
    mass = {n: k + 1.5 for k, n in enumerate(links)}

    def box(m, a, b, c):
        return m / 12 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])

    rot = pin.rpy.rpyToMatrix(*rpy)
    expected = {
        "box": rot @ box(mass["box"], 0.1, 0.04, 0.02) @ rot.T,  # collision at the COM
        "cyl": np.diag([(3 * 0.02**2 + 0.2**2) / 12] * 2 + [0.02**2 / 2]) * mass["cyl"]
        + mass["cyl"] * (0.05**2 * np.diag([1.0, 1.0, 0.0])),  # centroid 5 cm above the COM
        "ball": np.eye(3) * 0.4 * mass["ball"] * 0.03**2,
    }
    # the mesh: bounding box 0.08×0.02×0.02 (x scaled by 2) centred at (0.04, 0, 0.01) in the
    # mesh frame, turned 90° about z: 0.02×0.08×0.02 centred at (0, 0.04, 0.01); COM at 0
    d = np.array([0.0, 0.04, 0.01])
    mm = mass["mesh"]
    expected["mesh"] = box(mm, 0.02, 0.08, 0.02) + mm * (d @ d * np.eye(3) - np.outer(d, d))
    for n in links:
        assert got[n].mass == pytest.approx(mass[n])
        np.testing.assert_allclose(got[n].inertia, expected[n], rtol=1e-6, atol=1e-12, err_msg=n)
        assert _triangle_ok(got[n].inertia)
    np.testing.assert_allclose(got["box"].lever, xyz, atol=1e-12)
    np.testing.assert_allclose(got["cyl"].lever, [0, 0, 0.05], atol=1e-12)


def test_inertia_option_refuses_unknown_modes() -> None:
    from hexapod_kin.exceptions import ParameterError
    from hexapod_kin.kinematics import load

    with pytest.raises(ParameterError, match="'urdf', 'collision', 'point'") as info:
        load("hexabot_leg", inertia="mesh")
    assert info.value.parameter == "inertia"


def test_cli_torques_with_repaired_inertias(capsys) -> None:
    """``torques --inertia point|collision``: static torques need only masses and COMs."""
    from hexapod_kin.cli import main

    args = ["torques", str(PHANTOMX), "--tip", "tibia_lf", "--q", "0.2", "0.5", "-0.7", "--json"]
    assert main(args) == 2  # the file's inertias: refused, one line naming the repair
    assert "inertia='collision' or 'point'" in capsys.readouterr().err
    got = {}
    for mode in ("point", "collision"):
        assert main([*args, "--inertia", mode]) == 0
        got[mode] = json.loads(capsys.readouterr().out)
    raw = model.pin.buildModelFromUrdf(str(PHANTOMX))  # gravity: masses and COMs alone
    leg = [raw.joints[raw.getJointId(n)].idx_q for n in ("j_c1_lf", "j_thigh_lf", "j_tibia_lf")]
    q = np.zeros(18)
    q[leg] = [0.2, 0.5, -0.7]  # the other legs locked at 0, as --tip does
    g = model.pin.computeGeneralizedGravity(raw, raw.createData(), q)
    for out in got.values():
        np.testing.assert_allclose(out["gravity"], g[leg], atol=1e-12)


def test_cli_prints_the_loader_warnings_as_plain_lines() -> None:
    """``hexapod-kin: warning: ...``: one line per kind, no file:line, no source line."""
    env = {**os.environ, "PYTHONPATH": str(HERE.parent)}
    cmd = [sys.executable, "-m", "hexapod_kin", "fk", str(PHANTOMX), "--tip", "tibia_lf"]
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=600, env=env)
    assert done.returncode == 0, done.stderr
    lines = done.stderr.splitlines()
    assert [ln.split(": ")[3] for ln in lines] == ["meshes", "inertia"], lines
    assert all(ln.startswith("hexapod-kin: warning: 'phantomx.urdf': ") for ln in lines)
    assert len(done.stderr) < 700
