"""The loader gate: every URDF passes here before Pinocchio or yourdfpy see it.

Pinocchio segfaults on very long chains and accepts negative masses, indefinite inertias,
``lower > upper`` and a ``0 0 0`` axis; yourdfpy "repairs" malformed XML; both read meshes from
anywhere on disk. :func:`check_urdf` refuses all of that with a
:class:`~hexapod_kin.exceptions.UrdfError` naming the element, attribute, value and line.

Checks, in order (the first failure is raised; the caps are in :mod:`.limits`):

1. **Size**: at most :data:`MAX_URDF_BYTES` bytes.
2. **Strict XML**: lxml without recovery, DTD loading, entity expansion or network; any
   ``DOCTYPE`` or ``ENTITY`` is refused; UTF-8 (or ASCII) only; libxml2's nesting limit (256).
3. **Structure**: root ``<robot name=...>`` (``version`` 1.0 to 1.2); 1 to :data:`MAX_LINKS`
   links and at most :data:`MAX_DOF` degrees of freedom; non-empty, unique link and joint names
   (``universe`` is reserved); each joint has a known ``type`` and one ``<parent link>`` and
   ``<child link>`` naming existing, distinct links; each link has at most one parent joint;
   exactly one root, every link reachable from it (no cycles); ``<mimic joint>`` names another
   existing joint.
4. **Numbers**: every numeric attribute of the URDF spec (:data:`.limits.NUMERIC`) has the
   right count of plain decimal numbers (no ``nan``, ``inf``, hex or ``1_0``; a scalar without
   surrounding spaces, which urdfdom reads as 0), finite and at most :data:`MAX_ABS`
   (:data:`MAX_ABS_LIMIT` for limits) in magnitude; sizes, masses, ``effort``, ``velocity``,
   ``damping`` and ``friction`` >= 0. Top-level materials named and unique; ``<color rgba>``
   four numbers in [0, 1]; a visual's ``<material>`` has a ``name`` attribute; each
   ``<visual>``/``<collision>`` has one ``<geometry>`` with exactly one URDF shape and its
   required attributes (urdfdom silently drops the element otherwise).
5. **Joints**: a non-zero axis; ``revolute`` and ``prismatic`` joints need ``<limit>`` with
   ``effort`` and ``velocity`` (``lower``/``upper`` default to 0); ``lower <= upper``.
6. **Mass**: every ``<inertial>`` has ``<mass value>`` >= 0 and all six ``<inertia>`` entries;
   a link with mass > 0 has a positive-definite inertia obeying the triangle inequality
   (``I1 + I2 >= I3``, relative tolerance :data:`TRIANGLE_RTOL`), a massless one a
   positive-semi-definite inertia. Every *moving body* (the child link of a non-fixed joint
   plus the links fixed to it, which Pinocchio merges) has mass > 0, else the joint-space
   inertia matrix is singular.
7. **Files** (``<mesh filename>``, ``<texture filename>``, always checked):
   ``package://pkg/path`` resolves as ``<dir>/pkg/path`` in ``package_dirs``, a relative path
   against ``mesh_root`` (the URDF's directory); the real path (links followed) must stay in
   that root. Absolute and ``file://`` paths are read only for a URDF loaded from its file and
   only for mesh files (``.stl``, ``.dae``, ``.obj``, ``.ply``); other schemes and ``~`` are
   refused. Every file is a non-empty regular file of at most :data:`MAX_MESH_BYTES` bytes.

**Lenient mode** (``lenient=True``, what :class:`~hexapod_kin.model.Model` uses): a mesh
*not found*, *refused* or *empty*, and the physical plausibility of inertials (rule 6 beyond
``mass >= 0`` and six finite entries) are recorded (``missing_meshes`` as ``line N: 'uri':
refused|not found|empty: why``, ``inertia_defects``) instead of raised; the loader warns and
drops those visuals, dynamics refuses the inertials unless a repair is stated (:mod:`.repair`).
Escapes out of a root, non-regular or huge files and every other rule stay errors.

Modules, in the order a document flows through them: :mod:`.limits` (caps, numeric
attributes), :mod:`.parse` (strict XML, messages, numbers), :mod:`.meshes`, :mod:`.inertials`,
:mod:`.tree` (structure, joints, the verdict and its cache), :mod:`.repair`. Pure numpy and
lxml: importing the gate never imports numba, sympy or Pinocchio.
"""

from __future__ import annotations

from .inertials import principal_moments
from .limits import (
    JOINT_TYPES,
    MAX_ABS,
    MAX_ABS_LIMIT,
    MAX_DOF,
    MAX_LINKS,
    MAX_MESH_BYTES,
    MAX_URDF_BYTES,
    TRIANGLE_RTOL,
)
from .meshes import resolve_mesh
from .parse import parse_urdf
from .tree import GateResult, check_urdf

__all__ = ["MAX_URDF_BYTES", "MAX_LINKS", "MAX_DOF", "MAX_ABS", "MAX_ABS_LIMIT",
           "MAX_MESH_BYTES", "TRIANGLE_RTOL", "JOINT_TYPES", "GateResult", "check_urdf",
           "parse_urdf", "principal_moments", "resolve_mesh"]  # fmt: skip
