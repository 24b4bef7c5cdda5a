"""
The leg's reachable foot points
===============================

Forward kinematics of the seeds' 3-DOF leg over random configurations within its limits
(the compiled batch engine), seen from the side and from above, coloured by the smallest
singular value of the position Jacobian.
"""

import matplotlib.pyplot as plt
import numpy as np

import hexapod_kin as hk

leg = hk.load("hexabot_leg")
qs = leg.random_q(4000, seed=1)
feet = leg.fk_batch(qs)[:, :3, 3]
sigma = np.array(
    [
        np.linalg.svd(leg.jacobian(q, "local_world_aligned")[:3], compute_uv=False).min()
        for q in qs[:800]
    ]
)

fig, (side, top) = plt.subplots(1, 2, figsize=(9, 4))
side.scatter(np.hypot(feet[:800, 0], feet[:800, 1]), feet[:800, 2], c=sigma, s=4)
side.set(xlabel="radial distance [m]", ylabel="z [m]", title="side (colour: σ_min)")
top.scatter(feet[:, 0], feet[:, 1], s=1, alpha=0.4)
top.set(xlabel="x [m]", ylabel="y [m]", title="from above", aspect="equal")
fig.tight_layout()
plt.show()
