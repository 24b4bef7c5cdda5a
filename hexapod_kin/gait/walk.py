"""The walk: body motion, foot placement, joint angles and every check, over time.

:func:`walk` plans a periodic gait of the whole hexapod and returns a :class:`GaitRun`.

* **Body**: the body twist (vx, vy [m/s] in the body frame, ωz [rad/s]) integrated exactly on
  SE(2); level, at ``body_height`` above the feet's mean ground height (swing feet blended
  from lift-off to touch-down, so the height is continuous).
* **Feet**: each leg follows the phase table (:mod:`.tables`). A touch-down point is fixed
  when its swing is planned (à la Raibert): the neutral foot point under the body at the
  middle of the *next* stance, on the terrain. Swings: horizontal ``10s³ − 15s⁴ + 6s⁵``,
  lift ``64 s³(1 − s)³·h``: zero velocity and acceleration at lift-off and touch-down.
* **Round feet roll** (:func:`.paths.rolling_offsets`): planned points are the spheres'
  centres ``c = contact + r n``, rolling without slip in stance (``ċ = ω × (r n)``); IK and
  rolling iterate to a fixed point (``settings["rolling_residual"]``).
* **Body sway** (``sway``; on by default for four legs): :mod:`.sway`.
* The gait's periodic regime restricted to ``[0, duration]``: no start-up transient.
* **Joints**: body-pose IK (closed form per leg, nearest branch); rates by second-order
  finite differences.
* **Terrain edges**: a touch-down whose disc of radius r + :data:`FOOTHOLD_MARGIN` is not
  flat moves along its travel (:func:`.terrain.off_edges`); a swing over an edge is raised
  (:func:`.terrain.swing_raise`, by at most the step height).
* **Checks** at every sample: stance slip, static stability margin (:mod:`.stability`; within
  ``MARGIN_TOL`` × the robot's size of zero is no failure; patterns with
  ``statically_stable=False`` never fail on it), joint limits, speeds (URDF limits) and
  accelerations (optional limit), IK status, neighbouring legs' clearance, feet and links
  against the terrain.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._pose import rpy_to_matrix
from ..exceptions import ParameterError, positive
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
    leg_terrain_clearance,
    raise_checks,
    segment_clearance,
    support_margin,
    terrain_clearance,
)
from .sway import sway_poses
from .sway import zmp_margin as sway_zmp_margin
from .tables import PhaseTable, default_pattern, pattern_names, phase_table
from .terrain import Terrain, edge_distance, off_edges, raise_profile, swing_profile, swing_raise
from .terrain import terrain as make_terrain
from .zmp import rates

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
        robot: A :class:`~.robot.WholeBody`, a ``Hexapod``, or any source
            :func:`~.robot.as_whole_body` takes (a URDF path, ``erd:NAME``, a loaded model);
            default the built-in hexapod.
        pattern: A name of :func:`~.tables.pattern_names` for the robot's legs (``tripod``,
            ``wave``, ``ripple`` for six; ``crawl``, ``trot``, ``pace`` for four; ``wave``,
            ``ripple`` for eight) or a :class:`~.tables.PhaseTable` (default
            :func:`~.tables.default_pattern`).
        stride: Foot stroke during stance [m] for a straight forward walk (``vx = stride /
            (duty_factor · period)``); default :func:`default_stride` without ``velocity``.
            Give ``stride`` or ``velocity``, not both.
        step_height: Swing lift above the straight line between contacts [m] (default
            :func:`default_step_height`).
        period: Cycle time T [s]. Default 1 s, or for a straight walk (no ``velocity``) the
            shortest multiple of :data:`~.limits.PERIOD_STEP` that keeps every joint within
            its URDF velocity limit (and ``accel_limit``): :func:`~.limits.fit_period`.
        duty_factor: Stance fraction β in (0, 1) (default the pattern's).
        velocity: Body twist ``(vx, vy, wz)`` [m/s, m/s, rad/s] in the body frame.
        body_height: Body above the mean ground height of the feet's contacts [m] (default
            :attr:`~.robot.WholeBody.body_height`).
        foot_reach: Horizontal distance from each leg's mount to its neutral foot point [m]
            (default :attr:`~.robot.WholeBody.foot_reach`).
        terrain: ``"flat"`` (default), ``"slope"``, ``"step"``, a :class:`~.terrain.Terrain`
            or ``h(x, y)``.
        rate: Sample rate [Hz].
        duration: Length of the run [s].
        q0: (nq,) joints the first sample's IK branches are nearest to.
        strict: Raise on the first failed check (else return the run with its checks).
        foot_radius: Radius of the round feet [m] (default ``robot.foot_radius``; 0: point
            feet fixed in stance).
        sway: Body-sway gain in [0, 1] (default 1 for a statically stable pattern on four
            legs, else 0): :mod:`.sway`.
        accel_limit: Joint acceleration limit [rad/s²], one number or (nq,) (default none:
            reported, not checked).
        knee: Where the knees of the closed-form legs point at the first sample (one of
            :data:`~.knee.KNEES`; default: the branch inside the joint limits nearest
            ``q0``); reported in ``settings["knees"]``.
        open_loop: True (default): a pattern that is not statically stable (trot, pace) is
            refused with a :class:`GaitError` (check ``"statically unstable"``). False:
            planned anyway, for a balance controller (its static margin reported only).

    Returns:
        A :class:`GaitRun`.

    Raises:
        ParameterError: A bad parameter (named, with what is allowed).
        GaitError: (``strict``) a check fails: ``"terrain"``, ``"terrain clearance"``,
            ``"leg terrain clearance"``, ``"reach"``, ``"joint limit"``, ``"leg clearance"``,
            ``"stability margin"`` (statically stable patterns only), ``"joint speed"``,
            ``"joint acceleration"``; the message names the leg or joint, the time and by
            how much.

    """
    args = dict(locals())  # this walk's arguments (a period is fitted by walking again)
    wb = as_whole_body(robot)
    table = _phase_table(wb, pattern, duty_factor, open_loop)
    H = positive(
        "step_height",
        default_step_height(wb) if step_height is None else step_height,
        allow_zero=True,
        at_most=1.0,
    )
    if period is None and velocity is None:
        refit = ("robot", "pattern", "step_height", "period", "duration", "strict")
        same = {k: v for k, v in args.items() if k not in refit} | {"strict": False}

        def planned(T: float, whole: bool = False) -> GaitRun:
            length = duration if whole else T
            return walk(wb, **same, pattern=table, step_height=H, period=T, duration=length)

        period = fit_period(planned)  # one cycle: the whole walk on flat ground (periodic)
        if make_terrain(terrain).relief > 0:  # not periodic: the whole walk
            period = fit_period(lambda T: planned(T, True), period)
    beta = table.duty_factor
    T = positive("period", 1.0 if period is None else period, at_most=1e3)
    bh, reach = wb.body_height, wb.foot_reach
    if body_height is not None:
        bh = positive("body_height", body_height, at_most=10.0)
    if foot_reach is not None:
        reach = positive("foot_reach", foot_reach, at_most=10.0)
    dur = positive("duration", duration, allow_zero=True, at_most=1e5)
    hz = positive("rate", rate, at_most=1e5)
    rad = float(wb.foot_radius) if foot_radius is None else foot_radius
    rad = positive("foot_radius", rad, allow_zero=True, at_most=1.0)
    default_sway = 1.0 if (wb.n_legs == 4 and table.statically_stable) else 0.0
    gain = default_sway if sway is None else positive("sway", sway, allow_zero=True, at_most=1.0)
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
        L = positive(
            "stride",
            default_stride(wb) if stride is None else stride,
            allow_zero=True,
            at_most=MAX_STROKE,
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
    nb = wb.neutral_feet(reach)[:, :2]  # (L, 2)
    size = float(np.hypot(wb.mounts[:, 0, 3], wb.mounts[:, 1, 3]).max()) + reach
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
    t = np.arange(n) / hz
    st = _Setup(
        table, H, T, beta, vel, bh, reach, dur, hz, rad, gain, acc_lim, ground, t, nb, strokes, size
    )
    sw = _Swings.of(wb, st)
    plan = sw.planned_feet(st)
    base = _body_poses(st, sw)
    if knee is not None:
        q0 = knee_seed(wb, knee, base[0], plan[0], q0)
    if st.sway > 0.0:
        base = sway_poses(wb, table, st.T, st.vel, st.nb, st.sway, base, plan, st.t, q0)
    sol = _Solution(wb, st, sw, base, plan, q0)
    sol.clear_edges()
    return _checked(wb, st, sw, sol, q0, strict)


def _phase_table(wb: WholeBody, pattern: Any, duty_factor: Any, open_loop: bool) -> PhaseTable:
    """The walk's phase table; a pattern that is not statically stable refused when open loop."""
    pattern = default_pattern(wb.n_legs) if pattern is None else pattern
    xy = wb.mounts[:, :2, 3]
    table = phase_table(pattern, wb.n_legs, xy, wb.leg_names).with_duty_factor(duty_factor)
    if open_loop and not table.statically_stable:
        offered = pattern_names(wb.n_legs, xy)
        stable = [p for p in offered if phase_table(p, wb.n_legs, xy).statically_stable]
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
    return table


@dataclass(frozen=True)
class _Setup:
    """A walk's checked settings (SI units) and its sample times."""

    table: PhaseTable
    H: float  # step height [m]
    T: float  # period [s]
    beta: float  # duty factor
    vel: tuple[float, float, float]  # body twist (vx, vy, wz)
    body_height: float
    reach: float
    duration: float
    rate: float
    rad: float  # foot radius [m]
    sway: float
    acc_lim: np.ndarray
    ground: Terrain
    t: np.ndarray
    nb: np.ndarray  # (L, 2) neutral feet in the body frame
    strokes: np.ndarray  # (L,) each foot's stroke during a stance [m]
    size: float  # the robot's size [m] (the checks' rounding scale)

    @property
    def tol(self) -> float:
        """The margin tolerance [m]: :data:`MARGIN_TOL` × the robot's size."""
        return MARGIN_TOL * self.size


@dataclass
class _Swings:
    """Every swing of the run and, per sample and leg, where it stands in them.

    Each leg's contacts form a table over the swings the run touches (``m0 − 1`` first): row
    ``m`` is the touch-down after swing ``m``, fixed when the swing is planned (the leg's
    neutral foot point under the body at the middle of the next stance, moved off terrain
    edges). Per sample, ``row`` is the latest swing (lift-off index), ``s`` its progress.
    """

    row: np.ndarray  # (N, L) the latest swing's row in the contact table
    legs: np.ndarray  # (1, L) leg indices (for fancy indexing)
    swing: np.ndarray  # (N, L) True in swing
    sc: np.ndarray  # (N, L) swing progress clipped into [0, 1]
    blend: np.ndarray  # (N, L) the horizontal profile of :func:`swing_profile`
    tab: np.ndarray  # (M, L, 3) the contacts
    n_tab: np.ndarray  # (M, L, 3) the terrain normals at them
    moved: np.ndarray  # (M, L) each contact's move off an edge along its travel [m]
    used: np.ndarray  # (M, L) the contacts the run touches
    extra: np.ndarray  # (M, L) each swing's raise over edges [m]

    @classmethod
    def of(cls, wb: WholeBody, st: _Setup) -> _Swings:
        """The contacts and the swings of the run (raises check ``"terrain"``)."""
        offs = np.asarray(st.table.offsets)
        beta, T, t, nb, ground, rad = st.beta, st.T, st.t, st.nb, st.ground, st.rad
        tsw = (1.0 - beta) * T
        m = np.floor(t[:, None] / T + offs[None, :] - beta)  # latest lift-off index
        t_lo = (m + beta - offs[None, :]) * T
        s = (t[:, None] - t_lo) / tsw
        swing = s < 1.0 - 1e-9  # a touch-down instant is stance, whatever the rounding of t
        t_td = t_lo + tsw
        m0 = int(m.min()) - 1
        mm = np.arange(m0, int(m.max()) + 1, dtype=float)[:, None]
        td_tab = (mm + beta - offs[None, :]) * T + tsw  # (M, L) touch-down times
        legs = np.arange(wb.n_legs)[None, :]
        row = (m - m0).astype(np.int64)
        vx, vy, w = st.vel
        gb = np.stack([vx - w * nb[:, 1], vy + w * nb[:, 0]], axis=1)  # feet's travel (body)
        gb[np.hypot(gb[:, 0], gb[:, 1]) == 0.0] = (1.0, 0.0)
        gb /= np.hypot(gb[:, 0], gb[:, 1])[:, None]
        pose = se2_pose(td_tab + 0.5 * beta * T, st.vel)  # body at mid-stance
        c, sn = np.cos(pose[..., 2]), np.sin(pose[..., 2])
        x = pose[..., 0] + c * nb[:, 0] - sn * nb[:, 1]
        y = pose[..., 1] + sn * nb[:, 0] + c * nb[:, 1]
        along = np.stack([c * gb[:, 0] - sn * gb[:, 1], sn * gb[:, 0] + c * gb[:, 1]], axis=-1)
        tab = np.stack([x, y, ground(x, y)], axis=-1)
        moved = np.zeros(tab.shape[:2])
        if FOOTHOLD_MARGIN >= 0 and np.isfinite(tab[..., 2]).all():
            disc = rad + FOOTHOLD_MARGIN
            xy, shift = off_edges(ground, tab.reshape(-1, 3), along.reshape(-1, 2), disc, 4 * disc)
            moved = shift.reshape(moved.shape)
            if moved.any():
                z = ground(xy[:, 0], xy[:, 1])[:, None]
                tab = np.concatenate([xy, z], axis=1).reshape(tab.shape)
        used = np.zeros(tab.shape[:2], dtype=bool)
        used[row, legs] = True
        used[(row - 1)[swing], np.broadcast_to(legs, row.shape)[swing]] = True
        nxt = tab[row, legs]
        for pts, when in ((nxt, t_td), (tab[row - 1, legs], td_tab[row - 1, legs])):
            bad = ~np.isfinite(pts[..., 2]) & (swing | (pts is nxt))
            if bad.any():
                i, leg = np.argwhere(bad)[0]
                p, name, at = pts[i, leg], wb.leg_names[leg], float(max(when[i, leg], 0.0))
                raise GaitError(
                    f"leg {name}: touch-down point ({p[0]:.4g}, {p[1]:.4g}) m at "
                    f"t={at:.4g} s is off the terrain {ground.name!r} (check 'terrain')",
                    check="terrain",
                    leg=name,
                    time=at,
                    parameter="terrain",
                    value=[float(p[0]), float(p[1])],
                    allowed="feet where h(x, y) is defined",
                )
        sc = np.clip(s, 0.0, 1.0)
        n_tab = terrain_normals(ground, tab[..., 0], tab[..., 1])
        extra = np.zeros(tab.shape[:2])
        return cls(row, legs, swing, sc, swing_profile(sc)[0], tab, n_tab, moved, used, extra)

    def after(self, values: np.ndarray) -> np.ndarray:
        """(N, L, ...) per-contact ``values`` (M, L, ...) at each sample's next contact."""
        return np.asarray(values[self.row, self.legs])

    def before(self, values: np.ndarray) -> np.ndarray:
        """(N, L, ...) per-contact ``values`` at each sample's contact before its swing."""
        return np.asarray(values[self.row - 1, self.legs])

    @property
    def raise_profile(self) -> np.ndarray:
        """(N, L) the swing raise's profile (:func:`~.terrain.raise_profile`)."""
        return raise_profile(self.sc)

    def planned_feet(self, st: _Setup) -> np.ndarray:
        """(N, L, 3) the foot spheres' centres: on the contacts in stance, the swing between.

        Swings over an edge are raised to clear it (:func:`~.terrain.swing_raise`).
        """
        c_tab = self.tab + st.rad * self.n_tab  # sphere centres on the contacts
        c_nxt, c_prev = self.after(c_tab), self.before(c_tab)
        swing = self.swing
        plan = np.where(swing[..., None], c_prev + (c_nxt - c_prev) * self.blend[..., None], c_nxt)
        plan[..., 2] += np.where(swing, st.H * swing_profile(self.sc)[1], 0.0)
        self.raise_swings(plan, self.raised(st, np.zeros(self.tab.shape)))
        return plan

    def raised(self, st: _Setup, lift_off: np.ndarray) -> np.ndarray:
        """(M, L) each swing's raise over edges, from its lift-off's rolling ``lift_off``."""
        out = np.zeros(self.tab.shape[:2])
        if np.isfinite(self.tab[..., 2]).all():
            c_tab = self.tab + st.rad * self.n_tab
            c0, c1 = (c_tab[:-1] + lift_off[1:]).reshape(-1, 3), c_tab[1:].reshape(-1, 3)
            raise_ = swing_raise(st.ground, c0, c1, st.H, st.rad, SWING_MARGIN)
            out[1:] = raise_.reshape(-1, self.tab.shape[1])
        return out

    def raise_swings(self, plan: np.ndarray, more: np.ndarray) -> None:
        """Raise the swings by ``more`` (M, L) [m] over their raise profile, in ``plan``."""
        self.extra += more
        plan[..., 2] += np.where(self.swing, self.after(more) * self.raise_profile, 0.0)

    def ground_heights(self) -> np.ndarray:
        """(N, L) each foot's ground height: its contact's, blended through the swing."""
        z1, z0 = self.after(self.tab[..., 2]), self.before(self.tab[..., 2])
        return np.asarray(np.where(self.swing, z0 + (z1 - z0) * self.blend, z1))

    def planes(self, first_half: np.ndarray | None = None) -> np.ndarray:
        """(N, L, 4) each leg's ground plane ``n·x = k``: its contact's (stance).

        In swing, the lower of its two contacts' planes, or with ``first_half`` (N, L) the
        lift-off's where True and the touch-down's elsewhere.
        """
        prev, nxt = self.before(self.tab), self.after(self.tab)
        if first_half is None:
            first_half = self.swing & (prev[..., 2] < nxt[..., 2])
        which = first_half[..., None]
        n = np.where(which, self.before(self.n_tab), self.after(self.n_tab))
        k = np.einsum("nli,nli->nl", n, np.where(which, prev, nxt))
        return np.concatenate([n, k[..., None]], axis=-1)


def _body_poses(st: _Setup, sw: _Swings) -> np.ndarray:
    """(N, 4, 4) level body poses on the SE(2) path, ``body_height`` above the feet's ground."""
    n = len(st.t)
    pose = se2_pose(st.t, st.vel)
    base = np.zeros((n, 4, 4))
    rz = np.array([rpy_to_matrix(0.0, 0.0, psi)[:2, :2] for psi in pose[:, 2]])  # Rz(ψ)
    base[:, :2, :2] = rz
    base[:, 0, 1] = -rz[:, 1, 0]  # −sin ψ (rpy_to_matrix's 0 − sin ψ is +0.0 at ψ = 0)
    base[:, 2, 2] = base[:, 3, 3] = 1.0
    base[:, 0, 3], base[:, 1, 3] = pose[:, 0], pose[:, 1]
    base[:, 2, 3] = sw.ground_heights().mean(axis=1) + st.body_height
    return base


class _Solution:
    """The joints of the planned feet: IK and rolling to a fixed point (:func:`rolling_ik`)."""

    def __init__(
        self, wb: WholeBody, st: _Setup, sw: _Swings, base: np.ndarray, plan: np.ndarray, q0: Any
    ) -> None:
        self.wb, self.st, self.sw, self.base, self.plan = wb, st, sw, base, plan
        self.args = (
            ~sw.swing,
            sw.swing,
            sw.blend,
            sw.after(sw.n_tab),
            st.rad,
            st.t,
            q0,
            ROLLING_TOL * st.size,
            ROLLING_PASSES,
        )
        self.edge_gap = np.full(sw.swing.shape, np.inf)
        self.solve()
        if sw.extra.any():  # sized again from each swing's lift-off rolling, now known
            lo = np.zeros(sw.tab.shape)  # feet − plan = lo·(1 − b) in the swing's first half
            sel = sw.swing & (sw.blend < 0.5)
            lo[sw.row[sel], np.broadcast_to(sw.legs, sel.shape)[sel]] = (self.feet - plan)[sel] / (
                1.0 - sw.blend[sel]
            )[:, None]
            more = np.maximum(sw.raised(st, lo) - sw.extra, 0.0)
            if more.any():
                sw.raise_swings(plan, more)
                self.solve()

    def solve(self) -> None:
        """IK ↔ rolling of the current plan."""
        out = rolling_ik(self.wb, self.base, self.plan, *self.args)
        self.feet, self.q, self.ik, self.passes, self.residual, self.T, self.rolled = out

    def clear_edges(self) -> None:
        """Raise the swings short of :data:`SWING_MARGIN` over an edge, and solve again.

        The clearance is measured on the feet as solved, over the ground above the plane of
        the swing's lift-off in its first half, of its touch-down in its second (the edge it
        climbs, not the ground it leaves or lands on); a swing short of it is raised by the
        deficit over its raise profile (at most to twice the step height).
        """
        sw, st = self.sw, self.st
        if not (np.isfinite(sw.tab[..., 2]).all() and st.ground.relief > 0):
            return
        own = sw.planes(sw.swing & (sw.blend < 0.5))
        lift2 = sw.raise_profile
        for k in range(EDGE_PASSES + 1):
            self.edge_gap = gap = np.full(sw.swing.shape, np.inf)
            gap[sw.swing] = edge_distance(
                st.ground, self.feet[sw.swing], st.rad, SWING_MARGIN, own[sw.swing]
            )
            short = sw.swing & (gap < SWING_MARGIN - EDGE_SLACK) & (lift2 > 0.05)
            if not short.any() or k == EDGE_PASSES:
                return
            need = np.zeros(sw.tab.shape[:2])
            at = (sw.row[short], np.broadcast_to(sw.legs, short.shape)[short])
            aim = SWING_MARGIN + EDGE_HEADROOM  # the sampled distance errs by a fraction of it
            np.maximum.at(need, at, (aim - gap[short]) / lift2[short])
            need = np.minimum(need, np.maximum(st.H - sw.extra, 0.0))  # the raise stays <= H
            if not need.any():
                return
            sw.raise_swings(self.plan, need)
            self.solve()


def _checked(
    wb: WholeBody, st: _Setup, sw: _Swings, sol: _Solution, q0: Any, strict: bool
) -> GaitRun:
    """Every check of the solved walk (``strict``: the first failure raised), as a run."""
    t, names, rad, q, base, swing = st.t, wb.leg_names, st.rad, sol.q, sol.base, sw.swing
    support = ~swing
    n, nl = swing.shape
    n_nxt = sw.after(sw.n_tab)
    promised = SWING_MARGIN - EDGE_SLACK
    foot_gap = terrain_clearance(
        st.ground, sol.feet, swing, rad, t, names, st.H, strict, sol.edge_gap, promised
    )
    if strict and not np.asarray(sol.ik.ok).all():
        wb.body_ik(base, sol.feet, q_prev=q0, times=t, strict=True)  # raises, naming the check
    T_all = wb.joint_poses(q, base) if sol.T is None else sol.T
    pts, com = wb.points_of(T_all), wb.com_of(T_all, base)
    actual = np.ascontiguousarray(pts[:, :, -1])
    ref = actual[stance_start_index(support), np.arange(nl)[None, :]]
    # rolled: the rolling of the final q's foot rotations (by FK; 0 for point feet)
    slip = np.where(support, np.linalg.norm(actual - ref - sol.rolled, axis=-1), 0.0)
    contacts = actual - rad * n_nxt
    margin = support_margin(contacts, support, com)
    zmp_margin = np.zeros(0)  # below 4 samples or without a mass
    if len(t) >= 4 and wb.mass > 0:
        sup = support[..., None]  # the ground: the stance contacts' mean height
        h = ((contacts[..., 2:3] * sup).sum(axis=1) / np.maximum(sup.sum(axis=1), 1))[:, 0]
        zmp_margin = sway_zmp_margin(wb, q, base, contacts, support, t, h)
    order = np.argsort(np.arctan2(wb.mounts[:, 1, 3], wb.mounts[:, 0, 3]), kind="stable")
    ring = {tuple(sorted((int(a), int(b)))) for a, b in zip(order, np.roll(order, -1))}
    pairs = tuple(sorted((a, b) for a, b in ring if a != b))  # neighbouring legs
    clear = segment_clearance(pts, np.array(pairs, dtype=np.int64).reshape(-1, 2))
    clear -= 2.0 * wb.link_radius
    leg_gap = leg_terrain_clearance(
        st.ground, pts, wb.link_radius, rad, sw.planes(), t, names, strict
    )
    qdot, qddot = rates(q, t)
    vlim = np.asarray(wb.velocity_limit, dtype=float).reshape(-1)
    if strict:
        raise_checks(wb, st, pairs, clear, margin, qdot, qddot, vlim, support)
    phase = st.table.phase(t, st.T)
    read_only(t, base, actual, sol.feet, q, qdot, qddot, support, phase, com, slip, margin, clear)
    used, gap = sw.used, sol.edge_gap
    settings = {
        "stride": float(st.strokes.max()),
        "step_height": st.H,
        "period": st.T,
        "duty_factor": st.beta,
        "velocity": st.vel,
        "body_height": st.body_height,
        "foot_reach": st.reach,
        "terrain": st.ground.name,
        "duration": st.duration,
        "rate": st.rate,
        "foot_radius": rad,
        "sway": st.sway,
        "knees": knee_directions(wb, q[0]) if n else (),
        "rolling_passes": sol.passes,
        "rolling_residual": sol.residual,
        "margin_tol": st.tol,
        "footholds_moved": int(np.count_nonzero(used & (sw.moved != 0))),
        "foothold_shift_max": float(np.abs(np.where(used, sw.moved, 0.0)).max()),
        "swings_raised": int(np.count_nonzero(used[1:] & (sw.extra[1:] > 0))),
        "swing_raise_max": float(np.where(used, sw.extra, 0.0).max()),
        "min_edge_clearance": float(gap.min()) if gap.size and np.isfinite(gap.min()) else None,
    }
    ik_ok = np.asarray(sol.ik.ok)
    read_only(ik_ok, vlim, st.acc_lim, n_nxt, foot_gap, leg_gap)
    return GaitRun(
        t=t, base_poses=base, feet=actual, feet_planned=sol.feet, q=q, qdot=qdot,
        support=support, phase=phase, com=com, slip=slip, margin=margin, zmp_margin=zmp_margin,
        limit_margin=sol.ik.limit_margin, ik_ok=ik_ok, reach_excess=sol.ik.excess,
        clearance=clear, pairs=pairs, leg_names=names, joint_names=wb.joint_names,
        table=st.table, settings=settings, mass=wb.mass, qddot=qddot, velocity_limit=vlim,
        accel_limit=st.acc_lim, robot=wb, normals=n_nxt, foot_gap=foot_gap, leg_gap=leg_gap,
    )  # fmt: skip
