"""Forward dynamics of a loaded model: Pinocchio ABA, passive joint forces, fixed-step integration.

The equation of motion (q in [rad]/[m], gravity ``model.gravity``)::

    M(q) q̈ + C(q, q̇) q̇ + g(q) = τ(t) + τ_passive(q, q̇)
    τ_passive = − b ⊙ q̇ − F ⊙ tanh(q̇ / v_F) − K ⊙ (q − q_rest)

solved for ``q̈`` by ``pin.aba``. ``b`` is the URDF's viscous damping, ``F`` its Coulomb
friction smoothed by ``tanh(q̇/v_F)`` (Lipschitz for a fixed step; no stiction), ``K`` and
``q_rest`` an optional spring. Joint limits are not enforced.

Integrators (fixed step ``dt``): ``"rk4"`` (default; O(dt⁴)) and ``"symplectic_euler"``
(``q̇ₖ₊₁ = q̇ₖ + dt q̈ₖ``, ``qₖ₊₁ = qₖ + dt q̇ₖ₊₁``). Energies: kinetic ``½ q̇ᵀ M q̇``, potential
``−Σ mᵢ g·cᵢ`` (Pinocchio's) plus the springs' ``½ K (q − q_rest)²``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
import pinocchio as pin

from .._fields import fields_dict
from ..exceptions import ConfigurationError, ParameterError, one_of, positive
from ._common import as_model, check_inertials, check_state, finite_vector, read_only

__all__ = ["METHODS", "PassiveJoints", "Simulation", "passive_joints", "simulate"]

Method = Literal["rk4", "symplectic_euler"]
#: Integration methods, the default first.
METHODS: tuple[str, ...] = ("rk4", "symplectic_euler")
#: Largest number of steps of one run (a guard against a hang from a tiny ``dt``).
MAX_STEPS = 5_000_000


@dataclass(frozen=True)
class PassiveJoints:
    """The passive joint forces: damping, smoothed Coulomb friction, springs (per joint).

    Per joint (prismatic: [N·s/m], [N], [N/m]): ``damping`` ``b`` [N·m·s/rad], ``friction``
    ``F`` [N·m], ``stiffness`` ``K`` [N·m/rad], ``q_rest`` [rad]/[m]; ``friction_velocity``
    ``v_F`` [rad/s], the smoothing of ``F tanh(q̇/v_F)``.
    """

    damping: np.ndarray
    friction: np.ndarray
    friction_velocity: float
    stiffness: np.ndarray
    q_rest: np.ndarray

    def torque(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """``τ_passive(q, q̇)`` in [N·m]/[N] (see the module doc)."""
        tau = -self.damping * v - self.stiffness * (q - self.q_rest)
        if np.any(self.friction):
            tau = tau - self.friction * np.tanh(v / self.friction_velocity)
        return tau

    def spring_energy(self, q: np.ndarray) -> np.ndarray:
        """Spring potential energy ``½ Σ K (q − q_rest)²`` in [J] for (N, nq) or (nq,) ``q``."""
        dq = np.asarray(q) - self.q_rest
        return np.asarray(0.5 * np.sum(self.stiffness * dq * dq, axis=-1))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (lists of floats, SI units)."""
        return fields_dict(self, "damping", "friction", "friction_velocity", "stiffness", "q_rest")


def passive_joints(
    model: Any,
    *,
    damping: Any = None,
    friction: Any = None,
    friction_velocity: float = 1e-3,
    stiffness: Any = 0.0,
    q_rest: Any = None,
) -> PassiveJoints:
    """The passive joint forces of ``model``: the URDF's damping and friction unless overridden.

    Each value a scalar or (nq,), in the units of :class:`PassiveJoints`;
    ``friction_velocity`` > 0; ``q_rest`` defaults to zeros.

    Raises:
        ParameterError: A negative, non-finite or wrongly shaped value (named).

    """
    n, m = model.nq, model.model
    b = finite_vector("damping", m.damping if damping is None else damping, n, nonnegative=True)
    f = finite_vector("friction", m.friction if friction is None else friction, n, nonnegative=True)
    k = finite_vector("stiffness", stiffness, n, nonnegative=True)
    rest = finite_vector("q_rest", np.zeros(n) if q_rest is None else q_rest, n)
    vf = positive("friction_velocity", friction_velocity)
    read_only(b, f, k, rest)
    return PassiveJoints(b, f, vf, k, rest)


@dataclass(frozen=True)
class Simulation:
    """A forward-dynamics run, sampled every ``dt`` [s] (arrays read-only, SI units).

    Per sample: ``t`` [s]; ``q``, ``v`` (q̇), ``a`` (q̈ by ABA) (N, nq) in [rad]/[m] and their
    rates; ``kinetic``, ``potential`` (gravity plus springs), ``total`` energies (N,) in [J].
    ``passive``: the damping, friction and springs used; ``joint_names``: the columns of q.
    """

    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    a: np.ndarray
    kinetic: np.ndarray
    potential: np.ndarray
    total: np.ndarray
    method: str
    dt: float
    passive: PassiveJoints
    joint_names: tuple[str, ...]

    @property
    def energy_change(self) -> float:
        """Largest ``|E(t) − E(0)|`` in [J]."""
        return float(np.max(np.abs(self.total - self.total[0])))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: every array as (nested) lists of floats, units as in the fields."""
        out = fields_dict(self, "method", "dt", "joint_names")
        out["passive"] = self.passive.to_dict()
        return out | fields_dict(self, "t", "q", "v", "a", "kinetic", "potential", "total")


def _steps(dt: Any, duration: Any) -> tuple[int, float]:
    h, span = positive("dt", dt), positive("duration", duration)
    n = int(round(span / h))
    if n < 1:
        msg = f"duration={duration!r} is shorter than one step dt={dt!r}"
        raise ParameterError(msg, parameter="duration", value=duration, allowed=f">= dt = {h} s")
    if n > MAX_STEPS:
        msg = (
            f"duration/dt = {span}/{h} = {n} steps exceeds the cap of {MAX_STEPS}; use a larger "
            "dt or a shorter duration"
        )
        raise ParameterError(msg, parameter="dt", value=dt, allowed=f">= duration / {MAX_STEPS}")
    return n, h


def simulate(
    model: Any,
    q0: Any,
    v0: Any = None,
    *,
    dt: float = 1e-3,
    duration: float = 1.0,
    method: Method = "rk4",
    damping: Any = None,
    friction: Any = None,
    friction_velocity: float = 1e-3,
    stiffness: Any = 0.0,
    q_rest: Any = None,
    tau: Any = None,
) -> Simulation:
    """Integrate the forward dynamics of ``model`` from ``(q0, v0)``.

    ``q0``, ``v0`` (nq,) in [rad]/[m] and [rad/s]/[m/s] (``v0`` default zeros); ``dt`` and
    ``duration`` in [s] (rounded to whole steps); ``method`` as in the module doc; the passive
    overrides as in :func:`passive_joints`; ``tau``: None (zero), a constant (nq,) or a
    function ``tau(t, q, v) -> (nq,)`` in [N·m]/[N].

    Raises:
        ParameterError: Bad ``dt``, ``duration``, ``method``, passive parameters or inertials.
        ConfigurationError: Bad ``q0``/``v0``/``tau``, or the run diverged (reduce ``dt``).

    """
    mdl = as_model(model)
    check_inertials(mdl)
    one_of("method", method, METHODS)
    n, h = _steps(dt, duration)
    passive = passive_joints(mdl, damping=damping, friction=friction, stiffness=stiffness,
                             friction_velocity=friction_velocity, q_rest=q_rest)  # fmt: skip
    nq, q = mdl.nq, check_state(mdl, q0, "q0")
    v = np.zeros(nq) if v0 is None else check_state(mdl, v0, "v0")
    applied, pm = _applied(tau, nq), mdl.model
    data = pm.createData()
    aba, arr = pin.aba, np.array
    acc: Callable[[float, Any, Any], Any]
    state: tuple[Any, Any] = (q, v)
    ts = np.arange(n + 1) * h
    if tau is None and not (np.any(passive.friction) or np.any(passive.stiffness)):
        nb = -passive.damping  # the common case: damping only
        if pm.nq == nq == 1:  # one joint (the seed's pendulum): the state as Python floats
            nb0 = float(nb[0])

            def acc(tk: float, qk: Any, vk: Any) -> Any:
                return float(aba(pm, data, arr([qk]), arr([vk]), arr([nb0 * vk]))[0])

            state = (float(q[0]), float(v[0]))
        else:

            def acc(tk: float, qk: Any, vk: Any) -> Any:
                return aba(pm, data, qk, vk, nb * vk).copy()  # aba returns data.ddq: copy it

    else:
        ptorque = passive.torque

        def acc(tk: float, qk: Any, vk: Any) -> Any:
            return aba(pm, data, qk, vk, applied(tk, qk, vk) + ptorque(qk, vk)).copy()

    qs, vs, accs = (x.reshape(n + 1, nq) for x in _run(acc, *state, ts, h, method))
    kin = np.array([pin.computeKineticEnergy(pm, data, qs[i], vs[i]) for i in range(n + 1)])
    pot = np.array([pin.computePotentialEnergy(pm, data, qs[i]) for i in range(n + 1)])
    pot = pot + passive.spring_energy(qs)
    total = kin + pot
    read_only(ts, qs, vs, accs, kin, pot, total)
    names = tuple(mdl.joint_names)
    return Simulation(ts, qs, vs, accs, kin, pot, total, str(method), h, passive, names)


def _run(
    acc: Callable[[float, Any, Any], Any], q: Any, v: Any, ts: np.ndarray, h: float, method: str
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """RK4 or symplectic Euler from (q, v) ((nq,) arrays, or floats for one joint)."""
    a = acc(0.0, q, v)
    qs, vs, accs = [q], [v], [a]
    half, sixth = 0.5 * h, h / 6.0
    n = len(ts) - 1
    for k in range(n):
        tk = float(ts[k])
        if method == "rk4":
            v2 = v + half * a
            a2 = acc(tk + half, q + half * v, v2)
            v3 = v + half * a2
            a3 = acc(tk + half, q + half * v2, v3)
            v4 = v + h * a3
            a4 = acc(tk + h, q + h * v3, v4)
            q = q + sixth * (v + 2.0 * v2 + 2.0 * v3 + v4)
            v = v + sixth * (a + 2.0 * a2 + 2.0 * a3 + a4)
        else:
            v = v + h * a
            q = q + h * v
        a = acc(tk + h, q, v)
        # a diverged state stays non-finite: check now and then
        if (k % 64 == 63 or k == n - 1) and not math.isfinite(
            float(np.sum(q) + np.sum(v) + np.sum(a))
        ):
            msg = (
                f"the simulation diverged by t = {tk + h:.6g} s (non-finite state); reduce "
                f"dt={h!r} or check the model and torques"
            )
            raise ConfigurationError(msg, parameter="dt", value=h, allowed="a smaller step")
        qs.append(q)
        vs.append(v)
        accs.append(a)
    return np.array(qs), np.array(vs), np.array(accs)


def _applied(tau: Any, nq: int) -> Callable[[float, np.ndarray, np.ndarray], np.ndarray]:
    """``tau`` as a function ``(t, q, v) -> (nq,)`` (checked on use)."""
    if tau is None:
        zero = np.zeros(nq)
        return lambda t, q, v: zero
    if callable(tau):

        def call(t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
            out = np.asarray(tau(t, q, v), dtype=float)
            if out.shape != (nq,) or not np.all(np.isfinite(out)):
                raise ConfigurationError(
                    f"tau(t={t:.6g}) returned shape {out.shape} or non-finite values; "
                    f"({nq},) finite torques are needed",
                    parameter="tau",
                    value=out.tolist(),
                    allowed=f"({nq},) finite",
                )
            return out

        return call
    const = finite_vector("tau", tau, nq)
    return lambda t, q, v: const
