"""Parameter tables → deterministic URDF text, written atomically (no Pinocchio here).

Khalil row ``j`` becomes a URDF joint whose ``<origin>`` is ``^{j-1}T_j`` at ``q = 0`` and whose
axis is ``0 0 1``: the URDF link of row ``j`` *is* Khalil frame ``j`` (a fixed row: a fixed
joint). Visuals: a sphere at every joint, a cylinder from each frame's origin to the next, a
sphere at the tip; inertials from the chain (default: rods).

A chain's ``base_pose`` becomes the fixed joint ``<robot>_base_offset`` to the link
``<base>_frame0`` (Khalil frame 0), its ``tool`` the fixed joint ``<tip>_fixed`` to the tool
link ``tip``.
"""

from __future__ import annotations

import math
import os
import re
from pathlib import Path
from typing import Any

import numpy as np

from . import robots
from ._gate.limits import LIMIT_TAGS, MAX_ABS, MAX_ABS_LIMIT, NUMERIC
from ._io import atomic_write
from ._version import __version__
from .exceptions import ParameterError, SourceError, choices, did_you_mean
from .params import Chain, Hexapod, matrix_to_rpy, rpy_to_matrix
from .tables import read_table

__all__ = ["table_of", "to_urdf", "write_urdf", "matrix_to_rpy", "rpy_to_matrix"]

#: Material colours (RGBA) of the generated robots (the exporters in :mod:`hexapod_kin.export`
#: use the same). ``num``, ``vec`` and ``comment`` are the number and comment text they share.
COLORS = {
    "body": "0.25 0.30 0.35 1",
    "link": "0.85 0.55 0.15 1",
    "joint": "0.20 0.45 0.80 1",
    "foot": "0.80 0.15 0.15 1",
    "base": "0.50 0.50 0.50 1",
}


def num(x: float) -> str:
    """Shortest text that reads back as the same float (``repr``), ``0`` for zero."""
    x = float(x)
    if abs(x) < 1e-300 or x == 0.0:
        return "0"
    text = repr(x)
    return text[:-2] if text.endswith(".0") else text


def vec(v: np.ndarray | tuple[float, ...]) -> str:
    """Space-separated :func:`num` of each value."""
    return " ".join(num(c) for c in v)


def _origin(t: np.ndarray) -> str:
    rpy = matrix_to_rpy(t[:3, :3])
    return f'<origin xyz="{vec(t[:3, 3])}" rpy="{vec(rpy)}"/>'


def fixed_joint(pad: str, name: str, parent: str, child: str, origin: str) -> list[str]:
    """The lines of a fixed joint ``name`` from ``parent`` to ``child``, indented by ``pad``."""
    return [
        f'{pad}<joint name="{name}" type="fixed">',
        f'{pad}  <parent link="{parent}"/>',
        f'{pad}  <child link="{child}"/>',
        f"{pad}  {origin}",
        f"{pad}</joint>",
    ]


def _z_to(v: np.ndarray) -> tuple[float, float, float]:
    """Rpy of a rotation taking +z onto the unit vector ``v``."""
    z = v / np.linalg.norm(v)
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    return matrix_to_rpy(np.column_stack([x, y, z]))


def comment(text: str) -> str:
    """An XML comment of ``text`` (one line; ``--`` is not allowed inside a comment)."""
    clean = text.replace("\n", " ").strip()
    while "--" in clean:
        clean = clean.replace("--", "- -")
    return f"<!-- {clean} -->"


_ORIGIN0 = '<origin xyz="0 0 0" rpy="0 0 0"/>'


def _visual(pad: str, geometry: str, material: str, origin: str = _ORIGIN0) -> list[str]:
    """The lines of a ``<visual>`` (``geometry``: the element inside ``<geometry>``)."""
    return [f"{pad}<visual>", f"{pad}  {origin}", f"{pad}  <geometry>{geometry}</geometry>",
            f'{pad}  <material name="{material}"/>', f"{pad}</visual>"]  # fmt: skip


def _material(name: str) -> str:
    return f'<material name="{name}"><color rgba="{COLORS[name]}"/></material>'


def _inertial_xml(indent: str, mass: float, com: Any, inertia: Any) -> list[str]:
    """The lines of an ``<inertial>`` (``inertia``: ixx, iyy, izz, ixy, ixz, iyz)."""
    ixx, iyy, izz, ixy, ixz, iyz = inertia
    return [
        f"{indent}<inertial>",
        f'{indent}  <origin xyz="{vec(com)}" rpy="0 0 0"/>',
        f'{indent}  <mass value="{num(mass)}"/>',
        f'{indent}  <inertia ixx="{num(ixx)}" ixy="{num(ixy)}" ixz="{num(ixz)}" '
        f'iyy="{num(iyy)}" iyz="{num(iyz)}" izz="{num(izz)}"/>',
        f"{indent}</inertial>",
    ]


def _rod(indent: str, to: np.ndarray, radius: float) -> list[str]:
    """The visual of a link cylinder from the frame's origin to ``to`` (none when too short)."""
    length = float(np.linalg.norm(to))
    if length <= 1e-9:
        return []
    origin = f'<origin xyz="{vec(0.5 * to)}" rpy="{vec(_z_to(to))}"/>'
    return _visual(indent, f'<cylinder radius="{num(radius)}" length="{num(length)}"/>', "link",
                   origin)  # fmt: skip


def _visuals(chain: Chain, j: int, indent: str) -> list[str]:
    out: list[str] = []
    rad = chain.link_radius
    if j + 1 == len(chain.rows):  # the tip
        return _visual(indent, f'<sphere radius="{num(1.5 * rad)}"/>', "foot")
    if chain.rows[j].is_joint:  # a sphere at the joint and a short cylinder along its axis (z_j)
        out += _visual(indent, f'<sphere radius="{num(1.4 * rad)}"/>', "joint")
        cylinder = f'<cylinder radius="{num(0.8 * rad)}" length="{num(4.0 * rad)}"/>'
        out += _visual(indent, cylinder, "joint")
    return out + _rod(indent, chain.rows[j + 1].transform(0.0)[:3, 3], rad)


def _chain_body(chain: Chain, prefix: str, parent: str, indent: str = "  ") -> list[str]:
    """Joints and links of ``chain`` hanging from link ``parent`` (frame 0 = parent)."""
    lines: list[str] = []
    link_names = chain.link_names or ()
    joint_names = chain.joint_names or ()
    limits = chain.limits or ()
    damping, friction = chain.joint_damping(), chain.joint_friction()
    k = 0
    prev = parent
    if chain.base_pose is not None:
        frame0, offset = prefix + chain.frame0_link, f"{prefix}{chain.name}_base_offset"
        lines += [
            indent + comment(f"base offset T_{chain.base}_0 (Khalil frame 0 in the base link)"),
            *fixed_joint(indent, offset, prev, frame0, _origin(chain.base_pose.matrix)),
            f'{indent}<link name="{frame0}"/>',
        ]
        prev = frame0
    for j, row in enumerate(chain.rows):
        child = prefix + link_names[j]
        t0 = row.transform(0.0)
        values = f"alpha={num(row.alpha)} d={num(row.d)} theta={num(row.theta)} r={num(row.r)}"
        lines.append(indent + comment(f"row {j + 1}: sigma={row.sigma} {values}"))
        if row.is_joint:
            jname = prefix + joint_names[k]
            lim = limits[k]
            lines += [
                f'{indent}<joint name="{jname}" type="{row.sigma}">',
                f'{indent}  <parent link="{prev}"/>',
                f'{indent}  <child link="{child}"/>',
                f"{indent}  {_origin(t0)}",
                f'{indent}  <axis xyz="0 0 1"/>',
                f'{indent}  <limit lower="{num(lim.lower)}" upper="{num(lim.upper)}" '
                f'effort="{num(lim.effort)}" velocity="{num(lim.velocity)}"/>',
                f'{indent}  <dynamics damping="{num(damping[k])}" friction="{num(friction[k])}"/>',
                f"{indent}</joint>",
            ]
            k += 1
        else:
            lines += fixed_joint(indent, f"{child}_fixed", prev, child, _origin(t0))
        lines.append(f'{indent}<link name="{child}">')
        inn = chain.link_inertial(j)
        lines += _inertial_xml(indent + "  ", inn.mass, inn.com, inn.inertia)
        lines += _visuals(chain, j, indent + "  ")
        lines.append(f"{indent}</link>")
        prev = child
    if chain.tool is not None:
        tool = prefix + chain.tip
        t_tool = chain.tool.matrix
        lines += [
            indent + comment(f"tool frame T_{len(chain.rows)}_tool"),
            *fixed_joint(indent, f"{tool}_fixed", prev, tool, _origin(t_tool)),
            f'{indent}<link name="{tool}">',
            *_visual(indent + "  ", f'<sphere radius="{num(1.2 * chain.link_radius)}"/>', "foot"),
        ]
        back = -t_tool[:3, :3].T @ t_tool[:3, 3]
        lines += [*_rod(indent + "  ", back, 0.6 * chain.link_radius), f"{indent}</link>"]
    return lines


def _header(name: str, description: str, header: str | None) -> list[str]:
    return [
        '<?xml version="1.0" encoding="utf-8"?>',
        comment(f"Generated by hexapod_kin {__version__}: {description or name}"),
        *([comment(header)] if header else []),
        comment("Units: SI (m, rad, kg). Link j is Khalil-Kleinfinger frame j."),
        f'<robot name="{name}">',
        *["  " + _material(m) for m in ("base", "body", "link", "joint", "foot")],
    ]


_ELEMENT = re.compile(r"<([A-Za-z_]\w*)\s([^>]*)>")
_ATTRIBUTE = re.compile(r'(\w+)="([^"]*)"')


def _check_magnitudes(text: str, name: str) -> None:
    """Refuse a number beyond the loader's cap (1e9 SI, 1e20 in ``<limit>``-like tags).

    E.g. ``hexabot_leg(l1=1e12)`` (a rod inertia of 1e23 kg m²): one clear error here, not a
    file that ``fk`` then refuses.
    """
    for element in _ELEMENT.finditer(text):
        tag = element.group(1)
        cap = MAX_ABS_LIMIT if tag in LIMIT_TAGS else MAX_ABS
        for attribute, value in _ATTRIBUTE.findall(element.group(2)):
            if attribute not in NUMERIC.get(tag, ()):  # the gate's numeric attributes
                continue
            for word in value.split():
                try:
                    x = float(word)
                except ValueError:
                    continue
                if not math.isfinite(x) or abs(x) > cap:
                    raise ParameterError(
                        f"{name}: <{tag} {attribute}> would be {x:g}, beyond {cap:g} (the URDF "
                        "loader's cap, SI units: m, kg, kg m^2); choose smaller lengths or masses",
                        parameter=attribute,
                        value=x,
                        allowed=f"|value| <= {cap:g}",
                    )


#: File suffixes of parameter-table files (:mod:`hexapod_kin.tables`), wherever a source is read.
TABLE_SUFFIXES = (".toml", ".yaml", ".yml")


def table_of(source: Any, leg: str | None = None) -> Chain | Hexapod:
    """The parameter table of a source, read as :func:`hexapod_kin.load` reads it.

    A Chain or Hexapod is itself; a preset name builds the preset; a ``.toml``/``.yaml`` path
    is read (:func:`~hexapod_kin.tables.read_table`): what the exports of tables take.

    Raises:
        ParameterError: A URDF (it has no table), another type, or a bad ``leg``.
        SourceError: A string naming no preset and no file (close names suggested).

    """
    if isinstance(source, (str, os.PathLike)):
        text = os.fspath(source).strip()
        if text in robots.PRESETS:
            source = robots.get(text)
        elif not text.startswith("<") and Path(text).suffix.lower() in TABLE_SUFFIXES:
            source = read_table(Path(text).expanduser())
        elif not (text.startswith(("<", "erd:")) or Path(text).suffix.lower() in (".urdf", ".xml")):
            raise SourceError(
                f"source={text!r} is not a preset or a table file"
                f"{did_you_mean(text, robots.names())}; presets are {choices(robots.names())}",
                parameter="source",
                value=text,
                allowed=robots.names(),
            )
    if not isinstance(source, (Chain, Hexapod)):
        shown = repr(source) if isinstance(source, (str, os.PathLike)) else type(source).__name__
        raise ParameterError(
            f"source {shown[:80]} is a URDF without a parameter table (or not a source); this "
            "export writes what hexapod_kin builds: a Chain, a Hexapod, a preset name or a "
            "table file (.toml/.yaml)",
            parameter="source",
            value=shown[:80],
            allowed="a Chain, a Hexapod, a preset name or a table file",
        )
    if leg is not None:
        if isinstance(source, Chain):
            raise ParameterError(
                f"leg={leg!r} only applies to a Hexapod, not to a Chain", parameter="leg", value=leg
            )
        source.leg(leg)  # raises with the list of legs
    return source


def to_urdf(
    source: Chain | Hexapod | str | os.PathLike[str],
    *,
    leg: str | None = None,
    header: str | None = None,
) -> str:
    """Return the URDF text of a chain or robot (deterministic: same input, same bytes).

    ``source``: as :func:`table_of`; ``leg``: a :class:`Hexapod`'s one leg on the body;
    ``header``: an extra header comment line (e.g. which command made the file).

    Raises:
        ParameterError: ``source`` of another kind (a URDF), ``leg`` for a chain, or a number
            beyond what the package's URDF loader accepts (|x| <= 1e9).
        SourceError: A table file that cannot be read.

    """
    source = table_of(source, leg)
    if isinstance(source, Chain):  # its base link, then its rows
        rad, name = source.link_radius, source.name
        body = [
            f'  <link name="{source.base}">',
            *_visual("    ", f'<box size="{vec((6 * rad, 6 * rad, 2 * rad))}"/>', "base"),
            "  </link>",
            *_chain_body(source, "", source.base),
        ]
    else:  # its body, then each leg on its mount
        legs = source.legs if leg is None else (source.leg(leg),)
        name = source.name + ("" if leg is None else f"_{leg}")
        (lx, ly, lz), m = source.body_size, source.body_mass
        inertia = [m * (a**2 + b**2) / 12.0 for a, b in ((ly, lz), (lx, lz), (lx, ly))]
        body = [
            f'  <link name="{source.body}">',
            *_inertial_xml("    ", m, (0.0, 0.0, 0.0), (*inertia, 0.0, 0.0, 0.0)),
            *_visual("    ", f'<box size="{vec(source.body_size)}"/>', "body"),
            "  </link>",
        ]
        for one in legs:
            base = f"{one.name}_{one.chain.base}"
            mount = _origin(one.transform())
            body += [
                "  " + comment(f"{one.name}: mount xyz={vec(one.xyz)} yaw={num(one.yaw)} rad"),
                *fixed_joint("  ", f"{one.name}_mount", source.body, base, mount),
                f'  <link name="{base}"/>',
                *_chain_body(one.chain, f"{one.name}_", base),
            ]
    text = "\n".join([*_header(name, source.description, header), *body, "</robot>"]) + "\n"
    _check_magnitudes(text, source.name)
    return text


def write_urdf(
    source: Chain | Hexapod | str | os.PathLike[str],
    path: str | os.PathLike[str],
    *,
    leg: str | None = None,
    header: str | None = None,
) -> Path:
    """Write :func:`to_urdf` of ``source`` to ``path`` atomically and return the path."""
    return atomic_write(path, to_urdf(source, leg=leg, header=header))
