"""
A walk as a servo timeline
==========================

The same walk resampled at 50 Hz for AX-12-like servos (1024 ticks over 300°, centre 512):
the commands of leg 1's three joints, and the read-back error in ticks (within half a tick).
"""

import math
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import hexapod_kin as hk
from hexapod_kin.export.timeline import Calibration, read_timeline, timeline

run = hk.gait.walk(pattern="tripod", duration=4.0)
cal = Calibration.from_dict(
    {
        "defaults": {
            "units": "ticks",
            "ticks_per_revolution": 1228.8,
            "centre": 512,
            "limits": [0, 1023],
            "velocity_limit": 11.9,
        }
    }
)
tl = timeline(run, rate=50, calibration=cal)
back = read_timeline(tl.write(Path(tempfile.mkdtemp()) / "walk.json"))
plan = np.column_stack([np.interp(tl.t, run.t, run.q[:, j]) for j in range(run.q.shape[1])])
err_ticks = (back.q - plan) / (2 * math.pi / 1228.8)

fig, (a, b) = plt.subplots(2, 1, figsize=(7, 5), sharex=True)
for j in range(3):
    a.step(tl.t, tl.command[:, j], where="post", label=tl.joint_names[j])
a.set(ylabel="command [ticks]")
a.legend()
b.plot(tl.t, err_ticks[:, :3])
b.axhline(0.5, color="k", ls=":")
b.axhline(-0.5, color="k", ls=":")
b.set(xlabel="t [s]", ylabel="read-back error [ticks]")
plt.show()
