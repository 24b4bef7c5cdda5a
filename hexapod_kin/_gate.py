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
   path against ``mesh_root`` (the URDF's directory); ``file://``, other URI schemes and
   absolute paths are refused; the resolved real path (symlinks followed) must stay inside
   the root it was resolved against; it must be an existing regular file of at most
   :data:`MAX_MESH_BYTES` bytes.

**Lenient mode** (``check_urdf(..., lenient=True)``, what :class:`~hexapod_kin.model.Model`
uses for kinematics): a mesh that cannot be *found* (missing file, unknown package, relative
path of URDF text) and the physical plausibility of inertials (rule 6 beyond ``mass >= 0`` and
the six finite entries) are recorded in the result (``missing_meshes``, ``inertia_defects``)
instead of raised; the loader warns and drops those visuals, dynamics refuses the inertials.
Refused mesh URIs (schemes, absolute paths, escapes, non-regular or huge files) and every
other rule stay errors in both modes.

This module is longer than the package's ~600-line habit on purpose: it is one job (decide
whether a URDF may reach Pinocchio) whose rules refer to each other (numbers before masses,
structure before both), and splitting it would scatter that single decision.
"""

from __future__ import annotations

import math
import os
import re
import stat
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from lxml import etree

from .exceptions import UrdfError

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
    "resolve_mesh",
]

#: Largest URDF text accepted, in bytes (20 MiB; the largest example-robot-data file is < 1 MiB).
MAX_URDF_BYTES = 20 * 1024 * 1024
#: Most links accepted. Pinocchio 4.1 segfaults (recursion) on chains of about 4,000 links;
#: 1,000 leaves a wide margin and still covers every robot of example-robot-data. Since a tree
#: of N links has depth at most N, this is also the depth cap.
MAX_LINKS = 1000
#: Largest magnitude of any number (SI units). Finite but huge values overflow inside
#: Pinocchio (an inertial origin of 1e308 m makes the merged inertia infinite), so the gate
#: caps them; 1e9 (m, kg, N, rad/s ...) is far beyond any robot.
MAX_ABS = 1e9
#: The same for ``<limit>``, ``<safety_controller>``, ``<dynamics>``, ``<calibration>`` and
#: ``<mimic>``, where values such as ±1e16 are a common way to write "unbounded".
MAX_ABS_LIMIT = 1e20
_LIMIT_TAGS = ("limit", "safety_controller", "dynamics", "calibration", "mimic")
#: Most degrees of freedom accepted. Pinocchio's ``Data`` grows as about 64·nv³ bytes
#: (measured with pin 4.1: 0.2 GB at nv = 129, 4 GB at nv = 400; a 1,000-DoF chain exhausts
#: memory and gets killed), so 128 DoF keeps a model under about 0.2 GB. The largest robot of
#: example-robot-data (tiago_dual) has 101; a hexapod has 18.
MAX_DOF = 128
#: DoFs (nv) of each URDF joint type.
_JOINT_DOF = {
    "revolute": 1,
    "continuous": 1,
    "prismatic": 1,
    "fixed": 0,
    "floating": 6,
    "planar": 3,
}
#: Largest mesh or texture file accepted, in bytes (200 MiB).
MAX_MESH_BYTES = 200 * 1024 * 1024
#: Relative tolerance of the triangle inequality ``I1 + I2 >= I3 * (1 - TRIANGLE_RTOL)``
#: (CAD exports round their inertias; 1e-6 accepts that rounding, not a wrong tensor).
TRIANGLE_RTOL = 1e-6
#: Documents that passed and reference no files, by text (small LRU: generated URDFs are
#: loaded again and again).
_CACHE: dict[tuple[bool, str | bytes], GateResult] = {}
_CACHE_SIZE = 32
_CACHE_MAX_CHARS = 1_000_000
#: Joint types of the URDF spec.
JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar")

_NUM = r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?"
_NUMBER = re.compile(f"^{_NUM}$")
_WS = r"[ \t\r\n]"
# Vectors may be padded with whitespace; a scalar may not (urdfdom then silently reads 0).
_PATTERNS = {n: re.compile(f"{_WS}*" + f"{_WS}+".join([_NUM] * n) + f"{_WS}*$") for n in (3, 4)}
_PATTERNS[1] = re.compile(f"{_NUM}$")
_CHECKED_TOP = ("link", "joint", "material")
_VERSION = re.compile(r"^1\.[0-2]$")
#: URDF shapes and their required attributes.
_SHAPES = {
    "box": ("size",),
    "cylinder": ("radius", "length"),
    "sphere": ("radius",),
    "mesh": ("filename",),
}
_BIG = re.compile(r"[eE]\+?0*[1-9]\d|\d{10}")  # exponent >= 10 or 10 digits: maybe too big
_NEGATIVE = re.compile(r"(?:^|[ \t\r\n])-")
_SCHEME = re.compile(r"^([A-Za-z][A-Za-z0-9+.\-]*):")
_RESERVED = {"universe"}
#: Absolute tolerance on principal moments in [kg m^2] (rounding noise in exported files; a
#: 1 mg, 0.1 mm part has 1e-14).
_INERTIA_FLOOR = 1e-18

# (element tag, attribute) → (count of numbers, minimum or None). Attributes not listed are
# not numeric. The tag is the element's own tag; context-dependent ones are handled in code.
_NUMERIC: dict[str, dict[str, tuple[int, float | None]]] = {
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
_JOINT_CHILDREN = (
    "origin",
    "axis",
    "limit",
    "dynamics",
    "safety_controller",
    "calibration",
    "mimic",
)


@dataclass(frozen=True)
class GateResult:
    """What the gate learned about a URDF that passed.

    Attributes:
        root: The parsed ``<robot>`` element (lxml).
        links: Link names, in document order.
        joints: Joint names, in document order.
        root_link: Name of the root link.
        meshes: The resolved mesh and texture files, as ``(uri, path)`` pairs in document order.
        missing_meshes: Mesh/texture URIs that could not be found (lenient mode only), as
            ``(uri, reason)`` pairs; their visual/collision elements must be dropped.
        inertia_defects: Physically implausible inertials (lenient mode only), as
            ``(link, defect)`` pairs; harmless to kinematics, refused by dynamics.

    """

    root: etree._Element
    links: tuple[str, ...] = ()
    joints: tuple[str, ...] = ()
    root_link: str = ""
    meshes: tuple[tuple[str, Path], ...] = ()
    missing_meshes: tuple[tuple[str, str], ...] = ()
    inertia_defects: tuple[tuple[str, str], ...] = ()


class _MeshMissing(UrdfError):
    """A mesh file that cannot be found (as opposed to one that is refused)."""


# ------------------------------------------------------------------------ messages
def _where(el: etree._Element) -> str:
    """``<joint name="j1"> <axis>`` style path of an element, with its line."""
    parts: list[str] = []
    node: etree._Element | None = el
    while node is not None and node.tag != "robot":
        name = node.get("name")
        tag = node.tag if isinstance(node.tag, str) else "?"
        parts.append(
            f'<{tag} name="{name}">'
            if name is not None and tag in ("link", "joint", "material", "visual", "collision")
            else f"<{tag}>"
        )
        node = node.getparent()
    parts.reverse()
    return f"line {el.sourceline}: {' '.join(parts) or '<robot>'}"


def _error(el: etree._Element, attr: str | None, value: object, problem: str) -> UrdfError:
    attr_part = f" {attr}={value!r}" if attr is not None else ""
    return UrdfError(f"URDF {_where(el)}{attr_part}: {problem}")


# ------------------------------------------------------------------------ numbers
def _numbers(el: etree._Element, attr: str, count: int, minimum: float | None) -> tuple[float, ...]:
    raw = el.get(attr)
    if raw is None:
        return ()
    if count == 1 and raw != raw.strip():
        raise _error(el, attr, raw, "a single number without surrounding spaces is required")
    parts = re.split(r"[ \t\r\n]+", raw.strip(" \t\r\n"))
    if len(parts) != count:
        raise _error(el, attr, raw, f"{count} number(s) required, found {len(parts)}")
    out = []
    for p in parts:
        if not _NUMBER.match(p):
            raise _error(el, attr, raw, f"{p!r} is not a decimal number")
        x = float(p)
        if not math.isfinite(x):
            raise _error(el, attr, raw, "numbers must be finite")
        cap = MAX_ABS_LIMIT if el.tag in _LIMIT_TAGS else MAX_ABS
        if abs(x) > cap:
            raise _error(
                el,
                attr,
                raw,
                f"|{p}| exceeds {cap:g} (the cap for <{el.tag}>); numbers are SI values of a robot",
            )
        if minimum is not None and x < minimum:
            raise _error(el, attr, raw, f"must be >= {minimum:g}")
        out.append(x)
    return tuple(out)


def _check_numbers(root: etree._Element) -> None:
    """Check every numeric attribute under the ``<link>``, ``<joint>`` and ``<material>``s.

    Fast path: one regular expression per attribute (the exact count of plain decimal
    numbers); :func:`_numbers` runs only to explain a failure or to look for overflow.
    """
    patterns, numeric = _PATTERNS, _NUMERIC
    for top in root:
        if top.tag not in _CHECKED_TOP:
            continue
        for node in top.iter(*numeric):
            spec = numeric[node.tag]
            for attr, raw in node.items():
                kind = spec.get(attr)
                if kind is None:
                    continue
                if (
                    not patterns[kind[0]].match(raw)
                    or _BIG.search(raw)
                    or (kind[1] is not None and _NEGATIVE.search(raw))
                ):
                    _numbers(node, attr, kind[0], kind[1])


def _number(el: etree._Element, attr: str, default: float | None = None) -> float:
    """A single number already validated by :func:`_check_numbers` (or ``default``)."""
    raw = el.get(attr)
    if raw is None:
        if default is None:
            raise _error(el, attr, None, "attribute is required")
        return default
    return float(raw)


# ------------------------------------------------------------------------ parsing
def parse_urdf(text: str | bytes) -> etree._Element:
    """Parse URDF text with the gate's strict, hostile-safe parser (no other check).

    Raises:
        UrdfError: Malformed XML, DOCTYPE/ENTITY declarations, bad encodings.

    """
    return _parse(text)


def _parse(text: str | bytes) -> etree._Element:
    data = text.encode("utf-8") if isinstance(text, str) else bytes(text)
    if len(data) > MAX_URDF_BYTES:
        raise UrdfError(f"URDF size {len(data)} bytes exceeds the cap of {MAX_URDF_BYTES} bytes")
    if b"<!DOCTYPE" in data or b"<!ENTITY" in data:
        raise UrdfError(
            "URDF contains a DOCTYPE or ENTITY declaration; these are refused (entity "
            "expansion and external entities are not allowed)"
        )
    parser = etree.XMLParser(
        resolve_entities=False,
        no_network=True,
        recover=False,
        huge_tree=False,
        load_dtd=False,
        dtd_validation=False,
        remove_comments=True,
        remove_pis=True,
    )
    try:
        tree = etree.fromstring(data, parser).getroottree()
    except etree.XMLSyntaxError as exc:
        raise UrdfError(f"URDF is not well-formed XML: {exc}") from None
    info = tree.docinfo
    if info.doctype or info.internalDTD is not None or info.externalDTD is not None:
        raise UrdfError("URDF contains a DOCTYPE declaration; DOCTYPE is refused")
    enc = (info.encoding or "UTF-8").upper().replace("_", "-")
    if enc not in ("UTF-8", "UTF8", "US-ASCII", "ASCII"):
        raise UrdfError(f"URDF encoding={info.encoding!r} is not allowed; use UTF-8")
    root = tree.getroot()
    for node in root.iter(etree.Entity):  # entity references left unexpanded
        raise UrdfError(f"URDF line {node.sourceline}: entity reference {node!s}; refused")
    return root


def _name(el: etree._Element, what: str) -> str:
    name = el.get("name")
    if name is None or not name.strip():
        raise _error(el, "name", name, f"every <{what}> needs a non-empty name")
    if name in _RESERVED:
        raise _error(el, "name", name, "the name 'universe' is reserved by Pinocchio")
    return name


def _single(el: etree._Element, tag: str, required: bool) -> etree._Element | None:
    found = el.findall(tag)
    if len(found) > 1:
        raise _error(found[1], None, None, f"<{tag}> given {len(found)} times; at most once")
    if required and not found:
        raise _error(el, None, None, f"<{tag}> is required")
    return found[0] if found else None


# ------------------------------------------------------------------------ inertia
def _rpy_matrix(rpy: Sequence[float]) -> np.ndarray:
    """URDF ``Rz(yaw)·Ry(pitch)·Rx(roll)``."""
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = (
        math.cos(r),
        math.sin(r),
        math.cos(p),
        math.sin(p),
        math.cos(y),
        math.sin(y),
    )
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


def _origin(el: etree._Element | None) -> tuple[np.ndarray, np.ndarray]:
    """Rotation and translation of an element's ``<origin>`` (identity when absent)."""
    origin = None if el is None else el.find("origin")
    if origin is None:
        return np.eye(3), np.zeros(3)
    xyz = _numbers(origin, "xyz", 3, None) or (0.0, 0.0, 0.0)
    rpy = _numbers(origin, "rpy", 3, None) or (0.0, 0.0, 0.0)
    rot = np.eye(3) if not any(rpy) else _rpy_matrix(rpy)
    return rot, np.array(xyz, dtype=float)


@dataclass
class _Inertial:
    """A link's checked ``<inertial>`` (raw numbers; matrices only built when needed)."""

    mass: float
    values: tuple[float, float, float, float, float, float]  # ixx iyy izz ixy ixz iyz
    eig: tuple[float, float, float]  # principal moments [kg m^2], sorted
    element: etree._Element | None  # the <inertial>

    @property
    def present(self) -> bool:
        return self.mass > 0.0 or any(self.values)

    @property
    def definite(self) -> bool:
        return _definite(self.eig)

    @property
    def triangle(self) -> bool:
        return _triangle(self.eig)

    def in_link(self) -> tuple[np.ndarray, np.ndarray]:
        """Centre of mass [m] and inertia about it [kg m^2], in link axes."""
        rot, com = _origin(self.element)
        ixx, iyy, izz, ixy, ixz, iyz = self.values
        mat = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]], dtype=float)
        return com, rot @ mat @ rot.T


_NO_INERTIAL = _Inertial(0.0, (0.0,) * 6, (0.0, 0.0, 0.0), None)


def _definite(eig: Sequence[float]) -> bool:
    return eig[0] > 1e-12 * eig[2] + _INERTIA_FLOOR


def _triangle(eig: Sequence[float]) -> bool:
    return eig[0] + eig[1] >= eig[2] * (1.0 - TRIANGLE_RTOL)


def _eig_text(eig: Sequence[float]) -> str:
    return "[" + ", ".join(f"{e:.6g}" for e in eig) + "]"


def _link_inertial(link: etree._Element, defects: list[tuple[str, str]] | None = None) -> _Inertial:
    """Check a link's ``<inertial>``: mass >= 0, six finite entries, not indefinite.

    With ``defects`` (lenient mode) an indefinite inertia is recorded there instead of raised.
    """
    inertial = _single(link, "inertial", required=False)
    if inertial is None:
        return _NO_INERTIAL
    _single(inertial, "origin", required=False)
    mass_el = _single(inertial, "mass", required=True)
    inertia_el = _single(inertial, "inertia", required=True)
    assert mass_el is not None and inertia_el is not None
    mass = _number(mass_el, "value")
    keys = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
    ixx, ixy, ixz, iyy, iyz, izz = (_number(inertia_el, k) for k in keys)
    eig = _sym_eigvals(ixx, iyy, izz, ixy, ixz, iyz)
    scale = max(abs(ixx), abs(iyy), abs(izz), abs(ixy), abs(ixz), abs(iyz))
    if eig[0] < -(1e-9 * scale + _INERTIA_FLOOR):
        values = " ".join(f"{k}={inertia_el.get(k)}" for k in keys)
        err = _error(
            inertia_el,
            None,
            None,
            f"{values}: inertia is indefinite (principal moments {_eig_text(eig)}); an inertia "
            "tensor must be positive semi-definite",
        )
        if defects is None:
            raise err
        defects.append((str(link.get("name")), str(err)))
    return _Inertial(mass, (ixx, iyy, izz, ixy, ixz, iyz), eig, inertial)


def _check_moving_body(
    jname: str,
    child: str,
    link_el: dict[str, etree._Element],
    inertials: dict[str, _Inertial],
    fixed_children: dict[str, list[tuple[str, etree._Element]]],
    defects: list[tuple[str, str]] | None = None,
) -> None:
    """The body Pinocchio builds for joint ``jname``: ``child`` plus its fixed-joint subtree.

    It must have mass > 0 and a positive-definite inertia (about its centre of mass) whose
    principal moments satisfy the triangle inequality. With ``defects`` (lenient mode) a
    failure is recorded there as ``(child, message)`` instead of raised.
    """
    try:
        _check_body(jname, child, link_el, inertials, fixed_children)
    except UrdfError as err:
        if defects is None:
            raise
        defects.append((child, str(err)))


def _check_body(
    jname: str,
    child: str,
    link_el: dict[str, etree._Element],
    inertials: dict[str, _Inertial],
    fixed_children: dict[str, list[tuple[str, etree._Element]]],
) -> None:
    # Members with their pose in the child frame (poses computed only if >1 carries mass).
    members: list[tuple[str, etree._Element | None]] = [(child, None)]
    stack = [child]
    while stack:
        for grandchild, joint in fixed_children[stack.pop()]:
            members.append((grandchild, joint))
            stack.append(grandchild)
    parts = [n for n, _ in members if inertials[n].present]
    total = math.fsum(inertials[n].mass for n in parts)
    if total <= 0.0:
        raise _error(
            link_el[child],
            "name",
            child,
            f"the link moved by joint {jname!r} has no mass (nor do links fixed to it); a "
            "moving link needs <inertial> with mass > 0",
        )
    if len(parts) == 1:
        eig = inertials[parts[0]].eig  # rotation-invariant
    elif any(inertials[n].definite for n in parts) and all(inertials[n].triangle for n in parts):
        # Sums of physical inertias (tr(S)·E − S with S >= 0, moved by the parallel-axis
        # theorem, also of that form) stay physical, and adding a definite one makes the
        # sum definite: nothing to compute.
        return
    else:
        pose: dict[str, tuple[np.ndarray, np.ndarray]] = {child: (np.eye(3), np.zeros(3))}
        for name, joint in members[1:]:
            assert joint is not None
            rot_p, pos_p = pose[joint.find("parent").get("link")]
            r_j, p_j = _origin(joint)
            pose[name] = (rot_p @ r_j, rot_p @ p_j + pos_p)
        coms, mats, masses = [], [], []
        for name in parts:
            rot, pos = pose[name]
            com_l, mat_l = inertials[name].in_link()
            coms.append(rot @ com_l + pos)
            mats.append(rot @ mat_l @ rot.T)
            masses.append(inertials[name].mass)
        com = sum(m * c for m, c in zip(masses, coms)) / total
        mat = np.zeros((3, 3))
        for m, c, inertia in zip(masses, coms, mats):
            dc = c - com
            mat += inertia + m * (float(dc @ dc) * np.eye(3) - np.outer(dc, dc))
        eig = _sym_eigvals(mat[0, 0], mat[1, 1], mat[2, 2], mat[0, 1], mat[0, 2], mat[1, 2])
    own = inertials[child].element
    where = own.find("inertia") if own is not None and len(parts) == 1 else link_el[child]
    merged = (
        "" if len(parts) == 1 else f" (merged with the links fixed to it: {len(parts)} inertials)"
    )
    if not _definite(eig):
        raise _error(
            where,
            None,
            None,
            f"the body moved by joint {jname!r}{merged} has an inertia that is not positive "
            f"definite (principal moments {_eig_text(eig)} kg m^2, mass {total:g} kg); a moving "
            "link needs a positive-definite inertia",
        )
    if not _triangle(eig):
        raise _error(
            where,
            None,
            None,
            f"the body moved by joint {jname!r}{merged} has principal moments {_eig_text(eig)} "
            "kg m^2 that violate the triangle inequality I1 + I2 >= I3 (no real body has them)",
        )


def _sym_eigvals(
    a: float, b: float, c: float, d: float, e: float, f: float
) -> tuple[float, float, float]:
    """Sorted eigenvalues of ``[[a, d, e], [d, b, f], [e, f, c]]`` (trigonometric method)."""
    p1 = d * d + e * e + f * f
    if p1 == 0.0:
        s = sorted((a, b, c))
        return (s[0], s[1], s[2])
    q = (a + b + c) / 3.0
    p2 = (a - q) ** 2 + (b - q) ** 2 + (c - q) ** 2 + 2.0 * p1
    p = math.sqrt(p2 / 6.0)
    if p == 0.0:
        return (q, q, q)
    ba, bb, bc = (a - q) / p, (b - q) / p, (c - q) / p
    bd, be, bf = d / p, e / p, f / p
    det_b = ba * (bb * bc - bf * bf) - bd * (bd * bc - bf * be) + be * (bd * bf - bb * be)
    r = max(-1.0, min(1.0, det_b / 2.0))
    phi = math.acos(r) / 3.0
    e1 = q + 2.0 * p * math.cos(phi)
    e3 = q + 2.0 * p * math.cos(phi + 2.0 * math.pi / 3.0)
    e2 = 3.0 * q - e1 - e3
    s = sorted((e1, e2, e3))
    return (s[0], s[1], s[2])


# ------------------------------------------------------------------------ meshes
def _inside(path: str, root: str) -> bool:
    return path == root or path.startswith(root.rstrip(os.sep) + os.sep)


def resolve_mesh(
    uri: str,
    *,
    package_dirs: Sequence[str | os.PathLike[str]] = (),
    mesh_root: str | os.PathLike[str] | None = None,
) -> Path:
    """Resolve a mesh/texture ``filename`` to a regular file inside an allowed root.

    Args:
        uri: The ``filename`` attribute (``package://pkg/path`` or a relative path).
        package_dirs: Directories ``package://`` URIs resolve in (``<dir>/pkg/path``).
        mesh_root: Directory relative paths resolve against (the URDF's directory).

    Returns:
        The real path of the file.

    Raises:
        UrdfError: Refused scheme or absolute path, an escape out of the root, a missing,
            non-regular or too large file. (The caller adds the element and line.)

    """
    if not uri or not uri.strip():
        raise UrdfError("empty file name")
    scheme = _SCHEME.match(uri)
    candidates: list[tuple[str, str]] = []  # (root, joined path)
    if scheme and scheme.group(1).lower() == "package" and uri[8:10] == "//":
        # Pinocchio also accepts package:///pkg/path (it joins "<dir>/" + "/pkg/path").
        rest = uri[10:].lstrip("/")
        pkg = rest.split("/", 1)[0]
        if not pkg or "/" not in rest or pkg in (".", ".."):
            raise UrdfError(f"package URI {uri!r} must be package://<package>/<path>")
        if not package_dirs:
            raise _MeshMissing(
                f"{uri!r}: no package directories are known for this source (URDF text or "
                "file without package_dirs); package:// meshes cannot be resolved"
            )
        candidates = [
            (os.path.realpath(os.fspath(d)), os.path.join(os.fspath(d), rest)) for d in package_dirs
        ]
    elif scheme:
        raise UrdfError(
            f"{uri!r}: URI scheme {scheme.group(1)!r} is refused; use package://<package>/"
            "<path> or a path relative to the URDF file"
        )
    elif os.path.isabs(uri) or uri.startswith("~"):
        raise UrdfError(f"{uri!r}: absolute paths are refused; use a path relative to the URDF")
    else:
        if mesh_root is None:
            raise _MeshMissing(
                f"{uri!r}: relative mesh path but no mesh root (URDF given as text); load the "
                "URDF from its file so relative paths resolve next to it"
            )
        root = os.fspath(mesh_root)
        candidates = [(os.path.realpath(root), os.path.join(root, uri))]
    last: UrdfError | None = None
    for root_real, joined in candidates:
        real = os.path.realpath(joined)
        if not _inside(real, root_real):
            raise UrdfError(f"{uri!r} resolves to {real!r}, outside the allowed root {root_real!r}")
        try:
            st = os.stat(real)
        except OSError:
            last = _MeshMissing(f"{uri!r}: file {real!r} does not exist")
            continue
        if not stat.S_ISREG(st.st_mode):
            raise UrdfError(f"{uri!r}: {real!r} is not a regular file")
        if st.st_size > MAX_MESH_BYTES:
            raise UrdfError(
                f"{uri!r}: {real!r} has {st.st_size} bytes; the cap is {MAX_MESH_BYTES}"
            )
        return Path(real)
    assert last is not None
    raise last


# ------------------------------------------------------------------------ the gate
def check_urdf(
    text: str | bytes,
    *,
    package_dirs: Iterable[str | os.PathLike[str]] = (),
    mesh_root: str | os.PathLike[str] | None = None,
    check_meshes: bool = True,
    lenient: bool = False,
) -> GateResult:
    """Check a URDF document; raise :class:`UrdfError` on the first problem.

    See the module docstring for the full list of checks.

    Args:
        text: The URDF document (str, or bytes in UTF-8).
        package_dirs: Directories ``package://pkg/...`` meshes may resolve into.
        mesh_root: Directory relative mesh paths resolve against (``None`` for URDF text:
            relative mesh paths are then refused).
        check_meshes: Whether to resolve and check mesh/texture files (keep ``True``; only
            tools that never touch geometry may turn it off).
        lenient: Kinematics mode: a mesh that cannot be found (missing file, unknown package)
            and a physically implausible inertial (indefinite, massless moving link, zero
            inertia, triangle inequality) are recorded in ``missing_meshes`` /
            ``inertia_defects`` instead of raised. Refused meshes (schemes, absolute paths,
            escapes, non-regular or huge files) and nonsense (negative mass, NaN, missing
            entries, malformed XML ...) are refused in both modes.

    Returns:
        A :class:`GateResult` (shared between calls with the same text when the document
        references no files: the generated URDFs are loaded often; do not modify ``root``).

    Raises:
        UrdfError: Naming the element, attribute, value and line of the problem.

    """
    key = (lenient, text)
    if isinstance(text, str) and len(text) <= _CACHE_MAX_CHARS:
        cached = _CACHE.get(key)
        if cached is not None:
            return cached
    result = _check(text, tuple(package_dirs), mesh_root, check_meshes, lenient)
    if (
        isinstance(text, str)
        and len(text) <= _CACHE_MAX_CHARS
        and not result.meshes
        and (not result.missing_meshes)
        and (check_meshes or not any(True for _ in result.root.iter("mesh", "texture")))
    ):
        # Without file references the verdict depends on the text alone: remember it.
        if len(_CACHE) >= _CACHE_SIZE:
            _CACHE.pop(next(iter(_CACHE)))
        _CACHE[key] = result
    return result


def _check(
    text: str | bytes,
    package_dirs: tuple[str | os.PathLike[str], ...],
    mesh_root: str | os.PathLike[str] | None,
    check_meshes: bool,
    lenient: bool = False,
) -> GateResult:
    defects: list[tuple[str, str]] | None = [] if lenient else None
    root = _parse(text)
    if root.tag != "robot":
        raise UrdfError(f"URDF line {root.sourceline}: root element <{root.tag}>; <robot> required")
    robot_name = root.get("name")
    if robot_name is None or not robot_name.strip():
        raise _error(root, "name", robot_name, "<robot> needs a non-empty name")
    links = root.findall("link")
    if not links:
        raise UrdfError("URDF <robot> has no <link>; at least one link is required")
    if len(links) > MAX_LINKS:
        raise UrdfError(
            f"URDF <robot> has {len(links)} links; the cap is {MAX_LINKS} (Pinocchio crashes on "
            "very long chains)"
        )
    version = root.get("version")
    if version is not None and not _VERSION.match(version):
        raise _error(root, "version", version, "URDF version must be 1.0, 1.1 or 1.2")
    _check_numbers(root)
    _check_materials_and_geometry(root)

    link_el: dict[str, etree._Element] = {}
    for link in links:
        name = _name(link, "link")
        if name in link_el:
            raise _error(
                link,
                "name",
                name,
                f"duplicate link name (first at line "
                f"{link_el[name].sourceline}); link names must be unique",
            )
        link_el[name] = link

    joint_el: dict[str, etree._Element] = {}
    parent_of: dict[str, str] = {}  # child link -> joint name
    children: dict[str, list[str]] = {n: [] for n in link_el}
    for joint in root.findall("joint"):
        name = _name(joint, "joint")
        if name in joint_el:
            raise _error(
                joint,
                "name",
                name,
                f"duplicate joint name (first at line "
                f"{joint_el[name].sourceline}); joint names must be unique",
            )
        joint_el[name] = joint
        jtype = joint.get("type")
        if jtype not in JOINT_TYPES:
            raise _error(joint, "type", jtype, f"joint type must be one of {list(JOINT_TYPES)}")
        ends = []
        for tag in ("parent", "child"):
            el = _single(joint, tag, required=True)
            assert el is not None
            lname = el.get("link")
            if lname not in link_el:
                raise _error(el, "link", lname, f"{tag} link does not exist")
            ends.append(lname)
        parent, child = ends
        if parent == child:
            raise _error(joint, "name", name, f"parent and child are the same link {child!r}")
        if child in parent_of:
            raise _error(
                joint,
                "name",
                name,
                f"link {child!r} is already the child of joint "
                f"{parent_of[child]!r}; a link has at most one parent joint (tree)",
            )
        parent_of[child] = name
        children[parent].append(child)
        _check_joint(joint, jtype)

    dof = sum(_JOINT_DOF[j.get("type")] for j in joint_el.values())
    if dof > MAX_DOF:
        raise UrdfError(
            f"URDF has {dof} degrees of freedom; the cap is {MAX_DOF} (Pinocchio's Data grows as "
            "nv^3: 4 GB at 400)"
        )
    for joint in joint_el.values():
        mimic = joint.find("mimic")
        if mimic is not None:
            target = mimic.get("joint")
            if target not in joint_el or target == joint.get("name"):
                raise _error(mimic, "joint", target, "mimic must name another existing joint")

    roots = [n for n in link_el if n not in parent_of]
    if len(roots) != 1:
        if not roots:
            raise UrdfError(
                "URDF has no root link (every link is a child): the joints form a cycle"
            )
        raise UrdfError(
            f"URDF has {len(roots)} root links {roots[:10]}; exactly one is required "
            "(connect them with joints)"
        )
    # Reachability from the root (iterative; rejects cycles not containing the root).
    seen = {roots[0]}
    stack = [roots[0]]
    while stack:
        for c in children[stack.pop()]:
            if c not in seen:
                seen.add(c)
                stack.append(c)
    if len(seen) != len(link_el):
        lost = [n for n in link_el if n not in seen]
        raise _error(
            link_el[lost[0]],
            "name",
            lost[0],
            f"link not reachable from the root {roots[0]!r}: joints form a cycle",
        )

    # Masses: each link's inertial, then each moving body (child of a non-fixed joint plus
    # its fixed-joint descendants, as Pinocchio merges them) must carry mass and inertia.
    inertials = {n: _link_inertial(el, defects) for n, el in link_el.items()}
    fixed_children: dict[str, list[tuple[str, etree._Element]]] = {n: [] for n in link_el}
    for child, jname in parent_of.items():
        joint = joint_el[jname]
        if joint.get("type") == "fixed":
            fixed_children[joint.find("parent").get("link")].append((child, joint))
    for child, jname in parent_of.items():
        if joint_el[jname].get("type") != "fixed":
            _check_moving_body(jname, child, link_el, inertials, fixed_children, defects)

    meshes: list[tuple[str, Path]] = []
    missing: list[tuple[str, str]] = []
    if check_meshes:
        dirs = package_dirs
        for node in root.iter("mesh", "texture"):
            uri = node.get("filename")
            if node.tag == "texture" and uri is None:
                continue
            try:
                path = resolve_mesh(uri or "", package_dirs=dirs, mesh_root=mesh_root)
            except _MeshMissing as exc:
                if not lenient:
                    raise _error(node, "filename", uri, str(exc)) from None
                missing.append((uri or "", f"line {node.sourceline}: {exc}"))
                continue
            except UrdfError as exc:
                raise _error(node, "filename", uri, str(exc)) from None
            meshes.append((uri or "", path))
    return GateResult(
        root=root,
        links=tuple(link_el),
        joints=tuple(joint_el),
        root_link=roots[0],
        meshes=tuple(meshes),
        missing_meshes=tuple(missing),
        inertia_defects=tuple(defects or ()),
    )


def _check_rgba(color: etree._Element) -> None:
    rgba = _numbers(color, "rgba", 4, None)
    if not rgba:
        raise _error(color, "rgba", None, "<color> needs rgba (four numbers in [0, 1])")
    if not all(0.0 <= c <= 1.0 for c in rgba):
        raise _error(color, "rgba", color.get("rgba"), "colour components must be in [0, 1]")


def _check_materials_and_geometry(root: etree._Element) -> None:
    """Materials (named, unique, colours in [0, 1]) and visual/collision geometry."""
    defined: dict[str, etree._Element] = {}
    for mat in root.findall("material"):
        name = mat.get("name")
        if name is None or not name.strip():
            raise _error(mat, "name", name, "every <material> needs a non-empty name")
        if name in defined:
            raise _error(
                mat,
                "name",
                name,
                f"duplicate material name (first at line "
                f"{defined[name].sourceline}); material names must be unique",
            )
        defined[name] = mat
        color = _single(mat, "color", required=False)
        if color is not None:
            _check_rgba(color)
    for link in root.findall("link"):
        for part in ("visual", "collision"):
            for el in link.findall(part):
                _single(el, "origin", required=False)
                geometry = _single(el, "geometry", required=True)
                assert geometry is not None
                shapes = [c for c in geometry if isinstance(c.tag, str)]
                if len(shapes) != 1:
                    raise _error(
                        geometry,
                        None,
                        None,
                        f"<geometry> must hold exactly one shape "
                        f"({', '.join(_SHAPES)}), found {len(shapes)}",
                    )
                shape = shapes[0]
                if shape.tag not in _SHAPES:
                    raise _error(
                        shape,
                        None,
                        None,
                        f"unknown shape <{shape.tag}>; URDF shapes are {', '.join(_SHAPES)}",
                    )
                for attr in _SHAPES[shape.tag]:
                    if shape.get(attr) is None:
                        raise _error(shape, attr, None, f"<{shape.tag} {attr}> is required")
                mat = _single(el, "material", required=False) if part == "visual" else None
                if mat is None:
                    continue
                if mat.get("name") is None:  # urdfdom drops the visual; "" is accepted
                    raise _error(mat, "name", None, "a visual <material> needs a name attribute")
                color = _single(mat, "color", required=False)
                if color is not None:
                    _check_rgba(color)


def _check_joint(joint: etree._Element, jtype: str) -> None:
    seen: set[str] = set()
    for sub in joint:
        tag = sub.tag
        if tag in seen and tag in _JOINT_CHILDREN:
            raise _error(sub, None, None, f"<{tag}> given more than once; at most once")
        seen.add(tag)
    axis = joint.find("axis")
    if axis is not None and jtype not in ("fixed", "floating"):
        xyz = _numbers(axis, "xyz", 3, None)
        if xyz and math.fsum(v * v for v in xyz) <= 1e-24:
            raise _error(
                axis,
                "xyz",
                axis.get("xyz"),
                "joint axis has zero length; a non-zero vector is required",
            )
    limit = joint.find("limit")
    if jtype in ("revolute", "prismatic"):
        if limit is None:
            raise _error(
                joint, "type", jtype, "a revolute or prismatic joint needs <limit> (URDF spec)"
            )
        for attr in ("effort", "velocity"):
            if limit.get(attr) is None:
                raise _error(limit, attr, None, f"<limit {attr}> is required for {jtype} joints")
    if limit is not None:
        lower = _number(limit, "lower", 0.0)
        upper = _number(limit, "upper", 0.0)
        if jtype in ("revolute", "prismatic") and lower > upper:
            raise _error(
                limit,
                "lower",
                limit.get("lower"),
                f"lower > upper={limit.get('upper')!r}; lower <= upper required",
            )
    safety = joint.find("safety_controller")
    if safety is not None and safety.get("k_velocity") is None:
        raise _error(safety, "k_velocity", None, "<safety_controller k_velocity> is required")
