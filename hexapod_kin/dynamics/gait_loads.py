"""Contact forces and joint torques along a gait run (quasi-static), peak torque per joint.

Takes a walk's samples as data — ``t``, ``base_poses`` (``worldMbody``), ``q`` (leg joints,
named by ``joint_names``) and ``support`` (stance feet), as in ``hexapod_kin.gait.GaitRun`` —
and at every sample distributes the robot's weight over the stance feet exactly as
:func:`~hexapod_kin.dynamics.standing.contact_forces` does (minimum norm, or inside friction cones),
then ``τ = g(q) − Σ J_iᵀ f_i`` with gravity expressed in the body's axes (the body may yaw or
tilt). Quasi-static: the body's and the legs' accelerations are left out (a walk at constant
body velocity has none for the body; the legs' inertial torques are small at walking speeds —
see :func:`~hexapod_kin.dynamics.statics.torques_along` for a leg's).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from ..exceptions import ConfigurationError, ParameterError
from ._common import as_model, check_inertials, read_only
from .standing import ContactMethod, _hexapod, contact_forces, robot_mass_com

__all__ = ["GaitTorques", "gait_torques"]


@dataclass(frozen=True)
class GaitTorques:
    """Quasi-static loads along a gait run (SI units, world axes for forces; read-only).

    Attributes:
        t: (N,) times in [s].
        joint_names: The joints (columns of ``torque``).
        leg_names: The legs (second axis of ``forces``).
        support: (N, L) True for the stance feet.
        forces: (N, L, 3) ground-on-foot forces in [N] (zero for swing feet).
        torque: (N, nq) joint torques ``g(q) − Σ J_iᵀ f_i`` in [N·m].
        peak: (nq,) ``max_t |torque|`` per joint in [N·m].
        peak_time: (nq,) time of each peak in [s].
        force_residual: Largest ``‖Σ f − m g ẑ‖`` over the run in [N].
        moment_residual: Largest ``‖Σ (p − c) × f‖`` over the run in [N·m].
        min_normal_force: (N,) smallest stance ``f_z`` at each sample in [N].
        mass: Robot mass in [kg].
        method: Contact-force distribution.
        mu: Friction coefficient (None for min-norm).

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

    @property
    def feasible(self) -> bool:
        """True when no stance foot ever pulls on the ground."""
        return bool(np.all(self.min_normal_force >= -1e-9 * self.mass * 9.81))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready peaks per joint, residuals and feasibility."""
        return {
            "samples": int(len(self.t)),
            "duration": float(self.t[-1] - self.t[0]),
            "method": self.method,
            "mu": self.mu,
            "mass": self.mass,
            "joint_names": list(self.joint_names),
            "peak_torque": self.peak.tolist(),
            "peak_time": self.peak_time.tolist(),
            "peak_torque_max": float(self.peak.max()),
            "force_residual": self.force_residual,
            "moment_residual": self.moment_residual,
            "min_normal_force": float(self.min_normal_force.min()),
            "feasible": self.feasible,
        }


def gait_torques(
    run: Any,
    model: Any = None,
    *,
    method: ContactMethod = "min_norm",
    mu: float | None = None,
) -> GaitTorques:
    """Contact forces and joint torques at every sample of a gait run.

    Args:
        run: A walk (``hexapod_kin.gait.walk(...)``) or anything with ``t`` (N,),
            ``base_poses`` (N, 4, 4), ``q`` (N, nq), ``joint_names`` and ``support`` (N, L).
        model: The fixed-base whole robot the run walks (default ``load("hexapod")``).
        method: ``"min_norm"`` or ``"friction"``.
        mu: Friction coefficient.

    Raises:
        ParameterError: The run's joints are not the model's; bad method or mu.
        ConfigurationError: A sample whose stance feet cannot hold the robot (names the time).

    """
    mdl = as_model("hexapod" if model is None else model)
    params = _hexapod(mdl)
    check_inertials(mdl)
    names = tuple(run.joint_names)
    if sorted(names) != sorted(mdl.joint_names):
        raise ParameterError(
            f"the run's joints {list(names)} are not the model's {list(mdl.joint_names)}",
            parameter="run",
            value=list(names),
            allowed=list(mdl.joint_names),
        )
    cols = np.array([names.index(n) for n in mdl.joint_names])
    ts = np.asarray(run.t, dtype=float)
    qs = np.asarray(run.q, dtype=float)[:, cols]
    poses = np.asarray(run.base_poses, dtype=float)
    support = np.asarray(run.support, dtype=bool)
    n_legs = len(params.legs)
    pm = pin.Model(mdl.model)  # private copy: its gravity is set per sample (body axes)
    data = pm.createData()
    fids = [mdl.frame_id(f) for f in params.foot_frames]
    g_world = np.array(mdl.model.gravity.linear, dtype=float)
    mass = robot_mass_com(mdl, qs[0], data)[0]
    weight = mass * float(np.linalg.norm(g_world))
    n = len(ts)
    forces = np.zeros((n, n_legs, 3))
    torque = np.empty((n, mdl.nq))
    fmin = np.empty(n)
    f_res = m_res = 0.0
    for i in range(n):
        rot, pos = poses[i, :3, :3], poses[i, :3, 3]
        q = qs[i]
        pm.gravity = pin.Motion(rot.T @ g_world, np.zeros(3))
        com_b = robot_mass_com(mdl, q, data)[1]
        pin.computeJointJacobians(pm, data, q)
        pin.updateFramePlacements(pm, data)
        stance = np.nonzero(support[i])[0]
        feet_w = np.array([rot @ data.oMf[fids[k]].translation + pos for k in stance])
        try:
            sol = contact_forces(feet_w, rot @ com_b + pos, weight, method=method, mu=mu)
        except ConfigurationError as exc:
            raise ConfigurationError(
                f"at t = {ts[i]:.6g} s (stance legs {[params.legs[k].name for k in stance]}): "
                f"{exc}",
                parameter=exc.parameter,
                value=exc.value,
                allowed=exc.allowed,
            ) from None
        f_res, m_res = max(f_res, sol.force_residual), max(m_res, sol.moment_residual)
        tau = np.array(pin.computeGeneralizedGravity(pm, data, q))
        for k, f in zip(stance, sol.forces):
            jac = pin.getFrameJacobian(pm, data, fids[k], pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
            tau -= jac[:3].T @ (rot.T @ f)
            forces[i, k] = f
        torque[i] = tau
        fmin[i] = float(sol.forces[:, 2].min())
    idx = np.argmax(np.abs(torque), axis=0)
    peak = np.abs(torque[idx, np.arange(mdl.nq)])
    peak_time = ts[idx]
    read_only(ts, support, forces, torque, peak, peak_time, fmin)
    return GaitTorques(
        ts,
        tuple(mdl.joint_names),
        tuple(leg.name for leg in params.legs),
        support,
        forces,
        torque,
        peak,
        peak_time,
        f_res,
        m_res,
        fmin,
        mass,
        str(method),
        mu,
    )
