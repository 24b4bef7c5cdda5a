import nbformat as nbf
from nbformat.v4 import new_code_cell, new_markdown_cell, new_notebook

def nb(cells, path):
    n = new_notebook(cells=cells)
    n.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
    n.metadata["language_info"] = {"name": "python"}
    nbf.write(n, path)

nb([
    new_markdown_cell("# Your own leg, from a table file\n\nA 3-DOF leg written as a Khalil–Kleinfinger table (YAML), loaded through its generated URDF into Pinocchio: forward kinematics, the foot Jacobian, a singularity check, inverse kinematics along a straight foot path, a servo timeline of that path, and the 3-D viewer inline (a self-contained page in an `<iframe srcdoc>`, no server)."),
    new_code_cell('''from pathlib import Path
import tempfile
import numpy as np
import hexapod_kin as hk

work = Path(tempfile.mkdtemp())
table = work / "my_leg.yaml"
table.write_text("""
name: my_leg
convention: khalil
angles: deg
base: mount
tip: foot
row:
  - {name: coxa,  type: revolute, alpha: 0,  d: 0,    lower: -80, upper: 80, velocity: 300}
  - {name: femur, type: revolute, alpha: 90, d: 0.04, lower: -90, upper: 90, velocity: 300}
  - {name: tibia, type: revolute, alpha: 0,  d: 0.08, lower: -150, upper: 0, velocity: 300}
  - {type: fixed, d: 0.10}
""")
leg = hk.load(table)
leg'''),
    new_markdown_cell("Forward kinematics and the foot Jacobian (`local_world_aligned`: rows [v; ω] in base axes)."),
    new_code_cell('''q = np.radians([10, 20, -60])
print(np.round(leg.fk(q), 4))
J = leg.jacobian(q, "local_world_aligned")
print(np.round(J[:3], 4))
print("sigma_min of the position Jacobian:", np.linalg.svd(J[:3], compute_uv=False).min())'''),
    new_markdown_cell("Inverse kinematics along a straight foot path, then a servo timeline of that path (AX-12-like servos: 1024 ticks over 300°)."),
    new_code_cell('''p0 = leg.fk(q)[:3, 3]
times = np.linspace(0.0, 1.0, 21)
targets = p0 + np.outer(times, [0.0, 0.03, 0.02])
path, qk = [], q
for target in targets:
    sol = hk.ik.solve(leg, target, q0=qk)
    qk = sol.q
    path.append(qk)
path = np.array(path)
err = max(np.linalg.norm(leg.fk(p)[:3, 3] - t) for p, t in zip(path, targets))
print("IK path:", path.shape, "worst foot error [m]:", err)

from hexapod_kin.export.timeline import Calibration, timeline
cal = Calibration.from_dict({"defaults": {"units": "ticks", "ticks_per_revolution": 1228.8,
                                          "centre": 512, "limits": [0, 1023]}})
tl = timeline((times, path), rate=50, calibration=cal, joint_names=leg.joint_names)
tl.write(work / "path.csv")
print(tl.command[:3])'''),
    new_markdown_cell("The leg moving along that path, inline (drag to orbit, wheel to zoom)."),
    new_code_cell('''from hexapod_kin.viewer.notebook import show
show(leg, times, path, height=360)'''),
], "/work/wt/h8/examples/my_leg.ipynb")

nb([
    new_markdown_cell("# A hexapod walk\n\nThe six-legged preset walks a tripod gait: every sample is checked (IK, joint limits, slip, stability margin). The animation shows inline (self-contained page, no server); the joint timeline is written for AX-12-like servos and as a ROS 2 `JointTrajectory`."),
    new_code_cell('''import numpy as np
import hexapod_kin as hk

run = hk.gait.walk(pattern="tripod", duration=4.0)
print(f"{len(run.t)} samples, min stability margin {run.min_margin * 1e3:.1f} mm, "
      f"max slip {run.max_slip:.2e} m")'''),
    new_code_cell('''from hexapod_kin.viewer.notebook import show_walk
show_walk(run, height=420)'''),
    new_markdown_cell("The joint timeline at 50 Hz for AX-12-like servos, read back to within half a tick."),
    new_code_cell('''import tempfile, math
from pathlib import Path
from hexapod_kin.export.timeline import Calibration, read_timeline, timeline

cal = Calibration.from_dict({"defaults": {"units": "ticks", "ticks_per_revolution": 1228.8,
                                          "centre": 512, "limits": [0, 1023],
                                          "velocity_limit": 11.9}})
tl = timeline(run, rate=50, calibration=cal)
out = Path(tempfile.mkdtemp())
back = read_timeline(tl.write(out / "walk.csv"))
plan = np.column_stack([np.interp(tl.t, run.t, run.q[:, j]) for j in range(18)])
print("worst read-back error [ticks]:", np.abs(back.q - plan).max() / (2 * math.pi / 1228.8))
tl.write(out / "walk.yaml")   # ROS 2 trajectory_msgs/JointTrajectory
print((out / "walk.yaml").read_text()[:300])'''),
], "/work/wt/h8/examples/hexapod_walk.ipynb")
