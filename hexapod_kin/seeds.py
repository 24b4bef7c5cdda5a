"""The lab reports' experiments (``hexapod_kin/report/seeds/``) as functions.

:func:`seed_experiment`, the seeds' run (3-DOF leg, ``v = [A sin(2πt/T), 0, 0]``) with its
drift figures, and :func:`euler_baseline`, the seeds' plain Euler + ``np.linalg.solve`` loop;
:func:`step_torques` along that run; :func:`seed002_schedule`, seed 002's Table I.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ._fields import fields_dict
from .exceptions import ConfigurationError, ParameterError, finite, positive
from .motion import SEED_Q0, JointSchedule, Method, Trajectory, default_stance, resolved_rate

if TYPE_CHECKING:
    from .dynamics import StepTorques

__all__ = ["SEED_Q0", "SeedRun", "euler_baseline", "seed002_schedule", "seed_baseline",
           "seed_experiment", "step_torques"]  # fmt: skip


@dataclass(frozen=True)
class SeedRun:
    """The seeds' experiment (``trajectory``, amplitude A [m/s], period T [s]) and its drift.

    Attributes:
        drift_y: max |y(t) − y(0)| [m] of the tip (Pinocchio FK of the joint trajectory);
            ``drift_z`` the same of z.
        error_x: max |x(t) − x(0) − A T/(2π) (1 − cos 2πt/T)| [m] (the exact ∫v_x).
        baseline: The same figures of the plain Euler + ``np.linalg.solve`` open loop.
        baseline_deviation: Its (N, 3) |foot − reference| [m], or None; ``baseline_failure``:
            why it could not run (a singular J), or None.

    """

    trajectory: Trajectory
    amplitude: float
    period: float
    drift_y: float
    drift_z: float
    error_x: float
    baseline: dict[str, float]
    baseline_deviation: np.ndarray | None = None
    baseline_failure: str | None = None

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary."""
        tr = self.trajectory
        return {
            "method": tr.method,
            "gain": tr.gain,
            "dt": tr.dt,
            "duration": float(tr.t[-1]),
            "amplitude": self.amplitude,
            "period": self.period,
            "q0": [float(v) for v in tr.q[0]],
            **fields_dict(self, "drift_y", "drift_z", "error_x"),
            "baseline_euler_solve": self.baseline,
            "baseline_failure": self.baseline_failure,
            "closest_approach": tr.closest_approach.to_dict(),
            "max_joint_speed": float(np.max(np.abs(tr.qdot))),
        }


def _drift(
    foot: np.ndarray, t: np.ndarray, amplitude: float, period: float
) -> tuple[dict[str, float], np.ndarray]:
    """Drift figures of tip positions ``foot`` (N, 3) and the (N, 3) |foot − exact reference|."""
    ref = np.broadcast_to(foot[0], foot.shape).copy()
    ref[:, 0] += amplitude * period / (2 * np.pi) * (1 - np.cos(2 * np.pi * t / period))
    dev = np.abs(foot - ref)
    figs = {
        "drift_y": float(np.max(dev[:, 1])),
        "drift_z": float(np.max(dev[:, 2])),
        "error_x": float(np.max(dev[:, 0])),
    }
    return figs, dev


def euler_baseline(
    model: Any, velocity: Callable[[Any], Any], q0: Any, dt: float, duration: float
) -> np.ndarray:
    """The seeds' open loop ``q += dt · np.linalg.solve(J(q), v(t))``: the (N, n) trajectory."""
    q = model.check_q(q0, "q0").copy()
    steps = int(round(duration / dt))
    out = np.empty((steps + 1, model.nq))
    out[0] = q
    vs = None
    try:  # one call with every time, as resolved_rate does, when v(t) takes an array
        vs = np.asarray(velocity(np.arange(steps) * dt), dtype=float)
    except Exception:  # noqa: BLE001 - a scalar-only v(t): called per step below
        vs = None
    if vs is not None and vs.shape != (steps, 3):
        vs = None
    jacobian, solve, isfinite = model.jacobian, np.linalg.solve, math.isfinite
    for k in range(steps):
        jac = jacobian(q)[:3]  # the tip's linear velocity rows (local-world-aligned)
        v = vs[k] if vs is not None else np.asarray(velocity(k * dt), dtype=float)
        try:
            qdot = solve(jac, v)
        except np.linalg.LinAlgError:
            qdot = np.full(model.nq, np.nan)
        if not isfinite(qdot @ qdot):  # a NaN or inf anywhere makes it non-finite
            raise ConfigurationError(
                f"the plain Euler + np.linalg.solve loop stops at t = {k * dt:g} s: J(q) is "
                f"singular at q = {np.round(q, 6).tolist()} (the seeds' method needs det J != 0)",
                parameter="q0",
                value=np.asarray(q0, dtype=float).tolist(),
                allowed="a start where det J != 0",
            )
        q = q + dt * qdot
        out[k + 1] = q
    return out


def _start(model: Any, q0: Any) -> np.ndarray:
    """``q0`` checked, else ``SEED_Q0`` where it fits (no IK import), else the home pose."""
    if q0 is not None:
        return np.array(model.check_q(q0, "q0"))
    seed = np.array(SEED_Q0)
    if model.nq == 3 and np.all(seed >= model.lower) and np.all(seed <= model.upper):
        return seed
    return default_stance(model)


def _x_velocity(a: float, period: float) -> Callable[[Any], np.ndarray]:
    """The seeds' foot velocity ``v(t) = [a sin(2πt/T), 0, 0]`` in [m/s] (t scalar or array)."""
    w = 2 * np.pi / period

    def vel(t: Any) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        out = np.zeros(t.shape + (3,))
        out[..., 0] = a * np.sin(w * t)
        return out

    return vel


def seed_experiment(
    model: Any = None,
    *,
    amplitude: float = 0.05,
    period: float = 2.0,
    dt: float = 1e-3,
    duration: float = 10.0,
    q0: Any = None,
    method: Method = "rk4",
    gain: float = 10.0,
    baseline: bool = True,
) -> SeedRun:
    """The seeds' experiment: foot velocity ``[A sin(2πt/T), 0, 0]`` on the 3-DOF leg.

    The defaults (the seeds give none) move the foot 0 → 3.2 cm → 0 along x every period.

    ``model``: a loaded 3-joint model (default ``hexabot_leg``); ``amplitude`` A [m/s],
    ``period`` T, ``dt``, ``duration`` [s]; ``q0``: default ``SEED_Q0`` where it fits, else
    :func:`default_stance`; ``gain`` [1/s] toward the exact ``x0 + A T/(2π)(1 − cos 2πt/T)``;
    ``baseline``: also the plain Euler + ``np.linalg.solve`` loop (a square J).

    """
    from .kinematics import load

    mdl = load("hexabot_leg") if model is None else model
    a = finite("amplitude", amplitude)
    per = positive("period", period)
    q_start = _start(mdl, q0)
    w = 2 * np.pi / per
    vel = _x_velocity(a, per)
    p0 = mdl.position(q_start)

    def ref(t: Any) -> np.ndarray:
        t = np.asarray(t, dtype=float)
        out = np.broadcast_to(p0, t.shape + (3,)).copy()
        out[..., 0] += a / w * (1.0 - np.cos(w * t))
        return out

    traj = resolved_rate(mdl, vel, q_start, dt, duration, method=method, gain=gain, path=ref)
    figs, _ = _drift(traj.foot, traj.t, a, per)  # traj.foot: Pinocchio FK of traj.q
    base: dict[str, float] = {}
    base_dev, failure = None, None
    if baseline and mdl.nq == 3:
        base, base_dev, failure = seed_baseline(
            mdl, amplitude=a, period=per, dt=dt, duration=duration, q0=q_start
        )
    return SeedRun(
        traj, a, per, figs["drift_y"], figs["drift_z"], figs["error_x"], base, base_dev, failure
    )


def seed_baseline(
    model: Any,
    *,
    amplitude: float = 0.05,
    period: float = 2.0,
    dt: float = 1e-3,
    duration: float = 10.0,
    q0: Any = None,
) -> tuple[dict[str, float], np.ndarray | None, str | None]:
    """The baseline of :func:`seed_experiment` (its arguments) alone: the Euler + solve loop.

    Returns:
        ``(figures, deviation, failure)``: ``drift_y``, ``drift_z``, ``error_x`` in [m], the
        read-only (N, 3) |foot − reference| (``{}`` and None after a singular J), and why it
        stopped (or None).

    """
    a = finite("amplitude", amplitude)
    per = positive("period", period)
    q_start = _start(model, q0)
    vel = _x_velocity(a, per)
    try:
        qb = euler_baseline(model, vel, q_start, dt, duration)
    except ConfigurationError as exc:
        return {}, None, str(exc)
    t = np.arange(qb.shape[0]) * dt
    base, dev = _drift(np.array([model.position(q) for q in qb]), t, a, per)
    dev.setflags(write=False)
    return base, dev, None


def step_torques(
    model: Any = None, force: Any = None, *, frame: str | None = None, **seed_kwargs: Any
) -> StepTorques:
    """Joint torques along the seeds' resolved-rate step (:func:`seed_experiment`).

    ``force``: constant foot force on the environment (3,) [N], base axes, at ``frame``
    (default the tip); ``model`` and ``**seed_kwargs`` as :func:`seed_experiment` (no baseline).

    Raises:
        ParameterError: Not a 3-joint model; as
            :func:`hexapod_kin.dynamics.torques_along` and :func:`seed_experiment`.

    """
    from .dynamics import torques_along
    from .kinematics import load

    mdl = load("hexabot_leg") if model is None else model
    if mdl.nq != 3:
        raise ParameterError(
            f"model {mdl.name!r} has {mdl.nq} joints {list(mdl.joint_names)}; the seeds' "
            "resolved-rate step drives a 3-joint leg's foot (pick one leg with base=/tip=)",
            parameter="model",
            value=mdl.name,
            allowed="a 3-joint leg",
        )
    seed_kwargs.setdefault("baseline", False)
    tr = seed_experiment(mdl, **seed_kwargs).trajectory
    return torques_along(mdl, tr.t, tr.q, tr.qdot, force, frame=frame)


def seed002_schedule() -> JointSchedule:
    """Seed 002 Table I (movement planning of the 2-DOF leg), linear ramps in radians.

    Knots (t [s]: θ1, θ2 [deg]): 0: (0, −90); 2: (0, −90); 7: (0, −50); 11: (20, −50);
    15: (20, −50); 20: (0, −90); idle afterwards.
    """
    deg = np.array([(0, -90), (0, -90), (0, -50), (20, -50), (20, -50), (0, -90)], float)
    return JointSchedule(
        times=np.array([0, 2, 7, 11, 15, 20], float),
        values=np.radians(deg),
        description="seed 002 Table I (movement planning)",
    )
