"""The loader gate: every URDF passes here before Pinocchio or yourdfpy see it.

Pinocchio segfaults on very long chains and takes negative masses, indefinite inertias,
``lower > upper`` and zero axes; yourdfpy "repairs" malformed XML; both read meshes anywhere.
:func:`check_urdf` raises the first failure (a :class:`~hexapod_kin.exceptions.UrdfError`
naming element, attribute, value and line) of, in order:

1. **Size**: at most :data:`MAX_URDF_BYTES`.
2. **Strict XML**: no recovery, DTD, entities or network; UTF-8 (or ASCII); libxml2's nesting.
3. **Structure**: ``<robot name>`` (version 1.0 to 1.2); 1 to :data:`MAX_LINKS` links, at most
   :data:`MAX_DOF` DoF; unique non-empty names (``universe`` reserved); joints of a known type
   with one existing, distinct parent and child; one parent per link; one root reaching every
   link; ``<mimic>`` naming another joint.
4. **Numbers** (:data:`.limits.NUMERIC`): the right count of plain decimals (a scalar without
   spaces, which urdfdom reads as 0), finite, at most :data:`MAX_ABS` (:data:`MAX_ABS_LIMIT` in
   limits); sizes, masses, effort, velocity, damping, friction >= 0; materials named, unique,
   colours in [0, 1]; each visual/collision one geometry of one shape with its attributes.
5. **Joints**: a non-zero axis; revolute/prismatic ``<limit effort velocity>``, lower <= upper.
6. **Mass**: ``<mass>`` >= 0, six ``<inertia>`` entries; mass > 0 needs a positive-definite
   inertia with ``I1 + I2 >= I3`` (:data:`TRIANGLE_RTOL`), mass 0 a semi-definite one; every
   *moving body* (a non-fixed joint's child and the links fixed to it) has mass > 0.
7. **Files** (mesh, texture): ``package://pkg/path`` under a ``package_dirs`` entry, a relative
   path under ``mesh_root``, the real path inside that root; absolute and ``file://`` paths only
   for mesh files of a URDF loaded from its file; other schemes and ``~`` refused; a non-empty
   regular file of at most :data:`MAX_MESH_BYTES`.

**Lenient mode** (the loader's): meshes not found, refused or empty (``missing_meshes``:
``line N: 'uri': refused|not found|empty: why``) and implausible inertials (rule 6 beyond
``mass >= 0`` and six entries: ``inertia_defects``) are recorded, not raised; dynamics refuses
the inertials unless repaired (:mod:`.repair`). Pure numpy and lxml (no numba, sympy, Pinocchio).
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
