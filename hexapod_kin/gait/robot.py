"""A legged robot with a floating base (Pinocchio free-flyer), from any source; body-pose IK.

:func:`as_whole_body` describes the legs of the one robot :func:`hexapod_kin.load` gives
(its :attr:`~hexapod_kin.model.Model.floating_model`; no second parse): legs from the
kinematic tree (:mod:`.legs`), the tree's constants as arrays for batched forward
kinematics, centre of mass and leg segments (:mod:`hexapod_kin._tree`).
:meth:`WholeBody.body_ik` solves the leg joints of body poses with the feet fixed in the
world, leg by leg: closed form where recognised, else numerically. Poses are 4×4
``worldMbody`` arrays (body frame: x forward, z up).
"""

from __future__ import annotations

import math
import os
import threading
from dataclasses import dataclass, field, replace
from functools import cached_property, lru_cache
from typing import Any

import numpy as np

from .._chain import ChainArrays
from .._tree import Tree, mat_vec, tree_poses
from ..exceptions import ConfigurationError, HexapodKinError, ParameterError, positive
from ..frames import reduced_model
from ..params import Hexapod, rpy_to_matrix
from .leg_ik import leg_chain, solve_legs
from .legs import (
    BodyIK,
    FootSpec,
    GaitError,
    check_size,
    find_legs,
    finite_or_inf,
    leg_layout,
    offset_of,
    parse_feet,
    pick_branch,
    sphere_radius,
)
from .posture import roomiest_stance

__all__ = ["BodyIK", "GaitError", "WholeBody", "as_whole_body", "body_pose", "whole_body"]


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


@dataclass(frozen=True, eq=False)
class WholeBody:
    """A legged robot with a floating base: Pinocchio model and vectorised kinematics.

    Built by :func:`as_whole_body` or :func:`whole_body` (cached): a view of the one loaded
    robot (:attr:`kinematic`). Joint order: Pinocchio's ``v[6:]``; one angle per joint,
    continuous ones included (:meth:`pinocchio_q` makes their (cos, sin)); joints of no leg
    are locked at their neutral value (:attr:`locked_joints`).

    Attributes:
        params: The Hexapod it was built from (``None`` for a URDF robot).
        source: A label of the source (preset, file name, ``erd:NAME``).
        model: Pinocchio model with a free-flyer root (the loaded robot's
            :attr:`~hexapod_kin.model.Model.floating_model` reduced to the legs' joints)
            plus a frame ``<leg>_contact`` per foot (the contact sphere's centre).
        kinematic: The loaded robot (:func:`hexapod_kin.load` of the source).
        leg_names: The legs' names (the order of phase tables).
        joint_names: The leg joints (the columns of q).
        mass: Total mass in [kg] (from the URDF's inertials).
        lower: (nq,) lower joint limits in [rad] or [m].
        upper: (nq,) upper joint limits.
        velocity_limit: (nq,) joint speed limits from the URDF [rad/s] (inf if absent).
        effort_limit: (nq,) joint effort limits from the URDF [N·m] (inf if absent).
        mounts: (L, 4, 4) ``bodyMmount`` of each leg (a Hexapod's mount; a URDF robot's first
            joint frame of the leg at q = 0).
        link_radius: Radius of the leg links in [m] (for the leg clearance).
        foot_radius: Contact radius of the feet in [m] (the foot frames are the spheres'
            centres).
        body_height: The robot's default body height above flat ground [m] (see
            :meth:`neutral_feet`).
        foot_frames: The frames the feet are given on (with :attr:`foot_offsets`).
        foot_offsets: (L, 3) the feet in those frames [m].
        locked_joints: Joints of no leg, locked at their neutral value.
        ik_kind: Per leg, ``"closed"`` (closed form, :mod:`hexapod_kin.ik.closed`) or
            ``"numerical"`` (damped least squares, :func:`~.leg_ik.solve_legs`).

    """

    params: Hexapod | None
    source: str
    model: Any
    kinematic: Any
    leg_names: tuple[str, ...]
    joint_names: tuple[str, ...]
    mass: float
    lower: np.ndarray
    upper: np.ndarray
    velocity_limit: np.ndarray
    effort_limit: np.ndarray
    mounts: np.ndarray
    link_radius: float
    foot_radius: float
    body_height: float
    foot_frames: tuple[str, ...]
    foot_offsets: np.ndarray
    locked_joints: tuple[str, ...]
    ik_kind: tuple[str, ...]
    _tree: Tree = field(repr=False)
    _masses: np.ndarray = field(repr=False)
    _levers: np.ndarray = field(repr=False)
    _foot: np.ndarray = field(repr=False)  # (L, 4, 4) foot frame in its joint's frame
    _foot_joint: np.ndarray = field(repr=False)
    _leg_joints: np.ndarray = field(repr=False)  # (L, M) padded at the front
    _leg_cols: tuple[tuple[int, ...], ...] = field(repr=False)
    _closed: tuple[tuple[Any, np.ndarray] | None, ...] = field(repr=False)
    _reach_dir: np.ndarray = field(repr=False)  # (L, 2) horizontal foot direction
    _reach: np.ndarray = field(repr=False)  # (L,) default horizontal mount-to-foot distance
    _span: np.ndarray = field(repr=False)  # (L,) leg spans [m]
    _seed: np.ndarray = field(repr=False)
    _q_index: np.ndarray = field(repr=False)  # (nq,) each leg joint's first index in model q
    _bounded: np.ndarray = field(repr=False)  # (nq,) False for continuous joints (cos, sin)

    @cached_property
    def _chains(self) -> tuple[ChainArrays, ...]:
        """Each leg as a chain view (body → foot, its joints alone: :func:`~.leg_ik.leg_chain`)."""
        tr = self._tree
        return tuple(
            leg_chain(tr.placements[c], tr.axes[c], tr.prismatic[c], foot[:3, 3])
            for c, foot in zip(map(list, self._leg_cols), self._foot)
        )

    @property
    def n_legs(self) -> int:
        """Number of legs."""
        return len(self.leg_names)

    @property
    def nq(self) -> int:
        """Number of leg joints."""
        return len(self.joint_names)

    # ------------------------------------------------------------------ kinematics
    def joint_poses(self, q: Any, base: Any) -> np.ndarray:
        """World poses of the leg joints' frames, (N, nq, 4, 4).

        Args:
            q: (N, nq) joint values in [rad] / [m].
            base: (N, 4, 4) body poses ``worldMbody``.

        """
        return tree_poses(self._tree, np.asarray(q, dtype=float), np.asarray(base, dtype=float))

    def leg_points(self, q: Any, base: Any) -> np.ndarray:
        """World positions (N, L, K, 3) of each leg's joints (hip first) and foot, in [m]."""
        return self.points_of(self.joint_poses(q, base))

    def points_of(self, T: np.ndarray) -> np.ndarray:
        """:meth:`leg_points` from joint poses ``T`` (N, nq, 4, 4) of :meth:`joint_poses`.

        Legs with fewer joints than the longest repeat their first joint's point.
        """
        pts = T[:, self._leg_joints][..., :3, 3]  # (N, L, M, 3)
        foot = self.feet_of(T)
        return np.concatenate([pts, foot[:, :, None, :]], axis=2)

    def feet_of(self, T: np.ndarray) -> np.ndarray:
        """World foot positions (N, L, 3) from joint poses ``T``."""
        j = self._foot_joint
        return mat_vec(T[..., :3, :3][:, j], self._foot[:, :3, 3]) + T[..., :3, 3][:, j]

    def feet(self, q: Any, base: Any) -> np.ndarray:
        """World foot positions (N, L, 3) in [m] (the contact spheres' centres)."""
        return self.feet_of(self.joint_poses(q, base))

    def com(self, q: Any, base: Any) -> np.ndarray:
        """Centre of mass (N, 3) in the world in [m] (body and every link's inertial)."""
        return self.com_of(self.joint_poses(q, base), base)

    def require_mass(self) -> None:
        """Raise a :class:`ConfigurationError` when the robot has no mass (CoM undefined)."""
        if not self.mass > 0:
            raise ConfigurationError(
                f"{self.source}: the robot has no mass (no link gives an <inertial> mass), so "
                "its centre of mass, stability margin and standing forces are undefined; "
                "add <inertial> masses to the URDF"
            )

    def com_of(self, T: np.ndarray, base: Any) -> np.ndarray:
        """:meth:`com` from joint poses ``T`` (N, nq, 4, 4) and body poses (N, 4, 4)."""
        self.require_mass()
        base = np.asarray(base, dtype=float)
        acc = self._masses[0] * (base[:, :3, :3] @ self._levers[0] + base[:, :3, 3])
        m = self._masses[1:]  # Σ_j m_j (R_j l_j + p_j), contracted over j at once
        acc += np.tensordot(T[:, :, :3, :3], m[:, None] * self._levers[1:], axes=([1, 3], [0, 1]))
        acc += np.tensordot(T[:, :, :3, 3], m, axes=([1], [0]))
        return np.asarray(acc / self.mass)

    def points_and_com(self, q: Any, base: Any) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`leg_points` (N, L, K, 3) and :meth:`com` (N, 3) from one tree pass."""
        T = self.joint_poses(q, base)
        return self.points_of(T), self.com_of(T, base)

    def pinocchio_q(self, q: Any, base: Any) -> np.ndarray:
        """Pinocchio configurations (N, model.nq): base xyz, quaternion (x, y, z, w), joints.

        A continuous joint's angle becomes its ``(cos, sin)`` pair.
        """
        import pinocchio as pin

        q = np.asarray(q, dtype=float)
        base = np.asarray(base, dtype=float)
        out = np.empty((len(q), int(self.model.nq)))
        out[:, :3] = base[:, :3, 3]
        for i in range(len(q)):
            out[i, 3:7] = pin.Quaternion(base[i, :3, :3]).coeffs()
        if self._bounded.all():
            out[:, 7:] = q
        else:
            b = self._bounded
            out[:, self._q_index[b]] = q[:, b]
            out[:, self._q_index[~b]] = np.cos(q[:, ~b])
            out[:, self._q_index[~b] + 1] = np.sin(q[:, ~b])
        return out

    @property
    def urdf(self) -> str:
        """The URDF text of the robot (the loaded model's)."""
        return str(self.kinematic.urdf)

    # ------------------------------------------------------------------ standing defaults
    @property
    def leg_span(self) -> float:
        """The legs' mean span [m]: joint to joint to foot, at q = 0 (clipped into the limits)."""
        return float(np.mean(self._span))

    @property
    def foot_reach(self) -> float:
        """The default mount-to-foot horizontal distance [m] (legs' mean, :meth:`neutral_feet`)."""
        return float(np.mean(self._reach))

    def neutral_feet(self, foot_reach: float | None = None) -> np.ndarray:
        """Neutral foot points (L, 3) in the body frame [m] (the contact spheres' centres).

        Horizontally ``mount_i + r_i ê_i``: ``ê_i`` the horizontal direction from the mount to the
        foot at q = 0 (clipped into the limits) less the offset every leg shares (a joint-zero
        convention such as Unitree's bent knees; a Hexapod: the mount's x axis; a leg hanging
        straight down: outward), ``r_i = foot_reach`` or by default ``min(d_i, 0.64 ℓ_i)`` (``d_i``
        that distance at q = 0, ``ℓ_i`` the leg's span). Vertically ``−body_height +
        foot_radius``: the default height puts each neutral foot at most ``ℓ·√(0.64² + 0.32²)``
        from its mount.

        Raises:
            ParameterError: ``foot_reach`` not a number >= 0.

        """
        r = (
            self._reach
            if foot_reach is None
            else np.full(self.n_legs, positive("foot_reach", foot_reach, allow_zero=True))
        )
        out = np.empty((self.n_legs, 3))
        out[:, :2] = self.mounts[:, :2, 3] + r[:, None] * self._reach_dir
        out[:, 2] = -self.body_height + self.foot_radius
        return out

    def neutral_q(self) -> np.ndarray:
        """A standing configuration (nq,).

        A Hexapod's legs at :data:`hexapod_kin.ik.LEG_HOME`; another robot's feet at
        :meth:`neutral_feet` under the body at :attr:`body_height` (numerical IK from q = 0
        with the knees nudged off the stretched singularity).
        """
        return np.array(self._seed)

    def reach_excess(self, targets: np.ndarray, leg: int) -> np.ndarray:
        """Distance (N,) by which frame-0 foot targets lie outside a closed-form leg's reach [m].

        Exact for the ``leg3`` and ``coxa_tibia`` families; other legs: the numerical IK's residual.
        """
        from ..ik import detect_family

        closed = self._closed[leg]
        x = np.asarray(targets, dtype=float)
        if closed is not None:
            fam = detect_family(closed[0])
            if fam.family in ("leg3", "coxa_tibia"):  # tool, mount and lateral offset included
                return np.asarray(fam.reach_excess(x))
            T0 = closed[1]
            x = x @ T0[:3, :3].T + T0[:3, 3]  # frame 0 → body
        _q, res, _ok = self._numeric([leg], x[:, None, :], self._seed[None, :])
        return np.asarray(res[:, 0])

    def _numeric(
        self, legs: list[int], p_body: np.ndarray, q0: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Numerical IK of ``legs`` (same joint count) at body-frame targets (N, G, 3)."""
        cols = np.array([self._leg_cols[k] for k in legs])  # (G, m)
        return solve_legs(
            [self._chains[k] for k in legs],
            self.lower[cols],
            self.upper[cols],
            p_body,
            q0[-1][cols] if q0.ndim == 2 else q0[cols],
            span=float(self._span[legs].max()),
        )

    def body_ik(
        self,
        base: Any,
        feet: Any,
        *,
        q_prev: Any = None,
        times: Any = None,
        strict: bool = True,
    ) -> BodyIK:
        """The leg joints that put the feet at world points under body poses.

        Each leg on its own: its closed form where :mod:`hexapod_kin.ik.closed` recognises it (the
        branch nearest the previous sample's, the first to ``q_prev``), else numerically
        (:func:`~.leg_ik.solve_legs`, warm-started; :attr:`ik_kind` says which).

        Args:
            base: Body pose(s) ``worldMbody``: (4, 4) or (N, 4, 4) (see :func:`body_pose`), or
                (6,) / (N, 6) ``x, y, z`` [m], ``roll, pitch, yaw`` [rad].
            feet: Foot positions (the contact spheres' centres) in the world (L, 3) or
                (N, L, 3) in [m].
            q_prev: (nq,) joints the first sample's branch is nearest to (default
                :meth:`neutral_q`).
            times: (N,) sample times in [s], used in error messages (default: sample index).
            strict: Raise on the first unreachable foot or joint beyond its limits.

        Returns:
            A :class:`BodyIK` (per-leg status and out-of-reach distances).

        Raises:
            GaitError: ``strict`` and a foot out of reach (check ``"reach"``) or a joint beyond
                its limit (``"joint limit"``), naming the leg, the time and by how much.
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
        if q0.shape != (self.nq,):
            raise ParameterError(
                f"q_prev has shape {q0.shape}; expected ({self.nq},)",
                parameter="q_prev",
                value=q0.shape,
                allowed=(self.nq,),
            )
        # feet in the body frame: (worldMbody)^-1 · p; rows: Rᵀv = (vᵀR)ᵀ
        p_body = np.matmul(P - B[:, None, :3, 3], B[:, :3, :3])
        q = np.empty((n, self.nq))
        q[:] = q0  # locked columns never exist; every column belongs to a leg
        reached = np.empty((n, nl), dtype=bool)
        excess = np.zeros((n, nl))
        groups: dict[Any, list[int]] = {}
        for leg in range(nl):  # legs with the same table (or joint count) share one call
            closed = self._closed[leg]
            key = ("c", id(closed[0])) if closed is not None else ("n", len(self._leg_cols[leg]))
            groups.setdefault(key, []).append(leg)
        for key, legs in groups.items():
            cols = np.array([self._leg_cols[k] for k in legs])  # (G, m)
            if key[0] == "n":
                qn, res, ok = self._numeric(legs, p_body[:, legs], q0)
                for g, leg in enumerate(legs):
                    q[:, cols[g]] = qn[:, g]
                    reached[:, leg] = ok[:, g]
                    excess[:, leg] = np.where(ok[:, g], 0.0, res[:, g])
                continue
            chain = self._closed[legs[0]][0]  # type: ignore[index]
            T0 = np.array([self._closed[k][1] for k in legs])  # type: ignore[index]
            rel = p_body[:, legs] - T0[None, :, :3, 3]
            p0 = np.matmul(rel[:, :, None, :], T0[None, :, :3, :3])[:, :, 0, :]
            targets = np.ascontiguousarray(p0.transpose(1, 0, 2).reshape(-1, 3))
            try:
                batch = analytic_batch(chain, targets)
            except HexapodKinError as exc:
                raise ConfigurationError(
                    f"legs {[self.leg_names[k] for k in legs]}: {exc}", parameter="params"
                ) from None
            qk = batch.q.reshape(len(legs), n, *batch.q.shape[1:])
            vk = batch.valid.reshape(len(legs), n, -1)
            vk = self._within_limits(qk, vk, cols)
            picked, ok = pick_branch(qk, vk, q0[cols])
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

    def _within_limits(self, qk: np.ndarray, valid: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """``valid`` (G, N, K) narrowed to the branches inside the joint limits (modulo 2π).

        A sample with no valid branch inside keeps every valid one (the limit check names it).
        """
        lo, hi = self.lower[cols], self.upper[cols]  # (G, m)
        mid = np.where(np.isfinite(lo) & np.isfinite(hi), 0.5 * (lo + hi), 0.0)[:, None, None]
        qq = mid + np.remainder(qk - mid + np.pi, 2.0 * np.pi) - np.pi
        tol = 1e-9
        inside = np.all((qq >= lo[:, None, None] - tol) & (qq <= hi[:, None, None] + tol), axis=-1)
        narrowed = valid & inside
        keep = narrowed.any(axis=-1, keepdims=True)
        return np.asarray(np.where(keep, narrowed, valid))

    def leg_of_joint(self, j: int) -> str:
        """The name of the leg joint ``j`` (a column of q) belongs to."""
        for name, cols in zip(self.leg_names, self._leg_cols):
            if j in cols:
                return name
        return self.joint_names[j]  # pragma: no cover - every joint is on a leg

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
            leg = name = self.leg_of_joint(int(j))
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


def _build_model(
    km: Any,
    *,
    params: Hexapod | None = None,
    feet: tuple[FootSpec, ...] | None = None,
    foot_radius: float | None = None,
) -> WholeBody:
    """The :class:`WholeBody` on the loaded robot ``km`` (its floating-base model, no new parse)."""
    import pinocchio as pin

    text, label = km.urdf, km.name
    full = pin.Model(km.floating_model)  # a copy: the feet's contact frames are added to it
    hexa = params is not None
    if hexa:
        feet = tuple(FootSpec(f) for f in params.foot_frames)  # type: ignore[union-attr]
    legs, others = find_legs(full, feet, ccw=not hexa)
    model = full
    if others:
        specs = tuple(
            FootSpec(leg.foot_frame, tuple(float(v) for v in offset_of(full, leg)))  # type: ignore[arg-type]
            for leg in legs
        )
        model = reduced_model(full, list(others), pin.neutral(full))
        legs, _ = find_legs(model, specs, ccw=False)
    nq = model.njoints - 2
    tree = Tree.of_model(model, first=2, label=label)
    names = tuple(leg.name for leg in legs) if not hexa else tuple(x.name for x in params.legs)  # type: ignore[union-attr]
    foot_names = []
    for leg, name in zip(legs, names):
        fname = f"{name}_contact"
        if not model.existFrame(fname):
            parent, place = model.getFrameId(leg.foot_frame), pin.SE3(leg.foot_placement)
            frame = pin.Frame(fname, leg.foot_joint + 2, parent, place, pin.FrameType.OP_FRAME)
            model.addFrame(frame)
        foot_names.append(fname)
    iq = np.array([model.joints[j].idx_q for j in range(2, model.njoints)], dtype=int)
    bounded = np.array([model.joints[j].nq == 1 for j in range(2, model.njoints)])
    lower = np.where(bounded, finite_or_inf(model.lowerPositionLimit[iq]), np.inf)
    lower[np.isinf(lower)] = -np.inf
    upper = np.where(bounded, finite_or_inf(model.upperPositionLimit[iq]), np.inf)
    vel = finite_or_inf(model.velocityLimit[6:])
    eff = finite_or_inf(model.effortLimit[6:])
    cols = tuple(leg.joints for leg in legs)
    width = max(len(c) for c in cols)
    padded = np.array([(c[0],) * (width - len(c)) + tuple(c) for c in cols])
    foot = np.array([leg.foot_placement for leg in legs])
    q_zero = np.clip(np.zeros(nq), lower, upper)
    lay = leg_layout(model, tree, legs, cols, q_zero, lower, upper, params, km)
    span, mounts = lay["span"], lay["mounts"]
    # contact radius and link radius
    if foot_radius is not None:
        rad = check_size(foot_radius, model)  # as_whole_body checked it is a number >= 0
    elif hexa:
        rad = 1.5 * float(params.legs[0].chain.link_radius)  # type: ignore[union-attr]
    elif feet is None:  # leaf feet: their links' sphere collisions, if every foot has one
        radii = [sphere_radius(text, leg.foot_frame) for leg in legs]
        rad = min(float(r) for r in radii) if all(r is not None for r in radii) else 0.0  # type: ignore[arg-type]
    else:
        rad = 0.0
    link_r = float(params.legs[0].chain.link_radius) if hexa else 0.04 * float(span.mean())  # type: ignore[union-attr]
    inertias = [model.inertias[1]] + [model.inertias[j] for j in range(2, model.njoints)]
    wb = WholeBody(
        params=params,
        source=label,
        model=model,
        kinematic=km,
        leg_names=names,
        joint_names=tuple(str(model.names[j]) for j in range(2, model.njoints)),
        mass=float(pin.computeTotalMass(model)),
        lower=lower,
        upper=upper,
        velocity_limit=vel,
        effort_limit=eff,
        mounts=mounts,
        link_radius=link_r,
        foot_radius=rad,
        body_height=lay["body_height"],
        foot_frames=tuple(foot_names),
        foot_offsets=np.array([offset_of(model, leg) for leg in legs]),
        locked_joints=tuple(str(full.names[j]) for j in others),
        ik_kind=tuple("closed" if c is not None else "numerical" for c in lay["closed"]),
        _tree=tree,
        _masses=np.array([x.mass for x in inertias]),
        _levers=np.array([x.lever for x in inertias]),
        _foot=foot,
        _foot_joint=np.array([leg.foot_joint for leg in legs]),
        _leg_joints=padded,
        _leg_cols=cols,
        _closed=tuple(lay["closed"]),
        _reach_dir=lay["direction"],
        _reach=lay["reach"],
        _span=span,
        _seed=np.zeros(nq),
        _q_index=iq,
        _bounded=bounded,
    )
    object.__setattr__(wb, "_seed", _standing_seed(wb, params))
    better = None if hexa else roomiest_stance(wb)
    if better is not None:  # the geometric default leaves a joint no room to step
        reach = np.full(len(cols), better[1])
        wb = replace(wb, body_height=better[0], _reach=reach, _seed=np.zeros(nq))
        object.__setattr__(wb, "_seed", _standing_seed(wb, params))
    for a in (lower, upper, vel, eff, mounts, tree.placements, tree.axes, foot, wb._seed):
        a.setflags(write=False)
    return wb


def _standing_seed(wb: WholeBody, params: Hexapod | None) -> np.ndarray:
    """:meth:`WholeBody.neutral_q` (see there)."""
    if params is not None:
        return leg_home(wb.joint_names, wb.lower, wb.upper)
    q = np.zeros(wb.nq)
    for cols in wb._leg_cols:  # knees nudged off the stretched-leg singularity, inside limits
        for k, j in enumerate(cols):
            lo, hi = float(wb.lower[j]), float(wb.upper[j])
            for v in (0.3, -0.3) if k >= 1 else (0.0,):
                if lo < v < hi:
                    q[j] = v
                    break
            else:
                q[j] = 0.5 * (lo + hi) if math.isfinite(lo + hi) else float(np.clip(0.0, lo, hi))
    base = body_pose([0.0, 0.0, wb.body_height])
    feet = wb.neutral_feet(None) + base[:3, 3]
    ik = wb.body_ik(base, feet, q_prev=q, strict=False)
    return np.array(ik.q[0]) if bool(ik.reached.all()) else q


def leg_home(joint_names: tuple[str, ...], lower: Any, upper: Any) -> np.ndarray:
    """A Hexapod's joints (nq,) at :data:`hexapod_kin.ik.LEG_HOME` (hip, knee, ankle), clipped."""
    from ..ik import LEG_HOME

    home = dict(zip(("hip", "knee", "ankle"), LEG_HOME))
    q = np.array([home.get(name.rsplit("_", 1)[-1], 0.0) for name in joint_names])
    return np.clip(q, np.asarray(lower), np.asarray(upper))


@lru_cache(maxsize=8)
def _cached(params: Hexapod) -> WholeBody:
    from ..kinematics import load

    return _build_model(load(params), params=params)


@lru_cache(maxsize=1)
def _default() -> WholeBody:
    from ..robots import hexapod

    return _cached(hexapod())


def whole_body(params: Hexapod | None = None) -> WholeBody:
    """The whole-robot model of a hexapod (default ``robots.hexapod()``), cached.

    Raises:
        ParameterError: ``params`` is not a :class:`~hexapod_kin.params.Hexapod`.
        UrdfError: The generated URDF fails the loader gate.
        ConfigurationError: A leg joint that is neither revolute nor prismatic.

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
        if params == _default().params:  # the default stays one object, whatever the LRU holds
            return _default()
        return _cached(params)
    except TypeError:  # unhashable parameters
        return _cached.__wrapped__(params)


_SOURCES: dict[Any, WholeBody] = {}
_SOURCES_LOCK = threading.Lock()


def as_whole_body(robot: Any = None, *, feet: Any = None, foot_radius: Any = None) -> WholeBody:
    """The legged robot of any source, cached.

    Args:
        robot: ``None`` (the built-in hexapod), a :class:`WholeBody` (returned as is), a
            :class:`~hexapod_kin.params.Hexapod`, a loaded model, or a source
            :func:`hexapod_kin.load` takes (a URDF path or text, ``erd:NAME``, a preset).
        feet: Feet named as a frame plus an offset in that frame [m], for a URDF without foot
            links (see :func:`~.legs.parse_feet`: ``"tibia_lf:0,0.16,0.029 ..."``, a list of
            such strings, ``{"tibia_lf": (x, y, z), ...}`` or a YAML/TOML/JSON file). Default:
            the deepest frame of every branch of the joint tree.
        foot_radius: Contact radius of the feet [m] (default: a Hexapod's foot sphere,
            1.5 × its link radius; a URDF's foot links' sphere collision radius, else 0).

    Raises:
        ParameterError: A bad ``feet`` or ``foot_radius``, options given with a WholeBody, a
            source that is one chain (a table file, an arm preset).
        SourceError, UrdfError: The source cannot be loaded.
        ConfigurationError: No legs found (names the frames), a non-revolute/prismatic leg
            joint.

    """
    if isinstance(robot, WholeBody):
        if feet is not None or foot_radius is not None:
            raise ParameterError(
                "feet= and foot_radius= are properties of a robot being built; this robot is "
                "already a WholeBody",
                parameter="feet",
                value=repr(feet),
            )
        return robot
    spec = parse_feet(feet)
    rad = None if foot_radius is None else positive("foot_radius", foot_radius, allow_zero=True)
    if robot is None:
        robot = "hexapod"
    params = robot if isinstance(robot, Hexapod) else getattr(robot, "params", None)
    if isinstance(robot, Hexapod) or isinstance(params, Hexapod) and hasattr(robot, "urdf"):
        if spec is not None:
            raise ParameterError(
                "feet= is for URDF robots without foot links; a Hexapod has its feet",
                parameter="feet",
                value=repr(feet),
            )
        wb = whole_body(params)
        return wb if rad is None else replace(wb, foot_radius=check_size(rad, wb.model))
    key: Any = None
    if isinstance(robot, (str, os.PathLike)):
        text = os.fspath(robot)
        stamp = None
        if os.path.isfile(text):  # the file itself: a relative path means another in another cwd
            st = os.stat(text)
            text, stamp = os.path.realpath(text), (st.st_mtime_ns, st.st_size, st.st_ino)
        key = (text, stamp, spec, rad)
        with _SOURCES_LOCK:
            if key in _SOURCES:
                return _SOURCES[key]
    wb = _from_source(robot, spec, rad)
    if key is not None:
        with _SOURCES_LOCK:
            if len(_SOURCES) >= 16:
                _SOURCES.pop(next(iter(_SOURCES)))
            _SOURCES[key] = wb
    return wb


def _from_source(robot: Any, spec: tuple[FootSpec, ...] | None, rad: float | None) -> WholeBody:
    from ..kinematics import KinematicModel, load

    km = robot if isinstance(robot, KinematicModel) else load(robot)
    params = km.params
    if isinstance(params, Hexapod):
        return as_whole_body(params, feet=spec, foot_radius=rad)

    if params is not None:
        raise ParameterError(
            f"{km.name!r} is one serial chain, not a legged robot (a floating body with legs); "
            "give a Hexapod, a legged robot's URDF or erd:NAME",
            parameter="robot",
            value=km.name,
            allowed="a legged robot",
        )
    return km.cached(  # one description per loaded robot and feet
        f"gait.whole_body {spec!r} {rad!r}", lambda: _build_model(km, feet=spec, foot_radius=rad)
    )
