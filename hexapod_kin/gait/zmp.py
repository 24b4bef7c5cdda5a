"""The zero-moment point of a planned walk, from Pinocchio's centroidal dynamics.

On flat ground at height ``h`` (the stance contacts' mean), with gravity ``g`` along −z:

    x_z = c_x − (c_z − h) c̈_x / (g + c̈_z) − L̇_y / (m (g + c̈_z))
    y_z = c_y − (c_z − h) c̈_y / (g + c̈_z) + L̇_x / (m (g + c̈_z))

``c`` the centre of mass, ``L`` the angular momentum about it, ``m`` the mass: ``c`` and
``ḣ_G = (m c̈, L̇)`` from :func:`pinocchio.computeCentroidalMomentumTimeVariation` at each
planned configuration, with ``v`` and ``a`` by second-order finite differences on the
configuration manifold (:func:`manifold_derivatives`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["GRAVITY", "manifold_derivatives", "rates", "zmp_points"]

#: Gravity [m/s²].
GRAVITY = 9.81


def rates(x: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """dx/dt and d²x/dt² (N, ...) on uniform samples (zeros below 4 samples).

    The first by :func:`numpy.gradient` (``edge_order=2``); the second
    ``(x_{i+1} − 2x_i + x_{i−1}) / dt²`` inside, the second-order one-sided
    ``(2x₀ − 5x₁ + 4x₂ − x₃) / dt²`` at the ends.
    """
    if len(x) < 4:
        return np.zeros_like(x), np.zeros_like(x)
    dt = float(t[1] - t[0])
    out = np.empty_like(x)
    out[1:-1] = x[2:] - 2.0 * x[1:-1] + x[:-2]
    out[0] = 2.0 * x[0] - 5.0 * x[1] + 4.0 * x[2] - x[3]
    out[-1] = 2.0 * x[-1] - 5.0 * x[-2] + 4.0 * x[-3] - x[-4]
    return np.gradient(x, t, axis=0, edge_order=2), np.asarray(out / (dt * dt))


def manifold_derivatives(model: Any, Q: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Velocities and accelerations (N, nv) of configurations ``Q`` (N, nq) sampled every ``dt``.

    The stencils of :func:`rates` (:func:`numpy.gradient`, ``edge_order=2``; the second
    difference) on the manifold: with ``d_i = pin.difference(Q_i, Q_{i+1})`` (and ``difference(Q_i,
    Q_{i−1}) = −d_{i−1}``), ``v_i = (d_{i−1} + d_i) / 2dt`` and ``a_i = (d_i − d_{i−1}) / dt²``
    inside; at an end, ``e_k = difference(Q_end, Q_{end±k})`` gives ``v = ±(4e₁ − e₂) / 2dt``
    and ``a = (−5e₁ + 4e₂ − e₃) / dt²``. N ≥ 4.
    """
    import pinocchio as pin

    n = len(Q)
    step = np.array([pin.difference(model, Q[i], Q[i + 1]) for i in range(n - 1)])
    v, a = np.empty((n, model.nv)), np.empty((n, model.nv))
    v[1:-1] = (step[:-1] + step[1:]) / (2.0 * dt)
    a[1:-1] = (step[1:] - step[:-1]) / (dt * dt)
    for end, sign in ((0, 1), (n - 1, -1)):
        e1, e2, e3 = (pin.difference(model, Q[end], Q[end + sign * k]) for k in (1, 2, 3))
        v[end] = sign * (4.0 * e1 - e2) / (2.0 * dt)
        a[end] = (-5.0 * e1 + 4.0 * e2 - e3) / (dt * dt)
    return v, a


def zmp_points(
    wb: Any, q: np.ndarray, base: np.ndarray, t: np.ndarray, ground: np.ndarray
) -> np.ndarray:
    """ZMP (N, 3) on the ground plane of each sample (z = ``ground``) [m] (N ≥ 4 samples).

    Args:
        wb: The robot (:class:`~.robot.WholeBody`).
        q: (N, nq) leg joints [rad] / [m].
        base: (N, 4, 4) body poses.
        t: (N,) uniform sample times [s].
        ground: (N,) ground height under the robot [m].

    """
    import pinocchio as pin

    model = wb.model
    data = model.createData()
    Q = wb.pinocchio_q(q, base)
    v, a = manifold_derivatives(model, Q, float(t[1] - t[0]))
    c, dh = np.empty((len(Q), 3)), np.empty((len(Q), 6))
    for i in range(len(Q)):
        dh[i] = pin.computeCentroidalMomentumTimeVariation(model, data, Q[i], v[i], a[i]).vector
        c[i] = data.com[0]
    mass = float(data.mass[0])
    den = mass * GRAVITY + dh[:, 2]  # m (g + c̈_z)
    lever = (c[:, 2] - ground) / den
    out = np.empty_like(c)
    out[:, 0] = c[:, 0] - lever * dh[:, 0] - dh[:, 4] / den
    out[:, 1] = c[:, 1] - lever * dh[:, 1] + dh[:, 3] / den
    out[:, 2] = ground
    return out
