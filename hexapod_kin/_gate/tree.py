"""The verdict (:func:`check_urdf`): structure, joints, then the other checks."""

from __future__ import annotations

import math
import os
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from lxml import etree

from .._fields import fields_dict
from ..exceptions import UrdfError
from .inertials import check_gyration, check_moving_body, link_inertial, robot_size
from .limits import JOINT_CHILDREN, JOINT_DOF, JOINT_TYPES, MAX_DOF, MAX_LINKS, URDF_VERSION
from .meshes import (
    MeshEmpty,
    MeshMissing,
    MeshOutside,
    check_materials_and_geometry,
    resolve_mesh,
)
from .parse import (
    check_numbers,
    element_name,
    error_at,
    number_of,
    numbers_of,
    origin_of,
    parse_urdf,
    single,
    unique,
)


@dataclass(frozen=True)
class GateResult:
    """What the gate learned about a URDF that passed (names in document order).

    Attributes:
        root: The parsed ``<robot>`` element (lxml); ``links``, ``joints``: the names;
            ``root_link``: the root link's name.
        meshes: The resolved mesh and texture files, ``(uri, path)``.
        missing_meshes: Lenient mode: ``(uri, reason)`` of files not found (drop their
            elements); ``inertia_defects``: ``(link, defect)`` of implausible inertials.
        repairs: Harmless defects mended in lenient mode, one message each (a nameless
            ``<robot>`` named ``"robot"``; a ``<mimic>`` of no joint dropped).
        text: The mended document when there are :attr:`repairs` (for Pinocchio), else None.

    """

    root: etree._Element
    links: tuple[str, ...] = ()
    joints: tuple[str, ...] = ()
    root_link: str = ""
    meshes: tuple[tuple[str, Path], ...] = ()
    missing_meshes: tuple[tuple[str, str], ...] = ()
    inertia_defects: tuple[tuple[str, str], ...] = ()
    repairs: tuple[str, ...] = ()
    text: str | None = None

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready fields (the parsed element and the mended text left out)."""
        return {
            **fields_dict(self, "links", "joints", "root_link"),
            "meshes": [[uri, str(path)] for uri, path in self.meshes],
            "missing_meshes": [list(m) for m in self.missing_meshes],
            "inertia_defects": [list(d) for d in self.inertia_defects],
            **fields_dict(self, "repairs"),
        }


#: Documents that passed and reference no files, by text (generated URDFs load again and again).
_CACHE: dict[tuple[bool, str | bytes], GateResult] = {}
_CACHE_SIZE = 32
_CACHE_MAX_CHARS = 1_000_000


# ------------------------------------------------------------------------ the gate
def check_urdf(
    text: str | bytes,
    *,
    package_dirs: Iterable[str | os.PathLike[str]] = (),
    mesh_root: str | os.PathLike[str] | None = None,
    lenient: bool = False,
) -> GateResult:
    """Check a URDF document (str, or UTF-8 bytes): the rules of :mod:`hexapod_kin._gate`.

    ``mesh_root`` None (URDF text) refuses relative mesh paths. The :class:`GateResult` is
    shared by calls with the same text naming no files; the first problem, a
    :class:`UrdfError` naming element, attribute, value and line.
    """
    key = (lenient, text)
    cacheable = isinstance(text, str) and len(text) <= _CACHE_MAX_CHARS
    cached = _CACHE.get(key) if cacheable else None
    if cached is not None:
        return cached
    result = _check(text, tuple(package_dirs), mesh_root, lenient)
    if cacheable and not result.meshes and not result.missing_meshes:
        if len(_CACHE) >= _CACHE_SIZE:
            _CACHE.pop(next(iter(_CACHE)))
        _CACHE[key] = result
    return result


def _check(
    text: str | bytes,
    package_dirs: tuple[str | os.PathLike[str], ...],
    mesh_root: str | os.PathLike[str] | None,
    lenient: bool = False,
) -> GateResult:
    defects: list[tuple[str, str]] | None = [] if lenient else None
    root = parse_urdf(text)
    if root.tag != "robot":
        raise UrdfError(f"URDF line {root.sourceline}: root element <{root.tag}>; <robot> required")
    repairs: list[str] = []

    def mend(el: etree._Element, problem: str, attr: str, value: Any, done: str) -> None:
        """Lenient: say what is mended (the caller mends it); else the error."""
        if not lenient:
            raise error_at(el, problem, attr, value)
        repairs.append(str(error_at(el, f"{problem}: {done}", attr, value)))

    robot_name = root.get("name")
    if robot_name is None or not robot_name.strip():
        mend(root, "<robot> needs a non-empty name", "name", robot_name, "named 'robot'")
        root.set("name", "robot")
    links = root.findall("link")
    if not links:
        hint = ""
        if any("xacro" in (uri or "") for uri in root.nsmap.values()):
            hint = " (it declares the xacro namespace: a macro file rendered without a call?)"
        raise UrdfError(f"URDF <robot> has no <link>; at least one link is required{hint}")
    if len(links) > MAX_LINKS:
        raise UrdfError(
            f"URDF <robot> has {len(links)} links; the cap is {MAX_LINKS} (Pinocchio crashes on "
            "very long chains)"
        )
    version = root.get("version")
    if version is not None and not URDF_VERSION.match(version):
        raise error_at(root, "URDF version must be 1.0, 1.1 or 1.2", "version", version)
    check_numbers(root)
    check_materials_and_geometry(root)

    link_el: dict[str, etree._Element] = {}
    for link in links:
        unique(link_el, link, element_name(link, "link"), "link")

    joint_el: dict[str, etree._Element] = {}
    parent_of: dict[str, str] = {}  # child link -> joint name
    children: dict[str, list[str]] = {n: [] for n in link_el}
    for joint in root.findall("joint"):
        name = element_name(joint, "joint")
        unique(joint_el, joint, name, "joint")
        jtype = joint.get("type")
        if jtype not in JOINT_TYPES:
            raise error_at(joint, f"joint type must be one of {list(JOINT_TYPES)}", "type", jtype)
        ends = []
        for tag in ("parent", "child"):
            el = single(joint, tag, required=True)
            assert el is not None
            lname = el.get("link")
            if lname not in link_el:
                raise error_at(el, f"{tag} link does not exist", "link", lname)
            ends.append(lname)
        parent, child = ends
        if parent == child:
            raise error_at(joint, f"parent and child are the same link {child!r}", "name", name)
        if child in parent_of:
            why = f"link {child!r} is already the child of joint {parent_of[child]!r}"
            raise error_at(
                joint, f"{why}; a link has at most one parent joint (tree)", "name", name
            )
        parent_of[child] = name
        children[parent].append(child)
        _check_joint(joint, jtype)

    dof = sum(JOINT_DOF[j.get("type")] for j in joint_el.values())
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
                done = f"<mimic> dropped, the joint {joint.get('name')!r} moves on its own"
                mend(mimic, "mimic must name another existing joint", "joint", target, done)
                joint.remove(mimic)

    roots = [n for n in link_el if n not in parent_of]
    if not roots:
        raise UrdfError("URDF has no root link (every link is a child): the joints form a cycle")
    if len(roots) > 1:
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
        why = f"link not reachable from the root {roots[0]!r}: joints form a cycle"
        raise error_at(link_el[lost[0]], why, "name", lost[0])

    # masses: each link's inertial, then each moving body as Pinocchio merges it
    inertials = {n: link_inertial(el, defects) for n, el in link_el.items()}
    fixed_children: dict[str, list[tuple[str, etree._Element]]] = {n: [] for n in link_el}
    for child, jname in parent_of.items():
        joint = joint_el[jname]
        if joint.get("type") == "fixed":
            fixed_children[joint.find("parent").get("link")].append((child, joint))
    for child, jname in parent_of.items():
        if joint_el[jname].get("type") != "fixed":
            check_moving_body(jname, child, link_el, inertials, fixed_children, defects)
    size = robot_size([origin_of(joint)[1] for joint in joint_el.values()])
    for name, el in link_el.items():
        check_gyration(name, el, inertials[name], size, defects)

    meshes: list[tuple[str, Path]] = []
    missing: list[tuple[str, str]] = []
    for node in root.iter("mesh", "texture"):
        uri = node.get("filename")
        if node.tag == "texture" and uri is None:
            continue
        try:
            path = resolve_mesh(uri or "", package_dirs=package_dirs, mesh_root=mesh_root)
        except (MeshMissing, MeshOutside, MeshEmpty) as exc:
            if not lenient:
                raise error_at(node, str(exc), "filename", uri) from None
            # "line N: 'uri': refused|not found|empty: why" (parsed by messages.mesh_lines)
            missing.append((uri or "", f"line {node.sourceline}: {exc}"))
            continue
        except UrdfError as exc:
            raise error_at(node, str(exc), "filename", uri) from None
        meshes.append((uri or "", path))
    return GateResult(
        root=root,
        links=tuple(link_el),
        joints=tuple(joint_el),
        root_link=roots[0],
        meshes=tuple(meshes),
        missing_meshes=tuple(missing),
        inertia_defects=tuple(defects or ()),
        repairs=tuple(repairs),
        text=etree.tostring(root, encoding="unicode") if repairs else None,
    )


def _check_joint(joint: etree._Element, jtype: str) -> None:
    seen: set[str] = set()
    for sub in joint:
        tag = sub.tag
        if tag in seen and tag in JOINT_CHILDREN:
            raise error_at(sub, f"<{tag}> given more than once; at most once")
        seen.add(tag)
    axis = joint.find("axis")
    if axis is not None and jtype not in ("fixed", "floating"):
        xyz = numbers_of(axis, "xyz", 3, None)
        if xyz and math.fsum(v * v for v in xyz) <= 1e-24:
            why = "joint axis has zero length; a non-zero vector is required"
            raise error_at(axis, why, "xyz", axis.get("xyz"))
    limit = joint.find("limit")
    if jtype in ("revolute", "prismatic"):
        if limit is None:
            raise error_at(
                joint, "a revolute or prismatic joint needs <limit> (URDF spec)", "type", jtype
            )
        for attr in ("effort", "velocity"):
            if limit.get(attr) is None:
                raise error_at(limit, f"<limit {attr}> is required for {jtype} joints", attr)
    if limit is not None:
        lower = number_of(limit, "lower", 0.0)
        upper = number_of(limit, "upper", 0.0)
        if jtype in ("revolute", "prismatic") and lower > upper:
            why = f"lower > upper={limit.get('upper')!r}; lower <= upper required"
            raise error_at(limit, why, "lower", limit.get("lower"))
    safety = joint.find("safety_controller")
    if safety is not None and safety.get("k_velocity") is None:
        raise error_at(safety, "<safety_controller k_velocity> is required", "k_velocity")
