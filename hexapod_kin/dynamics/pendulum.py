"""The seed pendulum (seed 001 §1), simulated with ABA and measured against exact physics.

``θ = q − q_hang``, measured from the hanging equilibrium (found from the potential energy);
the seed's 30° is ``θ0``, released from rest. For a rigid body about a horizontal axis (``I``
about the axis, ``l_c`` axis to centre of mass, ``b`` viscous damping)::

    I θ̈ + b θ̇ + m g l_c sin θ = 0
    undamped period   T = 4 sqrt(I / (m g l_c)) K(k),  k = sin(θ0/2)
    small amplitude   θ ≈ A e^{−γt} cos(ω_d t + φ),     γ = b / (2 I)

``K`` is ``scipy.special.ellipk(k**2)``. Turning points are zero crossings of ``θ̇`` (cubic
Hermite interpolant, slope ``θ̈``); the period is the mean spacing of same-direction crossings;
the decay rate is minus the least-squares slope of ``ln θ_peak`` against time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from .._fields import fields_dict
from ..exceptions import ParameterError, positive
from ._common import as_model, check_inertials, read_only
from .forward import Method, Simulation, simulate

__all__ = ["PendulumExperiment", "PendulumRun", "PhysicalPendulum", "decay_rate",
           "exact_period", "hermite_crossings", "pendulum_experiment", "pendulum_run",
           "physical_pendulum"]  # fmt: skip


@dataclass(frozen=True)
class PhysicalPendulum:
    """A 1-joint model seen as a physical pendulum (SI units).

    ``inertia`` ``I`` about the axis [kg·m²] (``pin.crba``), ``mass`` [kg], ``com_distance``
    ``l_c`` axis to centre of mass [m], ``gravity`` ``g`` [m/s²], ``q_hanging`` the stable
    equilibrium [rad], ``potential_min`` Pinocchio's potential energy there [J].
    """

    inertia: float
    mass: float
    com_distance: float
    gravity: float
    q_hanging: float
    potential_min: float

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready."""
        return fields_dict(self, "inertia", "mass", "com_distance", "gravity", "q_hanging")


def physical_pendulum(model: Any) -> PhysicalPendulum:
    """``I``, ``m``, ``l_c`` and the hanging equilibrium of a one-revolute-joint model.

    ``V(q) = c + A cos q + B sin q`` at q = 0, π/2, π gives ``A``, ``B``: the minimum is at
    ``atan2(−B, −A)`` and ``m g l_c = sqrt(A² + B²)``.

    Raises:
        ParameterError: Not one revolute joint, implausible inertials, or no restoring torque.

    """
    mdl = as_model(model)
    if mdl.nq != 1 or bool(mdl.is_prismatic[0]):
        msg = (
            f"model {mdl.name!r} has joints {list(mdl.joint_names)}; a pendulum needs exactly "
            "one revolute joint"
        )
        raise ParameterError(msg, parameter="model", value=mdl.name, allowed="one revolute joint")
    check_inertials(mdl)
    pm = mdl.model
    data = pm.createData()
    v = [
        float(pin.computePotentialEnergy(pm, data, np.array([x])))
        for x in (0, math.pi / 2, math.pi)
    ]
    a, b = 0.5 * (v[0] - v[2]), v[1] - 0.5 * (v[0] + v[2])
    mass = float(pin.computeTotalMass(pm))
    g = float(np.linalg.norm(pm.gravity.linear))
    mgl = math.hypot(a, b)
    if g <= 0 or mgl <= 1e-12 * mass * max(g, 1.0):
        raise ParameterError(
            f"model {mdl.name!r}: gravity exerts no torque about its joint (axis along gravity "
            "or centre of mass on the axis); not a pendulum",
            parameter="model",
            value=mdl.name,
            allowed="a horizontal axis, offset mass",
        )
    q_hang = math.atan2(-b, -a)
    inertia = float(pin.crba(pm, data, np.array([q_hang]))[0, 0])
    vmin = float(pin.computePotentialEnergy(pm, data, np.array([q_hang])))
    return PhysicalPendulum(inertia, mass, mgl / (mass * g), g, q_hang, vmin)


def exact_period(pendulum: PhysicalPendulum, theta0: float) -> float:
    """``T = 4 sqrt(I/(m g l_c)) K(sin(θ0/2))`` in [s], the exact undamped period."""
    from scipy.special import ellipk  # scipy on use: the other dynamics commands skip it

    p, k = pendulum, math.sin(0.5 * theta0)
    return float(4.0 * math.sqrt(p.inertia / (p.mass * p.gravity * p.com_distance)) * ellipk(k * k))


def hermite_crossings(
    t: np.ndarray, y: np.ndarray, dy: np.ndarray, direction: int = 0
) -> np.ndarray:
    """Increasing times where ``y`` crosses zero, by the cubic Hermite interpolant (``dy`` = y').

    ``t``, ``y``, ``dy`` (N,); ``direction`` +1 upward crossings only, −1 downward only, 0 both.
    """
    sign = np.sign(y)
    idx = np.nonzero(sign[:-1] * sign[1:] < 0)[0]
    idx = np.union1d(idx, np.nonzero((sign[:-1] == 0) & (sign[1:] != 0))[0])
    out = []
    for i in idx:
        y0, y1 = float(y[i]), float(y[i + 1])
        if direction and (y1 - y0) * direction <= 0:
            continue
        if y0 == 0.0:
            out.append(float(t[i]))
            continue
        h = float(t[i + 1] - t[i])
        d0, d1 = h * float(dy[i]), h * float(dy[i + 1])
        coeffs = [2 * y0 + d0 - 2 * y1 + d1, -3 * y0 - 2 * d0 + 3 * y1 - d1, d0, y0]
        s_lin = y0 / (y0 - y1)
        roots = np.roots(coeffs) if abs(coeffs[0]) + abs(coeffs[1]) > 0 else np.array([s_lin])
        real = [r.real for r in roots if abs(r.imag) < 1e-9 and -1e-9 <= r.real <= 1 + 1e-9]
        s = min(real, key=lambda r: abs(r - s_lin)) if real else s_lin
        out.append(float(t[i]) + h * min(max(s, 0.0), 1.0))
    return np.array(out)


def _hermite_value(t: np.ndarray, y: np.ndarray, dy: np.ndarray, at: float) -> float:
    i = int(np.clip(np.searchsorted(t, at) - 1, 0, len(t) - 2))
    h = float(t[i + 1] - t[i])
    s = (at - float(t[i])) / h
    h00, h10 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s
    h01, h11 = -2 * s**3 + 3 * s**2, s**3 - s**2
    return float(h00 * y[i] + h10 * h * dy[i] + h01 * y[i + 1] + h11 * h * dy[i + 1])


def peaks(
    t: np.ndarray, theta: np.ndarray, omega: np.ndarray, alpha: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Maxima of ``θ`` (downward crossings of ``θ̇``): times [s] and values [rad]."""
    times = hermite_crossings(t, omega, alpha, direction=-1)
    values = np.array([_hermite_value(t, theta, omega, float(x)) for x in times])
    return times, values


def decay_rate(
    t: np.ndarray, theta: np.ndarray, omega: np.ndarray, alpha: np.ndarray
) -> float | None:
    """Envelope decay rate ``γ`` in [1/s]: −slope of ``ln θ_peak`` vs time (None if < 3 peaks)."""
    times, values = peaks(t, theta, omega, alpha)
    keep = values > 0
    times, values = times[keep], values[keep]
    if len(times) < 3:
        return None
    slope = np.polyfit(times, np.log(values), 1)[0]
    return float(-slope)


@dataclass(frozen=True)
class PendulumRun:
    """One pendulum run, angle measured from the hanging equilibrium (SI units).

    ``theta0`` [rad] (released from rest); ``damping`` ``b`` [N·m·s/rad]; ``simulation`` the
    run in joint coordinates; per sample ``theta`` [rad], ``omega`` [rad/s], ``energy`` [J]
    (zero at rest hanging); ``period`` measured [s] (None with < 2 turning points),
    ``period_exact`` undamped for ``theta0``; ``energy_drift`` ``max |E(t) − E(0)| / E(0)``;
    ``energy_max_increase`` largest step-to-step rise of E over ``E(0)``; ``decay_rate``
    measured [1/s] (None with < 3 maxima), ``decay_rate_exact`` ``b / (2 I)``.
    """

    theta0: float
    damping: float
    pendulum: PhysicalPendulum
    simulation: Simulation
    theta: np.ndarray
    omega: np.ndarray
    energy: np.ndarray
    period: float | None
    period_exact: float
    energy_drift: float
    energy_max_increase: float
    decay_rate: float | None
    decay_rate_exact: float

    @property
    def energy_monotone(self) -> bool:
        """True when the total energy never increases from one sample to the next."""
        return self.energy_max_increase <= 0.0

    def to_dict(self, samples: bool = False) -> dict[str, Any]:
        """JSON-ready figures (and the time series with ``samples=True``)."""

        def rel(meas: float | None, exact: float) -> float | None:
            return None if meas is None or exact == 0 else abs(meas - exact) / exact

        sim = self.simulation
        out = fields_dict(self, "theta0", "damping") | fields_dict(sim, "method", "dt")
        out |= {"duration": float(sim.t[-1])} | fields_dict(self, "period", "period_exact")
        out["period_error"] = rel(self.period, self.period_exact)
        out |= fields_dict(self, "energy_drift", "energy_max_increase", "energy_monotone")
        out |= fields_dict(self, "decay_rate", "decay_rate_exact")
        out["decay_rate_error"] = rel(self.decay_rate, self.decay_rate_exact)
        if samples:
            out["t"] = self.simulation.t.tolist()
            out.update(fields_dict(self, "theta", "omega", "energy"))
        return out


def pendulum_run(
    model: Any = None,
    theta0: float = math.pi / 6,
    *,
    damping: float | None = None,
    dt: float = 1e-3,
    duration: float = 20.0,
    method: Method = "rk4",
) -> PendulumRun:
    """Release a one-joint pendulum from ``theta0`` (rest) and measure period, energy, decay.

    ``model``: one revolute joint (default the ``pendulum`` preset); ``theta0`` in (0, π) rad
    from the hanging equilibrium; ``damping`` [N·m·s/rad], default the URDF's (the preset:
    0.01); ``dt``, ``duration`` in [s].

    Raises:
        ParameterError: Bad angle, damping, step, duration or model.

    """
    th0 = positive("theta0", theta0)
    if not th0 < math.pi:
        msg = (
            f"theta0={theta0!r} rad is not allowed; the initial angle from the hanging "
            "equilibrium must lie in (0, pi) (pi is the unstable upright equilibrium)"
        )
        raise ParameterError(msg, parameter="theta0", value=theta0, allowed="0 < theta0 < pi")
    if model is None:
        b_urdf = 0.01 if damping is None else positive("damping", damping, allow_zero=True)
        mdl = as_model("pendulum", damping=b_urdf)
    else:
        mdl = as_model(model)
    pend = physical_pendulum(mdl)
    b = positive("damping", damping, allow_zero=True) if damping is not None else None
    b = float(mdl.model.damping[0]) if b is None else b
    sim = simulate(mdl, [pend.q_hanging + th0], dt=dt, duration=duration, method=method, damping=b)
    theta = np.asarray(sim.q[:, 0] - pend.q_hanging)
    omega, alpha = np.asarray(sim.v[:, 0]), np.asarray(sim.a[:, 0])
    energy = np.asarray(sim.total - pend.potential_min)
    e0 = float(energy[0])
    drift = float(np.max(np.abs(energy - e0)) / e0)
    max_inc = float(np.max(np.diff(energy)) / e0) if len(energy) > 1 else 0.0
    crossings = hermite_crossings(sim.t, omega, alpha, direction=-1)
    period = None
    if len(crossings) >= 2:
        period = float((crossings[-1] - crossings[0]) / (len(crossings) - 1))
    rate = decay_rate(sim.t, theta, omega, alpha)
    read_only(theta, omega, energy)
    exact, gamma = exact_period(pend, th0), b / (2.0 * pend.inertia)
    return PendulumRun(th0, b, pend, sim, theta, omega, energy, period, exact, drift, max_inc,
                       rate, gamma)  # fmt: skip


@dataclass(frozen=True)
class PendulumExperiment:
    """Seed 001 §1: the undamped and the damped pendulum, and the small-amplitude decay check.

    ``undamped`` (damping 0) and ``damped`` from ``theta0``; ``small``: damped, from the small
    angle ``decay_theta0`` (the decay-rate check).
    """

    undamped: PendulumRun
    damped: PendulumRun
    small: PendulumRun

    def to_dict(self) -> dict[str, Any]:
        """The figures of ``hexapod-kin pendulum --json`` (SI units, angles in rad)."""
        u, d, s = self.undamped, self.damped, self.small
        us, ud, sd = u.simulation, u.to_dict(), s.to_dict()
        out: dict[str, Any] = {
            "theta0": u.theta0,
            "theta0_deg": math.degrees(u.theta0),
            "dt": us.dt,
        }
        out |= {"duration": float(us.t[-1]), "method": us.method, "pendulum": u.pendulum.to_dict()}
        out |= fields_dict(u, "period", "period_exact") | {"period_error": ud["period_error"]}
        out |= {"energy_drift": u.energy_drift, "damping": d.damping}
        out |= {"damped_energy_monotone": d.energy_monotone}
        out |= {"damped_energy_max_increase": d.energy_max_increase}
        out |= {
            "damped_energy_loss": float(1.0 - d.energy[-1] / d.energy[0]),
            "damped_period": d.period,
        }
        out |= fields_dict(s, "decay_rate", "decay_rate_exact")
        out |= {"decay_rate_error": sd["decay_rate_error"], "decay_theta0": s.theta0}
        out |= {"decay_rate_at_theta0": d.decay_rate, "undamped": ud, "damped": d.to_dict()}
        return out | {"small_amplitude": sd}


def pendulum_experiment(
    theta0: float = math.pi / 6,
    damping: float = 0.01,
    *,
    dt: float = 1e-3,
    duration: float = 20.0,
    method: Method = "rk4",
    decay_theta0: float = math.radians(1.0),
    length: float = 0.5,
    mass: float = 1.0,
) -> PendulumExperiment:
    """Run the seed's pendulum undamped and damped (and at small amplitude for the decay).

    Angles in [rad] (``theta0`` seed: 30°; ``decay_theta0`` the small-amplitude run's),
    ``damping`` [N·m·s/rad] of the damped runs, ``dt``, ``duration`` [s]; ``length`` [m] and
    ``mass`` [kg] of the preset.

    Raises:
        ParameterError: Any bad value (named).

    """
    b = positive("damping", damping, allow_zero=True)
    free = as_model("pendulum", damping=0.0, length=length, mass=mass)
    damped_model = as_model("pendulum", damping=b, length=length, mass=mass)
    kw: dict[str, Any] = {"dt": dt, "duration": duration, "method": method}
    return PendulumExperiment(
        pendulum_run(free, theta0, **kw),
        pendulum_run(damped_model, theta0, **kw),
        pendulum_run(damped_model, decay_theta0, **kw),
    )
