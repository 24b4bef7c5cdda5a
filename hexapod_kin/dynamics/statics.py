"""Joint torques of a leg: gravity (RNEA), a foot force (Jᵀ F), along a joint trajectory.

``force`` is the force the foot exerts on its environment, in [N], base axes: ``τ = g(q) + Jᵀ
F`` (``J`` the foot's LOCAL_WORLD_ALIGNED linear Jacobian). The cross-check computes ``Jᵀ F``
again by RNEA with the reaction ``−F`` as external force (gravity off; ``fext[i]`` in joint
i's frame).
"""

from __future__ import annotations

import threading
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from .._fields import fields_dict
from ..exceptions import ParameterError
from ._common import as_model, check_inertials, finite_vector, read_only, zero_gravity_model

__all__ = ["LegTorques", "StepTorques", "external_force", "leg_torques", "torques_along"]


def external_force(
    model: pin.Model, data: pin.Data, frame_id: int, force_world: np.ndarray
) -> list[pin.Force]:
    """``fext`` for ``pin.rnea``/``pin.aba``: ``force_world`` [N] applied at frame ``frame_id``.

    The force acts at the frame's origin on the parent joint's body, returned in that joint's
    frame (``Rᵀ f``, moment ``Rᵀ ((p − o) × f)``); needs ``data`` after
    ``pin.framesForwardKinematics``.
    """
    joint = model.frames[frame_id].parentJoint
    omi, p = data.oMi[joint], data.oMf[frame_id].translation
    rot_t = omi.rotation.T
    moment = np.cross(p - omi.translation, force_world)
    fext = [pin.Force.Zero() for _ in range(model.njoints)]
    fext[joint] = pin.Force(rot_t @ force_world, rot_t @ moment)
    return fext


@dataclass(frozen=True)
class LegTorques:
    """Static joint torques of a leg at ``q`` (SI units; arrays read-only).

    ``force`` (3,) of the foot on its environment in [N], base axes, acting at ``frame``; per
    joint in [N·m]: ``gravity`` ``g(q)``, ``force_torque`` ``Jᵀ F``, ``total`` their sum,
    ``force_torque_rnea`` ``Jᵀ F`` again by RNEA (reaction ``−F`` as external force, gravity
    off), ``effort_limit`` (the URDF's); ``crosscheck_error`` ``max |Jᵀ F − RNEA|`` and
    ``gravity_crosscheck_error`` ``max |computeGeneralizedGravity − rnea(q, 0, 0)|`` in [N·m].
    """

    q: np.ndarray
    force: np.ndarray
    frame: str
    gravity: np.ndarray
    force_torque: np.ndarray
    total: np.ndarray
    force_torque_rnea: np.ndarray
    crosscheck_error: float
    gravity_crosscheck_error: float
    joint_names: tuple[str, ...]
    effort_limit: np.ndarray

    @property
    def within_effort_limits(self) -> bool:
        """True when every ``|total|`` is within the URDF effort limit."""
        return bool(np.all(np.abs(self.total) <= self.effort_limit))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (lists of floats, SI units)."""
        return fields_dict(
            self,
            *("q", "force", "frame", "joint_names", "gravity", "force_torque", "total"),
            *("force_torque_rnea", "crosscheck_error", "gravity_crosscheck_error"),
            *("effort_limit", "within_effort_limits"),
        )


class _LegStatics:
    """Per-model state of the torque computations (own Data, zero-gravity copy, frame)."""

    def __init__(self, model: Any, frame: str | None) -> None:
        self.mdl = model
        self.frame = model.tip if frame is None else frame
        self.fid = model.frame_id(self.frame)
        self.pm = model.model
        self.data = self.pm.createData()
        self.zm = zero_gravity_model(model)
        self.zd = self.zm.createData()
        self.rot_base = np.asarray(model.oMbase.rotation)

    def at(self, q: np.ndarray, force: np.ndarray) -> tuple[np.ndarray, ...]:
        pm, d, zm, zd, fid = self.pm, self.data, self.zm, self.zd, self.fid
        frame = None if fid == self.mdl.tip_id else self.frame  # the tip: no name lookup
        jac = self.mdl.jacobian(q, "local_world_aligned", frame)[:3]
        tau_f = jac.T @ force
        grav = np.array(pin.computeGeneralizedGravity(pm, d, q))
        grav_rnea = np.array(pin.rnea(pm, d, q, np.zeros(pm.nv), np.zeros(pm.nv)))
        pin.framesForwardKinematics(zm, zd, q)
        fext = external_force(zm, zd, fid, -(self.rot_base @ force))
        tau_rnea = np.array(pin.rnea(zm, zd, q, np.zeros(zm.nv), np.zeros(zm.nv), fext))
        return grav, tau_f, tau_rnea, grav_rnea


def _statics(model: Any, frame: str | None) -> _LegStatics:
    """The model's :class:`_LegStatics` for ``frame``, one per thread (its Data are private)."""
    check_inertials(model)
    if not hasattr(model, "cached"):
        return _LegStatics(model, frame)
    table = vars(model.cached("dynamics.statics", threading.local)).setdefault("by_frame", {})
    if frame not in table:
        table[frame] = _LegStatics(model, frame)
    return table[frame]


def _force(force: Any) -> np.ndarray:
    return finite_vector("force", (0.0, 0.0, 0.0) if force is None else force, 3)


def leg_torques(model: Any, q: Any, force: Any = None, *, frame: str | None = None) -> LegTorques:
    """Joint torques holding the leg at ``q`` against gravity and a foot force.

    ``force``: of the foot on its environment (3,) in [N], base axes (default zero), acting at
    ``frame`` (default the tip).

    Raises:
        ConfigurationError: Bad ``q``.
        ParameterError: Bad ``force``; implausible inertials (names the link).
        FrameNotFoundError: Unknown ``frame``.

    """
    mdl = as_model(model)
    st = _statics(mdl, frame)
    qv = np.array(mdl.check_q(q), dtype=float)
    f = _force(force)
    grav, tau_f, tau_rnea, grav_rnea = st.at(qv, f)
    total = grav + tau_f
    limit = np.array(mdl.effort_limit, dtype=float)
    read_only(qv, f, grav, tau_f, tau_rnea, total, limit)
    err_f = float(np.max(np.abs(tau_f - tau_rnea), initial=0.0))
    err_g = float(np.max(np.abs(grav - grav_rnea), initial=0.0))
    names = tuple(mdl.joint_names)
    return LegTorques(qv, f, st.frame, grav, tau_f, total, tau_rnea, err_f, err_g, names, limit)


@dataclass(frozen=True)
class StepTorques:
    """Joint torques along a trajectory (e.g. the seeds' resolved-rate step), SI units.

    ``t`` (N,) in [s]; ``force`` (3,) constant, as in :class:`LegTorques`; (N, nq) in [N·m]:
    ``gravity``, ``force_torque``, ``inertial`` ``M q̈ + C q̇`` (q̈ by central differences),
    ``total`` their sum; ``peak`` and ``peak_gravity`` ``max_t |total|``, ``max_t |gravity|``
    per joint; ``crosscheck_error`` ``max_t max |Jᵀ F − RNEA with fext|`` in [N·m].
    """

    t: np.ndarray
    q: np.ndarray
    force: np.ndarray
    gravity: np.ndarray
    force_torque: np.ndarray
    inertial: np.ndarray
    total: np.ndarray
    peak: np.ndarray
    peak_gravity: np.ndarray
    crosscheck_error: float
    joint_names: tuple[str, ...]

    def to_dict(self, samples: bool = False) -> dict[str, Any]:
        """JSON-ready peaks and cross-check (the time series too with ``samples=True``)."""
        out = fields_dict(self, "joint_names", "force")
        out |= {"duration": float(self.t[-1]), "samples": int(len(self.t))}
        out |= fields_dict(self, "peak", "peak_gravity")
        out["peak_inertial"] = np.max(np.abs(self.inertial), axis=0).tolist()
        out["crosscheck_error"] = self.crosscheck_error
        if samples:
            out.update(fields_dict(self, "t", "q", "total", "gravity", "force_torque"))
        return out


def torques_along(
    model: Any, t: Any, q: Any, qdot: Any = None, force: Any = None, *, frame: str | None = None
) -> StepTorques:
    """Joint torques along a sampled trajectory ``q(t)`` (see :class:`StepTorques`).

    ``t`` (N,) strictly increasing times in [s] (N >= 2); ``q``, ``qdot`` (N, nq) (``qdot``
    default central differences of ``q``); ``force``, ``frame`` as in :func:`leg_torques`.

    Raises:
        ConfigurationError: Bad ``q``/``qdot`` shapes or values.
        ParameterError: Bad ``t`` or ``force``.

    """
    mdl = as_model(model)
    st, qs = _statics(mdl, frame), mdl.check_q_batch(q, "q")
    ts = np.asarray(t, dtype=float)
    if ts.shape != (len(qs),) or len(ts) < 2 or not np.all(np.diff(ts) > 0):
        msg = f"t has shape {ts.shape}; {len(qs)} strictly increasing times are needed"
        raise ParameterError(msg, parameter="t", value=ts.shape, allowed=f"({len(qs)},) increasing")
    qd = np.gradient(qs, ts, axis=0) if qdot is None else mdl.check_q_batch(qdot, "qdot")
    if qd.shape != qs.shape:
        msg = f"qdot has shape {qd.shape}; expected {qs.shape}"
        raise ParameterError(msg, parameter="qdot", value=qd.shape, allowed=qs.shape)
    qdd, f = np.gradient(qd, ts, axis=0), _force(force)
    n = len(ts)
    grav, tau_f, inert = (np.empty_like(qs) for _ in range(3))
    err = 0.0
    pm, d = st.pm, st.data
    for i in range(n):
        g, tf, tr, _ = st.at(qs[i], f)
        grav[i], tau_f[i] = g, tf
        err = max(err, float(np.max(np.abs(tf - tr))))
        inert[i] = np.asarray(pin.rnea(pm, d, qs[i], qd[i], qdd[i])) - g
    total = grav + tau_f + inert
    peak, peak_g = np.max(np.abs(total), axis=0), np.max(np.abs(grav), axis=0)
    read_only(ts, qs, f, grav, tau_f, inert, total, peak, peak_g)
    names = tuple(mdl.joint_names)
    return StepTorques(ts, qs, f, grav, tau_f, inert, total, peak, peak_g, err, names)
