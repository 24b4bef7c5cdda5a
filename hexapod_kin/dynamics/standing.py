"""The standing hexapod: a standing pose, the contact forces that hold its weight, joint torques.

The body is level at height ``h`` above flat ground (world z up; the feet at z = 0); mass and
centre of mass include the body fixed to the universe (``model.inertias[0]``, which
Pinocchio's ``computeTotalMass``/``centerOfMass`` leave out). Contact forces ``f_i`` (ground
on foot i, world axes, point contacts) balance gravity::

    Σ f_i = m g ẑ,    Σ (p_i − c) × f_i = 0

``method="min_norm"``: ``f = A⁺ b`` (least Σ‖f_i‖²; it may pull or slide, ``feasible`` says);
``"friction"``: the least Σ‖f_i‖² with ``f_z ≥ 0`` and ``‖f_t‖ ≤ μ f_z`` (SLSQP from the
minimum-norm point, projected back onto the equations). Static joint torques
``τ = g(q) − Σ_i J_iᵀ f_i`` (``J_i`` the LOCAL_WORLD_ALIGNED linear Jacobian of contact i).
Other legged robots stand by :func:`hexapod_kin.gait.stand.standing_pose`, the forces at the
foot spheres' lowest points (``J_i = J_v − [c_i − p_i]× J_ω``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
import pinocchio as pin

from .._fields import fields_dict
from ..exceptions import ConfigurationError, LimitError, ParameterError, choices, one_of, positive
from ..params import Hexapod
from ._common import as_model, check_inertials, finite_vector, read_only

__all__ = [
    "CONTACT_METHODS",
    "ContactSolution",
    "Stance",
    "contact_forces",
    "hexapod_model",
    "robot_mass_com",
    "stand",
    "standing_configuration",
]

ContactMethod = Literal["min_norm", "friction"]
CONTACT_METHODS: tuple[str, ...] = ("min_norm", "friction")


def _hexapod(model: Any) -> Hexapod:
    params = getattr(model, "params", None)
    if not isinstance(params, Hexapod):
        raise ParameterError(
            f"model {getattr(model, 'name', model)!r} is not a legged robot built from a "
            "Hexapod (e.g. the 'hexapod' preset); standing needs its legs and feet",
            parameter="model",
            value=getattr(model, "name", model),
            allowed="a Hexapod preset",
        )
    if model.nq != len(params.joint_names):
        msg = (
            f"model {model.name!r} is a sub-chain ({model.nq} joints); load the whole robot "
            "(no base=/tip=)"
        )
        raise ParameterError(msg, parameter="model", value=model.name, allowed="the whole robot")
    return params


def robot_mass_com(model: Any, q: Any, data: Any = None) -> tuple[float, np.ndarray]:
    """Total mass [kg] and centre of mass [m] (world frame) of the whole robot at ``q``.

    Bodies fixed to the world included; ``data``: a ``Data`` of ``model.model`` to reuse.
    """
    pm = model.model
    data = pm.createData() if data is None else data
    qv = np.array(model.check_q(q), dtype=float)
    m_joints = float(pin.computeTotalMass(pm))
    c_joints = np.array(pin.centerOfMass(pm, data, qv)) if m_joints > 0 else np.zeros(3)
    root = pm.inertias[0]
    m0 = float(root.mass)
    mass = m0 + m_joints
    com = (m0 * np.asarray(root.lever) + m_joints * c_joints) / mass
    return mass, com


def _knee_up(solutions: np.ndarray) -> np.ndarray:
    """The closed-form solution with the hip nearest 0, then the highest knee (min sin q2)."""
    hip = np.abs(np.remainder(solutions[:, 0] + np.pi, 2 * np.pi) - np.pi)
    best = solutions[hip <= hip.min() + 1e-9]
    return np.array(best[int(np.argmin(np.sin(best[:, 1])))])


def standing_configuration(
    model: Any, height: float = 0.10, reach: float | None = None, shift: Any = (0.0, 0.0)
) -> np.ndarray:
    """Joint values standing the robot's body level at ``height`` above the ground.

    Foot i is ``reach`` from its hip axis along the leg's mount direction, ``height`` below the
    body origin, moved by ``−shift``; each leg by the closed-form IK, hip nearest 0, knee up.

    ``model``: the whole robot (from a Hexapod, e.g. ``load("hexapod")``); ``height`` > 0,
    ``reach`` (default ``l1 + l2`` of the leg) and ``shift`` (dx, dy) in [m].

    Raises:
        ParameterError: Not a Hexapod, bad numbers; ``height``, ``reach`` or a ``shift``
            component over twice the robot's size (:func:`hexapod_kin._tree.robot_size`).
        LimitError: A foot cannot reach its ground point (names the leg).

    """
    from .. import ik
    from ..gait.legs import check_size

    params, h = _hexapod(model), positive("height", height)
    sh = finite_vector("shift", shift, 2)
    big = [("height", h), ("shift", float(np.abs(sh).max()))]
    if reach is not None:
        big.append(("reach", positive("reach", reach)))
    for name, v in big:  # a foot point many robot sizes away: refused before any IK
        check_size(v, model.model, name)
    q = np.zeros(model.nq)
    for leg in params.legs:
        chain = leg.chain
        r = _default_reach(chain) if reach is None else positive("reach", reach)
        c, s = math.cos(leg.yaw), math.sin(leg.yaw)
        mount = np.asarray(leg.xyz, dtype=float)
        foot_body = mount + np.array([r * c - sh[0], r * s - sh[1], -h - mount[2]])
        d = foot_body - mount
        target = np.array([c * d[0] + s * d[1], -s * d[0] + c * d[1], d[2]])
        sols = np.asarray(ik.analytic(chain, target[None, :])[0])  # (k, n): one target
        if len(sols) == 0:
            raise LimitError(
                f"leg {leg.name!r} cannot reach its foot point {target.round(6).tolist()} m "
                f"(mount frame) for height={h}, reach={r}, shift={sh.tolist()}",
                parameter="height",
                value=h,
                allowed="a reachable height and reach",
            )
        sol = _knee_up(np.asarray(sols))
        for name, value in zip(chain.joint_names or (), sol):
            q[model.joint_index(f"{leg.name}_{name}")] = value
    return q


def _default_reach(chain: Any) -> float:
    """``l1 + l2`` of a hexabot_leg-like chain (the d of its 2nd and 3rd rows), else 0.15 m."""
    try:
        return float(chain.rows[1].d + chain.rows[2].d)
    except (AttributeError, IndexError):
        return 0.15


@dataclass(frozen=True)
class ContactSolution:
    """Contact forces (k, 3) ground on foot [N] (read-only) and their balance residuals.

    ``force_residual`` ``‖Σ f − W ẑ‖`` [N]; ``moment_residual`` ``‖Σ (p − c) × f‖`` [N·m].
    """

    forces: np.ndarray
    force_residual: float
    moment_residual: float

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready."""
        return fields_dict(self, "forces", "force_residual", "moment_residual")


def contact_forces(
    feet: Any,
    com: Any,
    weight: float,
    *,
    method: ContactMethod = "min_norm",
    mu: float | None = None,
) -> ContactSolution:
    """Point-contact forces that hold a weight ``weight`` [N] at ``com`` on ``feet`` (k, 3).

    Positions in [m], world axes; ``weight`` ``m g`` > 0 acts along −z; ``method`` as in the
    module doc; ``mu`` > 0, needed by ``"friction"``.

    Raises:
        ParameterError: Bad method or ``mu``.
        ConfigurationError: The feet cannot balance the weight (collinear/too few feet).
        LimitError: No friction-cone solution (CoM outside the support polygon, small ``mu``).

    """
    one_of("method", method, CONTACT_METHODS)
    p, c = np.asarray(feet, dtype=float), np.asarray(com, dtype=float)
    w, k = positive("weight", weight), len(p)
    r, a = p - c, np.zeros((6, 3 * k))
    for i in range(k):
        a[0:3, 3 * i : 3 * i + 3] = np.eye(3)
        a[3:6, 3 * i : 3 * i + 3] = pin.skew(r[i])
    b = np.array([0.0, 0.0, w, 0.0, 0.0, 0.0])
    pinv = np.linalg.pinv(a, rcond=1e-12)
    f = pinv @ b

    def residuals(vec: np.ndarray) -> tuple[float, float]:
        res = a @ vec - b
        return float(np.linalg.norm(res[:3])), float(np.linalg.norm(res[3:]))

    if max(residuals(f)) > 1e-9 * max(w, 1.0):
        raise ConfigurationError(
            f"{k} feet at {p.round(6).tolist()} cannot balance the weight (too few or "
            "collinear contacts)",
            parameter="feet",
            value=k,
            allowed="at least 3 non-collinear feet",
        )
    if method == "friction":
        if mu is None:
            msg = "method='friction' needs a friction coefficient mu > 0"
            raise ParameterError(msg, parameter="mu", value=mu, allowed="> 0")
        f = _friction_qp(a, b, f, pinv, positive("mu", mu), w)
    fr, mr = residuals(f)
    forces = f.reshape(k, 3)
    read_only(forces)
    return ContactSolution(forces, fr, mr)


def _friction_qp(
    a: np.ndarray, b: np.ndarray, f0: np.ndarray, pinv: np.ndarray, mu: float, w: float
) -> np.ndarray:
    """Least ‖f‖² with ``A f = b``, ``f_z ≥ 0`` and ``‖f_t‖ ≤ μ f_z`` (SLSQP, then projected)."""
    k, tol = len(f0) // 3, 1e-9 * w

    def cone(f: np.ndarray) -> np.ndarray:
        ff = f.reshape(k, 3)
        return np.concatenate([ff[:, 2], (mu * ff[:, 2]) ** 2 - ff[:, 0] ** 2 - ff[:, 1] ** 2])

    def ok(f: np.ndarray) -> bool:
        ff = f.reshape(k, 3)
        return bool(
            np.all(ff[:, 2] >= -tol) and np.all(np.hypot(ff[:, 0], ff[:, 1]) <= mu * ff[:, 2] + tol)
        )

    if ok(f0):
        return f0
    from scipy.optimize import minimize

    res = minimize(
        lambda f: 0.5 * float(f @ f),
        f0,
        jac=lambda f: f,
        method="SLSQP",
        constraints=[
            {"type": "eq", "fun": lambda f: a @ f - b, "jac": lambda f: a},
            {"type": "ineq", "fun": cone},
        ],
        options={"ftol": 1e-15, "maxiter": 500},
    )
    f = res.x - pinv @ (a @ res.x - b)
    if not ok(f):
        raise LimitError(
            f"no contact forces within the friction cone mu={mu} hold the robot (its centre "
            "of mass is outside the support polygon, or mu is too small)",
            parameter="mu",
            value=mu,
            allowed="a larger mu or a stance around the CoM",
        )
    return f


@dataclass(frozen=True)
class Stance:
    """The standing robot (SI units, world: ground z = 0, z up; arrays read-only).

    ``height`` of the body origin [m]; ``q`` [rad] (columns ``joint_names``, as the torques);
    ``feet`` (k, 3) of the ``stance_legs`` [m]; ``mass`` [kg] (body included), ``com`` [m],
    ``weight`` ``m g`` [N]; ``forces`` (k, 3) ground on foot [N], by ``method`` with ``mu``
    (None for min-norm) and residuals as in :class:`ContactSolution`; ``gravity_torque``
    ``g(q)`` (legs in the air) and ``torque`` ``g(q) − Σ J_iᵀ f_i`` (standing) in [N·m].
    """

    height: float
    q: np.ndarray
    joint_names: tuple[str, ...]
    stance_legs: tuple[str, ...]
    feet: np.ndarray
    mass: float
    com: np.ndarray
    weight: float
    forces: np.ndarray
    method: str
    mu: float | None
    force_residual: float
    moment_residual: float
    gravity_torque: np.ndarray
    torque: np.ndarray

    @property
    def friction_ratio(self) -> float:
        """Largest ``‖f_t‖ / f_z`` over the stance feet (the least μ that holds; inf if f_z ≤ 0)."""
        ft = np.hypot(self.forces[:, 0], self.forces[:, 1])
        fz = self.forces[:, 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.where(fz > 0, ft / np.where(fz > 0, fz, 1.0), np.inf)
        return float(np.max(ratio))

    @property
    def feasible(self) -> bool:
        """No foot pulls (f_z ≥ 0) and, with ``mu``, every force is inside its cone."""
        tol = 1e-9 * self.weight
        if np.any(self.forces[:, 2] < -tol):
            return False
        return self.mu is None or self.friction_ratio <= self.mu * (1 + 1e-9)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (lists of floats, SI units)."""
        out = fields_dict(self, *"height method mu mass weight com joint_names q".split())
        out |= fields_dict(self, "stance_legs", "feet", "forces")
        out["force_sum"] = self.forces.sum(axis=0).tolist()
        out |= fields_dict(self, "force_residual", "moment_residual", "friction_ratio", "feasible")
        out |= fields_dict(self, "gravity_torque", "torque")
        return out | {"peak_torque": float(np.max(np.abs(self.torque)))}


def _stance_of(names: list[str], legs: Any) -> tuple[int, ...]:
    if legs is None:
        return tuple(range(len(names)))
    out = []
    for item in legs:
        if isinstance(item, str) and item in names:
            out.append(names.index(item))
        elif (
            isinstance(item, (int, np.integer))
            and not isinstance(item, bool)
            and (1 <= int(item) <= len(names))
        ):
            out.append(int(item) - 1)
        else:
            msg = (
                f"stance leg {item!r} does not exist; use leg names {choices(names)} or "
                f"numbers 1..{len(names)}"
            )
            raise ParameterError(msg, parameter="legs", value=item, allowed=names)
    return tuple(sorted(set(out)))


def stance_at(
    model: Any,
    q: Any,
    height: float,
    *,
    legs: Any = None,
    method: ContactMethod = "min_norm",
    mu: float | None = None,
) -> Stance:
    """Contact forces and joint torques of the robot standing at ``q`` with its body ``height``.

    The stance feet should be at ``−height`` [m] in the body frame; ``legs``: names or 1-based
    numbers (default all); ``mu``: the friction cone of ``"friction"`` (with ``"min_norm"``:
    what ``feasible`` checks).

    Raises:
        ParameterError, ConfigurationError: As :func:`contact_forces`; bad legs or q.

    """
    mdl = as_model(model)
    params = _hexapod(mdl)
    check_inertials(mdl)
    h = positive("height", height)
    qv = np.array(mdl.check_q(q), dtype=float)
    idx = _stance_of([leg.name for leg in params.legs], legs)
    pm = mdl.model
    data = pm.createData()
    mass, com = robot_mass_com(mdl, qv)
    lift = np.array([0.0, 0.0, h])
    pin.computeJointJacobians(pm, data, qv)
    pin.updateFramePlacements(pm, data)
    fids = [mdl.frame_id(params.foot_frames[i]) for i in idx]
    feet = np.array([data.oMf[f].translation for f in fids]) + lift
    names = (tuple(mdl.joint_names), tuple(params.legs[i].name for i in idx))
    return _stance(pm, data, qv, fids, feet, None, mass, com + lift, method, mu, h, qv, names, 0)


def _stance(
    pm: pin.Model, data: pin.Data, qp: np.ndarray, fids: list[int], contacts: np.ndarray,
    offsets: np.ndarray | None, mass: float, com: np.ndarray, method: ContactMethod,
    mu: float | None, height: float, q: np.ndarray, names: tuple[Any, Any], base: int,
) -> Stance:  # fmt: skip
    """The :class:`Stance` of forces at ``contacts`` holding ``mass`` at ``com``.

    ``data`` holds the Jacobians and placements at ``qp``; torques from joint ``base`` on, at the
    points ``offsets[i]`` (world axes) from frames ``fids[i]`` (None: the frames' origins).
    """
    weight = mass * float(np.linalg.norm(pm.gravity.linear))
    mu_v = None if mu is None else positive("mu", mu)
    sol = contact_forces(contacts, com, weight, method=method, mu=mu_v)
    grav = np.array(pin.computeGeneralizedGravity(pm, data, qp))
    tau = grav.copy()
    for k, (fid, f) in enumerate(zip(fids, sol.forces)):
        jac = pin.getFrameJacobian(pm, data, fid, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        lin = jac[:3] if offsets is None else jac[:3] - pin.skew(offsets[k]) @ jac[3:]
        tau -= lin.T @ f
    g_j, t_j = grav[base:].copy(), tau[base:].copy()
    read_only(q, contacts, com, g_j, t_j)
    return Stance(
        height, q, names[0], names[1], contacts, mass, com, weight, sol.forces, str(method),
        mu_v, sol.force_residual, sol.moment_residual, g_j, t_j,
    )  # fmt: skip


def stand(
    model: Any = None,
    *,
    height: float | None = None,
    reach: float | None = None,
    shift: Any = (0.0, 0.0),
    legs: Any = None,
    method: ContactMethod = "min_norm",
    mu: float | None = None,
    feet: Any = None,
    foot_radius: float | None = None,
    knee: str | None = None,
) -> Stance:
    """A legged robot standing level at ``height``: pose, contact forces and joint torques.

    ``model``: a Hexapod's model or preset (default ``load("hexapod")``), or any legged robot
    :func:`hexapod_kin.gait.as_whole_body` takes. Lengths in [m]: ``height`` (default: a
    Hexapod 0.10; another robot its ``body_height``), ``reach`` (hip axis to foot, default
    the robot's), ``shift`` (dx, dy), ``foot_radius`` (default the robot's). ``legs``: names
    or 1-based numbers (default all); ``feet``: frame plus offset for a URDF without foot links
    (:func:`hexapod_kin.gait.legs.parse_feet`); ``knee``: :data:`hexapod_kin.gait.knee.KNEES`
    (default: inside the limits nearest the neutral q).

    Raises:
        ParameterError, ConfigurationError: Bad values; unreachable pose; no balance.

    """
    if feet is None and foot_radius is None and knee is None:
        mdl = hexapod_model(model)
        if mdl is not None:
            h = 0.10 if height is None else height
            q = standing_configuration(mdl, h, reach, shift)
            return stance_at(mdl, q, h, legs=legs, method=method, mu=mu)
    from ..gait.stand import standing_pose

    pose = standing_pose(
        model,
        height=height,
        reach=reach,
        shift=shift,
        feet=feet,
        foot_radius=foot_radius,
        knee=knee,
    )
    return _legged_stance(pose, legs, method, mu)


def hexapod_model(model: Any) -> Any:
    """The loaded model when ``model`` is a Hexapod (preset, params or model), else None."""
    if model is None:
        return as_model("hexapod")
    if isinstance(model, Hexapod):
        return as_model(model)
    if hasattr(model, "model") and hasattr(model, "nq") and hasattr(model, "data"):
        return model if isinstance(getattr(model, "params", None), Hexapod) else None
    if isinstance(model, str) and not model.strip().startswith("<"):
        from .. import robots

        if model.strip() in robots.PRESETS:
            mdl = as_model(model)
            return mdl if isinstance(mdl.params, Hexapod) else None
    return None


def _legged_stance(pose: Any, legs: Any, method: ContactMethod, mu: float | None) -> Stance:
    """Contact forces and torques of a :class:`~hexapod_kin.gait.stand.StandingPose`."""
    wb = pose.robot
    idx = _stance_of(list(wb.leg_names), legs)
    pm = wb.model
    data = pm.createData()
    qp = wb.pinocchio_q(pose.q[None], pose.base[None])[0]
    wb.require_mass()
    mass = float(pin.computeTotalMass(pm))
    com = np.array(pin.centerOfMass(pm, data, qp))
    contacts = np.array(pose.contacts)[list(idx)]
    pin.computeJointJacobians(pm, data, qp)
    pin.updateFramePlacements(pm, data)
    fids = [pm.getFrameId(wb.foot_frames[k]) for k in idx]
    offsets = contacts - np.array([data.oMf[f].translation for f in fids]).reshape(-1, 3)
    names = (tuple(wb.joint_names), tuple(wb.leg_names[i] for i in idx))
    qv = np.array(pose.q)
    return _stance(
        pm, data, qp, fids, contacts, offsets, mass, com, method, mu, pose.height, qv, names, 6
    )
