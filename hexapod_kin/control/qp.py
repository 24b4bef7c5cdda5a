r"""Stance force distribution: a body wrench shared among the stance feet by a small QP.

Given the desired wrench ``w = (F, M)`` about the centre of mass (world axes) and the stance
feet at ``r_i`` from it, the forces ``f_i`` the ground applies to the feet solve

.. math::

    \min_f \; \|A f - w\|^2_S + \alpha \|f\|^2 \quad \text{s.t.}\quad
    f_{z,i} \in [f_{\min}, f_{\max}],\; |f_{x,i}|, |f_{y,i}| \le \mu f_{z,i},\;
    |\tau_{\text{bias},i} - J_i^\top f_i| \le \tau_{\max}

with ``A = [I … I; [r_1]× … [r_n]×]`` (the friction cone as its inscribed pyramid; the joint
torque limits through each leg's 3 × m foot Jacobian). Solved by proxsuite's dense ProxQP
(Bambade et al., RSS 2022).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["ForceQP", "wrench_matrix"]


def _proxsuite() -> Any:
    try:
        import proxsuite
    except ImportError:
        from ..exceptions import OptionalDependencyError

        raise OptionalDependencyError(
            "proxsuite is not installed; `pip install 'hexapod-kin[control]'` installs it",
            parameter="module",
            value="proxsuite",
        ) from None
    return proxsuite


def wrench_matrix(r: np.ndarray) -> np.ndarray:
    """The (6, 3n) map from foot forces to the wrench about the CoM; ``r`` (n, 3) levers [m]."""
    n = len(r)
    A = np.zeros((6, 3 * n))
    for i, (x, y, z) in enumerate(r):
        A[:3, 3 * i : 3 * i + 3] = np.eye(3)
        A[3:, 3 * i : 3 * i + 3] = ((0.0, -z, y), (z, 0.0, -x), (-y, x, 0.0))
    return A


@dataclass
class ForceQP:
    """The force distribution problem's constants.

    Attributes:
        mu: Friction coefficient used by the controller (below the ground's).
        f_min: Least normal force of a stance foot [N].
        f_max: Largest normal force of a foot [N].
        weights: (6,) weights S of the wrench rows (force, then moment).
        alpha: Regularisation of the forces [1/N²].

    """

    mu: float
    f_min: float
    f_max: float
    weights: np.ndarray
    alpha: float = 1e-4

    def solve(
        self,
        wrench: np.ndarray,
        r: np.ndarray,
        jac: list[np.ndarray] | None = None,
        bias: list[np.ndarray] | None = None,
        tau_max: list[np.ndarray] | None = None,
    ) -> np.ndarray:
        """The stance forces (n, 3) [N] for ``wrench`` (6,) [N, N·m] and levers ``r`` (n, 3).

        ``jac[i]`` (3, m) is leg i's foot Jacobian over its own joints (world axes),
        ``bias[i]`` (m,) its joint torques at zero force, ``tau_max[i]`` (m,) its limits [N·m]
        (all None: no torque rows). Falls back to the unconstrained least-squares
        solution clipped to the cones when the solver does not converge.
        """
        proxsuite = _proxsuite()
        n = len(r)
        if n == 0:
            return np.zeros((0, 3))
        A = wrench_matrix(r)
        S = np.diag(self.weights)
        H = A.T @ S @ A + self.alpha * np.eye(3 * n)
        g = -A.T @ S @ wrench
        rows, lo, hi = [], [], []
        mu = self.mu
        for i in range(n):
            for k in (0, 1):  # |f_k| <= mu f_z as f_k - mu f_z <= 0 and f_k + mu f_z >= 0
                row = np.zeros(3 * n)
                row[3 * i + k], row[3 * i + 2] = 1.0, -mu
                rows.append(row)
                lo.append(-1e20)
                hi.append(0.0)
                row = np.zeros(3 * n)
                row[3 * i + k], row[3 * i + 2] = 1.0, mu
                rows.append(row)
                lo.append(0.0)
                hi.append(1e20)
            row = np.zeros(3 * n)
            row[3 * i + 2] = 1.0
            rows.append(row)
            lo.append(self.f_min)
            hi.append(self.f_max)
            if jac is not None and bias is not None and tau_max is not None:
                # |bias - J^T f| <= tau_max  <=>  bias - tau_max <= J^T f <= bias + tau_max
                for j in range(jac[i].shape[1]):
                    if not np.isfinite(tau_max[i][j]):
                        continue
                    row = np.zeros(3 * n)
                    row[3 * i : 3 * i + 3] = jac[i][:, j]
                    rows.append(row)
                    lo.append(bias[i][j] - tau_max[i][j])
                    hi.append(bias[i][j] + tau_max[i][j])
        C = np.array(rows)
        res = proxsuite.proxqp.dense.solve(
            H, g, None, None, C, np.array(lo), np.array(hi), eps_abs=1e-6, max_iter=200
        )
        x = np.asarray(res.x)
        if res.info.status != proxsuite.proxqp.QPSolverOutput.PROXQP_SOLVED or not np.all(
            np.isfinite(x)
        ):
            x = np.linalg.lstsq(A, wrench, rcond=None)[0]
        f = x.reshape(n, 3)
        f[:, 2] = np.clip(f[:, 2], self.f_min, self.f_max)
        lim = mu * f[:, 2:3]
        f[:, :2] = np.clip(f[:, :2], -lim, lim)
        return f
