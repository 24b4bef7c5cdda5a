"""Parameter tables → a parametric xacro document (``<xacro:macro>`` per leg family).

A ``<xacro:property>`` per dimension and a macro per distinct chain (the hexapod's six legs
share one), instantiated once per leg; expanded it gives :func:`hexapod_kin.urdf.to_urdf`'s
model. Macro parameters: ``alpha<j> d<j> theta<j> r<j>`` per row (1-based),
``<joint>_lower/_upper/_velocity/_effort/_damping/_friction``, ``<link>_mass`` (``_cx .. _izz``
for given inertials; else rods), ``link_radius``, ``base_x .. base_yaw``/``tool_x .. tool_yaw``;
each defaults to the global property of its name (``name:=^``). With several families the
globals are prefixed by the family and every call passes them.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .._io import atomic_write
from ..exceptions import UrdfError
from ..params import Chain, Hexapod, matrix_to_rpy
from ..urdf import fixed_joint
from ._common import COLORS, comment, header_lines, ident, need, num, table_of

__all__ = ["to_xacro", "write_xacro", "expand_xacro"]

_NS = "http://www.ros.org/wiki/xacro"

#: The helper macros (``hk_`` prefix) every document defines, one string per line.
_HELPERS = Path(__file__).with_name("templates").joinpath("xacro_helpers.xml")


@dataclass
class _Family:
    """One leg family: a chain, its macro name and its parameters (name → value text)."""

    chain: Chain
    macro: str
    params: dict[str, str] = field(default_factory=dict)
    notes: dict[str, str] = field(default_factory=dict)
    joint_ids: list[str] = field(default_factory=list)
    link_ids: list[str] = field(default_factory=list)


def _unique_ids(names: tuple[str, ...], fallback: str, reserved: set[str]) -> list[str]:
    ids = [ident(n) for n in names]
    if len(set(ids)) != len(ids) or set(ids) & reserved:
        ids = [f"{fallback}{i + 1}" for i in range(len(names))]
    return ids


def _pose_params(prefix: str, t: np.ndarray) -> dict[str, str]:
    rpy = matrix_to_rpy(t[:3, :3])
    keys = ("x", "y", "z", "roll", "pitch", "yaw")
    return {f"{prefix}_{k}": num(v) for k, v in zip(keys, (*t[:3, 3], *rpy))}


def _family(chain: Chain, macro: str) -> _Family:
    fam = _Family(chain=chain, macro=macro)
    rows = chain.rows
    reserved = {f"{c}{j}" for c in ("alpha", "d", "theta", "r") for j in range(1, len(rows) + 1)}
    fam.joint_ids = _unique_ids(tuple(chain.joint_names or ()), "joint", reserved)
    fam.link_ids = _unique_ids(tuple(chain.link_names or ()), "link", reserved)
    p = fam.params
    links = chain.link_names or ()
    for j, row in enumerate(rows, start=1):
        prev = chain.base if j == 1 else links[j - 2]
        fam.notes[f"alpha{j}"] = (
            f"row {j} ({row.sigma}): frame {j} = link {links[j - 1]}; alpha about x{j - 1}, "
            f"d along x{j - 1} (length of {prev}), theta about z{j}, r along z{j}"
        )
        for key, value in (("alpha", row.alpha), ("d", row.d), ("theta", row.theta), ("r", row.r)):
            p[f"{key}{j}"] = num(value)
    damping, friction = chain.joint_damping(), chain.joint_friction()
    for k, (jid, lim) in enumerate(zip(fam.joint_ids, chain.limits or ())):
        fam.notes[f"{jid}_lower"] = (
            f"joint {(chain.joint_names or ())[k]}: limits [rad or m], velocity, effort, "
            "damping, friction"
        )
        values = (lim.lower, lim.upper, lim.velocity, lim.effort, damping[k], friction[k])
        for key, value in zip(
            ("lower", "upper", "velocity", "effort", "damping", "friction"), values
        ):
            p[f"{jid}_{key}"] = num(value)
    for j, lid in enumerate(fam.link_ids):
        if j == 0:
            fam.notes[f"{lid}_mass"] = "link masses [kg] (default links: rods of link_radius)"
        inn = chain.link_inertial(j)
        p[f"{lid}_mass"] = num(inn.mass)
        keys = ("cx", "cy", "cz", "ixx", "iyy", "izz", "ixy", "ixz", "iyz")
        if not _default_inertial(chain, j):
            p.update({f"{lid}_{key}": num(v) for key, v in zip(keys, (*inn.com, *inn.inertia))})
    p["link_radius"] = num(chain.link_radius)
    if chain.base_pose is not None:
        p.update(_pose_params("base", chain.base_pose.matrix))
    if chain.tool is not None:
        p.update(_pose_params("tool", chain.tool.matrix))
    return fam


def _pose_origin(name: str) -> str:
    """The ``<origin>`` of the pose properties ``<name>_x .. <name>_yaw``."""
    xyz = " ".join(f"${{{name}_{k}}}" for k in ("x", "y", "z"))
    rpy = " ".join(f"${{{name}_{k}}}" for k in ("roll", "pitch", "yaw"))
    return f'<origin xyz="{xyz}" rpy="{rpy}"/>'


def _default_inertial(chain: Chain, j: int) -> bool:
    return chain.inertials is None or chain.inertials[j] is None


def _next_origin(j: int, n_rows: int) -> tuple[str, str, str]:
    """Expressions of the origin of frame ``j + 1`` in frame ``j`` (1-based ``j``), at q = 0."""
    if j >= n_rows:
        return ("0", "0", "0")
    k = j + 1
    return (f"${{d{k}}}", f"${{-r{k}*sin(alpha{k})}}", f"${{r{k}*cos(alpha{k})}}")


def _macro_lines(fam: _Family, forward: bool) -> list[str]:
    chain = fam.chain
    rows = chain.rows
    pad = "    "
    fixed_params = "prefix:='' parent:='' xyz:='0 0 0' rpy:='0 0 0'"
    dims = " ".join(f"{k}:=^" if forward else k for k in fam.params)
    out = [
        "  " + comment(f"leg family {fam.macro}: {chain.description or chain.name}"),
        f'  <xacro:macro name="{fam.macro}" params="{fixed_params} {dims}">',
    ]
    base = f"${{prefix}}{chain.base}"
    out += [
        f"{pad}<xacro:if value=\"${{parent == ''}}\">",
        f'{pad}  <link name="{base}">',
        f"{pad}    <visual>",
        f'{pad}      <origin xyz="0 0 0" rpy="0 0 0"/>',
        f'{pad}      <geometry><box size="${{6*link_radius}} ${{6*link_radius}} '
        f'${{2*link_radius}}"/></geometry>',
        f'{pad}      <material name="base"/>',
        f"{pad}    </visual>",
        f"{pad}  </link>",
        f"{pad}</xacro:if>",
        f"{pad}<xacro:unless value=\"${{parent == ''}}\">",
        *fixed_joint(
            pad + "  ", "${prefix}mount", "${parent}", base, '<origin xyz="${xyz}" rpy="${rpy}"/>'
        ),
        f'{pad}  <link name="{base}"/>',
        f"{pad}</xacro:unless>",
    ]
    prev = base
    if chain.base_pose is not None:
        frame0 = f"${{prefix}}{chain.base}_frame0"
        out += [
            *fixed_joint(
                pad, f"${{prefix}}{chain.name}_base_offset", prev, frame0, _pose_origin("base")
            ),
            f'{pad}<link name="{frame0}"/>',
        ]
        prev = frame0
    link_names = chain.link_names or ()
    joint_names = chain.joint_names or ()
    k = 0
    for j0, row in enumerate(rows):
        j = j0 + 1
        child = f"${{prefix}}{link_names[j0]}"
        lid = fam.link_ids[j0]
        out.append(pad + comment(f"row {j}: sigma={row.sigma}"))
        origin = (
            f'<xacro:hk_khalil_origin alpha="${{alpha{j}}}" d="${{d{j}}}" '
            f'theta="${{theta{j}}}" r="${{r{j}}}"/>'
        )
        if row.is_joint:
            jid = fam.joint_ids[k]
            out += [
                f'{pad}<joint name="${{prefix}}{joint_names[k]}" type="{row.sigma}">',
                f'{pad}  <parent link="{prev}"/>',
                f'{pad}  <child link="{child}"/>',
                f"{pad}  {origin}",
                f'{pad}  <axis xyz="0 0 1"/>',
                f'{pad}  <limit lower="${{{jid}_lower}}" upper="${{{jid}_upper}}" '
                f'effort="${{{jid}_effort}}" velocity="${{{jid}_velocity}}"/>',
                f'{pad}  <dynamics damping="${{{jid}_damping}}" friction="${{{jid}_friction}}"/>',
                f"{pad}</joint>",
            ]
            k += 1
        else:
            out += fixed_joint(pad, f"${{prefix}}{link_names[j0]}_fixed", prev, child, origin)
        out.append(f'{pad}<link name="{child}">')
        vx, vy, vz = _next_origin(j, len(rows))
        if _default_inertial(chain, j0):
            out.append(
                f'{pad}  <xacro:hk_rod_inertial mass="${{{lid}_mass}}" radius="${{link_radius}}" '
                f'vx="{vx}" vy="{vy}" vz="{vz}"/>'
            )
        else:
            out += [
                f"{pad}  <inertial>",
                f'{pad}    <origin xyz="${{{lid}_cx}} ${{{lid}_cy}} ${{{lid}_cz}}" rpy="0 0 0"/>',
                f'{pad}    <mass value="${{{lid}_mass}}"/>',
                f'{pad}    <inertia ixx="${{{lid}_ixx}}" ixy="${{{lid}_ixy}}" '
                f'ixz="${{{lid}_ixz}}" iyy="${{{lid}_iyy}}" iyz="${{{lid}_iyz}}" '
                f'izz="${{{lid}_izz}}"/>',
                f"{pad}  </inertial>",
            ]
        if j == len(rows):
            out.append(f'{pad}  <xacro:hk_ball radius="${{1.5*link_radius}}" material="foot"/>')
        else:
            if row.is_joint:
                out.append(f'{pad}  <xacro:hk_joint_marker radius="${{link_radius}}"/>')
            out.append(
                f'{pad}  <xacro:hk_segment vx="{vx}" vy="{vy}" vz="{vz}" '
                f'radius="${{link_radius}}" material="link"/>'
            )
        out.append(f"{pad}</link>")
        prev = child
    if chain.tool is not None:
        t_tool = chain.tool.matrix
        back = -t_tool[:3, :3].T @ t_tool[:3, 3]
        tip = f"${{prefix}}{chain.tip}"
        out += [
            pad + comment("tool frame (its back-pointing visual is drawn for the exported pose)"),
            *fixed_joint(pad, f"{tip}_fixed", prev, tip, _pose_origin("tool")),
            f'{pad}<link name="{tip}">',
            f'{pad}  <xacro:hk_ball radius="${{1.2*link_radius}}" material="foot"/>',
            f'{pad}  <xacro:hk_segment vx="{num(back[0])}" vy="{num(back[1])}" '
            f'vz="{num(back[2])}" radius="${{0.6*link_radius}}" material="link"/>',
            f"{pad}</link>",
        ]
    out.append("  </xacro:macro>")
    return out


def _properties(
    params: dict[str, str], prefix: str = "", notes: dict[str, str] | None = None
) -> list[str]:
    out: list[str] = []
    for k, v in params.items():
        if notes and k in notes:
            out.append("  " + comment(notes[k]))
        out.append(f'  <xacro:property name="{prefix}{k}" value="{v}"/>')
    return out


def _families(chains: list[Chain]) -> list[_Family]:
    fams: list[_Family] = []
    used: set[str] = set()
    for chain in chains:
        if any(f.chain == chain for f in fams):
            continue
        name = ident(chain.name)
        n = 2
        while name in used or name.startswith("hk_"):
            name = f"{ident(chain.name)}_{n}"
            n += 1
        used.add(name)
        fams.append(_family(chain, name))
    return fams


def _document(
    name: str, description: str, header: str | None, props: list[str], body: list[str]
) -> str:
    """The xacro document: header, materials, the properties, the helper macros, ``body``."""
    intro = (
        "Units: SI (m, rad, kg). Link j is Khalil-Kleinfinger frame j. Expand with "
        "`xacro FILE > robot.urdf`: same kinematics and inertials as hexapod-kin urdf."
    )
    lines = [*header_lines("xacro", description, header), comment(intro)]
    lines.append(f'<robot name="{name}" xmlns:xacro="{_NS}">')
    lines += [
        f'  <material name="{m}"><color rgba="{COLORS[m]}"/></material>'
        for m in ("base", "body", "link", "joint", "foot")
    ]
    lines.append("  " + comment("dimensions (SI: m, rad, kg, N, N m, s); edit one number here"))
    lines += props + _HELPERS.read_text(encoding="utf-8").splitlines() + body
    return "\n".join([*lines, "</robot>"]) + "\n"


def _mount_props(legs: tuple[Any, ...]) -> tuple[list[str], dict[str, str]]:
    """Mount properties and the xyz expression per leg (circle form when the legs are on one)."""
    zs = {leg.xyz[2] for leg in legs}
    radius = math.hypot(legs[0].xyz[0], legs[0].xyz[1])
    tol = 1e-12 * max(1.0, radius)
    on_circle = len(zs) == 1 and all(
        abs(radius * math.cos(leg.yaw) - leg.xyz[0]) <= tol
        and abs(radius * math.sin(leg.yaw) - leg.xyz[1]) <= tol
        for leg in legs
    )
    props: list[str] = []
    xyz: dict[str, str] = {}
    if on_circle:
        props.append(f'  <xacro:property name="mount_radius" value="{num(radius)}"/>')
        props.append(f'  <xacro:property name="mount_z" value="{num(legs[0].xyz[2])}"/>')
    for leg in legs:
        lid = ident(leg.name)
        props.append(f'  <xacro:property name="{lid}_yaw" value="{num(leg.yaw)}"/>')
        if on_circle:
            xyz[leg.name] = (
                f"${{mount_radius*cos({lid}_yaw)}} ${{mount_radius*sin({lid}_yaw)}} ${{mount_z}}"
            )
        else:
            for axis, value in zip("xyz", leg.xyz):
                props.append(f'  <xacro:property name="{lid}_{axis}" value="{num(value)}"/>')
            xyz[leg.name] = f"${{{lid}_x}} ${{{lid}_y}} ${{{lid}_z}}"
    return props, xyz


def _robot_doc(robot: Hexapod, leg: str | None, header: str | None) -> str:
    legs = robot.legs if leg is None else (robot.leg(leg),)
    name = robot.name if leg is None else f"{robot.name}_{leg}"
    fams = _families([m.chain for m in legs])
    forward = len(fams) == 1
    keys = ("body_length", "body_width", "body_height", "body_mass")
    lines = _properties({k: num(v) for k, v in zip(keys, (*robot.body_size, robot.body_mass))})
    mount_props, mount_xyz = _mount_props(legs)
    lines += mount_props
    for fam in fams:
        if not forward:
            lines.append("  " + comment(f"leg family {fam.macro}"))
        lines += _properties(fam.params, "" if forward else f"{fam.macro}_", fam.notes)
    body = [line for fam in fams for line in _macro_lines(fam, forward=forward)]
    body += [
        f'  <link name="{robot.body}">',
        "    <inertial>",
        '      <origin xyz="0 0 0" rpy="0 0 0"/>',
        '      <mass value="${body_mass}"/>',
        '      <inertia ixx="${body_mass*(body_width**2 + body_height**2)/12.0}" ixy="0" '
        'ixz="0" iyy="${body_mass*(body_length**2 + body_height**2)/12.0}" iyz="0" '
        'izz="${body_mass*(body_length**2 + body_width**2)/12.0}"/>',
        "    </inertial>",
        '    <xacro:hk_box x="${body_length}" y="${body_width}" z="${body_height}" '
        'material="body"/>',
        "  </link>",
    ]
    for mount in legs:
        fam = next(f for f in fams if f.chain == mount.chain)
        lid = ident(mount.name)
        extra = "" if forward else " " + " ".join(f'{k}="${{{fam.macro}_{k}}}"' for k in fam.params)
        body.append(
            f'  <xacro:{fam.macro} prefix="{mount.name}_" parent="{robot.body}" '
            f'xyz="{mount_xyz[mount.name]}" rpy="0 0 ${{{lid}_yaw}}"{extra}/>'
        )
    return _document(name, robot.description or robot.name, header, lines, body)


def to_xacro(source: Any, *, leg: str | None = None, header: str | None = None) -> str:
    """The ``.urdf.xacro`` text of a source with a parameter table (deterministic).

    ``leg``: a robot's one leg with its mount on the body; ``header``: an extra comment line.

    Raises:
        ParameterError: If ``source`` is of another type or ``leg`` does not fit.

    """
    src = table_of(source, leg)
    if not isinstance(src, Chain):
        return _robot_doc(src, leg, header)
    fam = _families([src])[0]
    body = [*_macro_lines(fam, forward=True), f'  <xacro:{fam.macro} prefix="" parent=""/>']
    props = _properties(fam.params, notes=fam.notes)
    return _document(src.name, src.description or src.name, header, props, body)


def write_xacro(
    source: Any, path: str | os.PathLike[str], *, leg: str | None = None, header: str | None = None
) -> Path:
    """Write :func:`to_xacro` of ``source`` to ``path`` atomically; return the path.

    Raises:
        ParameterError: As :func:`to_xacro`, or when the directory does not exist.

    """
    return atomic_write(path, to_xacro(source, leg=leg, header=header))


def expand_xacro(text: str, mappings: dict[str, str] | None = None) -> str:
    """The URDF of a xacro document, expanded by the ``xacro`` package (``mappings``: its args).

    Raises:
        OptionalDependencyError: If ``xacro`` is not installed.
        UrdfError: If xacro refuses the document.

    """
    xacro = need("xacro")
    try:
        doc = xacro.parse(text)
        xacro.process_doc(doc, mappings=mappings)
    except Exception as exc:  # xacro raises XacroException, expat errors, NameError, ...
        raise UrdfError(f"xacro could not expand the document: {exc}") from None
    return str(doc.toxml())
