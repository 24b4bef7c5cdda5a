"""The walk: body motion, foot placement, joint angles and every check, over time.

:func:`walk` plans a periodic gait of the whole hexapod and returns a :class:`GaitRun`.

* **Body**: the commanded body twist (vx, vy forward/sideways in the body frame [m/s], ωz
  [rad/s]) is integrated exactly on SE(2) (arcs of circle; straight lines for ωz = 0; turning
  in place for vx = vy = 0); the body stays level and its height follows the mean ground height
  of the feet plus ``body_height`` (stance feet: their contact point; swing feet: blended
  from lift-off to touch-down with the swing's own profile, so the body height is continuous).
* **Feet**: each leg follows the phase table (:mod:`.tables`). Its touch-down point is fixed
  when the swing is planned (à la Raibert): the leg's neutral foot point under the body's pose
  at the middle of the *next* stance, projected on the terrain; during stance the foot stays
  exactly there in the world. The swing goes from the last contact to the next one with a
  quintic horizontal profile ``10s³ − 15s⁴ + 6s⁵`` and a vertical lift ``16 s²(1 − s)²·h``:
  zero velocity at lift-off and touch-down.
* The walk is the gait's periodic regime restricted to ``[0, duration]`` (every contact point
  is given by the same formula, before ``t = 0`` too), so no start-up transient.
* **Joints**: body-pose IK (closed form per leg, nearest branch) at every sample; joint
  rates by second-order finite differences.
* **Checks** at every sample: stance slip (world foot by forward kinematics, against its
  position at the first stance sample), static stability margin (:mod:`.stability`), joint
  limit margin, IK status, clearance between neighbouring legs (surface gap of the links).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..exceptions import ParameterError
from ..motion import read_only
from .robot import GaitError, WholeBody, as_whole_body
from .stability import segment_clearance, support_margin
from .tables import PhaseTable, phase_table
from .terrain import Terrain
from .terrain import terrain as make_terrain

__all__ = ["GaitRun", "se2_pose", "swing_profile", "walk"]

#: Default foot stroke during stance [m] when no velocity is given.
DEFAULT_STRIDE = 0.05


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


def se2_pose(t: Any, velocity: Any) -> np.ndarray:
    """Exact SE(2) integration of a constant body twist from the origin.

    Args:
        t: Times (...) in [s].
        velocity: ``(vx, vy, wz)``: body-frame velocity [m/s] and yaw rate [rad/s].

    Returns:
        (..., 3) ``x, y`` [m] and yaw ``ψ`` [rad]:
        ``x = (vx sin ψ − vy (1 − cos ψ)) / ωz``, ``y = (vx (1 − cos ψ) + vy sin ψ) / ωz``,
        ``ψ = ωz t`` (the limits ``vx t, vy t`` for ωz = 0).

    """
    vx, vy, w = (float(v) for v in velocity)
    tt = np.asarray(t, dtype=float)
    psi = w * tt
    half = psi / 2.0
    sinc = np.sinc(half / np.pi)  # sin(ψ/2)/(ψ/2)
    s = tt * sinc * np.cos(half)  # sin(ψ)/ω
    c = tt * sinc * np.sin(half)  # (1 − cos ψ)/ω
    out = np.empty(tt.shape + (3,))
    out[..., 0] = vx * s - vy * c
    out[..., 1] = vx * c + vy * s
    out[..., 2] = psi
    return out


def swing_profile(s: Any) -> tuple[np.ndarray, np.ndarray]:
    """Swing progress ``(10s³ − 15s⁴ + 6s⁵, 16 s²(1 − s)²)`` at ``s ∈ [0, 1]``.

    The first blends the horizontal position (and the ground height) from lift-off to
    touch-down, the second scales the step height; both have zero slope at s = 0 and 1.
    """
    s = np.asarray(s, dtype=float)
    return s**3 * (10.0 - 15.0 * s + 6.0 * s * s), 16.0 * s * s * (1.0 - s) ** 2


@dataclass(frozen=True)
class GaitRun:
    """A walk of the whole robot sampled in time (arrays read-only, SI units).

    Attributes:
        t: (N,) times [s].
        base_poses: (N, 4, 4) body poses ``worldMbody`` (the free-flyer's placement).
        feet: (N, L, 3) feet in the world by forward kinematics of ``q`` [m].
        feet_planned: (N, L, 3) planned feet [m].
        q: (N, 18) joint angles [rad] (legs in order, hip/knee/ankle).
        qdot: (N, 18) joint rates [rad/s] (second-order finite differences).
        support: (N, L) True for the stance feet (the support set).
        phase: (N, L) gait phase in cycles [0, 1) (stance below the duty factor).
        com: (N, 3) whole-body centre of mass in the world [m].
        slip: (N, L) distance of each stance foot from its position at the first stance
            sample [m] (0 in swing).
        margin: (N,) static stability margin [m] (negative: CoM outside the support polygon).
        limit_margin: (N, 18) distance of each joint to its nearest limit [rad].
        ik_ok: (N, L) True where the leg's IK reached its foot inside the joint limits.
        reach_excess: (N, L) distance a foot is out of its leg's reach [m] (0 if reached).
        clearance: (N, P) surface gap between the links of each neighbouring pair [m].
        pairs: The neighbouring pairs, by leg index.
        leg_names: The legs.
        joint_names: The 18 joints.
        table: The phase table used.
        settings: The walk's parameters (stride [m], step_height [m], period [s],
            duty_factor, velocity (vx [m/s], vy [m/s], wz [rad/s]), body_height [m],
            foot_reach [m], terrain, duration [s], rate [Hz]).
        mass: Total mass [kg].

    """

    t: np.ndarray
    base_poses: np.ndarray
    feet: np.ndarray
    feet_planned: np.ndarray
    q: np.ndarray
    qdot: np.ndarray
    support: np.ndarray
    phase: np.ndarray
    com: np.ndarray
    slip: np.ndarray
    margin: np.ndarray
    limit_margin: np.ndarray
    ik_ok: np.ndarray
    reach_excess: np.ndarray
    clearance: np.ndarray
    pairs: tuple[tuple[int, int], ...]
    leg_names: tuple[str, ...]
    joint_names: tuple[str, ...]
    table: PhaseTable
    settings: dict[str, Any] = field(default_factory=dict)
    mass: float = 0.0

    @property
    def min_margin(self) -> float:
        """Smallest stability margin over the run [m]."""
        return float(self.margin.min())

    @property
    def max_slip(self) -> float:
        """Largest stance-foot slip over the run [m]."""
        return float(self.slip.max())

    @property
    def min_limit_margin(self) -> float:
        """Smallest joint-limit margin over the run [rad]."""
        return float(self.limit_margin.min())

    @property
    def min_clearance(self) -> float:
        """Smallest gap between the links of neighbouring legs over the run [m]."""
        return float(self.clearance.min()) if self.clearance.size else math.inf

    @property
    def max_foot_error(self) -> float:
        """Largest distance between the feet by FK and the planned feet [m]."""
        return float(np.linalg.norm(self.feet - self.feet_planned, axis=-1).max())

    @property
    def ok(self) -> bool:
        """True when every check passes at every sample."""
        return bool(
            self.ik_ok.all()
            and self.min_margin > 0
            and self.min_limit_margin >= 0
            and self.min_clearance > 0
            and self.max_slip <= 1e-9
        )

    def pinocchio_q(self) -> np.ndarray:
        """Pinocchio free-flyer configurations (N, 25): xyz, quaternion (x, y, z, w), q."""
        import pinocchio as pin

        out = np.empty((len(self.q), 7 + self.q.shape[1]))
        out[:, :3] = self.base_poses[:, :3, 3]
        for i, B in enumerate(self.base_poses):
            out[i, 3:7] = pin.Quaternion(B[:3, :3]).coeffs()
        out[:, 7:] = self.q
        return out

    def base_velocity(self) -> np.ndarray:
        """Body twist (N, 6) in the body frame: linear [m/s], angular [rad/s].

        The free-flyer's velocity in Pinocchio's convention (``v[:6]``); by second-order
        finite differences of :attr:`base_poses` (the body stays level: ω = (0, 0, ψ̇)).
        """
        n = len(self.t)
        if n < 3:
            return np.zeros((n, 6))
        p_dot = np.gradient(self.base_poses[:, :3, 3], self.t, axis=0, edge_order=2)
        yaw = np.unwrap(np.arctan2(self.base_poses[:, 1, 0], self.base_poses[:, 0, 0]))
        out = np.zeros((n, 6))
        out[:, :3] = np.einsum("nji,nj->ni", self.base_poses[:, :3, :3], p_dot)
        out[:, 5] = np.gradient(yaw, self.t, edge_order=2)
        return out

    def pinocchio_v(self) -> np.ndarray:
        """Pinocchio free-flyer velocities (N, 24): :meth:`base_velocity` then ``qdot``."""
        return np.concatenate([self.base_velocity(), self.qdot], axis=1)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary of the checks and the settings.

        Keys: min_margin [m], max_slip [m], min_limit_margin [rad], min_clearance [m],
        max_foot_error [m], max_joint_rate [rad/s] (informative: joint velocity limits are
        not a check), samples, ok, pattern (the table), mass [kg], and the settings.
        """
        return {
            "min_margin": self.min_margin,
            "max_slip": self.max_slip,
            "min_limit_margin": self.min_limit_margin,
            "min_clearance": self.min_clearance,
            "max_foot_error": self.max_foot_error,
            "max_joint_rate": float(np.abs(self.qdot).max()) if self.qdot.size else 0.0,
            "samples": int(len(self.t)),
            "ok": self.ok,
            "pattern": self.table.to_dict(),
            "mass": self.mass,
            **{k: (list(v) if isinstance(v, tuple) else v) for k, v in self.settings.items()},
        }


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
    pattern: str | PhaseTable = "tripod",
    stride: float | None = None,
    step_height: float = 0.03,
    period: float = 1.0,
    duty_factor: float | None = None,
    velocity: Any = None,
    body_height: float | None = None,
    foot_reach: float | None = None,
    terrain: Any = None,
    rate: float = 100.0,
    duration: float = 10.0,
    q0: Any = None,
    strict: bool = True,
) -> GaitRun:
    """Walk the hexapod and check every sample.

    Args:
        robot: The robot: a :class:`~.robot.WholeBody`, a ``Hexapod``, or any source
            :func:`~.robot.as_whole_body` takes (a URDF path, ``erd:NAME``, a loaded model);
            default the built-in hexapod.
        pattern: ``"tripod"``, ``"wave"``, ``"ripple"`` or a :class:`~.tables.PhaseTable`.
        stride: Foot stroke during stance [m] for a straight forward walk (sets
            ``vx = stride / (duty_factor · period)``); default 0.05 m when ``velocity`` is
            not given. Give ``stride`` or ``velocity``, not both.
        step_height: Swing lift above the straight line between contacts [m].
        period: Cycle time T [s].
        duty_factor: Stance fraction β in (0, 1) (default the pattern's).
        velocity: Body twist ``(vx, vy, wz)`` [m/s, m/s, rad/s] in the body frame (curves with
            vx and wz, turning in place with only wz).
        body_height: Body above the mean ground height of the feet [m] (default the
            robot's :attr:`~.robot.WholeBody.body_height`; the built-in hexapod: 0.08 m).
        foot_reach: Horizontal distance from each leg's mount to its neutral foot point [m]
            (default the robot's own, :attr:`~.robot.WholeBody.foot_reach`; the built-in
            hexapod: 0.16 m).
        terrain: ``"flat"`` (default), ``"slope"``, ``"step"``, a
            :class:`~.terrain.Terrain` or ``h(x, y)``.
        rate: Sample rate [Hz].
        duration: Length of the run [s].
        q0: (18,) joints the first sample's IK branches are nearest to.
        strict: Raise on the first failed check (else return the run with its checks).

    Returns:
        A :class:`GaitRun`.

    Raises:
        ParameterError: A bad parameter (named, with what is allowed).
        GaitError: (``strict``) a check fails: ``"terrain"`` (a foot off the terrain),
            ``"terrain clearance"`` (a swing foot below the ground: step too low),
            ``"reach"`` (stride too long, step too high...), ``"joint limit"``,
            ``"leg clearance"``, ``"stability margin"``; the message names the leg, the time
            and by how much.

    """
    wb = as_whole_body(robot)
    table = phase_table(pattern, wb.n_legs).with_duty_factor(duty_factor)
    beta = table.duty_factor
    T = _num("period", period, hi=1e3)
    H = _num("step_height", step_height, zero=True, hi=1.0)
    bh = wb.body_height if body_height is None else _num("body_height", body_height, hi=10.0)
    reach = wb.foot_reach if foot_reach is None else _num("foot_reach", foot_reach, hi=10.0)
    dur = _num("duration", duration, zero=True, hi=1e5)
    hz = _num("rate", rate, hi=1e5)
    n = int(round(dur * hz)) + 1
    if n > 2_000_000:
        raise ParameterError(
            f"duration*rate = {dur * hz:.4g} samples is too many; at most 2e6",
            parameter="rate",
            value=rate,
            allowed="duration*rate <= 2e6",
        )
    if stride is not None and velocity is not None:
        raise ParameterError(
            f"stride={stride!r} and velocity={velocity!r}: give one (stride sets a straight "
            "walk; velocity any twist)",
            parameter="stride",
            value=stride,
            allowed="stride or velocity",
        )
    if velocity is None:
        L = _num("stride", DEFAULT_STRIDE if stride is None else stride, zero=True, hi=10.0)
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
    vx, vy, w = vel
    strokes = np.hypot(vx - w * nb[:, 1], vy + w * nb[:, 0]) * beta * T
    # --- contacts and swings, per sample and leg
    offs = np.asarray(table.offsets)
    tsw = (1.0 - beta) * T
    m = np.floor(t[:, None] / T + offs[None, :] - beta)  # latest lift-off index
    t_lo = (m + beta - offs[None, :]) * T
    s = (t[:, None] - t_lo) / tsw
    swing = s < 1.0
    support = ~swing
    t_td = t_lo + tsw

    def contact(t_touch: np.ndarray) -> np.ndarray:
        pose = se2_pose(t_touch + 0.5 * beta * T, vel)  # body at mid-stance
        c, sn = np.cos(pose[..., 2]), np.sin(pose[..., 2])
        x = pose[..., 0] + c * nb[:, 0] - sn * nb[:, 1]
        y = pose[..., 1] + sn * nb[:, 0] + c * nb[:, 1]
        return np.stack([x, y, ground(x, y)], axis=-1)

    nxt = contact(t_td)  # TD_m: the contact after swing m
    prev = contact(t_td - T)  # TD_{m-1}: the contact before it
    for pts, when in ((nxt, t_td), (prev, t_td - T)):
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
    feet = np.where(swing[..., None], prev + (nxt - prev) * blend[..., None], nxt)
    feet[..., 2] += np.where(swing, H * lift, 0.0)
    gz = feet[..., 2] - np.where(swing, H * lift, 0.0)  # ground height under each foot
    # swing feet above the ground
    if swing.any():
        under = ground(feet[..., 0], feet[..., 1])
        gap = np.where(swing, feet[..., 2] - under, np.inf)
        gap = np.where(np.isnan(gap), -np.inf, gap)
        if gap.min() < -1e-9:
            i, leg = np.unravel_index(int(np.argmin(gap)), gap.shape)
            d = float(-gap[i, leg])
            where = "off the terrain" if math.isinf(d) else f"{d:.4g} m below the ground"
            raise GaitError(
                f"leg {names[leg]}: swing foot {where} at t={t[i]:.4g} s (check 'terrain "
                f"clearance'; step_height={H:g} m is too low for this terrain)",
                check="terrain clearance",
                leg=names[leg],
                time=float(t[i]),
                amount=d,
                parameter="step_height",
                value=H,
                allowed="a swing above the terrain",
            )
    # --- body
    pose = se2_pose(t, vel)
    base = np.zeros((n, 4, 4))
    c, sn = np.cos(pose[:, 2]), np.sin(pose[:, 2])
    base[:, 0, 0], base[:, 0, 1], base[:, 1, 0], base[:, 1, 1] = c, -sn, sn, c
    base[:, 2, 2] = base[:, 3, 3] = 1.0
    base[:, 0, 3], base[:, 1, 3] = pose[:, 0], pose[:, 1]
    base[:, 2, 3] = gz.mean(axis=1) + bh
    # --- joints and checks
    ik = wb.body_ik(base, feet, q_prev=q0, times=t, strict=strict)
    q = np.array(ik.q)
    pts, com = wb.points_and_com(q, base)
    actual = np.ascontiguousarray(pts[:, :, 3])
    start = support.copy()
    start[1:] &= ~support[:-1]
    idx = np.where(start, np.arange(n)[:, None], 0)
    idx = np.maximum.accumulate(idx, axis=0)
    ref = actual[idx, np.arange(nl)[None, :]]
    slip = np.where(support, np.linalg.norm(actual - ref, axis=-1), 0.0)
    margin = support_margin(actual, support, com)
    pairs = _neighbour_pairs(wb)
    clear = segment_clearance(pts, np.array(pairs, dtype=np.int64).reshape(-1, 2))
    clear -= 2.0 * wb.link_radius
    qdot = np.gradient(q, t, axis=0, edge_order=2) if n > 2 else np.zeros_like(q)
    if strict:
        if clear.size and clear.min() <= 0:
            i, k = np.unravel_index(int(np.argmin(clear)), clear.shape)
            a, b = pairs[k]
            raise GaitError(
                f"legs {names[a]} and {names[b]} collide (links {-clear[i, k]:.4g} m into "
                f"each other) at t={t[i]:.4g} s (check 'leg clearance')",
                check="leg clearance",
                leg=names[a],
                time=float(t[i]),
                amount=float(-clear[i, k]),
                parameter="stride",
                value=strokes.max(),
            )
        if margin.min() <= 0:
            i = int(np.argmin(margin))
            raise GaitError(
                f"the centre of mass leaves the support polygon by {-margin[i]:.4g} m at "
                f"t={t[i]:.4g} s (check 'stability margin'; stance legs "
                f"{[names[k] for k in np.flatnonzero(support[i])]})",
                check="stability margin",
                time=float(t[i]),
                amount=float(-margin[i]),
                parameter="pattern",
                value=table.name,
                allowed="margin > 0",
            )
    phase = table.phase(t, T)
    read_only(t, base, actual, feet, q, qdot, support, phase, com, slip, margin, clear)
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
    }
    ik_ok = np.asarray(ik.ok)
    read_only(ik_ok)
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
    )
