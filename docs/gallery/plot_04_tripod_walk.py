"""
A tripod walk
=============

The hexapod walks 4 s in a tripod gait; every sample is checked. The gait diagram (stance in
black), the static stability margin and the feet seen from above.
"""

import matplotlib.pyplot as plt
import numpy as np

import hexapod_kin as hk

run = hk.gait.walk(pattern="tripod", duration=4.0)

fig, (g, m, f) = plt.subplots(3, 1, figsize=(7, 8))
g.imshow(
    run.support.T,
    aspect="auto",
    cmap="Greys",
    interpolation="nearest",
    extent=(run.t[0], run.t[-1], len(run.leg_names) - 0.5, -0.5),
)
g.set(
    yticks=range(len(run.leg_names)),
    yticklabels=run.leg_names,
    xlabel="t [s]",
    title="stance (black)",
)
m.plot(run.t, 1e3 * run.margin)
m.set(xlabel="t [s]", ylabel="margin [mm]", title=f"min {1e3 * run.min_margin:.1f} mm")
for leg in range(run.feet.shape[1]):
    f.plot(run.feet[:, leg, 0], run.feet[:, leg, 1], lw=1)
f.plot(run.com[:, 0], run.com[:, 1], "k--", lw=1, label="CoM")
f.set(xlabel="x [m]", ylabel="y [m]", aspect="equal")
f.legend()
fig.tight_layout()
plt.show()
