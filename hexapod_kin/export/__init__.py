"""Exports other tools consume: xacro, a ROS 2 description package, MJCF, STL meshes.

Each takes a source as :func:`hexapod_kin.load` does (:func:`to_mjcf` also a URDF) and writes
deterministic files atomically, headed by the command that made them. xacro, mujoco and
trimesh (extra ``hexapod-kin[export]``) are imported only when needed.
"""

from __future__ import annotations

from .meshes import MeshedUrdf, add_collisions, mesh_visuals
from .mjcf import INTEGRATORS, MjcfExport, to_mjcf, write_mjcf
from .ros2 import PackageExport, export_package, package_files, package_name_for
from .xacro import expand_xacro, to_xacro, write_xacro

__all__ = [
    "INTEGRATORS",
    "MeshedUrdf",
    "MjcfExport",
    "PackageExport",
    "add_collisions",
    "expand_xacro",
    "export_package",
    "mesh_visuals",
    "package_files",
    "package_name_for",
    "to_mjcf",
    "to_xacro",
    "write_mjcf",
    "write_xacro",
]
