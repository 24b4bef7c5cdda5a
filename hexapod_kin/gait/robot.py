"""The whole hexapod: floating base (Pinocchio free-flyer) + 18 leg joints, and body-pose IK.

:class:`WholeBody` builds the Pinocchio model of the ``hexapod`` preset with a free-flyer root
from its generated URDF (checked by the loader gate first), and keeps the tree's constants
(joint placements, link inertials, foot frames) as arrays so that forward kinematics, the
centre of mass and the leg segments are computed for many samples at once (vectorised over
time; Pinocchio's own ``centerOfMass``/``framesForwardKinematics`` are the reference in the
tests). :meth:`WholeBody.body_ik` solves the 18 joint angles of a body pose with the feet
fixed in the world, leg by leg, with the closed form of the leg (:func:`hexapod_kin.ik.
analytic_batch`) in its mount frame.

Poses are 4×4 ``worldMbody`` arrays (the body frame: x forward, z up, origin on the mounts'
plane at the body centre).
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from functools import lru_cache
from typing import Any

import numpy as np

from ..exceptions import ConfigurationError, HexapodKinError, ParameterError
from ..params import Hexapod, rpy_to_matrix

__all__ = ["BodyIK", "GaitError", "WholeBody", "body_pose", "whole_body"]


class GaitError(ConfigurationError):
    """A gait or body pose that the robot cannot perform (a check failed).

    Attributes:
        check: The failed check (``"reach"``, ``"joint limit"``, ``"terrain"``,
            ``"terrain clearance"``, ``"leg clearance"``, ``"stability margin"``).
        leg: The leg's name (``None`` when the check is about the whole robot).
        time: Time of the first failing sample in [s] (``None`` for a single pose).
        amount: By how much the check fails, in [m] or [rad] (≥ 0).

    """

    def __init__(
        self,
        message: str,
        *,
        check: str,
        leg: str | None = None,
        time: float | None = None,
        amount: float | None = None,
        parameter: str | None = None,
        value: Any = None,
        allowed: Any = None,
    ) -> None:
        super().__init__(message, parameter=parameter, value=value, allowed=allowed)
        self.check = check
        self.leg = leg
        self.time = time
        self.amount = amount


def body_pose(xyz: Any = (0.0, 0.0, 0.0), rpy: Any = (0.0, 0.0, 0.0)) -> np.ndarray:
    """The 4×4 pose of position ``xyz`` [m] and roll/pitch/yaw ``rpy`` [rad] (R = Rz·Ry·Rx).

    Raises:
        ParameterError: ``xyz`` or ``rpy`` is not three finite numbers.

    """
    p = np.asarray(xyz, dtype=float).reshape(-1)
    a = np.asarray(rpy, dtype=float).reshape(-1)
    if p.shape != (3,) or a.shape != (3,) or not np.all(np.isfinite(np.r_[p, a])):
        raise ParameterError(f"pose xyz={xyz!r}, rpy={rpy!r}: three finite numbers each")
    T = np.eye(4)
    T[:3, :3] = rpy_to_matrix(*(float(v) for v in a))
    T[:3, 3] = p
    return T


def _pick_branch(
    qk: np.ndarray, valid: np.ndarray, q0: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Per leg and sample, the valid IK slot nearest the previous sample (angles unwrapped).

    Args:
        qk: (G, N, K, m) candidate solutions of G legs at N samples.
        valid: (G, N, K) which candidates exist.
        q0: (G, m) the configuration before the first sample.

    Returns:
        ``(q, ok)``: (G, N, m) the continued joint angles (the previous value kept where no
        slot is valid) and (G, N) whether a slot was found.

    """
    g, n, _, m = qk.shape
    out = np.empty((n, g, m))
    ok = np.asarray(np.asarray(valid, dtype=bool).any(axis=2))
    cand = np.ascontiguousarray(np.moveaxis(qk, 1, 0))  # (N, G, K, m)
    usable = np.ascontiguousarray(np.moveaxis(valid, 1, 0))  # (N, G, K)
    found = np.ascontiguousarray(ok.T[:, :, None])  # (N, G, 1)
    prev = np.array(q0, dtype=float)
    rows = np.arange(g)
    step = np.empty(cand.shape[1:])
    two_pi = 2.0 * np.pi
    for i in range(n):
        np.subtract(cand[i], prev[:, None, :], out=step)
        step += np.pi
        np.mod(step, two_pi, out=step)
        step -= np.pi
        d = np.where(usable[i], np.abs(step).sum(axis=2), np.inf)
        prev = np.where(found[i], prev + step[rows, d.argmin(axis=1)], prev)
        out[i] = prev
    out = np.moveaxis(out, 0, 1)
    return out, ok


@dataclass(frozen=True)
class BodyIK:
    """Joint angles of body poses with the feet fixed in the world (arrays read-only).

    Attributes:
        q: (N, 18) joint angles in [rad], legs in order, hip/knee/ankle each.
        reached: (N, L) True where the leg's closed form has a solution.
        excess: (N, L) distance by which each foot is out of the leg's reach in [m]
            (0 when reachable).
        limit_margin: (N, 18) distance of each joint to its nearest limit in [rad]
            (negative beyond a limit).
        leg_names: The legs' names.

    """

    q: np.ndarray
    reached: np.ndarray
    excess: np.ndarray
    limit_margin: np.ndarray
    leg_names: tuple[str, ...]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary (arrays as nested lists, SI units)."""
        return {
            f.name: (v.tolist() if isinstance(v, np.ndarray) else v)
            for f in fields(self)
            for v in (getattr(self, f.name),)
        }

    @property
    def ok(self) -> np.ndarray:
        """(N, L) True where the leg is reached and inside its joint limits."""
        n_leg = len(self.leg_names)
        lim = self.limit_margin.reshape(len(self.q), n_leg, -1).min(axis=2)
        return np.asarray(self.reached & (lim >= 0))


@dataclass(frozen=True, eq=False)
class WholeBody:
    """The hexapod with a floating base: Pinocchio model and vectorised kinematics.

    Build it with :func:`whole_body` (cached per robot). Joint order: the legs in
    ``params.legs`` order, hip/knee/ankle each (the order of Pinocchio's ``q[7:]``).

    Attributes:
        params: The robot's parameters.
        model: Pinocchio model with a free-flyer root (nq = 7 + 18).
        leg_names: The legs' names.
        joint_names: The 18 joint names.
        mass: Total mass in [kg] (from the URDF's inertials).
        lower: (18,) lower joint limits in [rad].
        upper: (18,) upper joint limits in [rad].
        mounts: (L, 4, 4) ``bodyMmount`` of each leg.
        link_radius: Radius of the leg links in [m] (for the leg clearance).

    """

    params: Hexapod
    model: Any
    leg_names: tuple[str, ...]
    joint_names: tuple[str, ...]
    mass: float
    lower: np.ndarray
    upper: np.ndarray
    mounts: np.ndarray
    link_radius: float
    _parents: np.ndarray = field(repr=False)
    _placements: np.ndarray = field(repr=False)
    _masses: np.ndarray = field(repr=False)
    _levers: np.ndarray = field(repr=False)
    _foot: np.ndarray = field(repr=False)
    _foot_joint: np.ndarray = field(repr=False)
    _leg_joints: np.ndarray = field(repr=False)

    @property
    def n_legs(self) -> int:
        """Number of legs."""
        return len(self.leg_names)

    @property
    def nq(self) -> int:
        """Number of leg joints (18)."""
        return len(self.joint_names)

    # ------------------------------------------------------------------ kinematics
    def joint_poses(self, q: Any, base: Any) -> np.ndarray:
        """World poses of the leg joints' frames, (N, 18, 4, 4).

        Args:
            q: (N, 18) joint angles in [rad].
            base: (N, 4, 4) body poses ``worldMbody``.

        """
        q = np.asarray(q, dtype=float)
        base = np.asarray(base, dtype=float)
        n = q.shape[0]
        out = np.empty((n, self.nq, 4, 4))
        c, s = np.cos(q), np.sin(q)
        for j in range(self.nq):
            P = self._placements[j]
            local = np.empty((n, 4, 4))
            local[:, :, 0] = c[:, j, None] * P[:, 0] + s[:, j, None] * P[:, 1]
            local[:, :, 1] = -s[:, j, None] * P[:, 0] + c[:, j, None] * P[:, 1]
            local[:, :, 2] = P[:, 2]
            local[:, :, 3] = P[:, 3]
            parent = base if self._parents[j] < 0 else out[:, self._parents[j]]
            out[:, j] = parent @ local
        return out

    def leg_points(self, q: Any, base: Any) -> np.ndarray:
        """World positions (N, L, 4, 3) of each leg's hip, knee, ankle and foot, in [m]."""
        return self.points_of(self.joint_poses(q, base))

    def points_of(self, T: np.ndarray) -> np.ndarray:
        """:meth:`leg_points` from joint poses ``T`` (N, 18, 4, 4) of :meth:`joint_poses`."""
        pts = T[:, self._leg_joints][..., :3, 3]  # (N, L, 3, 3)
        Ta = T[:, self._foot_joint]  # (N, L, 4, 4)
        foot = np.matmul(Ta[..., :3, :], self._foot[None, :, :, None])[..., 0]
        return np.concatenate([pts, foot[:, :, None, :]], axis=2)

    def feet(self, q: Any, base: Any) -> np.ndarray:
        """World foot positions (N, L, 3) in [m]."""
        return self.leg_points(q, base)[:, :, 3]

    def com(self, q: Any, base: Any) -> np.ndarray:
        """Centre of mass (N, 3) in the world in [m] (body and every link's inertial)."""
        return self.com_of(self.joint_poses(q, base), base)

    def com_of(self, T: np.ndarray, base: Any) -> np.ndarray:
        """:meth:`com` from joint poses ``T`` (N, 18, 4, 4) and body poses (N, 4, 4)."""
        base = np.asarray(base, dtype=float)
        acc = self._masses[0] * (base[:, :3, :3] @ self._levers[0] + base[:, :3, 3])
        pts = np.einsum("njab,jb->nja", T[:, :, :3, :3], self._levers[1:]) + T[:, :, :3, 3]
        acc = acc + np.einsum("j,nja->na", self._masses[1:], pts)
        return np.asarray(acc / self.mass)

    def points_and_com(self, q: Any, base: Any) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`leg_points` (N, L, 4, 3) and :meth:`com` (N, 3) from one tree pass."""
        T = self.joint_poses(q, base)
        return self.points_of(T), self.com_of(T, base)

    def pinocchio_q(self, q: Any, base: Any) -> np.ndarray:
        """Pinocchio configurations (N, 25): base xyz, base quaternion (x, y, z, w), joints."""
        import pinocchio as pin

        q = np.asarray(q, dtype=float)
        base = np.asarray(base, dtype=float)
        out = np.empty((len(q), 7 + self.nq))
        for i in range(len(q)):
            out[i, :3] = base[i, :3, 3]
            out[i, 3:7] = pin.Quaternion(base[i, :3, :3]).coeffs()
        out[:, 7:] = q
        return out

    # ------------------------------------------------------------------ body-pose IK
    def neutral_q(self) -> np.ndarray:
        """A standing configuration (18,): every leg at :data:`hexapod_kin.ik.LEG_HOME`."""
        from ..ik import LEG_HOME

        q = np.zeros(self.nq)
        home = dict(zip(("hip", "knee", "ankle"), LEG_HOME))
        for i, name in enumerate(self.joint_names):
            q[i] = home.get(name.rsplit("_", 1)[-1], 0.0)
        return np.clip(q, self.lower, self.upper)

    def reach_excess(self, targets: np.ndarray, leg: int) -> np.ndarray:
        """Distance (N,) by which mount-frame foot targets lie outside the leg's reach [m]."""
        from ..ik import detect_family

        fam = detect_family(self.params.legs[leg].chain)
        x = np.asarray(targets, dtype=float)
        h = np.hypot(x[:, 0], x[:, 1])
        w = (x[:, 2] - fam.height) * fam.sign
        if fam.family == "leg3":
            l1, l2, l3 = fam.lengths
            rmin, rmax = abs(l2 - l3), l2 + l3
        else:
            l1, l2 = fam.lengths[:2]
            rmin = rmax = abs(l2)
        best = np.full(len(x), np.inf)
        for hs in (1.0, -1.0):
            r = np.hypot(hs * h - l1, w)
            best = np.minimum(best, np.maximum.reduce([r - rmax, rmin - r, np.zeros_like(r)]))
        return best

    def body_ik(
        self,
        base: Any,
        feet: Any,
        *,
        q_prev: Any = None,
        times: Any = None,
        strict: bool = True,
    ) -> BodyIK:
        """The 18 joint angles that put the feet at world points under body poses.

        Each leg is solved in its mount frame by its closed form; at each sample the branch
        nearest to the previous sample's (the first to ``q_prev``) is kept.

        Args:
            base: Body pose(s) ``worldMbody``: (4, 4) or (N, 4, 4) (see :func:`body_pose`), or
                (6,) / (N, 6) ``x, y, z`` [m], ``roll, pitch, yaw`` [rad].
            feet: Foot positions in the world (L, 3) or (N, L, 3) in [m].
            q_prev: (18,) joints the first sample's branch is nearest to (default
                :meth:`neutral_q`).
            times: (N,) sample times in [s], used in error messages (default: sample index).
            strict: Raise on the first unreachable foot or joint beyond its limits.

        Returns:
            A :class:`BodyIK` (per-leg status and out-of-reach distances).

        Raises:
            GaitError: ``strict`` and a foot is out of reach (check ``"reach"``: names the
                leg, the time and by how much) or a joint is beyond its limit
                (``"joint limit"``).
            ParameterError: Bad shapes.

        """
        from ..ik import analytic_batch

        try:
            B = np.asarray(base, dtype=float)
            P = np.asarray(feet, dtype=float)
        except (TypeError, ValueError):
            raise ParameterError(
                "base and feet must be arrays of numbers", parameter="base"
            ) from None
        if B.shape[-1:] == (6,) and B.ndim in (1, 2):  # x, y, z, roll, pitch, yaw
            B = np.array([body_pose(b[:3], b[3:]) for b in B.reshape(-1, 6)])
        if B.shape == (4, 4):
            B = B[None]
        if P.ndim == 2:
            P = np.broadcast_to(P, (len(B),) + P.shape)
        nl = self.n_legs
        if B.ndim != 3 or B.shape[1:] != (4, 4) or P.shape != (len(B), nl, 3):
            raise ParameterError(
                f"base has shape {np.shape(base)} and feet {np.shape(feet)}; expected (N, 4, 4) "
                f"and (N, {nl}, 3) (or (4, 4) and ({nl}, 3))",
                parameter="feet",
                value=np.shape(feet),
                allowed=f"(N, {nl}, 3)",
            )
        if not (np.all(np.isfinite(B)) and np.all(np.isfinite(P))):
            raise ParameterError("base and feet must be finite", parameter="feet")
        n = len(B)
        t = np.arange(n, dtype=float) if times is None else np.asarray(times, dtype=float)
        q0 = self.neutral_q() if q_prev is None else np.asarray(q_prev, dtype=float)
        # feet in each mount frame: (worldMbody · bodyMmount)^-1 · p; rows: Rᵀv = (vᵀR)ᵀ
        p_body = np.matmul(P - B[:, None, :3, 3], B[:, :3, :3])
        rel = (p_body - self.mounts[None, :, :3, 3])[:, :, None, :]
        p_mount = np.matmul(rel, self.mounts[None, :, :3, :3])[:, :, 0, :]
        q = np.empty((n, self.nq))
        reached = np.empty((n, nl), dtype=bool)
        excess = np.zeros((n, nl))
        groups: dict[int, list[int]] = {}
        for leg in range(nl):  # legs with the same table share one closed-form call
            groups.setdefault(id(self.params.legs[leg].chain), []).append(leg)
        for legs in groups.values():
            chain = self.params.legs[legs[0]].chain
            targets = np.ascontiguousarray(p_mount[:, legs].transpose(1, 0, 2).reshape(-1, 3))
            try:
                batch = analytic_batch(chain, targets)
            except HexapodKinError as exc:
                raise ConfigurationError(
                    f"legs {[self.leg_names[k] for k in legs]}: {exc}", parameter="params"
                ) from None
            qk = batch.q.reshape(len(legs), n, *batch.q.shape[1:])
            vk = batch.valid.reshape(len(legs), n, -1)
            cols = self._leg_joints[legs]  # (G, m)
            picked, ok = _pick_branch(qk, vk, q0[cols])
            for g, leg in enumerate(legs):
                q[:, cols[g]] = picked[g]
                reached[:, leg] = ok[g]
                if not ok[g].all():
                    excess[:, leg] = np.where(
                        ok[g], 0.0, self.reach_excess(targets[g * n : (g + 1) * n], leg)
                    )
        margin = np.minimum(q - self.lower, self.upper - q)
        if strict:
            self._raise_first(reached, excess, margin, t)
        for a in (q, reached, excess, margin):
            a.setflags(write=False)
        return BodyIK(q, reached, excess, margin, self.leg_names)

    def _raise_first(
        self, reached: np.ndarray, excess: np.ndarray, margin: np.ndarray, t: np.ndarray
    ) -> None:
        if not reached.all():
            i, leg = np.argwhere(~reached)[0]
            d = float(excess[i, leg])
            name = self.leg_names[leg]
            raise GaitError(
                f"leg {name}: foot out of reach by {d:.4g} m at t={t[i]:.4g} s (check 'reach'; "
                "shorten the stride, lower the step or the body, or slow down)",
                check="reach",
                leg=name,
                time=float(t[i]),
                amount=d,
                parameter="feet",
                value=d,
                allowed="a foot within the leg's reach",
            )
        if np.any(margin < 0):
            i, j = np.argwhere(margin < 0)[0]
            leg = name = self.joint_names[j].rsplit("_", 1)[0]
            d = float(-margin[i, j])
            raise GaitError(
                f"leg {leg}: joint {self.joint_names[j]} beyond its limit by {d:.4g} rad at "
                f"t={t[i]:.4g} s (check 'joint limit'; allowed [{self.lower[j]:.4g}, "
                f"{self.upper[j]:.4g}] rad)",
                check="joint limit",
                leg=name,
                time=float(t[i]),
                amount=d,
                parameter=self.joint_names[j],
                value=d,
                allowed=[float(self.lower[j]), float(self.upper[j])],
            )

    # ------------------------------------------------ minimal versions (h2; h1 builds them)
    @property
    def foot_radius(self) -> float:
        """Contact radius of the feet [m]: the foot spheres of the exported model (1.5 × link)."""
        return 1.5 * float(self.params.legs[0].chain.link_radius)

    @property
    def velocity_limit(self) -> np.ndarray:
        """(nq,) joint velocity limits from the URDF [rad/s] (inf if absent)."""
        v = np.asarray(self.model.velocityLimit[6:], dtype=float).copy()
        v[v > 1e300] = np.inf
        return v

    @property
    def effort_limit(self) -> np.ndarray:
        """(nq,) joint effort limits from the URDF [N·m] (inf if absent)."""
        v = np.asarray(self.model.effortLimit[6:], dtype=float).copy()
        v[v > 1e300] = np.inf
        return v

    def foot_poses(self, q: Any, base: Any) -> np.ndarray:
        """World poses (N, L, 4, 4) of the foot frames (the contact spheres' centres)."""
        T = self.joint_poses(q, base)
        Ta = T[:, self._foot_joint]  # (N, L, 4, 4): the foot's joint frame
        local = np.array(
            [
                self.model.frames[
                    self.model.getFrameId(f"{leg.name}_{leg.chain.tip}")
                ].placement.homogeneous
                for leg in self.params.legs
            ]
        )
        return np.asarray(np.matmul(Ta, local[None]))


def _build(params: Hexapod) -> WholeBody:
    import pinocchio as pin

    from .._gate import check_urdf
    from ..urdf import to_urdf

    text = to_urdf(params)
    check_urdf(text)
    model = pin.buildModelFromXML(text, pin.JointModelFreeFlyer())
    names = list(model.names)
    joint_names = tuple(params.joint_names)
    idx = []
    for jn in joint_names:
        if jn not in names:
            raise ConfigurationError(f"joint {jn!r} missing from the hexapod's URDF model")
        j = names.index(jn)
        if model.joints[j].shortname() != "JointModelRZ":
            raise ConfigurationError(
                f"joint {jn!r} is {model.joints[j].shortname()}; the vectorised kinematics "
                "handle revolute-z joints (Khalil tables)"
            )
        idx.append(j)
    if idx != sorted(idx) or idx != list(range(2, 2 + len(idx))):
        raise ConfigurationError("the URDF's joint order differs from params.joint_names")
    local = {j: k for k, j in enumerate(idx)}
    parents = np.array([local.get(model.parents[j], -1) for j in idx])
    placements = np.array([model.jointPlacements[j].homogeneous for j in idx])
    masses = np.array([model.inertias[1].mass] + [model.inertias[j].mass for j in idx])
    levers = np.array([model.inertias[1].lever] + [model.inertias[j].lever for j in idx])
    leg_joints, foot, foot_joint = [], [], []
    for leg in params.legs:
        cols = [joint_names.index(f"{leg.name}_{j}") for j in (leg.chain.joint_names or ())]
        if len(cols) != 3:
            raise ConfigurationError(f"leg {leg.name}: three joints expected, got {len(cols)}")
        leg_joints.append(cols)
        fid = model.getFrameId(f"{leg.name}_{leg.chain.tip}")
        fr = model.frames[fid]
        foot.append(np.append(fr.placement.translation, 1.0))  # in its joint's frame
        foot_joint.append(local[fr.parentJoint])
    foot_arr = np.array(foot)
    lower = np.asarray(model.lowerPositionLimit[7:], dtype=float).copy()
    upper = np.asarray(model.upperPositionLimit[7:], dtype=float).copy()
    mounts = np.array([leg.transform() for leg in params.legs])
    wb = WholeBody(
        params=params,
        model=model,
        leg_names=tuple(leg.name for leg in params.legs),
        joint_names=joint_names,
        mass=float(pin.computeTotalMass(model)),
        lower=lower,
        upper=upper,
        mounts=mounts,
        link_radius=float(params.legs[0].chain.link_radius),
        _parents=parents,
        _placements=placements,
        _masses=masses,
        _levers=levers,
        _foot=foot_arr,
        _foot_joint=np.array(foot_joint),
        _leg_joints=np.array(leg_joints),
    )
    for a in (lower, upper, mounts, placements, masses, levers, foot_arr):
        a.setflags(write=False)
    return wb


@lru_cache(maxsize=8)
def _cached(params: Hexapod) -> WholeBody:
    return _build(params)


@lru_cache(maxsize=1)
def _default() -> WholeBody:
    from ..robots import hexapod

    return _cached(hexapod())


def whole_body(params: Hexapod | None = None) -> WholeBody:
    """The whole-robot model of a hexapod (default ``robots.hexapod()``), cached.

    Raises:
        ParameterError: ``params`` is not a :class:`~hexapod_kin.params.Hexapod`.
        UrdfError: The generated URDF fails the loader gate.
        ConfigurationError: The legs are not 3-joint revolute-z chains.

    """
    if params is None:
        return _default()
    if not isinstance(params, Hexapod):
        raise ParameterError(
            f"params={params!r} is not a Hexapod",
            parameter="params",
            value=repr(params),
            allowed="hexapod_kin.params.Hexapod (e.g. robots.hexapod())",
        )
    try:
        return _cached(params)
    except TypeError:  # unhashable parameters
        return _build(params)
