"""The loader gate: every URDF passes here before Pinocchio or yourdfpy see it.

The libraries under hexapod_kin fail badly on bad input (pin 4.1.0 segfaults on chains of
about 4,000 links and silently accepts negative masses, indefinite inertias, ``lower > upper``
and a ``0 0 0`` axis; yourdfpy "repairs" malformed XML; both read meshes from anywhere on
disk). :func:`check_urdf` refuses all of that, with a :class:`~hexapod_kin.exceptions.UrdfError`
that names the element, the attribute, the value and the line.

Checks, in order (the first failure is raised):

1. **Size**: at most :data:`MAX_URDF_BYTES` bytes.
2. **Strict XML**: parsed by lxml with no recovery, no DTD loading, no entity expansion, no
   network; any ``DOCTYPE`` or ``ENTITY`` declaration is refused (billion laughs, XXE); the
   document must be UTF-8 (or ASCII); nesting deeper than libxml2's default limit (256) fails.
3. **Structure**: root ``<robot name=...>`` (``version``, when given, 1.0 to 1.2); at least
   one ``<link>``; at most :data:`MAX_LINKS` links (Pinocchio segfaults at about 4,000; the
   cap also bounds the tree depth) and at most :data:`MAX_DOF` degrees of freedom
   (Pinocchio's ``Data`` needs about 64·nv³ bytes; 1,000 DoF exhaust memory); non-empty,
   unique link and joint names (``universe`` is reserved by Pinocchio); each joint has a
   known ``type``, one ``<parent link>`` and one ``<child link>`` naming existing, distinct
   links; each link is the child of at most one joint; exactly one root link; every link
   reachable from the root (so no cycles); ``<mimic joint>`` names an existing other joint.
4. **Numbers**: every numeric attribute the URDF spec defines (``origin`` xyz/rpy, ``axis``,
   ``limit``, ``dynamics``, ``safety_controller``, ``calibration``, ``mimic``, ``mass``,
   ``inertia``, ``box``/``cylinder``/``sphere`` sizes, mesh ``scale``, colour ``rgba``) has
   the right count of plain decimal numbers (no ``nan``, ``inf``, hex or ``1_0``; a scalar
   without surrounding spaces, which urdfdom silently reads as 0) that are finite and at
   most :data:`MAX_ABS` (:data:`MAX_ABS_LIMIT` for limits) in magnitude (huge values
   overflow inside Pinocchio); geometry sizes, masses, ``effort``, ``velocity``,
   ``damping`` and ``friction`` are >= 0. Materials and geometry: top-level materials named
   and unique (Pinocchio refuses duplicates); every ``<color rgba>`` four numbers in
   [0, 1]; a visual's ``<material>`` has a ``name`` attribute (undefined or empty names are
   cosmetic and accepted); each ``<visual>``/``<collision>`` has one ``<geometry>`` with
   exactly one URDF shape (box, cylinder, sphere, mesh) and its required attributes
   (urdfdom only prints an error for these and silently drops the element).
5. **Joints**: the axis has a non-zero length (Pinocchio normalises it); ``revolute`` and
   ``prismatic`` joints need ``<limit>`` with ``effort`` and ``velocity`` (the URDF spec makes
   them required; ``lower``/``upper`` default to 0 as in the spec); ``lower <= upper``;
   ``velocity >= 0`` and ``effort >= 0``; damping and friction >= 0.
6. **Mass**: every ``<inertial>`` has ``<mass value>`` >= 0 and all six ``<inertia>``
   entries; a link with mass > 0 has a positive-definite inertia whose principal moments
   satisfy the triangle inequality (``I1 + I2 >= I3``, relative tolerance
   :data:`TRIANGLE_RTOL`); a link with mass 0 has a positive-semi-definite inertia. Every
   *moving body* has mass > 0: Pinocchio merges links attached by ``fixed`` joints into their
   parent, so a moving body is the child link of a non-fixed joint plus the links hanging
   from it through fixed joints, and at least one of them must carry mass (a massless body
   makes the joint-space inertia matrix singular).
7. **Files** (``<mesh filename>``, ``<texture filename>``): always checked when present (the
   kinematics never read meshes, but geometry and the viewer do): ``package://pkg/path``
   resolves against ``package_dirs`` (as Pinocchio does: ``<dir>/pkg/path``), a relative
   path against ``mesh_root`` (the URDF's directory); the resolved real path (symlinks
   followed) must stay inside the root it was resolved against. Absolute and ``file://``
   paths (what xacro's ``$(find pkg)`` writes) are read only when the URDF was loaded from
   its file (``mesh_root`` known) and only for mesh files (``.stl``, ``.dae``, ``.obj``,
   ``.ply``, also after following links); other URI schemes and ``~`` are refused. Every
   file must be an existing, non-empty regular file of at most :data:`MAX_MESH_BYTES` bytes.

**Lenient mode** (``check_urdf(..., lenient=True)``, what :class:`~hexapod_kin.model.Model`
uses for kinematics): a mesh that is *not found* (missing file, unknown package, relative path
of URDF text), *refused* (another scheme, ``~``, an absolute path that may not be read) or
*empty*, and the physical plausibility of inertials (rule 6 beyond ``mass >= 0`` and the six
finite entries) are recorded in the result (``missing_meshes`` as ``line N: 'uri': refused|not
found|empty: why``, ``inertia_defects``) instead of raised; the loader warns (one line per
kind) and drops those visuals, dynamics refuses the inertials unless the model is loaded with
a stated repair (:mod:`.repair`: ``inertia="collision"`` or ``"point"``). Escapes out of a
root, non-regular or huge files and every other rule stay errors in both modes.

Layout (one decision, in the order a document flows through it): :mod:`.limits` (the caps
and the numeric attribute table), :mod:`.parse` (strict XML, element paths in messages,
numbers), :mod:`.meshes` (materials, geometry, mesh/texture files), :mod:`.inertials`
(masses, inertias, moving bodies), :mod:`.tree` (structure, joints, the verdict and its
cache), :mod:`.repair` (the stated inertia repairs, after the verdict). Pure numpy and
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

__all__ = [
    "MAX_URDF_BYTES",
    "MAX_LINKS",
    "MAX_DOF",
    "MAX_ABS",
    "MAX_ABS_LIMIT",
    "MAX_MESH_BYTES",
    "TRIANGLE_RTOL",
    "JOINT_TYPES",
    "GateResult",
    "check_urdf",
    "parse_urdf",
    "principal_moments",
    "resolve_mesh",
]
