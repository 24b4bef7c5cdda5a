"""Contact forces and joint torques along a gait run: quasi-static and full inverse dynamics.

From a walk's ``t``, ``base_poses``, ``q``, ``joint_names`` and ``support`` (a
``hexapod_kin.gait.GaitRun``):

* **Quasi-static** (``torque``): the weight over the stance feet as
  :func:`~hexapod_kin.dynamics.standing.contact_forces` shares it, ``τ = g(q)[6:] − Σ
  J_i[:3, 6:]ᵀ f_i`` on the floating-base model (world axes).
* **Full inverse dynamics** (``torque_full``, with ``run.robot``): ``b = M(q) a + h(q, v)``
  (``rnea`` on the plan's velocities and accelerations); the contact forces (at ``centre −
  r n``) solve the base rows ``Σ_i J_{i,base}ᵀ f_i = b_base`` (minimum norm, or in the
  friction cones), ``τ = b_joints − Σ J_{i,joints}ᵀ f_i``; ``base_residual`` the largest
  ``‖b_base − Σ J_{i,base}ᵀ f_i‖``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin

from .._fields import fields_dict
from ..exceptions import ConfigurationError, ParameterError
from ..params import Hexapod
from ._common import as_model, check_inertials, read_only
from .standing import ContactMethod, _friction_qp, _hexapod, contact_forces

__all__ = ["GaitTorques", "full_dynamics", "gait_torques"]


@dataclass(frozen=True)
class GaitTorques:
    """Quasi-static loads along a gait run (SI units, world axes for forces; read-only).

    ``t`` (N,) [s]; ``support`` (N, L) True for the stance feet (L: ``leg_names``);
    ``forces`` (N, L, 3) ground on foot [N] (zero for swing feet); ``torque`` (N, nq)
    ``g(q) − Σ J_iᵀ f_i`` [N·m] (nq: ``joint_names``), ``peak`` its ``max_t`` per joint at
    ``peak_time`` [s]; ``force_residual`` [N], ``moment_residual`` [N·m]: the largest over the
    run (as :class:`~hexapod_kin.dynamics.standing.ContactSolution`); ``min_normal_force``
    (N,) smallest stance ``f_z`` [N]; ``mass`` [kg]; ``mu`` None for min-norm. Full inverse
    dynamics (empty without ``run.robot``): ``torque_full`` [N·m] and ``forces_full`` [N],
    ``peak_full`` at ``peak_full_time``, ``peak_difference`` ``max_t |torque_full − torque|``,
    ``base_residual`` [N, N·m] (see the module doc).
    """

    t: np.ndarray
    joint_names: tuple[str, ...]
    leg_names: tuple[str, ...]
    support: np.ndarray
    forces: np.ndarray
    torque: np.ndarray
    peak: np.ndarray
    peak_time: np.ndarray
    force_residual: float
    moment_residual: float
    min_normal_force: np.ndarray
    mass: float
    method: str
    mu: float | None
    torque_full: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    forces_full: np.ndarray = field(default_factory=lambda: np.zeros((0, 0, 3)))
    peak_full: np.ndarray = field(default_factory=lambda: np.zeros(0))
    peak_full_time: np.ndarray = field(default_factory=lambda: np.zeros(0))
    peak_difference: np.ndarray = field(default_factory=lambda: np.zeros(0))
    base_residual: float = math.nan

    @property
    def feasible(self) -> bool:
        """True when no stance foot ever pulls on the ground."""
        return bool(np.all(self.min_normal_force >= -1e-9 * self.mass * 9.81))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready peaks per joint (quasi-static, full, their difference), residuals."""
        out: dict[str, Any] = {}
        if self.peak_full.size:
            out["peak_torque_full"] = self.peak_full.tolist()
            out["peak_torque_full_time"] = self.peak_full_time.tolist()
            out["peak_torque_full_max"] = float(self.peak_full.max())
            out["peak_difference"] = self.peak_difference.tolist()
            out["peak_difference_max"] = float(self.peak_difference.max())
            out["base_residual"] = self.base_residual
        out |= {"samples": int(len(self.t)), "duration": float(self.t[-1] - self.t[0])}
        out |= fields_dict(self, "method", "mu", "mass", "joint_names")
        out |= {"peak_torque": self.peak.tolist(), "peak_time": self.peak_time.tolist()}
        out |= {"peak_torque_max": float(self.peak.max())}
        out |= fields_dict(self, "force_residual", "moment_residual")
        out["min_normal_force"] = float(self.min_normal_force.min())
        return out | {"feasible": self.feasible}


def gait_torques(
    run: Any, model: Any = None, *, method: ContactMethod = "min_norm", mu: float | None = None
) -> GaitTorques:
    """Contact forces and joint torques at every sample of a gait run (see the module doc).

    ``run``: a walk (``hexapod_kin.gait.walk(...)``) or anything with ``t`` (N,),
    ``base_poses`` (N, 4, 4), ``q`` (N, nq), ``joint_names`` and ``support`` (N, L) (with
    ``robot``, ``pinocchio_q/v/a()`` and ``feet``: full dynamics too). ``model``: the
    fixed-base whole robot the run walks (default: ``run.robot.kinematic``, else
    ``load("hexapod")``; a Hexapod's table model walks as its floating-base twin).

    Raises:
        ParameterError: The run's joints are not the model's; bad method or mu.
        ConfigurationError: A sample whose stance feet cannot hold the robot (names the time).

    """
    wb = getattr(run, "robot", None)
    if model is None:  # the robot that walked, as loaded
        model = getattr(wb, "kinematic", None) or "hexapod"
    mdl, ts = as_model(model), np.asarray(run.t, dtype=float)
    if wb is not None and (wb.kinematic is mdl or not isinstance(mdl.params, Hexapod)):
        if wb.kinematic is not mdl:
            msg = (
                f"model {mdl.name!r} is not the robot that walked ({wb.source!r}); leave "
                "model=None for a legged robot other than a Hexapod"
            )
            raise ParameterError(msg, parameter="model", value=mdl.name, allowed=wb.source)
        pm, feet, legs, names = wb.model, wb.foot_frames, wb.leg_names, tuple(wb.joint_names)
        qp = run.pinocchio_q()
    else:  # a Hexapod's table model: its floating-base twin, the run's joints by name
        params, names = _hexapod(mdl), tuple(mdl.joint_names)
        if sorted(run.joint_names) != sorted(names):
            raise ParameterError(
                f"the run's joints {list(run.joint_names)} are not the model's {list(names)}",
                parameter="run",
                value=list(run.joint_names),
                allowed=list(names),
            )
        pm, feet = mdl.floating_model, params.foot_frames
        legs = tuple(leg.name for leg in params.legs)
        cols = [tuple(run.joint_names).index(n) for n in names]
        poses = np.asarray(run.base_poses, dtype=float)
        qp = np.empty((len(ts), pm.nq))
        qp[:, :3] = poses[:, :3, 3]
        qp[:, 3:7] = [pin.Quaternion(p[:3, :3]).coeffs() for p in poses]
        qp[:, 7:] = np.asarray(run.q, dtype=float)[:, cols]
    check_inertials(mdl)
    support = np.asarray(run.support, dtype=bool)
    fids = [pm.getFrameId(f) for f in feet]
    forces, torque, fmin, f_res, m_res, mass = _quasi_static(
        pm, fids, qp, ts, support, legs, method, mu
    )
    peak, peak_time = _peaks(torque, ts)
    read_only(ts, support, forces, torque, peak, peak_time, fmin)
    extra: dict[str, Any] = {}
    if wb is not None and hasattr(run, "pinocchio_a"):
        tau_f, f_full, base_res = full_dynamics(run, method=method, mu=mu)
        tau_f = tau_f[:, [tuple(wb.joint_names).index(nm) for nm in names]]
        peak_f, peak_ft = _peaks(tau_f, ts)
        diff = np.abs(tau_f - torque).max(axis=0)
        extra = dict(torque_full=tau_f, forces_full=f_full, peak_full=peak_f)
        extra |= dict(peak_full_time=peak_ft, peak_difference=diff, base_residual=base_res)
        read_only(*(v for v in extra.values() if isinstance(v, np.ndarray)))
    return GaitTorques(ts, names, legs, support, forces, torque, peak, peak_time, f_res, m_res,
                       fmin, mass, str(method), mu, **extra)  # fmt: skip


def _peaks(torque: np.ndarray, ts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``max_t |torque|`` per joint (nq,) [N·m] and the time of each [s]."""
    idx = np.argmax(np.abs(torque), axis=0)
    return np.abs(torque[idx, np.arange(torque.shape[1])]), ts[idx]


def _at(exc: ConfigurationError, where: str) -> ConfigurationError:
    """``exc`` told where it happened: ``"{where}: {exc}"``, its fields kept."""
    return ConfigurationError(
        f"{where}: {exc}", parameter=exc.parameter, value=exc.value, allowed=exc.allowed
    )


def _quasi_static(
    pm: Any, fids: list[int], qp: np.ndarray, ts: np.ndarray, support: np.ndarray,
    legs: tuple[str, ...], method: ContactMethod, mu: float | None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float, float, float]:  # fmt: skip
    """The quasi-static loads of :func:`gait_torques` on the floating-base model ``pm``.

    Returns:
        ``(forces (N, L, 3) [N], torque (N, nq) [N·m], min_normal_force (N,) [N],
        force_residual [N], moment_residual [N·m], mass [kg])``.

    """
    data = pm.createData()
    g_world = np.array(pm.gravity.linear, dtype=float)
    mass = float(pin.computeTotalMass(pm))
    weight = mass * float(np.linalg.norm(g_world))
    n = len(ts)
    forces, torque = np.zeros((n, len(fids), 3)), np.empty((n, pm.nv - 6))
    fmin = np.empty(n)
    f_res = m_res = 0.0
    lwa = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    for i in range(n):
        q = qp[i]
        com = np.array(pin.centerOfMass(pm, data, q))
        pin.computeJointJacobians(pm, data, q)
        pin.updateFramePlacements(pm, data)
        stance = np.nonzero(support[i])[0]
        feet_w = np.array([data.oMf[fids[k]].translation for k in stance])
        try:
            sol = contact_forces(feet_w, com, weight, method=method, mu=mu)
        except ConfigurationError as exc:
            where = f"at t = {ts[i]:.6g} s (stance legs {[legs[k] for k in stance]})"
            raise _at(exc, where) from None
        f_res, m_res = max(f_res, sol.force_residual), max(m_res, sol.moment_residual)
        tau = np.array(pin.computeGeneralizedGravity(pm, data, q))[6:]
        for k, f in zip(stance, sol.forces):
            tau -= pin.getFrameJacobian(pm, data, fids[k], lwa)[:3, 6:].T @ f
            forces[i, k] = f
        torque[i] = tau
        fmin[i] = float(sol.forces[:, 2].min())
    return forces, torque, fmin, f_res, m_res, mass


def full_dynamics(
    run: Any, *, method: ContactMethod = "min_norm", mu: float | None = None
) -> tuple[np.ndarray, np.ndarray, float]:
    """Full inverse-dynamics joint torques along a run (see the module doc).

    Args:
        run: A :class:`~hexapod_kin.gait.GaitRun` with its ``robot``.
        method: ``"min_norm"`` or ``"friction"`` (Coulomb cones, ``mu``).
        mu: Friction coefficient.

    Returns:
        ``(tau, forces, base_residual)``: (N, nq) torques [N·m] in ``run.robot.joint_names``
        order, (N, L, 3) contact forces [N] (world axes), the largest base-row residual.

    Raises:
        ConfigurationError: No forces within the friction cones (names the time).

    """
    wb = run.robot
    model = wb.model
    data = model.createData()
    Q, V, A = run.pinocchio_q(), run.pinocchio_v(), run.pinocchio_a()
    support = np.asarray(run.support, dtype=bool)
    feet = np.asarray(run.feet, dtype=float)
    n, nl = support.shape
    rad = float(getattr(run, "settings", {}).get("foot_radius", 0.0))
    normals = getattr(run, "normals", None)
    nrm = np.broadcast_to([0.0, 0.0, 1.0], feet.shape)
    if normals is not None and np.size(normals):
        nrm = np.asarray(normals, dtype=float)
    fids = [model.getFrameId(f) for f in wb.foot_frames]
    weight, tau = float(run.mass) * 9.81, np.zeros((n, model.nv - 6))
    forces, worst = np.zeros((n, nl, 3)), 0.0
    lwa = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    for i in range(n):
        b = np.array(pin.rnea(model, data, Q[i], V[i], A[i]))
        stance = np.flatnonzero(support[i])
        pin.computeJointJacobians(model, data, Q[i])
        pin.updateFramePlacements(model, data)
        jac = np.empty((len(stance), 3, model.nv))
        for m, k in enumerate(stance):
            J = pin.getFrameJacobian(model, data, fids[k], lwa)
            arm = feet[i, k] - rad * nrm[i, k] - data.oMf[fids[k]].translation
            jac[m] = J[:3] - pin.skew(arm) @ J[3:]  # the contact point, fixed on the foot
        a_base = jac[:, :, :6].transpose(2, 0, 1).reshape(6, -1)  # (6, 3k): Σ J_baseᵀ f
        if len(stance):
            pinv = np.linalg.pinv(a_base, rcond=1e-12)
            f = pinv @ b[:6]
            if method == "friction":
                try:
                    f = _friction_qp(a_base, b[:6], f, pinv, float(mu or 0.0), weight)
                except ConfigurationError as exc:
                    raise _at(exc, f"at t = {float(run.t[i]):.6g} s (full dynamics)") from None
        else:
            f = np.zeros(0)
        fk = f.reshape(-1, 3)
        gen = np.einsum("kav,ka->v", jac, fk) if len(stance) else np.zeros(model.nv)
        worst = max(worst, float(np.abs(b[:6] - gen[:6]).max()))
        tau[i] = b[6:] - gen[6:]
        forces[i, stance] = fk
    read_only(tau, forces)
    return tau, forces, worst
