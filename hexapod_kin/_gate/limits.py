"""The gate's caps and tables: sizes, magnitudes, DoF, joint types, numeric attributes."""

from __future__ import annotations

import re

#: Largest URDF text accepted, in bytes (example-robot-data's largest is < 1 MiB).
MAX_URDF_BYTES = 20 * 1024 * 1024
#: Most links (also the depth cap): Pinocchio 4.1 segfaults on chains of about 4,000.
MAX_LINKS = 1000
#: Largest magnitude of any number (SI units; huge values overflow inside Pinocchio).
MAX_ABS = 1e9
#: The same in :data:`LIMIT_TAGS`, where ±1e16 is a common way to write "unbounded".
MAX_ABS_LIMIT = 1e20
LIMIT_TAGS = ("limit", "safety_controller", "dynamics", "calibration", "mimic")
#: Most degrees of freedom: Pinocchio's ``Data`` is about 64·nv³ bytes (tiago_dual has 101).
MAX_DOF = 128
#: DoFs (nv) of each URDF joint type.
JOINT_DOF = {"revolute": 1, "continuous": 1, "prismatic": 1, "fixed": 0, "floating": 6, "planar": 3}
#: Largest mesh or texture file accepted, in bytes (200 MiB).
MAX_MESH_BYTES = 200 * 1024 * 1024
#: Relative tolerance of ``I1 + I2 >= I3 * (1 - TRIANGLE_RTOL)`` (CAD exports round inertias).
TRIANGLE_RTOL = 1e-6
#: A radius of gyration ``sqrt(I_max / m)`` beyond ``GYRATION_FACTOR`` times the robot's size
#: (the sum of its joint offsets) and beyond ``GYRATION_MAX`` [m] cannot be a link's.
GYRATION_FACTOR = 10.0
GYRATION_MAX = 1.0
#: Joint types of the URDF spec.
JOINT_TYPES = tuple(JOINT_DOF)

_NUM = r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?"
NUMBER = re.compile(f"^{_NUM}$")
_WS = r"[ \t\r\n]"
# Vectors may be padded with whitespace; a scalar may not (urdfdom then silently reads 0).
PATTERNS = {n: re.compile(f"{_WS}*" + f"{_WS}+".join([_NUM] * n) + f"{_WS}*$") for n in (3, 4)}
PATTERNS[1] = re.compile(f"{_NUM}$")
CHECKED_TOP = ("link", "joint", "material")
URDF_VERSION = re.compile(r"^1\.[0-2]$")
#: URDF shapes and their required attributes.
SHAPES = {"box": ("size",), "cylinder": ("radius", "length"), "sphere": ("radius",),
          "mesh": ("filename",)}  # fmt: skip
BIG_NUMBER = re.compile(r"[eE]\+?0*[1-9]\d|\d{10}")  # exponent >= 10 or 10 digits: maybe too big
NEGATIVE = re.compile(r"(?:^|[ \t\r\n])-")
SCHEME = re.compile(r"^([A-Za-z][A-Za-z0-9+.\-]*):")
RESERVED = {"universe"}
#: Absolute tolerance on principal moments [kg m^2] (a 1 mg, 0.1 mm part has 1e-14).
INERTIA_FLOOR = 1e-18

# element tag → attribute → (count of numbers, minimum or None); others are not numeric
NUMERIC: dict[str, dict[str, tuple[int, float | None]]] = {
    "origin": {"xyz": (3, None), "rpy": (3, None)},
    "axis": {"xyz": (3, None)},
    "limit": {"lower": (1, None), "upper": (1, None), "effort": (1, 0.0), "velocity": (1, 0.0)},
    "dynamics": {"damping": (1, 0.0), "friction": (1, 0.0)},
    "safety_controller": {
        "soft_lower_limit": (1, None),
        "soft_upper_limit": (1, None),
        "k_position": (1, None),
        "k_velocity": (1, None),
    },
    "calibration": {"rising": (1, None), "falling": (1, None)},
    "mimic": {"multiplier": (1, None), "offset": (1, None)},
    "mass": {"value": (1, 0.0)},
    "inertia": {a: (1, None) for a in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")},
    "box": {"size": (3, 0.0)},
    "cylinder": {"radius": (1, 0.0), "length": (1, 0.0)},
    "sphere": {"radius": (1, 0.0)},
    "mesh": {"scale": (3, None)},
    "color": {"rgba": (4, None)},
}
JOINT_CHILDREN = ("origin", "axis", *LIMIT_TAGS)
