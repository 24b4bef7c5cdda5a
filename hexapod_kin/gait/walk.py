"""The walk: body motion, foot placement, joint angles and every check, over time.

:func:`walk` plans a periodic gait of the whole hexapod and returns a :class:`GaitRun`.

* **Body**: the commanded body twist (vx, vy forward/sideways in the body frame [m/s], ωz
  [rad/s]) is integrated exactly on SE(2) (arcs of circle; straight lines for ωz = 0; turning
  in place for vx = vy = 0); the body stays level and its height follows the mean ground height
  of the feet plus ``body_height`` (stance feet: their contact point; swing feet: blended
  from lift-off to touch-down with the swing's own profile, so the body height is continuous).
* **Feet**: each leg follows the phase table (:mod:`.tables`). Its touch-down point is fixed
  when the swing is planned (à la Raibert): the leg's neutral foot point under the body's pose
  at the middle of the *next* stance, projected on the terrain. The swing goes from the last
  contact to the next one with a quintic horizontal profile ``10s³ − 15s⁴ + 6s⁵`` and a
  vertical lift ``64 s³(1 − s)³·h`` (peak h at s = ½): zero velocity **and zero acceleration**
  at lift-off and touch-down.
* **Round feet roll** (:func:`.paths.rolling_offsets`): the planned foot points are the centres
  of the foot spheres (radius ``r = robot.foot_radius``), ``c = contact + r n`` (n the terrain
  normal). During stance the centre moves as a sphere rolling without slip,
  ``ċ = ω × (r n)`` with ω the foot frame's angular velocity, so the material point in contact
  stays put and the body moves over the ground as planned. ω depends on the joint angles, so
  IK and rolling are iterated to a fixed point (``settings["rolling_residual"]``). With
  ``r = 0`` the feet are points fixed in the world during stance.
* **Body sway** (``sway``; on by default for four legs): the body's horizontal position gets a
  periodic offset, in the body frame, that is the periodic cubic spline (C², period T) through
  one knot per swing group at mid-swing; each knot moves the centre of mass to the centroid of
  that swing's support polygon (the stance contacts at that instant), times the gain
  ``sway`` (two correction passes with the centre of mass by FK).
* The walk is the gait's periodic regime restricted to ``[0, duration]`` (every contact point
  is given by the same formula, before ``t = 0`` too), so no start-up transient.
* **Joints**: body-pose IK (closed form per leg, nearest branch) at every sample; joint
  rates and accelerations by second-order finite differences.
* **Terrain edges**: a touch-down whose disc of radius r + ``FOOTHOLD_MARGIN`` is not flat
  moves along its travel to the nearest flat one (:func:`.terrain.off_edges`); a swing over an
  edge is raised by ΔH·p(s) (:func:`.terrain.swing_raise`; ΔH ≤ step_height).
* **Checks** at every sample: stance slip (the contact point's material point, by forward
  kinematics), static stability margin (:mod:`.stability`; a margin within
  ``MARGIN_TOL`` × the robot's size of zero is not a failure; patterns with
  ``statically_stable=False`` report it but never fail on it), joint limit margin, joint speed
  against the URDF's velocity limits (and acceleration against an optional limit), IK status,
  clearance between neighbouring legs; foot spheres and leg links against the terrain.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .._pose import rpy_to_matrix
from ..exceptions import ParameterError
from ..motion import read_only
from .knee import knee_directions, knee_seed
from .limits import fit_period, top_speed
from .paths import (
    rolling_ik,
    se2_pose,
    stance_start_index,
    terrain_normals,
)
from .robot import GaitError, WholeBody, as_whole_body
from .run import GaitRun
from .stability import (
    accel_limit_of,
    edge_clearance,
    leg_terrain_clearance,
    raise_checks,
    segment_clearance,
    support_margin,
    terrain_clearance,
)
from .sway import sway_poses
from .tables import PhaseTable, default_pattern, pattern_names, phase_table
from .terrain import Terrain, edge_distance, off_edges, raise_profile, swing_raise
from .terrain import terrain as make_terrain
from .zmp import second_difference, zmp_points

__all__ = [
    "GaitRun",
    "default_step_height",
    "default_stride",
    "highest_speed",
    "se2_pose",
    "swing_profile",
    "walk",
]

#: The longest foot stroke during one stance [m] a velocity may ask (the stride's own cap).
MAX_STROKE = 10.0
#: The largest body turn during one stance [rad] a velocity may ask.
MAX_TURN = 2.0 * math.pi
#: Default foot stroke during stance [m] when no velocity is given.
DEFAULT_STRIDE = 0.05

#: The default step height of a robot whose legs are long enough [m].
DEFAULT_STEP_HEIGHT = 0.03

#: Rounding tolerance of the checks, relative to the robot's size (the largest mount-to-centre
#: distance plus the foot reach) [m/m]: a margin above ``−MARGIN_TOL·size`` is not a failure.
MARGIN_TOL = 1e-9

#: Footholds keep a flat disc of radius ``foot_radius`` + this [m] (terrain.off_edges).
FOOTHOLD_MARGIN = 0.02

#: Swings over an edge clear the terrain by this [m] (terrain.swing_raise).
SWING_MARGIN = 0.005

#: Passes that raise the swings found short of SWING_MARGIN over an edge; the slack [m] the
#: sampled clearance may fall short of it by (the disc sampling's resolution).
EDGE_PASSES = 3
EDGE_SLACK = 1e-4

#: A swing found short of SWING_MARGIN is raised to clear it by this much more [m].
EDGE_HEADROOM = 5e-4

#: Most IK ↔ rolling passes, and the residual [m] (times the robot's size) that ends them.
ROLLING_PASSES = 12
ROLLING_TOL = 1e-13


def _num(
    name: str, value: Any, *, lo: float = 0.0, zero: bool = False, hi: float = math.inf
) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        v = math.nan
    ok = math.isfinite(v) and (v >= lo if zero else v > lo) and v <= hi
    if not ok:
        rng = f"{'>=' if zero else '>'} {lo:g}" + (f" and <= {hi:g}" if math.isfinite(hi) else "")
        raise ParameterError(
            f"{name}={value!r} is not allowed; give a finite number {rng} (SI units)",
            parameter=name,
            value=value,
            allowed=rng,
        )
    return v


def default_stride(wb: WholeBody) -> float:
    """The default stride [m]: :data:`DEFAULT_STRIDE`, or a quarter of a short leg's span."""
    return min(DEFAULT_STRIDE, 0.25 * wb.leg_span)


def default_step_height(wb: WholeBody) -> float:
    """The default step height [m]: :data:`DEFAULT_STEP_HEIGHT`, or 0.15 × a short leg's span."""
    return min(DEFAULT_STEP_HEIGHT, 0.15 * wb.leg_span)


def highest_speed(robot: Any = None, **options: Any) -> tuple[float, float, float]:
    """The highest straight speed of a walk for this robot: :func:`~.limits.top_speed`.

    Args:
        robot: Any robot :func:`walk` takes.
        **options: Keywords of :func:`walk` (``pattern``, ``step_height``...); ``stride``,
            ``velocity``, ``period``, ``duration`` and ``strict`` are the search's own.

    Returns:
        ``(v, stride, period)`` [m/s, m, s].

    """
    wb = as_whole_body(robot)
    kw = {k: v for k, v in options.items() if k not in _SEARCHED}

    def plan(L: float, T: float) -> GaitRun:
        return walk(wb, **kw, stride=L, period=T, duration=T, strict=False)

    return top_speed(plan, default_stride(wb))


_SEARCHED = ("stride", "velocity", "period", "duration", "strict")


def swing_profile(s: Any) -> tuple[np.ndarray, np.ndarray]:
    """Swing progress ``(10s³ − 15s⁴ + 6s⁵, 64 s³(1 − s)³)`` at ``s ∈ [0, 1]``.

    The first blends the horizontal position (and the ground height) from lift-off to
    touch-down, the second scales the step height (1 at s = ½); both have zero first **and
    second** derivatives at s = 0 and 1 (``30s²(1 − s)²`` and ``60s(1 − s)(1 − 2s)``;
    ``192 s²(1 − s)²(1 − 2s)`` and ``384 s(1 − s)(5s² − 5s + 1)``), so a swing starts and ends
    with zero velocity and zero acceleration.
    """
    s = np.asarray(s, dtype=float)
    u = s * (1.0 - s)
    return s**3 * (10.0 - 15.0 * s + 6.0 * s * s), 64.0 * u * u * u


def _zmp_margin(
    wb: WholeBody,
    T: np.ndarray,
    base: np.ndarray,
    contacts: np.ndarray,
    support: np.ndarray,
    t: np.ndarray,
) -> np.ndarray:
    """(N,) :attr:`GaitRun.zmp_margin` (empty below 4 samples or without a mass)."""
    if len(t) < 4 or not wb.mass > 0:
        return np.zeros(0)
    sup = support[..., None]
    h = ((contacts[..., 2:3] * sup).sum(axis=1) / np.maximum(sup.sum(axis=1), 1))[:, 0]
    zmp = np.ascontiguousarray(zmp_points(wb, T, base, t, h))
    return np.asarray(support_margin(contacts, support, zmp))


def _neighbour_pairs(wb: WholeBody) -> tuple[tuple[int, int], ...]:
    yaw = np.arctan2(wb.mounts[:, 1, 3], wb.mounts[:, 0, 3])
    order = [int(i) for i in np.argsort(yaw, kind="stable")]
    n = len(order)
    if n < 2:
        return ()
    pairs = {tuple(sorted((order[k], order[(k + 1) % n]))) for k in range(n)}
    return tuple(sorted((int(a), int(b)) for a, b in pairs if a != b))


def walk(
    robot: Any = None,
    *,
    pattern: str | PhaseTable | None = None,
    stride: float | None = None,
    step_height: float | None = None,
    period: float | None = None,
    duty_factor: float | None = None,
    velocity: Any = None,
    body_height: float | None = None,
    foot_reach: float | None = None,
    terrain: Any = None,
    rate: float = 100.0,
    duration: float = 10.0,
    q0: Any = None,
    strict: bool = True,
    foot_radius: float | None = None,
    sway: float | None = None,
    accel_limit: Any = None,
    knee: str | None = None,
    open_loop: bool = True,
) -> GaitRun:
    """Walk the robot and check every sample.

    Args:
        robot: The robot: a :class:`~.robot.WholeBody`, a ``Hexapod``, or any source
            :func:`~.robot.as_whole_body` takes (a URDF path, ``erd:NAME``, a loaded model);
            default the built-in hexapod.
        pattern: A name of :func:`~.tables.pattern_names` for the robot's legs (``tripod``,
            ``wave``, ``ripple`` for six; ``crawl``, ``trot``, ``pace`` for four; ``wave``,
            ``ripple`` for eight) or a :class:`~.tables.PhaseTable` (default
            :func:`~.tables.default_pattern`: tripod, crawl for four legs, else wave).
        stride: Foot stroke during stance [m] for a straight forward walk (sets
            ``vx = stride / (duty_factor · period)``); default :func:`default_stride` when
            ``velocity`` is not given. Give ``stride`` or ``velocity``, not both.
        step_height: Swing lift above the straight line between contacts [m] (default
            :func:`default_step_height`).
        period: Cycle time T [s]. Default 1 s, or for a straight walk (no ``velocity``) the
            shortest multiple of :data:`~.limits.PERIOD_STEP` that keeps every joint within
            its URDF velocity limit (and ``accel_limit``): :func:`~.limits.fit_period`.
        duty_factor: Stance fraction β in (0, 1) (default the pattern's).
        velocity: Body twist ``(vx, vy, wz)`` [m/s, m/s, rad/s] in the body frame (curves with
            vx and wz, turning in place with only wz).
        body_height: Body above the mean ground height of the feet's contacts [m] (default the
            robot's :attr:`~.robot.WholeBody.body_height`; the built-in hexapod: 0.08 m).
        foot_reach: Horizontal distance from each leg's mount to its neutral foot point [m]
            (default the robot's own, :attr:`~.robot.WholeBody.foot_reach`; the built-in
            hexapod: 0.16 m).
        terrain: ``"flat"`` (default), ``"slope"``, ``"step"``, a
            :class:`~.terrain.Terrain` or ``h(x, y)``.
        rate: Sample rate [Hz].
        duration: Length of the run [s].
        q0: (nq,) joints the first sample's IK branches are nearest to.
        strict: Raise on the first failed check (else return the run with its checks).
        foot_radius: Radius of the round feet [m] (default ``robot.foot_radius``; 0: point
            feet fixed in stance).
        sway: Body-sway gain in [0, 1] (default 0.5 for a statically stable pattern on four
            legs, else 0): see the module docstring.
        accel_limit: Joint acceleration limit [rad/s²], one number or (nq,) (default none:
            accelerations are reported, not checked; URDF has no acceleration limit).
        knee: Where the knees of the closed-form legs point at the first sample (one of
            :data:`~.knee.KNEES`: ``up``, ``down``, ``forward``, ``backward``, ``out``,
            ``in``; default: the branch inside the joint limits nearest ``q0``). The
            directions taken are reported (``settings["knees"]``).
        open_loop: True (default): the plan is played as it is, so a pattern that is not
            statically stable (trot, pace: two feet on the ground) is refused with a
            :class:`GaitError` (check ``"statically unstable"``). False: planned anyway,
            for a balance controller to track (its static margin reported, not checked).

    Returns:
        A :class:`GaitRun`.

    Raises:
        ParameterError: A bad parameter (named, with what is allowed).
        GaitError: (``strict``) a check fails: ``"terrain"`` (a foot off the terrain),
            ``"terrain clearance"`` (a foot sphere into the ground: step too low),
            ``"leg terrain clearance"`` (a link into the terrain),
            ``"reach"`` (stride too long, step too high...), ``"joint limit"``,
            ``"leg clearance"``, ``"stability margin"`` (statically stable patterns only),
            ``"joint speed"``, ``"joint acceleration"``; the message names the leg or joint,
            the time and by how much.

    """
    wb = as_whole_body(robot)
    pattern = default_pattern(wb.n_legs) if pattern is None else pattern
    table = phase_table(pattern, wb.n_legs, wb.mounts[:, :2, 3], wb.leg_names).with_duty_factor(
        duty_factor
    )
    if open_loop and not table.statically_stable:
        offered = pattern_names(wb.n_legs, wb.mounts[:, :2, 3])
        stable = [
            p for p in offered if phase_table(p, wb.n_legs, wb.mounts[:, :2, 3]).statically_stable
        ]
        raise GaitError(
            f"pattern {table.name!r} keeps two feet on the ground: it is not statically stable "
            "and needs a balance controller, so the open-loop planner refuses it (check "
            "'statically unstable'; plan it for a controller with walk(..., open_loop=False), "
            f"or walk {', '.join(stable)})",
            check="statically unstable",
            parameter="pattern",
            value=table.name,
            allowed="a statically stable pattern",
        )
    beta = table.duty_factor
    H = _num(
        "step_height",
        default_step_height(wb) if step_height is None else step_height,
        zero=True,
        hi=1.0,
    )
    if period is None and velocity is None:

        def planned(T: float, whole: bool = False) -> GaitRun:
            return walk(
                wb,
                pattern=table,
                stride=stride,
                step_height=H,
                period=T,
                body_height=body_height,
                foot_reach=foot_reach,
                terrain=terrain,
                rate=rate,
                duration=duration if whole else T,
                q0=q0,
                strict=False,
                foot_radius=foot_radius,
                sway=sway,
                accel_limit=accel_limit,
                knee=knee,
                open_loop=open_loop,
            )

        period = fit_period(planned)  # one cycle: the whole walk on flat ground (periodic)
        if make_terrain(terrain).relief > 0:  # not periodic: the whole walk
            period = fit_period(lambda T: planned(T, True), period)
    T = _num("period", 1.0 if period is None else period, hi=1e3)
    bh = wb.body_height if body_height is None else _num("body_height", body_height, hi=10.0)
    reach = wb.foot_reach if foot_reach is None else _num("foot_reach", foot_reach, hi=10.0)
    dur = _num("duration", duration, zero=True, hi=1e5)
    hz = _num("rate", rate, hi=1e5)
    rad = float(wb.foot_radius) if foot_radius is None else foot_radius
    rad = _num("foot_radius", rad, zero=True, hi=1.0)
    default_sway = 0.5 if (wb.n_legs == 4 and table.statically_stable) else 0.0
    gain = default_sway if sway is None else _num("sway", sway, zero=True, hi=1.0)
    n = int(round(dur * hz)) + 1
    if n > 2_000_000:
        raise ParameterError(
            f"duration*rate = {dur * hz:.4g} samples is too many; at most 2e6",
            parameter="rate",
            value=rate,
            allowed="duration*rate <= 2e6",
        )
    acc_lim = accel_limit_of(accel_limit, wb.nq)
    if stride is not None and velocity is not None:
        raise ParameterError(
            f"stride={stride!r} and velocity={velocity!r}: give one (stride sets a straight "
            "walk; velocity any twist)",
            parameter="stride",
            value=stride,
            allowed="stride or velocity",
        )
    if velocity is None:
        L = _num(
            "stride", default_stride(wb) if stride is None else stride, zero=True, hi=MAX_STROKE
        )
        vel = (L / (beta * T), 0.0, 0.0)
    else:
        try:
            v = np.asarray(velocity, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            v = np.full(1, np.nan)
        if v.shape != (3,) or not np.all(np.isfinite(v)):
            raise ParameterError(
                f"velocity={velocity!r}: three finite numbers vx [m/s], vy [m/s], wz [rad/s]",
                parameter="velocity",
                value=velocity,
                allowed="(vx, vy, wz)",
            )
        vel = (float(v[0]), float(v[1]), float(v[2]))
    ground: Terrain = make_terrain(terrain)
    t = np.arange(n) / hz
    names = wb.leg_names
    nl = wb.n_legs
    # neutral foot points in the body frame (xy)
    nb = wb.neutral_feet(reach)[:, :2]  # (L, 2)
    size = float(np.hypot(wb.mounts[:, 0, 3], wb.mounts[:, 1, 3]).max()) + reach
    tol = MARGIN_TOL * size
    vx, vy, w = vel
    with np.errstate(over="ignore", invalid="ignore"):
        strokes = np.hypot(vx - w * nb[:, 1], vy + w * nb[:, 0]) * beta * T
    if not (np.all(strokes <= MAX_STROKE) and abs(w) * beta * T <= MAX_TURN):
        raise ParameterError(  # absurd twists refused before any arithmetic overflows
            f"velocity={vel!r}: a foot would stroke {float(np.max(strokes)):.3g} m and the body "
            f"turn {abs(w) * beta * T:.3g} rad during one stance; allowed: strokes up to "
            f"{MAX_STROKE:g} m (as stride) and turns up to {MAX_TURN:g} rad",
            parameter="velocity",
            value=velocity,
            allowed=f"strokes <= {MAX_STROKE:g} m, turns <= {MAX_TURN:g} rad per stance",
        )
    # --- contacts and swings, per sample and leg
    offs = np.asarray(table.offsets)
    tsw = (1.0 - beta) * T
    m = np.floor(t[:, None] / T + offs[None, :] - beta)  # latest lift-off index
    t_lo = (m + beta - offs[None, :]) * T
    s = (t[:, None] - t_lo) / tsw
    swing = s < 1.0 - 1e-9  # a touch-down instant is stance, whatever the rounding of t
    support = ~swing
    t_td = t_lo + tsw
    # one contact per swing (m, leg): a table over the swings the run touches, m0 - 1 first
    m0 = int(m.min()) - 1
    mm = np.arange(m0, int(m.max()) + 1, dtype=float)[:, None]
    td_tab = (mm + beta - offs[None, :]) * T + tsw  # (M, L) touch-down times
    legs = np.arange(nl)[None, :]
    row = (m - m0).astype(np.int64)
    gb = np.stack([vx - w * nb[:, 1], vy + w * nb[:, 0]], axis=1)  # feet's travel, body frame
    gb[np.hypot(gb[:, 0], gb[:, 1]) == 0.0] = (1.0, 0.0)
    gb /= np.hypot(gb[:, 0], gb[:, 1])[:, None]

    def contact(t_touch: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        pose = se2_pose(t_touch + 0.5 * beta * T, vel)  # body at mid-stance
        c, sn = np.cos(pose[..., 2]), np.sin(pose[..., 2])
        x = pose[..., 0] + c * nb[:, 0] - sn * nb[:, 1]
        y = pose[..., 1] + sn * nb[:, 0] + c * nb[:, 1]
        u = np.stack([c * gb[:, 0] - sn * gb[:, 1], sn * gb[:, 0] + c * gb[:, 1]], axis=-1)
        return np.stack([x, y, ground(x, y)], axis=-1), u

    tab, along = contact(td_tab)
    moved = np.zeros(tab.shape[:2])
    if FOOTHOLD_MARGIN >= 0 and np.isfinite(tab[..., 2]).all():
        xy, moved_flat = off_edges(
            ground,
            tab.reshape(-1, 3),
            along.reshape(-1, 2),
            rad + FOOTHOLD_MARGIN,
            4.0 * (rad + FOOTHOLD_MARGIN),
        )
        moved = moved_flat.reshape(moved.shape)
        if moved.any():
            tab = np.concatenate([xy, ground(xy[:, 0], xy[:, 1])[:, None]], axis=1).reshape(
                tab.shape
            )
    nxt = tab[row, legs]  # TD_m: the contact after swing m
    prev = tab[row - 1, legs]  # TD_{m-1}: the contact before it
    used = np.zeros(tab.shape[:2], dtype=bool)
    used[row, legs] = True
    used[(row - 1)[swing], np.broadcast_to(legs, row.shape)[swing]] = True
    for pts, when in ((nxt, t_td), (prev, td_tab[row - 1, legs])):
        bad = ~np.isfinite(pts[..., 2]) & (swing | (pts is nxt))
        if bad.any():
            i, leg = np.argwhere(bad)[0]
            p = pts[i, leg]
            raise GaitError(
                f"leg {names[leg]}: touch-down point ({p[0]:.4g}, {p[1]:.4g}) m at "
                f"t={max(when[i, leg], 0.0):.4g} s is off the terrain {ground.name!r} "
                "(check 'terrain')",
                check="terrain",
                leg=names[leg],
                time=float(max(when[i, leg], 0.0)),
                parameter="terrain",
                value=[float(p[0]), float(p[1])],
                allowed="feet where h(x, y) is defined",
            )
    sc = np.clip(s, 0.0, 1.0)
    blend, lift = swing_profile(sc)
    n_tab = terrain_normals(ground, tab[..., 0], tab[..., 1])
    c_tab = tab + rad * n_tab  # sphere centres on the contacts
    n_nxt = n_tab[row, legs]
    c_nxt, c_prev = c_tab[row, legs], c_tab[row - 1, legs]
    plan = np.where(swing[..., None], c_prev + (c_nxt - c_prev) * blend[..., None], c_nxt)
    plan[..., 2] += np.where(swing, H * lift, 0.0)
    # swings over an edge: raised to clear it (terrain.swing_raise); sized again from the
    # lift-off's rolling once the IK knows it (a swing's height does not change its stance)
    lift2 = raise_profile(sc)
    ok_tab = bool(np.isfinite(tab[..., 2]).all())

    def raised(lo: np.ndarray) -> np.ndarray:
        out = np.zeros(tab.shape[:2])
        if ok_tab:
            c0, c1 = (c_tab[:-1] + lo[1:]).reshape(-1, 3), c_tab[1:].reshape(-1, 3)
            out[1:] = swing_raise(ground, c0, c1, H, rad, SWING_MARGIN).reshape(-1, nl)
        return out

    extra = raised(np.zeros(tab.shape))
    plan[..., 2] += np.where(swing, extra[row, legs] * lift2, 0.0)
    gz = np.where(swing, prev[..., 2] + (nxt[..., 2] - prev[..., 2]) * blend, nxt[..., 2])
    # --- body
    pose = se2_pose(t, vel)
    base = np.zeros((n, 4, 4))
    rz = np.array([rpy_to_matrix(0.0, 0.0, psi)[:2, :2] for psi in pose[:, 2]])  # Rz(ψ)
    base[:, :2, :2] = rz
    base[:, 0, 1] = -rz[:, 1, 0]  # −sin ψ (rpy_to_matrix's 0 − sin ψ is +0.0 at ψ = 0)
    base[:, 2, 2] = base[:, 3, 3] = 1.0
    base[:, 0, 3], base[:, 1, 3] = pose[:, 0], pose[:, 1]
    base[:, 2, 3] = gz.mean(axis=1) + bh
    # --- joints: sway (optional), then IK <-> rolling to a fixed point
    if knee is not None:
        q0 = knee_seed(wb, knee, base[0], plan[0], q0)
    if gain > 0.0:
        base = sway_poses(wb, table, T, vel, nb, gain, base, plan, t, q0)
    args = (support, swing, blend, n_nxt, rad, t, q0, ROLLING_TOL * size, ROLLING_PASSES)
    feet, q, ik, passes, residual, T_last, rolled = rolling_ik(wb, base, plan, *args)
    if extra.any():
        lo = np.zeros(tab.shape)  # each swing's lift-off rolling: feet − plan = lo·(1 − b)
        sw = swing & (blend < 0.5)
        lo[row[sw], np.broadcast_to(legs, sw.shape)[sw]] = (
            ((feet - plan)[sw]) / (1.0 - blend[sw])[:, None]
        )
        more = np.maximum(raised(lo) - extra, 0.0)
        if more.any():
            extra += more
            plan[..., 2] += np.where(swing, more[row, legs] * lift2, 0.0)
            feet, q, ik, passes, residual, T_last, rolled = rolling_ik(wb, base, plan, *args)
    # each leg's own ground: its contact's plane (in swing the lower of the two contacts')
    low = np.where((swing & (prev[..., 2] < nxt[..., 2]))[..., None], prev, nxt)
    n_low = np.where((swing & (prev[..., 2] < nxt[..., 2]))[..., None], n_tab[row - 1, legs], n_nxt)
    plane = np.concatenate([n_low, np.einsum("nli,nli->nl", n_low, low)[..., None]], axis=-1)
    # the swing clearance promised over edges (SWING_MARGIN), measured on the feet as solved:
    # a swing short of it is raised by the deficit over its raise profile, and solved again
    # (over the ground above the plane of the swing's lift-off in its first half, of its
    # touch-down in its second: the edge it climbs, not the ground it leaves or lands on)
    edge_gap = np.full(swing.shape, np.inf)
    if ok_tab and ground.relief > 0:
        first = (swing & (blend < 0.5))[..., None]
        n_own = np.where(first, n_tab[row - 1, legs], n_nxt)
        own = np.concatenate(
            [n_own, np.einsum("nli,nli->nl", n_own, np.where(first, prev, nxt))[..., None]],
            axis=-1,
        )
        for _ in range(EDGE_PASSES + 1):
            edge_gap = np.full(swing.shape, np.inf)
            edge_gap[swing] = edge_distance(ground, feet[swing], rad, SWING_MARGIN, own[swing])
            short = swing & (edge_gap < SWING_MARGIN - EDGE_SLACK) & (lift2 > 0.05)
            if not short.any() or _ == EDGE_PASSES:
                break
            need = np.zeros(tab.shape[:2])
            at = (row[short], np.broadcast_to(legs, short.shape)[short])
            aim = SWING_MARGIN + EDGE_HEADROOM  # the sampled distance errs by a fraction of it
            np.maximum.at(need, at, (aim - edge_gap[short]) / lift2[short])
            need = np.minimum(need, np.maximum(H - extra, 0.0))  # the raise stays <= H
            if not need.any():
                break
            extra += need
            plan[..., 2] += np.where(swing, need[row, legs] * lift2, 0.0)
            feet, q, ik, passes, residual, T_last, rolled = rolling_ik(wb, base, plan, *args)
    foot_gap = terrain_clearance(ground, feet, swing, rad, t, names, H, strict)
    edge_clearance(edge_gap, swing, SWING_MARGIN - EDGE_SLACK, t, names, H, strict)
    if strict and not np.asarray(ik.ok).all():
        wb.body_ik(base, feet, q_prev=q0, times=t, strict=True)  # raises, naming the check
    if T_last is None:
        pts, com = wb.points_and_com(q, base)
    else:
        pts = wb.points_of(T_last)
        com = wb.com_of(T_last, base) if hasattr(wb, "com_of") else wb.com(q, base)
    actual = np.ascontiguousarray(pts[:, :, -1])
    ref = actual[stance_start_index(support), np.arange(nl)[None, :]]
    # rolled: the rolling of the final q's foot rotations (by FK; 0 for point feet)
    slip = np.where(support, np.linalg.norm(actual - ref - rolled, axis=-1), 0.0)
    margin = support_margin(actual - rad * n_nxt, support, com)
    T_all = wb.joint_poses(q, base) if T_last is None else T_last
    zmp_margin = _zmp_margin(wb, T_all, base, actual - rad * n_nxt, support, t)
    pairs = _neighbour_pairs(wb)
    clear = segment_clearance(pts, np.array(pairs, dtype=np.int64).reshape(-1, 2))
    clear -= 2.0 * wb.link_radius
    leg_gap = leg_terrain_clearance(ground, pts, wb.link_radius, rad, plane, t, names, strict)
    if n > 3:
        qdot = np.gradient(q, t, axis=0, edge_order=2)
        qddot = second_difference(q, t)
    else:
        qdot, qddot = np.zeros_like(q), np.zeros_like(q)
    vlim = np.asarray(wb.velocity_limit, dtype=float).reshape(-1)
    if strict:
        raise_checks(
            wb.joint_names,
            table,
            names,
            pairs,
            t,
            clear,
            margin,
            tol,
            strokes,
            qdot,
            qddot,
            vlim,
            acc_lim,
            support,
        )
    phase = table.phase(t, T)
    read_only(t, base, actual, feet, q, qdot, qddot, support, phase, com, slip, margin, clear)
    settings = {
        "stride": float(strokes.max()),
        "step_height": H,
        "period": T,
        "duty_factor": beta,
        "velocity": vel,
        "body_height": bh,
        "foot_reach": reach,
        "terrain": ground.name,
        "duration": dur,
        "rate": hz,
        "foot_radius": rad,
        "sway": gain,
        "knees": knee_directions(wb, q[0]) if n else (),
        "rolling_passes": passes,
        "rolling_residual": residual,
        "margin_tol": tol,
        "footholds_moved": int(np.count_nonzero(used & (moved != 0))),
        "foothold_shift_max": float(np.abs(np.where(used, moved, 0.0)).max()),
        "swings_raised": int(np.count_nonzero(used[1:] & (extra[1:] > 0))),
        "swing_raise_max": float(np.where(used, extra, 0.0).max()),
        "min_edge_clearance": (
            float(edge_gap.min()) if edge_gap.size and np.isfinite(edge_gap.min()) else None
        ),
    }
    ik_ok = np.asarray(ik.ok)
    read_only(ik_ok, vlim, acc_lim, n_nxt, foot_gap, leg_gap)
    return GaitRun(
        t=t,
        base_poses=base,
        feet=actual,
        feet_planned=feet,
        q=q,
        qdot=qdot,
        support=support,
        phase=phase,
        com=com,
        slip=slip,
        margin=margin,
        zmp_margin=zmp_margin,
        limit_margin=ik.limit_margin,
        ik_ok=ik_ok,
        reach_excess=ik.excess,
        clearance=clear,
        pairs=pairs,
        leg_names=names,
        joint_names=wb.joint_names,
        table=table,
        settings=settings,
        mass=wb.mass,
        qddot=qddot,
        velocity_limit=vlim,
        accel_limit=acc_lim,
        robot=wb,
        normals=n_nxt,
        foot_gap=foot_gap,
        leg_gap=leg_gap,
    )
