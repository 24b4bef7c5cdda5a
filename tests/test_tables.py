"""Table files (TOML/YAML, Khalil or standard DH) as sources: FK against hand-written products."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import hexapod_kin as hk
from hexapod_kin.exceptions import ParameterError, SourceError
from hexapod_kin.tables import read_table

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
DEG = math.pi / 180


def _rx(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1.0]])


def _rz(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])


def _t(x=0.0, y=0.0, z=0.0):
    out = np.eye(4)
    out[:3, 3] = (x, y, z)
    return out


def _khalil(rows, q):
    """rows: (sigma, alpha, d, theta, r); the textbook product, written out here."""
    out, k = np.eye(4), 0
    for sigma, alpha, d, theta, r in rows:
        qi = q[k] if sigma != "fixed" else 0.0
        k += sigma != "fixed"
        th = theta + (qi if sigma == "revolute" else 0.0)
        rr = r + (qi if sigma == "prismatic" else 0.0)
        out = out @ _rx(alpha) @ _t(x=d) @ _rz(th) @ _t(z=rr)
    return out


def _dh(rows, q):
    """rows: (d, a, alpha), revolute; Rz(q) Tz(d) Tx(a) Rx(alpha)."""
    out = np.eye(4)
    for (d, a, alpha), qi in zip(rows, q):
        out = out @ _rz(qi) @ _t(z=d) @ _t(x=a) @ _rx(alpha)
    return out


LEG4 = [
    ("revolute", 0, 0, 0, 0),
    ("revolute", 90 * DEG, 0.045, 0, 0),
    ("revolute", 0, 0.110, 0, 0),
    ("revolute", 0, 0.130, 0, 0),
    ("fixed", 0, 0.060, 0, 0),
]
PRISMATIC = [
    ("revolute", 0, 0, 0, 0),
    ("revolute", 90 * DEG, 0.05, 0, 0),
    ("prismatic", 90 * DEG, 0.0, 90 * DEG, 0.08),
    ("fixed", 0, 0, 0, 0.02),
]
PUMA = [
    (0, 0, 90 * DEG),
    (0, 0.4318, 0),
    (0.15005, 0.0203, -90 * DEG),
    (0.4318, 0, 90 * DEG),
    (0, 0, -90 * DEG),
    (0, 0, 0),
]
UR5 = [
    (0.089159, 0, 90 * DEG),
    (0, -0.425, 0),
    (0, -0.39225, 0),
    (0.10915, 0, 90 * DEG),
    (0.09465, 0, -90 * DEG),
    (0.0823, 0, 0),
]


@pytest.mark.parametrize(
    ("file", "reference"),
    [
        ("leg4.toml", lambda q: _khalil(LEG4, q)),
        ("leg_prismatic.yaml", lambda q: _khalil(PRISMATIC, q)),
        ("puma560.toml", lambda q: _dh(PUMA, q)),
        ("ur5.toml", lambda q: _dh(UR5, q) @ _t(z=0.10)),
    ],
)
def test_example_tables_fk_equals_the_hand_product(file, reference):
    model = hk.load(EXAMPLES / file)
    assert model.name == file
    for q in model.random_q(25, seed=7):
        np.testing.assert_allclose(model.fk(q), reference(q), atol=1e-12)
    as_text = hk.load(str(EXAMPLES / file))  # a path given as a string
    q = model.random_q(seed=8)
    np.testing.assert_allclose(as_text.fk(q), model.fk(q), atol=0)


def test_leg4_names_limits_masses():
    chain = read_table(EXAMPLES / "leg4.toml")
    assert chain.joint_names == ("coxa", "femur", "tibia", "tarsus")
    assert chain.base == "mount" and chain.tip == "foot"
    assert chain.limits[2].lower == pytest.approx(-150 * DEG)
    assert chain.limits[0].velocity == pytest.approx(300 * DEG)
    assert chain.limits[0].effort == 8.0  # efforts are not angles
    tarsus = chain.link_inertial(3)
    assert tarsus.mass == 0.04 and tarsus.com == (0.03, 0.0, 0.0)
    coxa = chain.link_inertial(0)
    assert coxa.mass == 0.08  # a rod to the next frame: centre of mass at its middle
    np.testing.assert_allclose(coxa.com, [0.0225, 0, 0], atol=1e-15)
    model = hk.load(EXAMPLES / "leg4.toml")
    masses = {model.model.names[i]: model.model.inertias[i].mass for i in range(1, 5)}
    assert masses["tarsus"] == pytest.approx(0.04 + 0.2 * chain.link_mass)  # + the fixed foot


def test_prismatic_joint_is_metres():
    model = hk.load(EXAMPLES / "leg_prismatic.yaml")
    assert list(model.is_prismatic) == [False, False, True]
    assert (model.lower[2], model.upper[2]) == (0.0, 0.10)
    base = model.fk([0.0, 0.0, 0.0])[:3, 3]
    moved = model.fk([0.0, 0.0, 0.03])[:3, 3]
    assert np.linalg.norm(moved - base) == pytest.approx(0.03, abs=1e-14)


def test_toml_and_yaml_of_one_table_agree(tmp_path):
    yaml_text = (EXAMPLES / "leg_prismatic.yaml").read_text()
    import yaml

    data = yaml.safe_load(yaml_text)
    lines = [f'{k} = "{v}"' for k, v in data.items() if isinstance(v, str)]
    for row in data["row"]:
        lines.append("[[row]]")
        lines += [f'{k} = "{v}"' if isinstance(v, str) else f"{k} = {v}" for k, v in row.items()]
    (tmp_path / "p.toml").write_text("\n".join(lines) + "\n")
    a, b = hk.load(tmp_path / "p.toml"), hk.load(EXAMPLES / "leg_prismatic.yaml")
    for q in a.random_q(10, seed=1):
        np.testing.assert_allclose(a.fk(q), b.fk(q), atol=0)


def test_table_exports_to_urdf_and_back(tmp_path):
    model = hk.load(EXAMPLES / "ur5.toml")
    path = tmp_path / "ur5.urdf"
    hk.write_urdf(model.params, path)
    again = hk.load(path, tip="tool0")
    for q in model.random_q(10, seed=2):
        np.testing.assert_allclose(again.fk(q), model.fk(q), atol=1e-12)


def test_overrides_and_base_pose(tmp_path):
    text = (
        (EXAMPLES / "leg4.toml")
        .read_text()
        .replace(
            "link_radius = 0.012",
            "link_radius = 0.012\nbase_pose = { xyz = [0.1, 0, 0], rpy = [0, 0, 90] }",
        )
    )
    (tmp_path / "l.toml").write_text(text)
    chain = read_table(tmp_path / "l.toml", name="leg4b")
    assert chain.name == "leg4b"
    model = hk.load(tmp_path / "l.toml")
    q = np.array([0.1, 0.2, -0.3, 0.4])
    np.testing.assert_allclose(
        model.fk(q), _t(x=0.1) @ _rz(90 * DEG) @ _khalil(LEG4, q), atol=1e-12
    )


@pytest.mark.parametrize(
    ("edit", "match"),
    [
        (("alpha = 90", "alpah = 90"), r"unknown key 'alpah' \(did you mean 'alpha'"),
        (('convention = "khalil"', 'convention = "mdh"'), "convention='mdh' is not allowed"),
        (("d = 0.110", 'd = "long"'), r"row 3.d='long' is not a finite number"),
        (("mass = 0.04\n", ""), "row 4: com/inertia need a mass"),
        (("inertia = [2e-6", "# inertia = [2e-6"), "give com and inertia together"),
        (('type = "fixed"', 'type = "ball"'), "row 5"),
        (("lower = -150", "lower = 150"), "lower <= upper"),
        (("[[row]]", "[[rows]]"), r"unknown key 'rows' \(did you mean 'row'"),
        (('name = "leg4"', 'name = "leg4"\nname = "x"'), "not valid TOML"),
    ],
)
def test_bad_tables_name_the_problem(tmp_path, edit, match):
    text = (EXAMPLES / "leg4.toml").read_text()
    assert edit[0] in text
    path = tmp_path / "bad.toml"
    path.write_text(text.replace(edit[0], edit[1], 1))
    with pytest.raises((ParameterError, SourceError), match=match):
        hk.load(path)


def test_missing_table_file_and_unknown_override(tmp_path):
    with pytest.raises(SourceError, match="no such file"):
        hk.load(tmp_path / "none.toml")
    with pytest.raises(ParameterError, match="unknown key 'l1'"):
        read_table(EXAMPLES / "leg4.toml", l1=0.3)
    (tmp_path / "list.yaml").write_text("- 1\n- 2\n")
    with pytest.raises(SourceError, match="must hold a mapping"):
        hk.load(tmp_path / "list.yaml")
