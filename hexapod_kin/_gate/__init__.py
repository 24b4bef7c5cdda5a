"""The loader gate: every URDF passes here before Pinocchio or yourdfpy see it.

Pinocchio segfaults on very long chains and accepts negative masses, indefinite inertias,
``lower > upper`` and a ``0 0 0`` axis; yourdfpy "repairs" malformed XML; both read meshes from
anywhere on disk. :func:`check_urdf` raises the first failure, a
:class:`~hexapod_kin.exceptions.UrdfError` naming element, attribute, value and line, of:

1. **Size**: at most :data:`MAX_URDF_BYTES` bytes.
2. **Strict XML**: no recovery, DTD, entity expansion or network; ``DOCTYPE``/``ENTITY``
   refused; UTF-8 (or ASCII) only; libxml2's nesting limit (256).
3. **Structure**: ``<robot name=...>`` (``version`` 1.0 to 1.2); 1 to :data:`MAX_LINKS` links,
   at most :data:`MAX_DOF` degrees of freedom; unique non-empty link and joint names
   (``universe`` reserved); each joint of a known ``type`` with one ``<parent link>`` and
   ``<child link>``, existing and distinct; at most one parent joint per link; one root
   reaching every link (no cycles); ``<mimic joint>`` names another joint.
4. **Numbers**: every numeric attribute (:data:`.limits.NUMERIC`) holds the right count of
   plain decimals (no ``nan``, ``inf``, hex, ``1_0``; a scalar without surrounding spaces,
   which urdfdom reads as 0), at most :data:`MAX_ABS` (:data:`MAX_ABS_LIMIT` in limits);
   sizes, masses, ``effort``, ``velocity``, ``damping``, ``friction`` >= 0. Top-level
   materials named and unique, ``<color rgba>`` in [0, 1], a visual's ``<material>`` named;
   each ``<visual>``/``<collision>`` one ``<geometry>`` of exactly one URDF shape with its
   required attributes (urdfdom silently drops it otherwise).
5. **Joints**: a non-zero axis; ``revolute``/``prismatic`` need ``<limit effort velocity>``
   (``lower``/``upper`` default to 0) and ``lower <= upper``.
6. **Mass**: every ``<inertial>`` has ``<mass value>`` >= 0 and six ``<inertia>`` entries; mass
   > 0 needs a positive-definite inertia obeying ``I1 + I2 >= I3`` (:data:`TRIANGLE_RTOL`),
   mass 0 a semi-definite one. Every *moving body* (a non-fixed joint's child link with the
   links fixed to it, merged by Pinocchio) has mass > 0 (else the mass matrix is singular).
7. **Files** (``<mesh>``/``<texture filename>``): ``package://pkg/path`` is
   ``<dir>/pkg/path`` for a dir of ``package_dirs``, a relative path is under ``mesh_root``
   (the URDF's folder); the real path stays in that root. Absolute and ``file://`` paths: only
   mesh files (``.stl``, ``.dae``, ``.obj``, ``.ply``) of a URDF loaded from its file; other
   schemes and ``~`` refused. A non-empty regular file of at most :data:`MAX_MESH_BYTES`.

**Lenient mode** (``lenient=True``, the loader's): meshes *not found*, *refused* or *empty*
(``missing_meshes``: ``line N: 'uri': refused|not found|empty: why``) and implausible
inertials (rule 6 beyond ``mass >= 0`` and six finite entries: ``inertia_defects``) are
recorded, not raised: the loader warns and drops those visuals; dynamics refuses the
inertials unless a repair is stated (:mod:`.repair`). Everything else stays an error.

Modules in the order a document flows: :mod:`.limits`, :mod:`.parse`, :mod:`.meshes`,
:mod:`.inertials`, :mod:`.tree` (the verdict and its cache), :mod:`.repair`. Pure numpy and
lxml: never imports numba, sympy or Pinocchio.
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
