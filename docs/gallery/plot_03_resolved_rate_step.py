"""
The seeds' step by resolved rate
================================

The foot pushed along x with ``v = [A sin(2πt/T), 0, 0]`` by ``q̇ = J⁺v`` integrated with RK4:
the sideways and vertical drift stay at rounding level, where the seeds' plain Euler drifts.
"""

import matplotlib.pyplot as plt

from hexapod_kin import seeds

run = seeds.seed_experiment(duration=4.0)
traj = run.trajectory

fig, (a, b) = plt.subplots(2, 1, figsize=(7, 5), sharex=True)
a.plot(traj.t, traj.foot[:, 0], label="x")
a.plot(traj.t, traj.reference[:, 0], "--", label="reference x")
a.set(ylabel="foot x [m]")
a.legend()
b.plot(traj.t, traj.q)
b.set(xlabel="t [s]", ylabel="q [rad]")
fig.suptitle(f"drift y {run.drift_y:.1e} m, z {run.drift_z:.1e} m")
plt.show()
