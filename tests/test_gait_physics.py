"""Issue 22 (h2): patterns for any leg count, body sway, the C² swing, round feet rolling,
joint speed/acceleration checks and full inverse-dynamics gait torques.

Every number is held against something independent: closed-form derivatives, finite
differences, scipy's periodic spline, Pinocchio (CRBA, frame velocities and Jacobians),
a hand rule for the rolled distance.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from hexapod_kin.exceptions import ParameterError
from hexapod_kin.gait import GaitError, PhaseTable, phase_table, swing_profile, walk, whole_body
from hexapod_kin.gait.paths import rolling_offsets, rotation_increments
from hexapod_kin.gait.stability import periodic_spline
from hexapod_kin.gait.tables import default_positions, pattern_names
from hexapod_kin.robots import hexapod

pin = pytest.importorskip("pinocchio")

QUAD_YAW = (45.0, 135.0, -135.0, -45.0)  # front-left, rear-left, rear-right, front-right
OCTO_YAW = (22.5, 67.5, 112.5, 157.5, -157.5, -112.5, -67.5, -22.5)


@pytest.fixture(scope="module")
def quad():
    return whole_body(hexapod(mount_yaw_deg=QUAD_YAW, name="quad"))


@pytest.fixture(scope="module")
def octo():
    return whole_body(hexapod(mount_yaw_deg=OCTO_YAW, name="octo", body_radius=0.15))


@pytest.fixture(scope="module")
def wb():
    return whole_body()


# ====================================================================== swing profile
def test_swing_profile_has_zero_velocity_and_acceleration_at_both_ends():
    s = np.linspace(0.0, 1.0, 41)
    blend, lift = swing_profile(s)
    # closed forms of the derivatives (hand-differentiated) against central differences
    d1 = (30 * s**2 * (1 - s) ** 2, 192 * s**2 * (1 - s) ** 2 * (1 - 2 * s))
    d2 = (60 * s * (1 - s) * (1 - 2 * s), 384 * s * (1 - s) * (5 * s**2 - 5 * s + 1))
    h = 1e-5
    up, dn = swing_profile(s + h), swing_profile(s - h)
    for k in range(2):
        assert np.allclose((up[k] - dn[k]) / (2 * h), d1[k], atol=1e-6)
        assert np.allclose((up[k] - 2 * (blend, lift)[k] + dn[k]) / h**2, d2[k], atol=2e-3)
        assert d1[k][0] == d1[k][-1] == 0.0 and d2[k][0] == d2[k][-1] == 0.0
    assert lift[20] == pytest.approx(1.0) and lift.max() == pytest.approx(1.0)  # peak h at s=½
    assert blend[0] == 0.0 and blend[-1] == pytest.approx(1.0)


@pytest.mark.parametrize("pattern", ["tripod", "wave"])
def test_planned_feet_start_and_end_swings_with_zero_acceleration(pattern):
    """Second differences of the planned feet at lift-off / touch-down samples → 0 with dt."""

    def edge_accel(rate: float) -> tuple[float, float]:
        run = walk(pattern=pattern, duration=0.6, rate=rate, foot_radius=0.0)
        acc = (
            np.linalg.norm(
                run.feet_planned[2:] - 2 * run.feet_planned[1:-1] + run.feet_planned[:-2], axis=-1
            )
            * rate**2
        )  # (N-2, L) at samples 1..N-2
        st = run.support[1:-1]
        lift = st[:-1] & ~st[1:]  # last stance sample before a swing
        touch = ~st[:-1] & st[1:]  # last swing sample
        peak = float(acc.max())
        return float(acc[1:][lift].max()) / peak, float(acc[:-1][touch].max()) / peak

    # the jerk is not zero at the ends, so one sample in the acceleration is O(dt)
    coarse, fine = edge_accel(2000.0), edge_accel(10000.0)
    assert max(fine) < 2e-2  # relative to the peak swing acceleration
    assert fine[0] < 0.3 * coarse[0] + 1e-12 and fine[1] < 0.3 * coarse[1] + 1e-12


# ====================================================================== patterns
def _stance_counts(table: PhaseTable) -> np.ndarray:
    t = (np.arange(4000) + 0.5) / 4000
    return table.stance(t, 1.0).sum(axis=1)


def test_patterns_for_four_six_and_eight_legs(quad, octo):
    assert pattern_names(4) == ("crawl", "pace", "trot")  # a four-legged wave is the crawl
    assert pattern_names(6) == ("ripple", "tripod", "wave")
    assert pattern_names(8) == ("ripple", "wave")
    pos4 = quad.mounts[:, :2, 3]
    crawl = phase_table("crawl", 4, pos4)
    assert crawl.duty_factor == 0.8 and crawl.statically_stable
    counts = _stance_counts(crawl)
    assert counts.min() == 3 and counts.max() == 4  # never two feet: a statically stable crawl
    # lateral sequence: left hind, left fore, right hind, right fore, a quarter cycle apart
    lift = {k: (crawl.duty_factor - o) % 1.0 for k, o in enumerate(crawl.offsets)}
    assert [lift[k] for k in (1, 0, 2, 3)] == pytest.approx([0.0, 0.25, 0.5, 0.75])
    trot, pace = phase_table("trot", 4, pos4), phase_table("pace", 4, pos4)
    assert not trot.statically_stable and not pace.statically_stable
    assert trot.offsets[0] == trot.offsets[2] and trot.offsets[1] == trot.offsets[3]  # diagonals
    assert pace.offsets[0] == pace.offsets[1] and pace.offsets[2] == pace.offsets[3]  # sides
    pos8 = octo.mounts[:, :2, 3]
    assert np.all(_stance_counts(phase_table("wave", 8, pos8)) == 7)
    assert np.all(_stance_counts(phase_table("ripple", 8, pos8)) == 6)
    assert np.all(_stance_counts(phase_table("wave", 5, default_positions(5))) == 4)
    with pytest.raises(ParameterError, match="crawl") as err:
        phase_table("tripod", 4, pos4)
    assert err.value.allowed == ["crawl", "pace", "trot"]
    with pytest.raises(ParameterError, match="wave on four legs is the crawl"):
        phase_table("wave", 4, pos4)
    with pytest.raises(ParameterError, match="positions"):
        phase_table("wave", 4, np.zeros((3, 2)))


def _ring_layout(exact: bool) -> np.ndarray:
    """Six mounts at 0°, 60°, ... 300° on a 0.125 m circle (the RARL hexapod-sim's layout)."""
    ang = np.deg2rad(60.0 * np.arange(6))
    xy = 0.125 * np.stack([np.cos(ang), np.sin(ang)], axis=1)
    if exact:
        xy[[0, 3], 1] = 0.0  # the two legs on the x axis, without the 1e-17 residue
    return xy


def test_legs_on_the_axis_make_three_a_side_and_ripple():
    """RARL's ring: the legs at 0° and 180° are on the axis, not split by a round-off residue."""
    ring, exact = _ring_layout(False), _ring_layout(True)
    assert abs(ring[3, 1]) > 0  # the residue the old sign test split the legs by
    assert pattern_names(6, ring) == ("ripple", "tripod", "wave") == pattern_names(6, exact)
    ripple = phase_table("ripple", 6, ring)
    counts = _stance_counts(ripple)
    assert ripple.duty_factor == pytest.approx(2 / 3) and counts.min() == 4  # one leg a side up
    # the front axis leg joins the left side, the rear one the right: as the preset's ring
    lift = {k: (ripple.duty_factor - o) % 1.0 for k, o in enumerate(ripple.offsets)}
    assert [lift[k] for k in (2, 1, 0)] == pytest.approx([0.0, 1 / 3, 2 / 3])  # left, rear first
    assert [lift[k] for k in (3, 4, 5)] == pytest.approx([0.5, 5 / 6, 1 / 6])
    tripod = phase_table("tripod", 6, ring)
    assert tripod.offsets[0] == tripod.offsets[2] == tripod.offsets[4] != tripod.offsets[1]


@pytest.mark.parametrize("n", [4, 6, 8])
def test_offered_patterns_unchanged_when_a_mount_moves_1e_12(n, quad, octo):
    layouts = {4: quad.mounts[:, :2, 3], 6: _ring_layout(True), 8: octo.mounts[:, :2, 3]}
    base = np.array(layouts[n])
    names = pattern_names(n, base)
    ref = {p: phase_table(p, n, base).offsets for p in names}
    rng = np.random.default_rng(7)
    for _ in range(40):
        moved = base + rng.choice([-1e-12, 0.0, 1e-12], size=base.shape)
        assert pattern_names(n, moved) == names
        for p in names:
            assert phase_table(p, n, moved).offsets == ref[p]


def test_a_refused_pattern_says_why_in_the_robots_terms():
    xy = np.array([[0.2, 0.1], [0.0, 0.1], [-0.2, 0.1], [0.2, -0.1], [-0.2, -0.1]])
    legs = ("lf", "lm", "lr", "rf", "rr")
    with pytest.raises(
        ParameterError, match=r"3 on the left \(lr, lm, lf\) and 2 on the right"
    ) as err:
        phase_table("ripple", 5, xy, legs)
    assert "ripple" not in err.value.allowed and "an even number" in str(err.value)
    with pytest.raises(ParameterError, match="needs 6 legs; this robot has 4"):
        phase_table("tripod", 4, xy[:4])


def test_legs_near_the_axis_balance_the_sides():
    """Kraby: legs 0.011 m left of the axis at front and rear; the rear one goes right."""
    xy = np.array(
        [
            [0.0922, 0.011],
            [0.0574, 0.073],
            [-0.0574, 0.073],
            [-0.0922, 0.011],
            [-0.073, -0.0574],
            [0.073, -0.0574],
        ]
    )
    assert pattern_names(6, xy) == ("ripple", "tripod", "wave")
    ripple = phase_table("ripple", 6, xy)
    lift = {k: (ripple.duty_factor - o) % 1.0 for k, o in enumerate(ripple.offsets)}
    assert [lift[k] for k in (2, 1, 0)] == pytest.approx([0.0, 1 / 3, 2 / 3])  # left, rear first
    assert [lift[k] for k in (3, 4, 5)] == pytest.approx([0.5, 5 / 6, 1 / 6])  # right
    assert _stance_counts(ripple).min() == 4


def test_patterns_follow_the_legs_not_their_order(quad):
    """Permuting the legs permutes the offsets (the pattern is built from where legs are)."""
    pos = quad.mounts[:, :2, 3]
    perm = [2, 0, 3, 1]
    for name in ("crawl", "trot", "pace"):
        a, b = phase_table(name, 4, pos), phase_table(name, 4, pos[perm])
        assert np.allclose(np.asarray(a.offsets)[perm], b.offsets, atol=1e-12)


def test_quadruped_crawls_ten_seconds_with_sway_and_positive_margin(quad):
    run = walk(quad, pattern="crawl", duration=10.0, rate=100.0)
    assert run.ok and run.settings["sway"] == 1.0 and run.min_margin > 0.002
    assert run.min_zmp_margin > 0.005  # the ZMP at the support's incentre at mid-swing
    assert run.robot is quad and run.statically_stable
    # without sway the crawl tips: its zero-moment point leaves the support by far more
    bare = walk(quad, pattern="crawl", duration=3.0, sway=0.0, strict=False)
    assert bare.min_margin < 0.3 * run.min_margin
    assert bare.min_zmp_margin < run.min_zmp_margin - 0.005
    # the sway is C² and periodic: the body's lateral offset repeats every period and its
    # second difference has no jumps bigger than a smooth curve's (the incentre's sway asks
    # more speed of the joints than 1 s allows: the fitted period is longer)
    y = run.base_poses[:, 1, 3]
    n = round(run.settings["period"] * 100)
    assert run.settings["period"] == pytest.approx(1.05) and n == 105
    assert np.allclose(y[:n], y[n : 2 * n], atol=1e-12)
    acc = np.diff(y, 2) * 100**2
    assert np.abs(np.diff(acc)).max() < 0.1 * np.abs(acc).max()


def test_margin_within_rounding_of_zero_is_not_a_failure(quad):
    """A β = 0.75 crawl without sway hands over on the diagonal: margin ≈ −1e-16 m."""
    run = walk(quad, pattern="crawl", duty_factor=0.75, sway=0.0, foot_radius=0.0, stride=0.05)
    assert -run.settings["margin_tol"] < run.min_margin < 1e-12 and run.ok
    assert run.settings["margin_tol"] == pytest.approx(1e-9 * (0.12 + 0.16))


def test_trot_and_pace_walk_but_are_reported_not_statically_stable(quad):
    for name in ("trot", "pace"):
        with pytest.raises(GaitError, match="needs a balance controller") as err:
            walk(quad, pattern=name, duration=2.0)  # the open-loop planner refuses them
        assert err.value.check == "statically unstable" and "or walk crawl)" in str(err.value)
        run = walk(quad, pattern=name, duration=2.0, open_loop=False)  # for a controller
        assert run.min_margin < 0 and run.ok and not run.statically_stable
        d = run.to_dict()
        assert d["statically_stable"] is False and d["pattern"]["statically_stable"] is False


def test_eight_legs_walk_wave_and_ripple(octo):
    for name, period in (("wave", 1.5), ("ripple", 1.0)):
        run = walk(octo, pattern=name, period=period, duration=4.0)
        assert run.ok and run.min_margin > 0.1 and run.max_slip <= 1e-9


def test_periodic_spline_matches_scipy_and_is_c2():
    from scipy.interpolate import CubicSpline

    rng = np.random.default_rng(3)
    knots = np.array([0.1, 0.35, 0.6, 0.8])
    vals = rng.normal(size=(4, 2))
    t = np.linspace(-1.0, 2.0, 301)
    ours = periodic_spline(knots, vals, 1.0, t)
    ref = CubicSpline(np.append(knots, 1.1), np.vstack([vals, vals[:1]]), bc_type="periodic")
    assert np.allclose(ours, ref(np.remainder(t - 0.1, 1.0) + 0.1), atol=1e-12)
    assert np.allclose(periodic_spline([0.3], vals[:1], 1.0, t), vals[0])


# ====================================================================== rolling feet
def test_rotation_increments_are_the_rotation_vectors():
    rng = np.random.default_rng(0)
    axis = rng.normal(size=(50, 3))
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    ang = rng.uniform(0, 1.0, 50)
    ang[:5] = [0.0, 1e-9, 1e-7, 1e-5, 3.0]
    R0 = np.array([pin.exp3(v) for v in rng.normal(size=(50, 3))])
    R1 = np.array([pin.exp3(a * u) @ R for a, u, R in zip(ang, axis, R0)])
    theta = rotation_increments(np.stack([R0, R1]))[0]
    assert np.allclose(theta, ang[:, None] * axis, atol=1e-12)


def test_round_feet_roll_without_slip_and_the_roll_is_r_times_the_pitch(wb):
    run = walk(pattern="tripod", duration=3.0, rate=200.0)
    r = wb.foot_radius
    assert r == 0.012 and run.max_slip <= 1e-9
    assert run.settings["rolling_residual"] <= 1e-10 and run.settings["rolling_passes"] >= 2
    # hand rule: on level ground with a level body, the leg's foot frame turns about the
    # horizontal knee/ankle axes at (q̇_knee + q̇_ankle) and about z (no rolling) with the hip:
    # the contact point's path length over each stance is r Σ |Δ(q_knee + q_ankle)|
    q = run.q.reshape(len(run.t), 6, 3)
    pitch = q[:, :, 1] + q[:, :, 2]
    for k in range(6):
        st = run.support[:, k]
        runs = np.flatnonzero(np.diff(st.astype(int)) != 0) + 1
        for a, b in zip(np.r_[0, runs][:-1], runs):
            if st[a] and b - a > 10:
                path = np.linalg.norm(np.diff(run.feet[a:b, k], axis=0), axis=1).sum()
                assert path == pytest.approx(r * np.abs(np.diff(pitch[a:b, k])).sum(), rel=1e-6)
    # the stance centre moves (it rolls), unlike point feet
    moved = np.linalg.norm(run.feet - run.feet[np.argmax(run.support, axis=0), range(6)], axis=-1)
    assert moved[run.support].max() > 1e-3
    point = walk(pattern="tripod", duration=3.0, rate=200.0, foot_radius=0.0)
    assert point.settings["rolling_passes"] == 1 and point.max_slip <= 1e-12


def test_rolling_offsets_of_a_wheel():
    """A sphere turning at a constant rate about y rolls along x by r·angle (closed form)."""
    n, r = 101, 0.02
    ang = np.linspace(0.0, 1.5, n)
    rot = np.array([pin.exp3(np.array([0.0, a, 0.0])) for a in ang])[:, None]
    support = np.ones((n, 1), dtype=bool)
    D = rolling_offsets(rot, support, np.tile([0.0, 0.0, 1.0], (n, 1, 1)), r)
    assert np.allclose(D[:, 0, 0], r * ang, atol=1e-15) and np.allclose(D[:, 0, 1:], 0.0)


# ====================================================================== joint speed
def test_joint_speed_is_checked_against_the_urdf_limit(wb):
    assert np.all(wb.velocity_limit == 10.0)
    with pytest.raises(GaitError) as err:
        walk(pattern="wave", terrain="slope", duration=2.0, period=1.0)  # a period asked
    e = err.value
    assert e.check == "joint speed" and e.amount > 0 and e.time is not None
    assert e.parameter in wb.joint_names and e.allowed == 10.0
    run = walk(pattern="wave", terrain="slope", duration=2.0, strict=False, period=1.0)
    assert not run.ok and not run.speed_ok
    j = wb.joint_names.index(e.parameter)
    assert run.max_joint_speed[j] == pytest.approx(10.0 + e.amount)
    d = run.to_dict()
    assert d["max_joint_speed"][e.parameter] == pytest.approx(run.max_joint_speed[j])
    json.dumps(d, allow_nan=False)


def test_the_default_period_keeps_the_joints_within_their_limits(wb):
    """No period given: the joints' speed (and acceleration) limits set it; time scaling."""
    from hexapod_kin.gait.limits import PERIOD_STEP

    fast = walk(pattern="wave", terrain="slope", duration=1.0, period=1.0, strict=False)
    ratio = float(np.max(fast.max_joint_speed / wb.velocity_limit))
    assert ratio > 1  # the 1-s wave on the slope asks too much of a joint
    run = walk(pattern="wave", terrain="slope", duration=4.0)
    T = run.settings["period"]
    assert run.ok and run.speed_ok and T > 1.0
    assert T / PERIOD_STEP == pytest.approx(round(T / PERIOD_STEP), abs=1e-9)
    assert ratio * 0.9 < T < ratio * 1.2  # speeds scale as 1/T (the same path, slower)
    acc = walk(pattern="tripod", duration=2.0, accel_limit=20.0)  # acceleration scales as 1/T²
    ref = walk(pattern="tripod", duration=1.0, period=1.0, strict=False)
    need = math.sqrt(float(ref.max_joint_accel.max()) / 20.0)
    assert acc.speed_ok and acc.settings["period"] == pytest.approx(need, rel=0.2)
    assert walk(duration=1.0).settings["period"] == 1.0  # within the limits: unchanged


def test_joint_acceleration_by_finite_differences_and_its_optional_limit():
    run = walk(pattern="tripod", duration=1.0, rate=400.0)
    assert np.allclose(run.qddot[1:-1], np.diff(run.q, 2, axis=0) * 400.0**2, atol=1e-9)
    assert run.max_joint_accel == pytest.approx(np.abs(run.qddot).max(axis=0))
    with pytest.raises(GaitError) as err:
        walk(pattern="tripod", duration=1.0, rate=400.0, accel_limit=1.0, period=1.0)
    assert err.value.check == "joint acceleration"
    with pytest.raises(ParameterError, match="accel_limit"):
        walk(duration=1.0, accel_limit=-1.0)


def test_pinocchio_a_is_the_derivative_of_pinocchio_v():
    run = walk(
        pattern="ripple", velocity=(0.05, 0.01, 0.2), duration=1.0, rate=1000.0, foot_radius=0.0
    )
    v, a = run.pinocchio_v(), run.pinocchio_a()
    fd = np.gradient(v, run.t, axis=0)
    # (the two stencils differ by O(dt) where the jerk jumps: lift-off, touch-down)
    assert np.abs(fd[5:-5] - a[5:-5]).max() < 2e-2 * np.abs(a).max()
    # the base origin's classical acceleration is p̈ (Pinocchio's convention)
    model, data = run.robot.model, run.robot.model.createData()
    Q = run.pinocchio_q()
    p_dd = np.diff(run.base_poses[:, :3, 3], 2, axis=0) * 1000.0**2
    for i in (100, 500, 900):
        pin.forwardKinematics(model, data, Q[i], v[i], a[i])
        acc = pin.getFrameClassicalAcceleration(
            model, data, model.getFrameId("root_joint"), pin.LOCAL_WORLD_ALIGNED
        )
        assert np.allclose(acc.linear, p_dd[i - 1], atol=1e-6)


# ====================================================================== full dynamics
def test_full_inverse_dynamics_equals_crba_plus_bias_with_the_contact_forces(wb):
    from hexapod_kin.dynamics import gait_torques

    run = walk(pattern="wave", duration=1.0, rate=200.0)
    res = gait_torques(run)
    assert res.base_residual <= 1e-9
    model, data = wb.model, wb.model.createData()
    Q, V, A = run.pinocchio_q(), run.pinocchio_v(), run.pinocchio_a()
    fids = [model.getFrameId(f"{leg}_foot") for leg in wb.leg_names]
    cols = [run.joint_names.index(n) for n in res.joint_names]
    r = run.settings["foot_radius"]
    worst = 0.0
    for i in range(0, len(run.t), 7):
        M = pin.crba(model, data, Q[i])
        M = np.triu(M) + np.triu(M, 1).T
        b = M @ A[i] + pin.nonLinearEffects(model, data, Q[i], V[i])
        for k, f in enumerate(fids):
            if run.support[i, k]:
                J = pin.computeFrameJacobian(model, data, Q[i], f, pin.LOCAL_WORLD_ALIGNED)
                arm = -r * run.normals[i, k]  # the contact point from the sphere's centre
                Jc = J[:3] + np.cross(J[3:].T, arm).T  # v + ω × arm
                b -= Jc.T @ res.forces_full[i, k]
        assert np.abs(b[:6]).max() <= 1e-9  # the floating base is balanced
        worst = max(worst, float(np.abs(b[6:][cols] - res.torque_full[i]).max()))
    assert worst <= 1e-9
    # Newton: the contact forces carry the weight and accelerate the centre of mass
    com_acc = np.diff(run.com, 2, axis=0) * 200.0**2
    total = res.forces_full.sum(axis=1)[1:-1]
    m = run.mass
    assert np.abs(total - m * (com_acc + [0, 0, 9.81])).max() < 0.02 * m * 9.81
    d = res.to_dict()
    assert d["peak_torque_full_max"] == pytest.approx(res.peak_full.max())
    assert np.all(res.peak_difference <= res.peak + res.peak_full + 1e-12)
    assert np.abs(res.torque_full - res.torque).max() == pytest.approx(res.peak_difference.max())


def test_full_inverse_dynamics_equals_mujoco_mj_inverse_on_the_exported_mjcf(wb):
    """MuJoCo's own inverse dynamics of the exported robot, sample by sample ≤ 1e-9 N·m."""
    mujoco = pytest.importorskip("mujoco")
    from hexapod_kin.dynamics import gait_torques
    from hexapod_kin.export.mjcf import to_mjcf

    run = walk(pattern="wave", duration=1.0, rate=200.0)
    res = gait_torques(run)
    m = mujoco.MjModel.from_xml_string(to_mjcf("hexapod", floating=True, floor=False).xml)
    d = mujoco.MjData(m)
    names = [m.joint(j).name for j in range(1, m.njnt)]
    cols = [run.joint_names.index(n) for n in names]
    ours_cols = [res.joint_names.index(n) for n in names]
    V, A = run.pinocchio_v(), run.pinocchio_a()
    r = run.settings["foot_radius"]
    worst = base = 0.0
    for i in range(0, len(run.t), 5):
        B = run.base_poses[i]
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, B[:3, :3].ravel())
        d.qpos[:3], d.qpos[3:7], d.qpos[7:] = B[:3, 3], quat, run.q[i, cols]
        # MuJoCo's free joint: world linear velocity, body angular velocity; qacc = d/dt qvel
        v_b, w_b = V[i, :3], V[i, 3:6]
        d.qvel[:3], d.qvel[3:6], d.qvel[6:] = B[:3, :3] @ v_b, w_b, run.qdot[i, cols]
        d.qacc[:3] = B[:3, :3] @ (A[i, :3] + np.cross(w_b, v_b))
        d.qacc[3:6], d.qacc[6:] = A[i, 3:6], run.qddot[i, cols]
        mujoco.mj_inverse(m, d)
        gen = d.qfrc_inverse + d.qfrc_passive
        for k, leg in enumerate(run.leg_names):
            if run.support[i, k]:
                jacp, jacr = np.zeros((3, m.nv)), np.zeros((3, m.nv))
                point = run.feet[i, k] - r * run.normals[i, k]
                mujoco.mj_jac(m, d, jacp, jacr, point, m.body(f"{leg}_foot").id)
                gen = gen - jacp.T @ res.forces_full[i, k]
        base = max(base, float(np.abs(gen[:6]).max()))
        worst = max(worst, float(np.abs(gen[6:] - res.torque_full[i, ours_cols]).max()))
    assert base <= 1e-9 and worst <= 1e-9


# ====================================================================== terrain edges (h9)
# The reference is a box step by hand: ground z = 0 for x < 0.25 m, the step's solid is the
# box x >= 0.25 m, z <= 0.02 m (gait.terrain.step_terrain()).
EDGE, RISE = 0.25, 0.02


def _box_distance(c: np.ndarray) -> np.ndarray:
    """Distance [m] from points (..., 3) to the step's box, and to the lower ground (z = 0)."""
    to_box = np.hypot(np.maximum(EDGE - c[..., 0], 0.0), np.maximum(c[..., 2] - RISE, 0.0))
    return np.minimum(to_box, np.where(c[..., 0] < EDGE, c[..., 2], np.inf))


def _dense_gap(c: np.ndarray, r: float) -> float:
    """min over a 0.1 mm grid of the disc of c_z − h(c + d) − √(r² − |d|²), by brute force."""
    g = np.arange(-r, r + 1e-12, 1e-4)
    dx, dy = np.meshgrid(g, g)
    keep = dx**2 + dy**2 <= r * r
    dx, dy = dx[keep], dy[keep]
    h = np.where(c[0] + dx >= EDGE, RISE, 0.0)
    return float((c[2] - h - np.sqrt(np.maximum(r * r - dx**2 - dy**2, 0.0))).min())


def test_sphere_gap_against_the_box_step_by_hand():
    from hexapod_kin.gait.terrain import sphere_gap, step_terrain

    ground, r = step_terrain(), 0.012
    # level ground, far from the edge: exactly c_z − r (the centre sample)
    c = np.array([[0.0, 0.1, 0.05], [0.6, -0.2, 0.035]])
    np.testing.assert_allclose(sphere_gap(ground, c, r), [0.05 - r, 0.035 - 0.02 - r], atol=0)
    # beside the riser, 6 mm into it: the ring r/2 is turned by π/16 (reaches 5.9 mm along x),
    # so the innermost sample on the top is on the ring 3r/4 at angle 0:
    # c_z − 0.02 − √(r² − (3r/4)²) by hand
    c = np.array([EDGE - 0.006, 0.0, r])
    assert float(sphere_gap(ground, c, r)) == pytest.approx(r - RISE - np.sqrt(r**2 * 7 / 16))
    # around the corner: never below the dense minimum, within the rings' resolution of it,
    # and clear (>= 0) wherever the hand distance to the box and the ground is at least r
    rng = np.random.default_rng(5)
    pts = np.column_stack(
        [
            EDGE + rng.uniform(-0.02, 0.01, 60),
            rng.uniform(-0.01, 0.01, 60),
            rng.uniform(0.01, 0.04, 60),
        ]
    )
    sampled = sphere_gap(ground, pts, r)
    dense = np.array([_dense_gap(p, r) for p in pts])
    assert np.all(sampled >= dense - 1e-9)
    # a sphere more than r/4 (the ring spacing) into the box or the ground is always caught
    deep = _box_distance(pts) < 0.75 * r
    assert deep.any() and np.all(sampled[deep] < 0)
    clear = _box_distance(pts) >= r
    assert clear.any() and (~clear).any()
    assert np.all(sampled[clear] >= -1e-12)
    assert np.all(dense[~clear] < 0)  # the dense reference agrees with the hand distance


def test_footholds_move_off_the_edge_to_the_nearest_flat_disc_by_hand():
    from hexapod_kin.gait.terrain import disc_residual, off_edges, step_terrain

    ground, rho = step_terrain(), 0.019
    q = rho / 64  # the search step
    p = np.array([[EDGE - 0.010, 0.0, 0.0], [EDGE + 0.040, 0.0, RISE], [EDGE + 0.012, 0.0, RISE]])
    u = np.array([[1.0, 0.0], [1.0, 0.0], [1.0, 0.0]])
    xy, shift = off_edges(ground, p, u, rho, 4 * rho)
    # the sampled rings reach rho along x (the outer ring, r/cos(π/16), turned by π/16):
    # a disc is flat before the edge when x + rho < 0.25 and on the top when x − rho >= 0.25
    back = -(np.floor(0.009 / q) + 1) * q  # 0.24 + s + 0.019 < 0.25: s < −0.009
    assert shift[0] == pytest.approx(back, abs=1e-15)  # backward (forward would be 29 mm)
    assert shift[1] == 0.0  # 40 mm onto the top: flat already
    fwd = np.ceil((rho - 0.012) / q - 1e-9) * q  # 0.262 + s − 0.019 >= 0.25: s >= 0.007
    assert shift[2] == pytest.approx(fwd, abs=1e-15)  # forward (backward would be 31 mm)
    np.testing.assert_allclose(xy[:, 0], p[:, 0] + shift, atol=0)
    assert np.all(disc_residual(ground, xy, rho / np.cos(np.pi / 16)) <= 1e-3)


def test_the_step_walk_keeps_contacts_off_the_edge_and_swing_spheres_out_of_the_step():
    from hexapod_kin.gait.walk import FOOTHOLD_MARGIN

    run = walk(pattern="tripod", terrain="step", duration=10.0)
    r = run.settings["foot_radius"]
    # every touch-down contact by FK is at least r + margin from the edge (by hand: |x − 0.25|)
    start = run.support.copy()
    start[1:] &= ~run.support[:-1]
    contacts = (run.feet - r * run.normals)[start]
    assert np.all(np.abs(contacts[:, 0] - EDGE) >= r + FOOTHOLD_MARGIN - 1e-9)
    assert run.settings["footholds_moved"] >= 1 and run.settings["foothold_shift_max"] > 0
    # no foot sphere (swing or stance, by FK) enters the box or the ground: hand distance
    assert _box_distance(np.asarray(run.feet)).min() >= r - 1e-9
    # the swings over the edge were raised, the others not
    assert run.settings["swings_raised"] >= 1
    assert 0 < run.settings["swing_raise_max"] <= run.settings["step_height"]
    assert run.foot_gap.min() >= -1e-9 and run.leg_gap.min() > 0 and run.ok
    # flat ground: nothing moves or rises (the same plan as before the edge rules)
    flat = walk(pattern="tripod", duration=2.0)
    assert flat.settings["footholds_moved"] == flat.settings["swings_raised"] == 0


def test_raise_profile_is_c2_with_zero_rate_and_acceleration_at_both_ends():
    from hexapod_kin.gait.terrain import RAMP, raise_profile

    s = np.linspace(0.0, 1.0, 401)
    p = raise_profile(s)
    h = 1e-5
    d1 = (raise_profile(s + h) - raise_profile(s - h)) / (2 * h)
    d2 = (raise_profile(s + h) - 2 * p + raise_profile(s - h)) / h**2
    u = np.clip(s / RAMP, 0, 1)
    # the quintic ramp by hand: q'(u)/a = 30u²(1 − u)²/a
    rising = s < RAMP
    np.testing.assert_allclose(
        d1[rising][1:], (30 * u**2 * (1 - u) ** 2 / RAMP)[rising][1:], atol=1e-5
    )
    assert p[0] == p[-1] == 0.0 and np.all(p[(s >= RAMP) & (s <= 1 - RAMP)] == 1.0)
    ends = (s == 0.0) | (s == 1.0)
    # by hand: p(h) = 10(h/a)³, so the differences are 5h²/a³ and 10h/a³ there
    assert np.abs(d1[ends]).max() < 1e-7 and np.abs(d2[ends]).max() < 1e-2
    # no jump of the acceleration at the joins: between samples ds apart it changes by at
    # most max|q3|·ds/a³ = 60·ds/a³ (q3 = 60 − 360u + 360u², the third derivative); a jump
    # would be of the order of q''/a²
    assert np.abs(np.diff(d2[1:-1])).max() <= 60 * (s[1] - s[0]) / RAMP**3 * 1.01


def test_legs_against_the_terrain_by_hand():
    from hexapod_kin.gait.stability import leg_terrain_clearance
    from hexapod_kin.gait.terrain import step_terrain

    ground, rho = step_terrain(), 0.008
    t = np.zeros(1)
    below = np.array([[[0.0, 0.0, 1.0, -1.0]]])  # a plane far below: nothing ignored
    # a level link 30 mm above the top, its foot end far past the corner: clear without
    # sampling, its gap the bound z − ρ − max(h(a), h(b)) − relief (relief = the rise)
    pts = np.array([[[[0.2, 0.0, 0.05], [0.3, 0.0, 0.05], [0.4, 0.0, 0.05]]]])
    gap = leg_terrain_clearance(ground, pts, rho, 0.0, below, t, ("a",))
    assert float(gap[0, 0]) == pytest.approx(0.05 - rho - RISE - RISE, abs=1e-15)
    # 12 mm lower the bound fails and the balls are sampled: the exact z − 0.02 − ρ
    pts[..., 2] = 0.038
    gap = leg_terrain_clearance(ground, pts, rho, 0.0, below, t, ("a",))
    assert float(gap[0, 0]) == pytest.approx(0.038 - RISE - rho, abs=1e-15)
    # lowered to 5 mm above the top: 3 mm into the corner's top
    pts[..., 2] = RISE + 0.005
    gap = leg_terrain_clearance(ground, pts, rho, 0.0, below, t, ("a",), strict=False)
    assert float(gap[0, 0]) == pytest.approx(0.005 - rho, abs=1e-15)
    with pytest.raises(GaitError) as err:
        leg_terrain_clearance(ground, pts, rho, 0.0, below, t, ("a",))
    assert err.value.check == "leg terrain clearance" and err.value.leg == "a"
    assert err.value.amount == pytest.approx(rho - 0.005, abs=1e-15)
    # the leg's own ground plane (z = 0.02 here) is ignored: the same link is then clear
    own = np.array([[[0.0, 0.0, 1.0, RISE]]])
    pts2 = np.array([[[[0.3, 0.0, 0.05], [0.35, 0.0, 0.05], [0.4, 0.0, RISE + 0.005]]]])
    assert leg_terrain_clearance(ground, pts2, rho, 0.0, own, t, ("a",)).min() > 0


def test_zmp_equals_pinocchio_centroidal_dynamics_and_rnea():
    """The run's ZMP against its own evaluation here, to 1e-9: v and a by the manifold
    stencils written out per sample (``pin.difference`` both ways inside, the one-sided
    second-order ones at the ends), ``ḣ_G`` from Pinocchio's ``dccrba`` path
    (``computeCentroidalMomentumTimeVariation``) and again from the RNEA without gravity (the
    free-flyer's wrench is the robot's rate of momentum; ``L̇_G = L̇_O − c × ṗ``), put in the
    closed form ``c − (c_z − h) c̈ / (g + c̈_z) − L̇ / (m (g + c̈_z))``. The ZMP-aware sway keeps
    a Solo12 crawl's ZMP within 3 mm of the support."""
    from hexapod_kin.gait import as_whole_body, walk
    from hexapod_kin.gait.stability import support_margin
    from hexapod_kin.gait.zmp import zmp_points

    wb = as_whole_body("erd:solo12")
    assert walk(wb, pattern="crawl", duration=3.0).min_zmp_margin > -3e-3
    run = walk(wb, pattern="crawl", duration=1.0, rate=400.0)
    m = wb.model
    d = m.createData()
    free = m.copy()
    free.gravity = pin.Motion.Zero()
    dfree = free.createData()
    Q = wb.pinocchio_q(run.q, run.base_poses)
    n, dt, g = len(Q), float(run.t[1] - run.t[0]), 9.81
    mass = float(pin.computeTotalMass(m))
    contacts = run.feet - wb.foot_radius * run.normals
    h = np.array([contacts[i, run.support[i], 2].mean() for i in range(n)])
    got = zmp_points(wb, run.q, run.base_poses, run.t, h)
    ref = np.empty((n, 2, 3))
    for i in range(n):
        if 0 < i < n - 1:
            fwd, back = pin.difference(m, Q[i], Q[i + 1]), pin.difference(m, Q[i], Q[i - 1])
            v, a = (fwd - back) / (2 * dt), (fwd + back) / dt**2
        else:
            s = 1 if i == 0 else -1
            e1, e2, e3 = (pin.difference(m, Q[i], Q[i + s * k]) for k in (1, 2, 3))
            v, a = s * (4 * e1 - e2) / (2 * dt), (-5 * e1 + 4 * e2 - e3) / dt**2
        dhg = pin.computeCentroidalMomentumTimeVariation(m, d, Q[i], v, a)
        c = pin.centerOfMass(m, d, Q[i])
        wrench = d.oMi[1].act(pin.Force(pin.rnea(free, dfree, Q[i], v, a)[:6]))
        by_rnea = (wrench.linear, wrench.angular - np.cross(c, wrench.linear))
        for k, (lin, ang) in enumerate([(dhg.linear, dhg.angular), by_rnea]):
            den = mass * (g + lin[2] / mass)
            lever = (c[2] - h[i]) / den
            ref[i, k] = [c[0] - lever * lin[0] - ang[1] / den,
                         c[1] - lever * lin[1] + ang[0] / den, h[i]]  # fmt: skip
    assert np.abs(got - ref[:, 0]).max() <= 1e-9
    assert np.abs(got - ref[:, 1]).max() <= 1e-9
    zmp_margin = support_margin(contacts, run.support, got)
    assert np.abs(zmp_margin - run.zmp_margin).max() <= 1e-12 and zmp_margin.min() > -3e-3


@pytest.mark.parametrize("pattern", ["tripod", "wave", "ripple"])
def test_swings_clear_the_step_corner_by_the_promised_margin(pattern):
    """The 2 cm step: every swing foot sphere stays SWING_MARGIN from the step's corner line
    (closed form: the distance from the sphere centre to the edge x = 0.25 m, z = 0.02 m, or
    to the face below it); the plan reports its own figure."""
    from hexapod_kin.gait.walk import EDGE_SLACK, SWING_MARGIN

    run = walk(pattern=pattern, terrain="step", duration=10.0)
    c, r = np.asarray(run.feet), run.settings["foot_radius"]
    before = ~run.support & (c[..., 0] < 0.25)
    dx, dz = 0.25 - c[..., 0], c[..., 2] - 0.02
    corner = np.where(dz > 0, np.hypot(dx, dz), dx) - r
    assert corner[before].min() >= SWING_MARGIN  # the promise, by the closed form
    assert run.settings["min_edge_clearance"] >= SWING_MARGIN - EDGE_SLACK


def test_a_swing_short_of_the_edge_margin_is_refused():
    import importlib

    w = importlib.import_module("hexapod_kin.gait.walk")
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(w, "FOOTHOLD_MARGIN", 0.0)  # touch-downs right at the step's face
        mp.setattr(w, "EDGE_PASSES", 0)  # and no raise of the swings
        with pytest.raises(GaitError, match="swing clearance") as err:
            w.walk(pattern="tripod", terrain="step", duration=10.0)
    assert err.value.check == "swing clearance" and err.value.amount > 0


def test_asking_too_much_shows_the_patterns_top_speed_for_this_robot(capsys):
    """The top speed printed is walkable: its stride and period keep reach and speed limits."""
    import re

    from hexapod_kin.cli import main
    from hexapod_kin.gait.walk import highest_speed

    assert main(["gait", "--velocity", "0.6", "0", "0", "--duration", "1"]) == 1
    err = capsys.readouterr().err
    m = re.search(r"of tripod for this robot is ([\d.]+) m/s \(--stride ([\d.]+)", err)
    assert m is not None, err
    v, stride, period = highest_speed(pattern="tripod")
    assert float(m.group(1)) == pytest.approx(v, rel=1e-2) and v > 0.1
    run = walk(pattern="tripod", stride=stride, period=period * 1.001, duration=2.0, strict=False)
    assert np.all(run.ik_ok) and run.speed_ok and run.min_limit_margin >= 0
    assert run.to_dict()["velocity"][0] == pytest.approx(v / 1.001, rel=1e-9)
    assert main(["gait", "erd:solo12", "--pattern", "trot", "--duration", "1"]) == 1
    assert "needs a balance controller" in capsys.readouterr().err


def test_the_sway_puts_the_zmp_at_each_support_triangles_incentre():
    """``support_centre``: the point at the same distance from a triangle's three edges, the
    inradius ``2 · area / perimeter`` (independent closed form); the feet's mean for other
    supports. erd:go2's crawl: at mid-swing (the sway's knots) the whole robot's ZMP sits at
    the incentre of the stance contacts, computed here from the run's feet, not at their
    centroid (34 mm away)."""
    from hexapod_kin.gait import as_whole_body
    from hexapod_kin.gait.sway import support_centre
    from hexapod_kin.gait.zmp import zmp_points

    rng = np.random.default_rng(7)
    for _ in range(20):
        p = rng.uniform(-1.0, 1.0, (3, 2))
        c = support_centre(p)
        e = np.roll(p, -1, axis=0) - p  # the edges p_i -> p_i+1
        area = 0.5 * abs(e[0, 0] * e[1, 1] - e[0, 1] * e[1, 0])
        r = 2.0 * area / np.linalg.norm(e, axis=1).sum()
        dist = np.abs(e[:, 0] * (c - p)[:, 1] - e[:, 1] * (c - p)[:, 0]) / np.linalg.norm(e, axis=1)
        assert dist == pytest.approx([r, r, r], abs=1e-12)
    square = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]])
    assert support_centre(square) == pytest.approx([1.0, 1.0], abs=1e-15)
    assert support_centre(np.zeros((0, 2))).tolist() == [0.0, 0.0]

    wb = as_whole_body("erd:go2")
    run = walk(wb, pattern="crawl", duration=2.0)
    sup = np.asarray(run.support)
    contacts = np.asarray(run.feet) - wb.foot_radius * np.asarray(run.normals)
    h = np.array([contacts[i, sup[i], 2].mean() for i in range(len(sup))])
    zmp = zmp_points(wb, run.q, run.base_poses, run.t, h)
    checked = 0
    for leg in range(4):
        swing = ~sup[:, leg]
        for a in np.flatnonzero(swing[1:] & ~swing[:-1]) + 1:  # lift-offs
            b = a + int(np.argmax(~swing[a:]))  # the touch-down after
            if b <= a:
                continue
            i = (a + b) // 2
            p = contacts[i, sup[i], :2]
            side = np.linalg.norm(np.roll(p, -1, axis=0) - np.roll(p, 1, axis=0), axis=1)
            incentre = side @ p / side.sum()
            assert len(p) == 3 and np.linalg.norm(zmp[i, :2] - incentre) < 1e-4
            assert np.linalg.norm(zmp[i, :2] - p.mean(axis=0)) > 0.02
            checked += 1
    assert checked >= 6


def test_the_support_centre_within_a_reach_is_the_discs_deepest_point():
    """``support_centre(p, reach)``: the point of the disc ``|P| <= reach`` farthest inside
    the triangle, against a dense polar grid of the disc (the margin, min of the three edge
    distances, computed here from cross products); the incentre when it is within reach."""
    from hexapod_kin.gait.sway import support_centre

    def margin(p: np.ndarray, q: np.ndarray) -> np.ndarray:  # q (M, 2)
        e = np.roll(p, -1, axis=0) - p
        cross = e[None, :, 0] * (q[:, None, 1] - p[None, :, 1])
        cross = cross - e[None, :, 1] * (q[:, None, 0] - p[None, :, 0])
        sign = np.sign(e[0, 0] * e[1, 1] - e[0, 1] * e[1, 0])  # counter-clockwise: +
        return np.min(sign * cross / np.linalg.norm(e, axis=1)[None, :], axis=1)

    rng = np.random.default_rng(31)
    ang = np.linspace(0.0, 2.0 * np.pi, 721)
    rad = np.linspace(0.0, 1.0, 201)
    grid = (rad[:, None, None] * np.stack([np.cos(ang), np.sin(ang)], axis=1)[None]).reshape(-1, 2)
    bound = 0
    for _ in range(30):
        p = rng.uniform(-1.0, 1.0, (3, 2))
        full = support_centre(p)
        reach = float(rng.uniform(0.05, 1.2) * np.hypot(*full))
        c = support_centre(p, reach)
        if reach >= np.hypot(*full):
            assert np.array_equal(c, full)
            continue
        bound += 1
        assert np.hypot(*c) <= reach * (1.0 + 1e-12)
        best = margin(p, reach * grid).max()
        assert margin(p, c[None])[0] >= best - 1e-12
        assert margin(p, c[None])[0] <= best + 1e-2 * reach  # the grid: 0.5 deg, reach / 200
    assert bound >= 10


def test_a_long_bodys_sway_keeps_within_the_friction_budget(monkeypatch):
    """erd:hyq's incentres lie 0.33 m ahead and behind its centre (0.63 of its height): the
    sway that puts the ZMP there accelerates the body at 0.63 g (second differences of the
    planned body positions), beyond a floor of friction 0.6. Within the budget: at most
    about SWAY_FRICTION g, the ZMP still 1 cm inside the support."""
    import hexapod_kin.gait.sway as sway
    from hexapod_kin.gait import as_whole_body

    wb = as_whole_body("erd:hyq")

    def peak(run) -> float:
        p = np.asarray(run.base_poses)[:, :2, 3]
        a = np.diff(p, 2, axis=0) * run.settings["rate"] ** 2
        return float(np.hypot(*a.T).max()) / 9.81

    run = walk(wb, pattern="crawl", duration=2.0, period=1.0)
    assert sway.SWAY_FRICTION == 0.3 and run.ok
    assert 0.25 < peak(run) < 0.34 and run.min_zmp_margin > 0.01
    monkeypatch.setattr(sway, "SWAY_FRICTION", math.inf)
    bare = walk(wb, pattern="crawl", duration=2.0, period=1.0)
    assert peak(bare) > 0.6
