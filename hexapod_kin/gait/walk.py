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
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..exceptions import ConfigurationError, ParameterError
from ..motion import read_only
from .knee import knee_directions, knee_seed
from .paths import (
    rolling_ik,
    se2_pose,
    stance_start_index,
    terrain_normals,
)
from .robot import GaitError, WholeBody, as_whole_body
from .stability import (
    accel_limit_of,
    leg_terrain_clearance,
    raise_checks,
    segment_clearance,
    support_margin,
    terrain_clearance,
)
from .sway import sway_poses
from .tables import PhaseTable, phase_table
from .terrain import Terrain, off_edges, raise_profile, swing_raise
from .terrain import terrain as make_terrain
from .zmp import second_difference, zmp_points

__all__ = ["GaitRun", "se2_pose", "swing_profile", "walk"]

#: The longest foot stroke during one stance [m] a velocity may ask (the stride's own cap).
MAX_STROKE = 10.0
#: The largest body turn during one stance [rad] a velocity may ask.
MAX_TURN = 2.0 * math.pi
#: Default foot stroke during stance [m] when no velocity is given.
DEFAULT_STRIDE = 0.05

#: Rounding tolerance of the checks, relative to the robot's size (the largest mount-to-centre
#: distance plus the foot reach) [m/m]: a margin above ``−MARGIN_TOL·size`` is not a failure.
MARGIN_TOL = 1e-9

#: Footholds keep a flat disc of radius ``foot_radius`` + this [m] (terrain.off_edges).
FOOTHOLD_MARGIN = 0.007

#: Swings over an edge clear the terrain by this [m] (terrain.swing_raise).
SWING_MARGIN = 0.005

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


@dataclass(frozen=True)
class GaitRun:
    """A walk of the whole robot sampled in time (arrays read-only, SI units).

    Attributes:
        t: (N,) times [s].
        base_poses: (N, 4, 4) body poses ``worldMbody`` (the free-flyer's placement).
        feet: (N, L, 3) feet (foot-sphere centres) in the world by forward kinematics of ``q``
            [m].
        feet_planned: (N, L, 3) planned feet [m].
        q: (N, nq) joint angles [rad] (in ``joint_names`` order).
        qdot: (N, nq) joint rates [rad/s] (second-order finite differences).
        support: (N, L) True for the stance feet (the support set).
        phase: (N, L) gait phase in cycles [0, 1) (stance below the duty factor).
        com: (N, 3) whole-body centre of mass in the world [m].
        slip: (N, L) how far the material point of each stance foot in contact with the ground
            has slid since the stance's first sample [m] (0 in swing): ``‖c − c_s − D‖``,
            c the sphere's centre by FK and D its rolling (:func:`.paths.rolling_offsets`)
            from the FK rotations (for point feet, the distance from the first stance sample).
        margin: (N,) static stability margin [m] (negative: CoM outside the support polygon
            of the contact points).
        limit_margin: (N, nq) distance of each joint to its nearest limit [rad].
        ik_ok: (N, L) True where the leg's IK reached its foot inside the joint limits.
        reach_excess: (N, L) distance a foot is out of its leg's reach [m] (0 if reached).
        clearance: (N, P) surface gap between the links of each neighbouring pair [m].
        pairs: The neighbouring pairs, by leg index.
        leg_names: The legs.
        joint_names: The joints.
        table: The phase table used (``table.statically_stable``: False for trot and pace,
            whose margin is reported but not a check).
        settings: The walk's parameters (stride [m], step_height [m], period [s],
            duty_factor, velocity (vx [m/s], vy [m/s], wz [rad/s]), body_height [m],
            foot_reach [m], terrain, duration [s], rate [Hz], foot_radius [m], sway,
            rolling_passes, rolling_residual [m], margin_tol [m]).
        mass: Total mass [kg].
        qddot: (N, nq) joint accelerations [rad/s²] (second differences).
        velocity_limit: (nq,) the joints' velocity limits [rad/s] (inf: none).
        accel_limit: (nq,) the acceleration limits checked [rad/s²] (inf: none given).
        robot: The whole-robot model that walked (for viewers and simulators).
        normals: (N, L, 3) the ground's unit normal at each foot's current (stance) or next
            (swing) contact; the contact point is ``feet − foot_radius · normals``.
        foot_gap: (N, L) how far each foot sphere clears the terrain [m] (sampled,
            :func:`.stability.terrain_clearance`; 0 in stance, negative: into it).
        leg_gap: (N, L) how far each leg's links clear the terrain above its foot's ground
            [m] (:func:`.stability.leg_terrain_clearance`).
        zmp_margin: (N,) the zero-moment point's signed distance to the support polygon's
            edge [m] (:func:`.zmp.zmp_points`: the whole robot's centroidal dynamics, the
            legs' momentum included, on the stance contacts' mean height). Reported, not a
            check.

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
    qddot: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    velocity_limit: np.ndarray = field(default_factory=lambda: np.zeros(0))
    accel_limit: np.ndarray = field(default_factory=lambda: np.zeros(0))
    robot: WholeBody | None = field(default=None, repr=False)
    normals: np.ndarray = field(default_factory=lambda: np.zeros((0, 0, 3)))
    foot_gap: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    leg_gap: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    zmp_margin: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def min_zmp_margin(self) -> float:
        """Smallest dynamic (zero-moment point) stability margin over the run [m] (nan: none)."""
        return float(self.zmp_margin.min()) if self.zmp_margin.size else math.nan

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
    def statically_stable(self) -> bool:
        """False for patterns that are not statically stable (trot, pace): margin not checked."""
        return self.table.statically_stable

    @property
    def margin_ok(self) -> bool:
        """The margin check: ``min_margin > −margin_tol`` (always True if not statically stable)."""
        tol = float(self.settings.get("margin_tol", 0.0))
        return (not self.statically_stable) or self.min_margin > -tol

    @property
    def max_joint_speed(self) -> np.ndarray:
        """(nq,) largest |q̇| of each joint over the run [rad/s]."""
        return np.abs(self.qdot).max(axis=0) if self.qdot.size else np.zeros(self.q.shape[1])

    @property
    def max_joint_accel(self) -> np.ndarray:
        """(nq,) largest |q̈| of each joint over the run [rad/s²]."""
        return np.abs(self.qddot).max(axis=0) if self.qddot.size else np.zeros(self.q.shape[1])

    @property
    def speed_ok(self) -> bool:
        """Every joint within its velocity limit (and acceleration limit, if given)."""
        lim = self.velocity_limit if self.velocity_limit.size else np.inf
        acc = self.accel_limit if self.accel_limit.size else np.inf
        return bool(
            np.all(self.max_joint_speed <= lim * (1 + 1e-9))
            and np.all(self.max_joint_accel <= acc * (1 + 1e-9))
        )

    @property
    def ok(self) -> bool:
        """True when every check passes at every sample (margin only if statically stable)."""
        return bool(
            self.ik_ok.all()
            and self.margin_ok
            and self.min_limit_margin >= 0
            and self.min_clearance > 0
            and self.max_slip <= 1e-9
            and self.speed_ok
            and (not self.foot_gap.size or self.foot_gap.min() >= -1e-9)
            and (not self.leg_gap.size or self.leg_gap.min() >= -1e-9)
        )

    def pinocchio_q(self) -> np.ndarray:
        """Pinocchio free-flyer configurations (N, nq): xyz, quaternion (x, y, z, w), joints.

        Raises:
            ConfigurationError: A run without its robot (``robot=None``).

        """
        if self.robot is None:
            raise ConfigurationError(
                "this run carries no robot (robot=None): its Pinocchio configurations are "
                "the robot's (WholeBody.pinocchio_q)",
                parameter="robot",
            )
        return self.robot.pinocchio_q(self.q, self.base_poses)

    def _base_rates(self) -> tuple[np.ndarray, np.ndarray]:
        n = len(self.t)
        p = self.base_poses[:, :3, 3]
        yaw = np.unwrap(np.arctan2(self.base_poses[:, 1, 0], self.base_poses[:, 0, 0]))
        x = np.concatenate([p, yaw[:, None]], axis=1)
        if n < 4:
            return np.zeros_like(x), np.zeros_like(x)
        return np.gradient(x, self.t, axis=0, edge_order=2), second_difference(x, self.t)

    def base_velocity(self) -> np.ndarray:
        """Body twist (N, 6) in the body frame: linear [m/s], angular [rad/s].

        The free-flyer's velocity in Pinocchio's convention (``v[:6] = (Rᵀ ṗ, ω)``); by
        second-order finite differences of :attr:`base_poses` (the body stays level:
        ω = (0, 0, ψ̇)).
        """
        rate, _ = self._base_rates()
        out = np.zeros((len(self.t), 6))
        out[:, :3] = np.einsum("nji,nj->ni", self.base_poses[:, :3, :3], rate[:, :3])
        out[:, 5] = rate[:, 3]
        return out

    def base_acceleration(self) -> np.ndarray:
        """The free-flyer's acceleration (N, 6), Pinocchio's ``a[:6] = d/dt v[:6]``.

        ``(Rᵀ p̈ − ω × Rᵀ ṗ, ω̇)`` with p̈ and ψ̈ by second differences (the classical
        acceleration of the body origin is ``p̈``).
        """
        rate, acc = self._base_rates()
        v = self.base_velocity()
        out = np.zeros((len(self.t), 6))
        out[:, :3] = np.einsum("nji,nj->ni", self.base_poses[:, :3, :3], acc[:, :3])
        out[:, :3] -= np.cross(v[:, 3:], v[:, :3])
        out[:, 5] = acc[:, 3]
        return out

    def pinocchio_v(self) -> np.ndarray:
        """Pinocchio free-flyer velocities (N, 6 + nq): :meth:`base_velocity` then ``qdot``."""
        return np.concatenate([self.base_velocity(), self.qdot], axis=1)

    def pinocchio_a(self) -> np.ndarray:
        """Pinocchio free-flyer accelerations (N, 6 + nq): :meth:`base_acceleration`, ``qddot``."""
        return np.concatenate([self.base_acceleration(), self.qddot], axis=1)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary of the checks and the settings.

        Keys: min_margin [m], statically_stable, max_slip [m], min_limit_margin [rad],
        min_clearance [m], max_foot_error [m], max_joint_rate [rad/s], max_joint_speed and
        max_joint_accel per joint [rad/s], [rad/s²], velocity_limit [rad/s] (None: no
        limit), speed_ok, samples, ok, pattern (the table), mass [kg], and the settings.
        """

        def finite(a: np.ndarray) -> list[float | None]:
            return [float(x) if math.isfinite(x) else None for x in a]

        return {
            "min_margin": self.min_margin,
            "min_zmp_margin": self.min_zmp_margin,
            "statically_stable": self.statically_stable,
            "max_slip": self.max_slip,
            "min_limit_margin": self.min_limit_margin,
            "min_clearance": self.min_clearance,
            "max_foot_error": self.max_foot_error,
            "max_joint_rate": float(np.abs(self.qdot).max()) if self.qdot.size else 0.0,
            "max_joint_speed": dict(zip(self.joint_names, finite(self.max_joint_speed))),
            "max_joint_accel": dict(zip(self.joint_names, finite(self.max_joint_accel))),
            "velocity_limit": dict(zip(self.joint_names, finite(self.velocity_limit))),
            "speed_ok": self.speed_ok,
            "samples": int(len(self.t)),
            "ok": self.ok,
            "pattern": self.table.to_dict(),
            "mass": self.mass,
            **{k: (list(v) if isinstance(v, tuple) else v) for k, v in self.settings.items()},
        }


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
    foot_radius: float | None = None,
    sway: float | None = None,
    accel_limit: Any = None,
    knee: str | None = None,
) -> GaitRun:
    """Walk the robot and check every sample.

    Args:
        robot: The robot: a :class:`~.robot.WholeBody`, a ``Hexapod``, or any source
            :func:`~.robot.as_whole_body` takes (a URDF path, ``erd:NAME``, a loaded model);
            default the built-in hexapod.
        pattern: A name of :func:`~.tables.pattern_names` for the robot's legs (``tripod``,
            ``wave``, ``ripple`` for six; ``crawl``, ``wave``, ``trot``, ``pace`` for four;
            ``wave``, ``ripple`` for eight) or a :class:`~.tables.PhaseTable`.
        stride: Foot stroke during stance [m] for a straight forward walk (sets
            ``vx = stride / (duty_factor · period)``); default 0.05 m when ``velocity`` is
            not given. Give ``stride`` or ``velocity``, not both.
        step_height: Swing lift above the straight line between contacts [m].
        period: Cycle time T [s].
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
    table = phase_table(pattern, wb.n_legs, wb.mounts[:, :2, 3], wb.leg_names).with_duty_factor(
        duty_factor
    )
    beta = table.duty_factor
    T = _num("period", period, hi=1e3)
    H = _num("step_height", step_height, zero=True, hi=1.0)
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
        L = _num("stride", DEFAULT_STRIDE if stride is None else stride, zero=True, hi=MAX_STROKE)
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
    c, sn = np.cos(pose[:, 2]), np.sin(pose[:, 2])
    base[:, 0, 0], base[:, 0, 1], base[:, 1, 0], base[:, 1, 1] = c, -sn, sn, c
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
    foot_gap = terrain_clearance(ground, feet, swing, rad, t, names, H, strict)
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
    # each leg's own ground: its contact's plane (in swing the lower of the two contacts')
    low = np.where((swing & (prev[..., 2] < nxt[..., 2]))[..., None], prev, nxt)
    n_low = np.where((swing & (prev[..., 2] < nxt[..., 2]))[..., None], n_tab[row - 1, legs], n_nxt)
    plane = np.concatenate([n_low, np.einsum("nli,nli->nl", n_low, low)[..., None]], axis=-1)
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
