"""
Where the leg is singular
=========================

``det J`` of the position Jacobian over the knee and ankle angles (hip fixed), with the
symbolic families ``q3 = 0``, ``q3 = π`` and ``l1 + l2 cos q2 + l3 cos(q2 + q3) = 0`` drawn
over it: the numeric zeros fall on the derived curves.
"""

import matplotlib.pyplot as plt
import numpy as np

import hexapod_kin as hk

leg = hk.load("hexabot_leg")
q2, q3 = np.meshgrid(np.linspace(-np.pi, np.pi, 121), np.linspace(-np.pi, np.pi, 121))
det = np.array(
    [
        np.linalg.det(leg.jacobian([0.0, a, b], "local_world_aligned")[:3])
        for a, b in zip(q2.ravel(), q3.ravel())
    ]
).reshape(q2.shape)

l1, l2, l3 = 0.05, 0.10, 0.10
fig, ax = plt.subplots(figsize=(6, 5))
mesh = ax.pcolormesh(q2, q3, det, cmap="RdBu_r", shading="auto")
fig.colorbar(mesh, label="det J [m³]")
ax.contour(q2, q3, l1 + l2 * np.cos(q2) + l3 * np.cos(q2 + q3), levels=[0], colors="k")
for v in (0.0, np.pi, -np.pi):
    ax.axhline(v, color="k", lw=1)
ax.set(xlabel="q2 [rad]", ylabel="q3 [rad]", title="det J and the symbolic families")
plt.show()
