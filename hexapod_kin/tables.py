"""Parameter-table files: your own robot as a TOML or YAML file → a :class:`~.params.Chain`.

A table file is a source like any other (``hexapod_kin.load("leg4.toml")``, ``hexapod-kin urdf
leg4.toml``). The format (examples in ``examples/``)::

    name = "leg4"                  # robot name (default: the file stem)
    convention = "khalil"          # "khalil" (modified DH, Khalil–Kleinfinger) or "dh" (standard)
    angles = "rad"                 # "rad" or "deg": alpha, theta, rpy, revolute limits/velocity
    description = "free text"      # optional
    base = "base"                  # base link name (optional)
    tip = "foot"                   # tip frame name (optional)
    link_mass = 0.1                # default link mass [kg] (optional)
    link_radius = 0.01             # visual/default-inertia radius [m] (optional)
    base_pose = { xyz = [0, 0, 0.1], rpy = [0, 0, 0] }   # T_base_0 (optional)
    tool = { xyz = [0, 0, 0.05], rpy = [0, 0, 0] }       # T_n_tool (optional)

    [[row]]                        # one per table row, from the base
    type = "revolute"              # "revolute", "prismatic" or "fixed" (alias: sigma = 0/1/2)
    alpha = 0.0                    # khalil: alpha, d, theta, r   dh: theta, d, a, alpha
    d = 0.0
    theta = 0.0
    r = 0.0
    name = "coxa"                  # joint name (joint rows; optional)
    link = "coxa_link"             # link name (optional; all rows or none)
    lower = -1.5                   # limits (joint rows; optional): lower, upper [rad]/[m],
    upper = 1.5                    #   velocity [rad/s]/[m/s], effort [N m]/[N]
    mass = 0.2                     # link mass [kg] (optional): a rod to the next frame, or
    com = [0.05, 0, 0]             #   with com [m] and inertia [ixx, iyy, izz, ixy, ixz, iyz]
    inertia = [1e-4, 1e-4, 1e-4, 0, 0, 0]   # [kg m^2] about the com, in the row's link frame

Standard DH rows become Khalil rows by :meth:`Chain.from_dh` (``link``, ``mass`` and inertials
of the joint's frame; one fixed row more, its link named ``tip``). Unknown keys are refused.
YAML needs PyYAML (``pip install hexapod-kin[tables]``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from ._gate.limits import MAX_ABS, MAX_DOF, MAX_LINKS
from ._reader import check_keys, clip, named, number, numbers, read_data, text
from .exceptions import ParameterError, one_of
from .params import (
    Chain,
    DHRow,
    Inertial,
    JointLimits,
    KhalilRow,
    Pose,
    default_limits,
    rod_inertial,
)

__all__ = ["read_table", "chain_from_table", "TOP_KEYS", "ROW_KEYS"]

#: Keys allowed at the top of a table file.
TOP_KEYS = (
    "name", "convention", "angles", "description", "base", "tip", "link_mass", "link_radius",
    "base_pose", "tool", "row", "damping", "friction",
)  # fmt: skip
#: Keys allowed in a row (beside the geometry keys of the convention).
ROW_KEYS = (
    "type", "sigma", "name", "link", "lower", "upper", "velocity", "effort", "mass", "com",
    "inertia",
)  # fmt: skip
_GEOMETRY = {"khalil": ("alpha", "d", "theta", "r"), "dh": ("theta", "d", "a", "alpha")}
_ANGLE_KEYS = {"alpha", "theta"}

#: Largest magnitude of a length in a table [m] (and of a com or pose offset).
MAX_LENGTH = 1e3
#: Smallest non-zero length of a row [m] (below it the Jacobian's singular values underflow).
MIN_LENGTH = 1e-9
#: The URDF gate's caps in a table's terms: any other number; rows (links less the base, frame
#: 0, tool and DH tip links); joint rows.
MAX_NUMBER, MAX_ROWS, MAX_JOINTS = MAX_ABS, MAX_LINKS - 4, MAX_DOF


def read_table(path: Path | str, **overrides: Any) -> Chain:
    """Read a TOML/YAML table file into a :class:`Chain`, ``overrides`` replacing top-level keys.

    Raises:
        SourceError: Unreadable file or invalid TOML/YAML.
        ParameterError: A bad key or value; the message names the row (1-based) and key.

    """
    path = Path(path)
    data = read_data(path, "source", mapping="name, convention, row, ...")
    with named(path, "source"):
        check_keys(overrides, TOP_KEYS, "overrides")
        return chain_from_table({"name": path.stem, **data, **overrides})


def _number(value: Any, where: str, limit: float = MAX_NUMBER, floor: float = 0.0) -> float:
    out = number(value, where)
    key = where.rsplit(".", 1)[-1]
    if abs(out) > limit:
        problem, allowed = f"is out of range; allowed |{key}| <= {limit:g}", f"|value| <= {limit:g}"
    elif 0.0 < abs(out) < floor:
        problem = f"is below the smallest length {floor:g} m; allowed 0 or {floor:g} <= |{key}|"
        problem, allowed = f"{problem} <= {limit:g}", f"0 or {floor:g} <= |value| <= {limit:g}"
    else:
        return out
    raise ParameterError(f"{where}={out:g} {problem}", parameter=where, value=out, allowed=allowed)


def _numbers(value: Any, n: int, where: str, limit: float = MAX_NUMBER) -> tuple[float, ...]:
    return tuple(_number(v, f"{where}[{i}]", limit) for i, v in enumerate(numbers(value, where, n)))


def _pose(value: Any, scale: float, where: str) -> Pose:
    if not isinstance(value, dict):
        raise ParameterError(
            f"{where}={value!r}: a table {{xyz = [...], rpy = [...]}} is required",
            parameter=where,
            value=value,
        )
    check_keys(value, ("xyz", "rpy"), where)
    xyz = _numbers(value.get("xyz", [0, 0, 0]), 3, f"{where}.xyz", MAX_LENGTH)
    rpy = _numbers(value.get("rpy", [0, 0, 0]), 3, f"{where}.rpy")
    return Pose.of((xyz, tuple(a * scale for a in rpy)), where)


def chain_from_table(data: dict[str, Any]) -> Chain:
    """Build a :class:`Chain` from the mapping of a table file (else ParameterError, row named)."""
    check_keys(data, TOP_KEYS, "table")
    convention = one_of("convention", str(data.get("convention", "khalil")).lower(), _GEOMETRY)
    angles = one_of("angles", str(data.get("angles", "rad")).lower(), ("rad", "deg"))
    scale = math.pi / 180.0 if angles == "deg" else 1.0
    rows_in = data.get("row")
    if not isinstance(rows_in, list) or not rows_in:
        raise ParameterError(
            "table: at least one [[row]] is required (one per row of the table)", parameter="row"
        )
    if len(rows_in) > MAX_ROWS:
        raise ParameterError(
            f"table: {len(rows_in)} rows; allowed: at most {MAX_ROWS}",
            parameter="row",
            value=len(rows_in),
            allowed=f"at most {MAX_ROWS} rows",
        )
    geometry = _GEOMETRY[convention]
    allowed = (*geometry, *ROW_KEYS)
    rows: list[KhalilRow | DHRow] = []
    joint_names: list[str] = []
    limits: list[JointLimits] = []
    links: list[str] = []
    masses: list[tuple[float, tuple[float, ...] | None, tuple[float, ...] | None] | None] = []
    for j, row in enumerate(rows_in, start=1):
        where = f"row {j}"
        if not isinstance(row, dict):
            raise ParameterError(f"{where}={row!r}: a table of keys is required", parameter="row")
        check_keys(row, allowed, where)
        if "type" in row and "sigma" in row:
            raise ParameterError(f"{where}: give type or sigma, not both", parameter="type")
        sigma: Any = row["type"] if "type" in row else row.get("sigma", "revolute")
        if isinstance(sigma, bool) or not isinstance(sigma, (str, int)):
            key = "type" if "type" in row else "sigma"
            raise ParameterError(
                f"{where}.{key}={clip(sigma)} is not allowed; use 'revolute', 'prismatic' or "
                "'fixed' (sigma 0, 1 or 2)",
                parameter=key,
                value=clip(sigma),
                allowed=["revolute", "prismatic", "fixed", 0, 1, 2],
            )
        geo = {}
        for k in geometry:  # angles in the file's unit, lengths within [MIN_, MAX_LENGTH]
            angle = k in _ANGLE_KEYS
            bounds = () if angle else (MAX_LENGTH, MIN_LENGTH)
            geo[k] = _number(row.get(k, 0.0), f"{where}.{k}", *bounds) * (scale if angle else 1.0)
        try:
            built: KhalilRow | DHRow = (
                KhalilRow(sigma, **geo) if convention == "khalil" else DHRow(sigma=sigma, **geo)
            )
        except ParameterError as exc:
            raise ParameterError(f"{where}: {exc}", parameter="type", value=sigma) from None
        rows.append(built)
        if built.sigma != "fixed":
            joint_names.append(text(row.get("name", f"q{len(joint_names) + 1}"), f"{where}.name"))
            lim_scale = scale if built.sigma == "revolute" else 1.0
            default = default_limits(str(built.sigma))
            units = {"lower": lim_scale, "upper": lim_scale, "velocity": lim_scale, "effort": 1.0}
            try:
                given = {k: _number(row[k], f"{where}.{k}") * units[k] for k in units if k in row}
                limits.append(replace(default, **given))
            except ParameterError as exc:
                raise ParameterError(f"{where}: {exc}", parameter="lower") from None
        else:
            for key in ("name", "lower", "upper", "velocity", "effort"):
                if key in row:
                    raise ParameterError(
                        f"{where}: {key!r} is for joint rows; this row is fixed", parameter=key
                    )
        if "link" in row:
            links.append(text(row["link"], f"{where}.link"))
        if "mass" in row:
            mass = _number(row["mass"], f"{where}.mass")
            com = _numbers(row["com"], 3, f"{where}.com", MAX_LENGTH) if "com" in row else None
            inertia = _numbers(row["inertia"], 6, f"{where}.inertia") if "inertia" in row else None
            if (com is None) != (inertia is None):
                raise ParameterError(
                    f"{where}: give com and inertia together (or only mass: a rod)",
                    parameter="inertia",
                )
            masses.append((mass, com, inertia))
        else:
            if "com" in row or "inertia" in row:
                raise ParameterError(f"{where}: com/inertia need a mass", parameter="mass")
            masses.append(None)
    if len(joint_names) > MAX_JOINTS:
        raise ParameterError(
            f"table: {len(joint_names)} joint rows; allowed: at most {MAX_JOINTS} (the loader's "
            "cap on degrees of freedom)",
            parameter="row",
            value=len(joint_names),
            allowed=f"at most {MAX_JOINTS} joint rows",
        )
    if links and len(links) != len(rows):
        raise ParameterError(
            f"table: 'link' given on {len(links)} of {len(rows)} rows; name all links or none",
            parameter="link",
        )
    kwargs: dict[str, Any] = {"joint_names": tuple(joint_names), "limits": tuple(limits)}
    readers: dict[str, Callable[[Any, str], Any]] = {"name": text, "description": text,
        "base": text, "tip": text, "link_mass": _number, "link_radius": _number}  # fmt: skip
    kwargs.update({key: read(data[key], key) for key, read in readers.items() if key in data})
    for key in ("damping", "friction"):
        if key in data:
            value = data[key]
            kwargs[key] = (
                tuple(_number(v, f"{key}[{i}]") for i, v in enumerate(value))
                if isinstance(value, list)
                else _number(value, key)
            )
    poses = {k: _pose(data[k], scale, k) for k in ("base_pose", "tool") if k in data}
    if convention == "dh":
        if links:
            kwargs["link_names"] = (*links, str(data.get("tip", "tip")))
        dh_rows = [r for r in rows if isinstance(r, DHRow)]
        chain = Chain.from_dh(
            dh_rows, tool=poses.get("tool"), base_pose=poses.get("base_pose"), **kwargs
        )
        masses.append(None)
    else:
        if links:
            kwargs["link_names"] = tuple(links)
            if "tip" not in data and "tool" not in poses:  # the last link is the tip
                kwargs["tip"] = links[-1]
        khalil = tuple(r for r in rows if isinstance(r, KhalilRow))
        chain = Chain(
            rows=khalil, base_pose=poses.get("base_pose"), tool=poses.get("tool"), **kwargs
        )
    if any(m is not None for m in masses):  # a rod to the next frame, or the given com/inertia
        inertials: list[Inertial | None] = []
        for j, spec in enumerate(masses):
            if spec is None:
                inertials.append(None)
                continue
            mass, com, inertia = spec
            try:
                if com is None or inertia is None:
                    last = j + 1 == len(chain.rows)
                    nxt = np.zeros(3) if last else chain.rows[j + 1].transform(0.0)[:3, 3]
                    inertials.append(rod_inertial(np.zeros(3), nxt, mass, chain.link_radius))
                else:
                    inn = Inertial(mass=mass, com=com, inertia=inertia)  # type: ignore[arg-type]
                    inertials.append(inn)
            except ParameterError as exc:
                raise ParameterError(f"row {j + 1}: {exc}", parameter="mass", value=mass) from None
        chain = chain.replace(inertials=tuple(inertials))
    return chain
