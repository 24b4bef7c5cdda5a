"""Exports that other tools consume: xacro, a ROS 2 description package, MJCF, STL meshes.

Each exporter takes a source as :func:`hexapod_kin.load` does (a chain, a robot, a preset name, a
table file; :func:`to_mjcf` also a URDF) and writes files that are deterministic (same input,
same bytes), atomically, with a header recording the command that made them:

* :func:`to_xacro` / :func:`write_xacro` — ``<xacro:macro>`` per leg family, a property per
  dimension; :func:`expand_xacro` runs the real ``xacro`` package on it.
* :func:`export_package` — a ROS 2 ``ament_cmake`` description package (package.xml format 3,
  CMakeLists.txt, urdf/, launch/, rviz/, meshes/, README).
* :func:`to_mjcf` / :func:`write_mjcf` — MJCF through MuJoCo's own URDF compiler, with a floor.
* :func:`mesh_visuals` / :func:`add_collisions` — STL visuals (trimesh) and primitive
  collisions.

xacro, mujoco and trimesh are the optional extra ``hexapod-kin[export]``; each is imported
only when the function that needs it runs.
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
