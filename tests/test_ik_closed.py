"""Closed-form IK of the leg families, checked by Pinocchio FK (``ik.closed``)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import hexapod_kin as hk
from hexapod_kin import ik, robots
from hexapod_kin.exceptions import IKError
from hexapod_kin.params import Chain, JointLimits, KhalilRow


def _fk_many(model, qs):
    return np.array([model.position(q) for q in qs])


def _wrapdiff(a, b):
    return np.remainder(a - b + np.pi, 2 * np.pi) - np.pi


# ------------------------------------------------------------------ family detection
@pytest.mark.parametrize(
    ("preset", "family"),
    [("coxa_tibia_leg", "coxa_tibia"), ("hexabot_leg", "leg3"), ("scara", "scara")],
)
def test_family_from_table(preset, family):
    chain = robots.get(preset)
    assert ik.detect_family(chain).family == family
    # same table, another name and other lengths: still recognised (pattern, not name)
    renamed = chain.replace(name="renamed_robot")
    assert ik.detect_family(renamed).family == family
    assert ik.detect_family(hk.load(chain)).family == family


def test_no_closed_form_is_a_clear_error():
    with pytest.raises(IKError, match="no closed-form IK"):
        ik.detect_family(robots.pendulum())
    leg = robots.hexabot_leg(alpha2=0.3)  # not a ±π/2 twist: no closed form
    with pytest.raises(IKError, match="leg3"):
        ik.analytic(leg, [0.1, 0.0, 0.0])
    from_urdf = hk.load(hk.to_urdf(robots.hexabot_leg()))  # URDF text: no table
    with pytest.raises(IKError, match="ik.solve"):
        ik.analytic(from_urdf, [0.1, 0.0, 0.0])


# ------------------------------------------------------------------ seed 002 (2-DOF)
def test_seed002_points_and_tibia_sign():
    chain = robots.coxa_tibia_leg()
    c30 = 10 + 5 * math.cos(math.radians(30))
    # the seed's P1 (0°, −30°) and P2 (20°, −30°)
    p1 = [c30, 0.0, -2.5]
    p2 = [c30 * math.cos(math.radians(20)), c30 * math.sin(math.radians(20)), -2.5]
    np.testing.assert_allclose(p2, [13.4659, 4.9012, -2.5], atol=1e-4)
    s1 = ik.analytic(chain, p1)[0]
    s2 = ik.analytic(chain, p2)[0]
    np.testing.assert_allclose(s1, np.radians([[0.0, -30.0]]), atol=1e-12)
    np.testing.assert_allclose(s2, np.radians([[20.0, -30.0]]), atol=1e-12)
    # +30° lifts the foot: the seed's θ2 = 180° − β gives the same value for both; we do not
    s_up = ik.analytic(chain, [c30, 0.0, +2.5])[0]
    np.testing.assert_allclose(s_up, np.radians([[0.0, 30.0]]), atol=1e-12)
    beta = lambda p: math.degrees(  # noqa: E731 - the seed's formula (11)
        math.acos((10**2 + 5**2 - sum(v * v for v in p)) / (2 * 10 * 5))
    )
    assert beta(p1) == pytest.approx(beta([c30, 0.0, 2.5]))


def test_coxa_tibia_off_surface_has_no_solution():
    chain = robots.coxa_tibia_leg()
    assert ik.analytic(chain, [14.0, 0.0, -2.5])[0].shape == (0, 2)  # not on the reachable surface


# ------------------------------------------------------------------ FK(IK(x)) = x, 10,000 targets
@pytest.mark.parametrize("preset", ["coxa_tibia_leg", "hexabot_leg", "scara"])
def test_closed_form_roundtrip_10000(preset):
    chain = robots.get(preset)
    model = hk.load(chain)
    qs = model.random_q(10_000, seed=11)
    targets = _fk_many(model, qs)
    batch = ik.analytic_batch(chain, targets)
    assert batch.reachable.all()
    scale = ik.detect_family(chain).scale
    worst = 0.0
    found = np.zeros(len(qs), dtype=bool)
    for i in range(len(qs)):
        sols = batch.q[i][batch.valid[i]]
        back = _fk_many(model, sols)
        worst = max(worst, float(np.max(np.abs(back - targets[i]))))
        d = _wrapdiff(sols, qs[i])
        if preset == "scara":
            d = d[:, [0, 1, 3]]  # θ3 is free for a position target (we return θ3 = 0)
            d[:, 2] = sols[:, 3] - qs[i, 3]
        found[i] = np.any(np.max(np.abs(d), axis=1) < 1e-7)
    assert worst <= 1e-9 * max(scale, 1.0)
    # the configuration the target came from is among the solutions (all branches are there)
    assert found.all()


def test_leg3_all_four_solutions_distinct_and_correct():
    chain = robots.hexabot_leg()
    model = hk.load(chain)
    target = model.position([0.4, 1.0, 1.5])  # foot close to the hip axis: reachable reversed
    sols = ik.analytic(chain, target)[0]
    assert sols.shape == (4, 3)  # hip toward/reversed × both knee branches
    np.testing.assert_allclose(_fk_many(model, sols), np.tile(target, (4, 1)), atol=1e-15)
    assert len({tuple(np.round(s, 9)) for s in sols}) == 4


def test_scara_yaw_target_sets_tool_yaw():
    chain = robots.scara()
    model = hk.load(chain)
    target = [0.3, 0.2, 0.4, 0.7]
    sols = ik.analytic(chain, target)[0]
    assert sols.shape == (2, 4)
    for s in sols:
        pose = model.fk(s)
        np.testing.assert_allclose(pose[:3, 3], target[:3], atol=1e-14)
        assert math.atan2(pose[1, 0], pose[0, 0]) == pytest.approx(0.7, abs=1e-12)
    # position only: θ3 = 0
    assert np.all(ik.analytic(chain, target[:3])[0][:, 2] == 0.0)


def test_unreachable_closed_form_and_limits_filter():
    chain = robots.hexabot_leg()
    assert ik.analytic(chain, [1.0, 0.0, 0.0])[0].shape == (0, 3)
    assert ik.analytic(robots.scara(), [1.0, 0.0, 0.4])[0].shape == (0, 4)
    lim = tuple(JointLimits(-0.5, 1.6) for _ in range(3))
    limited = robots.hexabot_leg(limits=lim)
    target = hk.load(chain).position([0.4, 0.3, 1.2])
    sols = ik.analytic(limited, target, within_limits=True)[0]
    assert sols.shape == (1, 3)
    np.testing.assert_allclose(sols[0], [0.4, 0.3, 1.2], atol=1e-12)


def test_vectorised_list_and_batch_shapes():
    chain = robots.hexabot_leg()
    model = hk.load(chain)
    targets = _fk_many(model, model.random_q(5, seed=2))
    out = ik.analytic(chain, targets)
    assert isinstance(out, list) and len(out) == 5
    single = ik.analytic(chain, targets[0])  # one type whatever the input: a list
    assert isinstance(single, list) and len(single) == 1
    np.testing.assert_array_equal(single[0], out[0])
    b = ik.analytic_batch(chain, targets)
    assert b.q.shape == (5, 4, 3) and b.valid.shape == (5, 4)
    assert not b.q.flags.writeable
    assert np.all(np.isnan(b.q[~b.valid]))
    # every branch reaches its target (FK), and the batch holds the list's branches
    for target, sols, q, valid in zip(targets, out, b.q, b.valid):
        assert len(sols) >= 1
        for sol in sols:
            np.testing.assert_allclose(model.position(sol), target, atol=1e-9)
        np.testing.assert_allclose(np.sort(q[valid], axis=0), np.sort(sols, axis=0), atol=1e-12)


@pytest.mark.parametrize("bad", [[np.nan, 0, 0], [0, np.inf, 0], [1, 2], "abc"])
def test_bad_targets_refused(bad):
    with pytest.raises(IKError):
        ik.analytic(robots.hexabot_leg(), bad)
    with pytest.raises(IKError):
        ik.solve(hk.load("hexabot_leg"), bad)


# ------------------------------------------------------------------ legs on mounts, base poses
@pytest.mark.parametrize("leg", range(6))
def test_hexapod_leg_closed_form_through_its_mount(leg):
    from hexapod_kin import ik, load, robots

    foot = robots.hexapod().foot_frames[leg]
    model = load("hexapod", tip=foot)
    assert ik.detect_family(model).family == "leg3"
    for q in model.random_q(50, seed=leg):
        p = model.fk(q)[:3, 3]  # the foot in the BODY frame (Pinocchio)
        sols = ik.analytic(model, p)[0]
        assert len(sols) >= 1
        assert any(np.allclose(s, q, atol=1e-9) for s in sols)  # the original branch is found
        for s in sols:
            np.testing.assert_allclose(model.fk(s)[:3, 3], p, atol=1e-9)


def test_base_pose_maps_targets():
    from hexapod_kin import Chain, ik, robots, table_fk

    leg = robots.hexabot_leg()
    moved = Chain(rows=leg.rows, base_pose=([0.1, -0.2, 0.05], [0.3, -0.2, 1.0]))
    rng = np.random.default_rng(3)
    for q in rng.uniform(-1.0, 1.0, size=(50, 3)):
        p = table_fk(moved, q)[:3, 3]
        sols = ik.analytic(moved, p)[0]
        assert any(np.allclose(s, q, atol=1e-9) for s in sols)
    scara = Chain(rows=robots.scara().rows, tool=([0.0, 0.02, 0.0], [0.0, 0.0, 0.0]))
    with pytest.raises(hk.exceptions.IKError, match="tool offset"):  # SCARA: still refused
        ik.detect_family(scara)


# ------------------------------------------------------------------ tool offsets, near twists
def _random_leg(rng, nq, *, ankle_flip=False, dev=0.0):
    """A leg table with a mount, θ/r offsets, a tool offset and twists ``dev`` off the pattern."""
    sigma = float(rng.choice([-1.0, 1.0]))
    rows = [
        KhalilRow("revolute", rng.uniform(-1, 1), rng.uniform(-0.05, 0.05), rng.uniform(-1, 1),
                  rng.uniform(-0.05, 0.05)),
        KhalilRow("revolute", sigma * math.pi / 2 + dev, rng.uniform(0.03, 0.08),
                  rng.uniform(-1, 1), rng.uniform(-0.02, 0.02)),
    ]  # fmt: skip
    if nq == 3:
        a3 = (math.pi if ankle_flip else 0.0) - dev
        rows.append(
            KhalilRow("revolute", a3, rng.uniform(0.06, 0.12), rng.uniform(-1, 1),
                      rng.uniform(-0.02, 0.02))
        )  # fmt: skip
    tool_xyz = [rng.uniform(0.05, 0.15), rng.uniform(-0.08, 0.08), rng.uniform(-0.03, 0.03)]
    return Chain(
        rows=tuple(rows),
        base_pose=(rng.uniform(-0.1, 0.1, 3), rng.uniform(-1, 1, 3)),
        tool=(tool_xyz, rng.uniform(-1, 1, 3)),
    )


def _check_solutions(chain, qs, *, model=None, pin_every=7):
    """Every closed-form solution's foot on its target (table FK; Pinocchio on a subset)."""
    targets = np.array([hk.table_fk(chain, q)[:3, 3] for q in qs])
    batch = ik.analytic_batch(chain, targets)
    assert batch.reachable.all()
    worst = 0.0
    for i, q in enumerate(qs):
        sols = batch.q[i][batch.valid[i]]
        assert any(np.abs(_wrapdiff(s, q)).max() < 1e-7 for s in sols)  # its own branch
        for s in sols:
            worst = max(worst, float(np.linalg.norm(hk.table_fk(chain, s)[:3, 3] - targets[i])))
            if model is not None and i % pin_every == 0:
                np.testing.assert_allclose(model.position(s), targets[i], rtol=0, atol=1e-9)
    assert worst <= 1e-9
    return batch


@pytest.mark.parametrize(
    ("nq", "ankle_flip", "dev"),
    [(2, False, 0.0), (3, False, 0.0), (3, True, 0.0), (2, False, 6e-4), (3, True, -8e-4)],
    ids=["2dof-tool", "3dof-tool", "3dof-antiparallel-ankle", "2dof-near-twist",
         "3dof-near-twists"],
)  # fmt: skip
def test_legs_with_tool_offsets_and_near_twists(nq, ankle_flip, dev):
    rng = np.random.default_rng(20 + nq + int(ankle_flip))
    for k in range(3):
        chain = _random_leg(rng, nq, ankle_flip=ankle_flip, dev=dev)
        fam = ik.detect_family(chain)
        assert fam.family == ("leg3" if nq == 3 else "coxa_tibia")
        assert fam.lateral != 0.0
        assert fam.deviation == pytest.approx(abs(dev), abs=1e-15)
        qs = rng.uniform(-math.pi, math.pi, size=(120, nq))
        _check_solutions(chain, qs, model=hk.load(chain) if k == 0 else None)


def test_near_twists_beyond_the_tolerance_are_refused():
    chain = _random_leg(np.random.default_rng(1), 3, dev=2e-3)
    with pytest.raises(IKError, match="angle_tol"):
        ik.detect_family(chain)
    assert ik.detect_family(chain, angle_tol=3e-3).deviation == pytest.approx(2e-3)


def test_lateral_offset_reach_and_excess():
    """Off the leg plane by e: nothing within |e| of the hip axis; reach_excess is 0 iff reached."""
    leg = robots.hexabot_leg()
    e = 0.04
    chain = leg.replace(rows=(*leg.rows[:3], KhalilRow("fixed", 0.0, 0.1, 0.0, e)))
    fam = ik.detect_family(chain)
    assert fam.lateral == pytest.approx(e)
    rng = np.random.default_rng(5)
    pts = rng.uniform(-0.3, 0.3, size=(3000, 3))
    pts[:200, :2] *= 0.1  # some inside the |e| cylinder
    batch = ik.analytic_batch(chain, pts)
    excess = fam.reach_excess(pts)
    np.testing.assert_array_equal(excess <= 1e-12, batch.reachable)
    inner = np.hypot(pts[:, 0], pts[:, 1]) < e - 1e-9
    assert inner.any() and not batch.reachable[inner].any()
    assert np.all(excess[inner] >= e - np.hypot(pts[inner, 0], pts[inner, 1]) - 1e-12)
    for i in np.flatnonzero(batch.reachable)[::10]:
        for s in batch.q[i][batch.valid[i]]:
            np.testing.assert_allclose(hk.table_fk(chain, s)[:3, 3], pts[i], rtol=0, atol=1e-12)


#: The PhantomX foot: the centre of the tibia mesh's spherical tip (tibia_l.STL of
#: HumaRobotics/phantomx_description, fitted: radius 7.1 mm), in each tibia link's frame.
PHANTOMX_FOOT = ((0.00155, 0.1535, 0.0288), (0.0, 0.0, 0.0))
PHANTOMX = "tests/data/phantomx/phantomx.urdf"


@pytest.mark.filterwarnings("ignore::hexapod_kin.UrdfWarning")
@pytest.mark.parametrize("leg", ["lf", "lm", "lr", "rf", "rm", "rr"])
def test_phantomx_legs_closed_form(leg):
    """Recovered PhantomX legs (foot on the tibia) are leg3; solutions hit ≤ 1e-9 m."""
    tip = f"tibia_{leg}"
    rec = hk.recover_chain(PHANTOMX, base="base_link", tip=tip, tool=PHANTOMX_FOOT)
    fam = ik.detect_family(rec.chain)
    assert fam.family == "leg3"
    assert fam.joint_signs == (1.0, 1.0, -1.0)  # tibia axis anti-parallel to the thigh's
    # 1.5704 in the URDF for π/2: the coxa/thigh twist is 3.96e-4 rad off (not snapped)
    assert fam.deviation == pytest.approx(math.pi / 2 - 1.5704, rel=1e-6)
    assert fam.lateral == pytest.approx(-PHANTOMX_FOOT[0][0], abs=1e-9)
    urdf = hk.load(PHANTOMX, base="base_link", tip=tip, tool=PHANTOMX_FOOT)
    qs = urdf.random_q(150, seed=7)
    batch = _check_solutions(rec.chain, qs, model=hk.load(rec.chain))
    # the URDF itself (Pinocchio) puts every solution within the snap's bound of the target
    targets = np.array([hk.table_fk(rec.chain, q)[:3, 3] for q in qs])
    for i in range(0, len(qs), 5):
        for s in batch.q[i][batch.valid[i]]:
            assert np.linalg.norm(urdf.position(s) - targets[i]) <= rec.fk_bound + 1e-12


def test_leg_solutions_is_the_one_home_per_target_lengths_and_limits():
    """leg_solutions with one design per target equals analytic_batch design by design."""
    rng = np.random.default_rng(4)
    designs = [(0.05, 0.1, 0.1), (0.03, 0.12, 0.08)]
    lim = JointLimits(-2.0, 2.0)
    pts, rows, ref = [], [], []
    for l1, l2, l3 in designs:
        chain = robots.hexabot_leg(l1=l1, l2=l2, l3=l3).replace(limits=(lim, lim, lim))
        p = rng.uniform(-0.25, 0.25, size=(500, 3))
        b = ik.analytic_batch(chain, p, tol=0.0, within_limits=True)
        pts.append(p)
        rows.append(np.tile([l1, l2, l3], (500, 1)))
        ref.append(b)
    p, r = np.vstack(pts), np.vstack(rows)
    lo, hi = np.full((len(p), 3), -2.0), np.full((len(p), 3), 2.0)
    q, valid = ik.leg_solutions(p, (r[:, 0], r[:, 1], r[:, 2]), sign=-1.0, limits=(lo, hi))
    np.testing.assert_array_equal(valid, np.vstack([b.valid for b in ref]))
    np.testing.assert_allclose(q, np.vstack([b.q for b in ref]), rtol=0, atol=1e-12)
    # independent: every valid slot within the limits and its table FK on the target
    chains = [
        robots.hexabot_leg(l1=a, l2=b, l3=c).replace(limits=(lim, lim, lim)) for a, b, c in designs
    ]
    for i in np.flatnonzero(valid.any(axis=1))[::7]:
        for qk in q[i][valid[i]]:
            assert np.all(np.abs(qk) <= 2.0 + 1e-12)
            foot = hk.table_fk(chains[i // 500], qk)[:3, 3]
            np.testing.assert_allclose(foot, p[i], rtol=0, atol=1e-12)
    reach = ik.leg_reachable(p, (r[:, 0], r[:, 1], r[:, 2]), sign=-1.0, limits=(lo, hi))
    np.testing.assert_array_equal(reach, valid.any(axis=1))
    assert 0.05 < reach.mean() < 0.95
    d = ref[0].to_dict()
    assert d["family"] == "leg3" and len(d["q"]) == 500
    assert ik.detect_family(robots.hexabot_leg()).to_dict()["lengths"] == [0.05, 0.1, 0.1]


@pytest.mark.parametrize(
    ("source", "base", "tip"),
    [("erd:solo12", "base_link", "FL_FOOT"), ("erd:anymal", "base", "RH_FOOT")],
)
def test_quadruped_legs_closed_form(source, base, tip):
    """solo12 / ANYmal legs: hip and thigh axes meet (l1 = 0), the foot off the leg plane."""
    rec = hk.recover_chain(source, base=base, tip=tip)
    fam = ik.detect_family(rec.chain)
    assert fam.family == "leg3" and fam.lengths[0] == 0.0 and fam.lateral != 0.0
    model = hk.load(source, base=base, tip=tip)
    qs = model.random_q(200, seed=3)
    targets = np.array([model.position(q) for q in qs])  # Pinocchio on the URDF itself
    batch = ik.analytic_batch(rec.chain, targets)
    assert batch.reachable.all()
    for i in range(len(qs)):
        sols = batch.q[i][batch.valid[i]]
        assert any(np.abs(_wrapdiff(s, qs[i])).max() < 1e-7 for s in sols)
        for s in sols:
            np.testing.assert_allclose(model.position(s), targets[i], rtol=0, atol=1e-9)
