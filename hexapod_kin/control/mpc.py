r"""Convex model-predictive control of the stance forces (MIT Cheetah 3 style).

The body is one rigid body of mass ``m`` and inertia ``I`` (the robot's, at its neutral
pose); its state is ``x = (Θ, p, ω, v, g)`` (roll-pitch-yaw [rad], CoM position [m],
angular velocity in world axes [rad/s], CoM velocity [m/s], and gravity as a constant
state) and its inputs the stance feet's ground forces ``f_i`` [N] applied at ``r_i`` from the
CoM. With roll and pitch small the dynamics are linear in yaw ``ψ`` (Di Carlo et al., "Dynamic
locomotion in the MIT Cheetah 3 through convex model-predictive control", IROS 2018):

.. math::

    \dot Θ = R_z(ψ)^\top ω,\quad \dot p = v,\quad
    \dot ω = I_w^{-1} \sum_i r_i \times f_i,\quad \dot v = \frac{1}{m}\sum_i f_i + g,

with ``I_w = R_z(ψ) I R_z(ψ)^\top``. Discretised by forward Euler at the gait's step ``dt``
over ``N`` steps, with the contact schedule (which feet stand at each step, from the gait's
phase table) and the levers of the feet that will stand (where they stand, or their planned
footholds), the predicted states are ``X = A_{qp} x_0 + B_{qp} U``; the forces solve the
condensed QP

.. math::

    \min_U\; \|A_{qp} x_0 + B_{qp} U - X_{ref}\|^2_L + \alpha \|U - U_g\|^2 \quad\text{s.t.}\quad
    f_{z} \in [f_{\min}, f_{\max}],\; |f_x|, |f_y| \le \mu f_z,\;
    |\tau_{\text{bias},i} - J_i^\top f_i| \le \tau_{\max}

(only the standing feet's forces are variables; ``U_g`` the weight shared equally among the
feet standing at each step; the cone as its inscribed pyramid; the joint torque limits of the
legs standing now through their foot Jacobians, for every step they stand), solved by
proxsuite's dense ProxQP (Bambade et al., RSS 2022). The first step's forces are applied.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .._pose import rpy_to_matrix
from .qp import _proxsuite

__all__ = ["MPC_WEIGHTS", "Catch", "ConvexMPC"]

#: State weights of ``(Θ, p, ω, v)`` (12,): roll, pitch, yaw, x, y, z, ω_x, ω_y, ω_z,
#: v_x, v_y, v_z (MIT Cheetah 3's, in proportion).
MPC_WEIGHTS = (25.0, 25.0, 10.0, 100.0, 100.0, 100.0, 0.5, 0.5, 0.3, 3.0, 3.0, 1.0)


#: Catching mode (:class:`Catch`): entered when the capture-point offset of the velocity error,
#: ``sqrt(h/g) |v − v_ref|``, exceeds ``CATCH`` of the feet's lateral half-width, left below
#: ``CATCH_EXIT`` of it; while catching the position weights are scaled by ``CATCH_WXY``;
#: once caught the goal returns to the path at ``CATCH_RETURN`` [leg spans/s].
CATCH = 0.6
CATCH_EXIT = 0.15
CATCH_WXY = 0.1
CATCH_RETURN = 0.3

#: Push observer: the time constant [s] of the filtered horizontal external acceleration
#: (measured less the MPC forces' own), and the least one [m/s²] passed to the MPC (smaller
#: ones are the model's own errors).
EXT_TAU = 0.02
EXT_MIN = 3.0


def _skew(r: np.ndarray) -> np.ndarray:
    x, y, z = (float(c) for c in r)
    return np.array(((0.0, -z, y), (z, 0.0, -x), (-y, x, 0.0)))


@dataclass
class ConvexMPC:
    """The stance-force MPC's constants (see the module docstring).

    Attributes:
        mass: Body mass [kg].
        inertia: (3, 3) inertia about the CoM in the body frame [kg·m²].
        mu: Friction coefficient assumed.
        f_min: Least normal force of a standing foot [N].
        f_max: Largest normal force of a foot [N].
        horizon: Number of steps ``N``.
        weights: (12,) state weights (see :data:`MPC_WEIGHTS`).
        alpha: Force regularisation [1/N²].
        status: 1 when the last :meth:`solve` converged, else 0 (its forces are then the
            solver's last iterate, clipped to the cones).

    """

    mass: float
    inertia: np.ndarray
    mu: float
    f_min: float
    f_max: float
    horizon: int = 10
    weights: np.ndarray = field(default_factory=lambda: np.array(MPC_WEIGHTS))
    alpha: float = 1e-5
    status: int = field(default=1, init=False)

    def dynamics(self, yaw: float, levers: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """The discrete ``A`` (13, 13) and ``B`` (13, 3n) for levers ``levers`` (n, 3) [m]."""
        Rz = rpy_to_matrix(0.0, 0.0, yaw)
        A = np.eye(13)
        A[0:3, 6:9] = Rz.T * dt
        A[3:6, 9:12] = np.eye(3) * dt
        A[11, 12] = dt  # v_z' = ... + g (the 13th state is g = -9.81)
        Iw_inv = np.linalg.inv(Rz @ self.inertia @ Rz.T)
        n = len(levers)
        B = np.zeros((13, 3 * n))
        for i, r in enumerate(levers):
            B[6:9, 3 * i : 3 * i + 3] = Iw_inv @ _skew(r) * dt
            B[9:12, 3 * i : 3 * i + 3] = np.eye(3) * (dt / self.mass)
        return A, B

    def solve(
        self,
        x0: np.ndarray,
        x_ref: np.ndarray,
        contact: np.ndarray,
        levers: np.ndarray,
        dt: float,
        accel: np.ndarray | None = None,
        weights: np.ndarray | None = None,
        torque: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] | None = None,
    ) -> np.ndarray:
        """The first step's ground forces (L, 3) [N] (zero for a foot not standing).

        Args:
            x0: (12,) the measured state ``(Θ, p, ω, v)``.
            x_ref: (N, 12) the reference of steps 1..N.
            contact: (N, L) True where foot ``l`` stands during step ``k``.
            levers: (N, L, 3) each foot's position from the CoM at step ``k`` [m].
            dt: The step [s].
            accel: (3,) an external acceleration of the CoM [m/s²] (a push's), held over
                the horizon (None: none).
            weights: (12,) state weights for this solve (None: :attr:`weights`).
            torque: Joint torque limits of feet ``l``: ``{l: (J, bias, limit)}``, ``J``
                (3, m) the foot's Jacobian over its leg's joints (world axes), ``bias``
                (m,) the joint torques at zero force, ``limit`` (m,) [N·m]: every force of
                foot ``l`` in the horizon keeps ``|bias − Jᵀ f| ≤ limit`` (the Jacobian of
                now; None: no torque rows).

        """
        proxsuite = _proxsuite()
        N, L = contact.shape
        yaw = float(np.mean(x_ref[:, 2]))
        A, _ = self.dynamics(yaw, np.zeros((0, 3)), dt)
        if accel is not None:  # v' = ... + a: through the constant state g = -9.81
            A[9:12, 12] += np.asarray(accel, dtype=float) * (dt / -9.81)
        # the variables: (step, foot) pairs in contact
        idx = [(k, i) for k in range(N) for i in range(L) if contact[k, i]]
        nv = 3 * len(idx)
        if nv == 0:
            return np.zeros((L, 3))
        start = np.zeros(N + 1, dtype=int)
        for k in range(N):
            start[k + 1] = start[k] + 3 * int(contact[k].sum())
        Bs = [self.dynamics(yaw, levers[k][contact[k]], dt)[1] for k in range(N)]
        powers = [np.eye(13)]
        for _ in range(N):
            powers.append(A @ powers[-1])
        xa = np.array([*x0, -9.81])
        Aqp = np.vstack([powers[k + 1] for k in range(N)])  # (13N, 13)
        Bqp = np.zeros((13 * N, nv))
        for k in range(N):  # row block k: state after step k
            for j in range(k + 1):
                Bqp[13 * k : 13 * k + 13, start[j] : start[j + 1]] = powers[k - j] @ Bs[j]
        w = np.tile(np.array([*(self.weights if weights is None else weights), 0.0]), N)
        ref = np.hstack([x_ref, np.full((N, 1), -9.81)]).ravel()
        BtL = Bqp.T * (w / self.alpha)  # the cost divided by alpha: well scaled for the solver
        H = BtL @ Bqp + np.eye(nv)
        # the regularisation pulls towards the weight shared among the standing feet
        u_nom = np.zeros(nv)
        for k in range(N):
            n_k = int(contact[k].sum())
            u_nom[start[k] + 2 : start[k + 1] : 3] = self.mass * 9.81 / max(n_k, 1)
        g = BtL @ (Aqp @ xa - ref) - u_nom
        nf = len(idx)
        C = np.zeros((5 * nf, nv))
        lo = np.zeros(5 * nf)
        hi = np.zeros(5 * nf)
        mu = self.mu
        for n in range(nf):
            c0, r0 = 3 * n, 5 * n
            for k in (0, 1):
                C[r0 + 2 * k, c0 + k], C[r0 + 2 * k, c0 + 2] = 1.0, -mu  # f_k - mu f_z <= 0
                lo[r0 + 2 * k], hi[r0 + 2 * k] = -1e20, 0.0
                C[r0 + 2 * k + 1, c0 + k], C[r0 + 2 * k + 1, c0 + 2] = 1.0, mu  # >= 0
                lo[r0 + 2 * k + 1], hi[r0 + 2 * k + 1] = 0.0, 1e20
            C[r0 + 4, c0 + 2] = 1.0
            lo[r0 + 4], hi[r0 + 4] = self.f_min, self.f_max
        rows, r_lo, r_hi = [], [], []
        for n, (_, i) in enumerate(idx):  # |bias - J^T f| <= limit
            if torque is None or i not in torque:
                continue
            J, bias, limit = torque[i]
            for col in np.flatnonzero(np.isfinite(limit)).tolist():
                row = np.zeros(nv)
                row[3 * n : 3 * n + 3] = J[:, col]
                rows.append(row)
                r_lo.append(bias[col] - limit[col])
                r_hi.append(bias[col] + limit[col])
        if rows:
            C = np.vstack([C, np.array(rows)])
            lo, hi = np.concatenate([lo, r_lo]), np.concatenate([hi, r_hi])
        res = proxsuite.proxqp.dense.solve(H, g, None, None, C, lo, hi, eps_abs=1e-6, max_iter=300)
        self.status = int(res.info.status == proxsuite.proxqp.QPSolverOutput.PROXQP_SOLVED)
        u = np.asarray(res.x)
        f = np.zeros((L, 3))
        if not np.all(np.isfinite(u)):
            return f

        legs = np.flatnonzero(contact[0])
        f[legs] = u[: 3 * len(legs)].reshape(-1, 3)
        f[legs, 2] = np.clip(f[legs, 2], self.f_min, self.f_max)
        lim = mu * f[legs, 2:3]
        f[legs, :2] = np.clip(f[legs, :2], -lim, lim)
        return f


@dataclass
class Catch:
    """The MPC's catching mode for pushes, and its push observer.

    A push (see :data:`CATCH`) is caught velocity first: the position weights drop to
    :data:`CATCH_WXY` of theirs, so the body goes with the push while the MPC stops it; the
    push as observed (the CoM's measured acceleration less the MPC forces' own, low-passed
    over :data:`EXT_TAU`) enters the MPC's prediction (:meth:`accel`). Once caught, the goal
    starts where the body is (:attr:`ret`, from the path) and returns to the path at
    ``speed``.

    Attributes:
        mass: Body mass [kg].
        dt: Control period [s].
        width: The feet's lateral half-width [m].
        speed: The goal's return speed [m/s].
        catching: In the catching mode.
        ext: (3,) the observed external acceleration [m/s²] (horizontal).
        ret: (2,) the goal's offset from the path [m].

    """

    mass: float
    dt: float
    width: float
    speed: float
    catching: bool = False
    ext: np.ndarray = field(default_factory=lambda: np.zeros(3))
    ret: np.ndarray = field(default_factory=lambda: np.zeros(2))
    _caught: bool = False
    _v_prev: np.ndarray | None = None

    def mode(self, offset: float, walking: bool) -> None:
        """Enter or leave the mode from the capture-point offset [m] of the velocity error."""
        if not self.catching:
            self.catching = walking and offset > CATCH * self.width
        elif offset < CATCH_EXIT * self.width:
            self.catching = False

    def observe(self, vcom: np.ndarray, force: np.ndarray, off: np.ndarray) -> None:
        """One tick of the observer and of the goal's offset.

        ``vcom`` (3,) the CoM velocity [m/s], ``force`` (3,) the stance forces' sum applied
        since the last tick [N], ``off`` (2,) the CoM's offset from the path [m].
        """
        if self._v_prev is not None:
            acc = (vcom - self._v_prev) / self.dt - force / self.mass
            acc[2] = 0.0
            self.ext += min(1.0, self.dt / EXT_TAU) * (acc - self.ext)
        self._v_prev = vcom
        if self.catching:
            self._caught = True
        elif self._caught:
            self._caught = False
            self.ret = np.array(off, dtype=float)
        else:
            n = float(np.linalg.norm(self.ret))
            if n > 0:
                self.ret *= max(0.0, 1.0 - self.speed * self.dt / n)

    def accel(self) -> np.ndarray | None:
        """The external acceleration for the MPC (None below :data:`EXT_MIN`)."""
        return self.ext if np.linalg.norm(self.ext[:2]) > EXT_MIN else None

    def weights(self, weights: np.ndarray) -> np.ndarray | None:
        """The MPC's state weights while catching (None: ``weights`` unchanged)."""
        if not self.catching:
            return None
        w = np.array(weights, dtype=float)
        w[[3, 4]] *= CATCH_WXY
        return w


def schedule(phase: float, offsets: np.ndarray, duty: float, step: float, steps: int) -> np.ndarray:
    """(steps, L) True where leg ``l`` stands at the middle of step ``k`` (1..``steps``).

    ``phase`` is the gait clock now, ``offsets`` (L,) the legs' phase offsets, ``duty`` the
    stance fraction and ``step`` the clock's advance per step (all in cycles).
    """
    ph = phase + step * (np.arange(steps)[:, None] + 0.5) + np.asarray(offsets)[None, :]
    return np.asarray(ph % 1.0 < duty)
