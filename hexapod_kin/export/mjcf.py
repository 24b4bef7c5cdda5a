"""URDF → MJCF through MuJoCo's own URDF compiler, with a floor and full-precision numbers.

The URDF gets a ``<mujoco><compiler/>`` extension (every link a body, only the URDF's
inertials); MuJoCo compiles and saves it, then every number that matters is written back from
the compiled model in full precision (MuJoCo writes 6 digits), and a floor, a light and
``<option>`` are added. Damping, friction loss, ranges, effort limits, masses and inertias
carry over (velocity limits have no MJCF counterpart). The base is fixed unless ``floating``;
contacts between a body and its parent are excluded.
"""

from __future__ import annotations

import contextlib
import math
import os
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .._io import atomic_write
from ..exceptions import ParameterError, UrdfError, finite, one_of, positive
from ..params import Chain, Hexapod
from ..sources import resolve_source
from ..urdf import to_urdf
from ._common import comment, need, num, vec
from .meshes import add_collisions, mesh_visuals

__all__ = ["to_mjcf", "write_mjcf", "MjcfExport", "INTEGRATORS", "reach"]

#: MuJoCo integrators accepted by ``integrator=``.
INTEGRATORS = ("Euler", "RK4", "implicit", "implicitfast")


@dataclass(frozen=True)
class MjcfExport:
    """An MJCF document (``xml``) and its mesh files (``assets``: path relative to it → STL)."""

    xml: str
    assets: dict[str, bytes]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: the MJCF size and the mesh files with their sizes in [bytes]."""
        return {"xml_chars": len(self.xml), "assets": {k: len(v) for k, v in self.assets.items()}}


def _chain_reach(chain: Chain) -> float:
    total, k = 0.0, 0
    for row in chain.rows:
        total += abs(row.d) + abs(row.r)
        if row.sigma == "prismatic":
            lim = (chain.limits or ())[k]
            total += max(abs(lim.lower), abs(lim.upper))
        k += int(row.is_joint)
    for pose in (chain.base_pose, chain.tool):
        if pose is not None:
            total += float(np.linalg.norm(pose.xyz))
    return total + 3.0 * chain.link_radius


def reach(source: Chain | Hexapod) -> float:
    """An upper bound in [m] of how far any point of the robot gets from its root frame."""
    if isinstance(source, Chain):
        return _chain_reach(source)
    body = 0.5 * float(np.linalg.norm(source.body_size))
    legs = max(float(np.linalg.norm(m.xyz)) + _chain_reach(m.chain) for m in source.legs)
    return max(body, legs)


def _with_compiler(urdf_text: str, discard_visual: bool, balance: bool = False) -> str:
    from lxml import etree

    root = etree.fromstring(urdf_text.encode("utf-8"))
    if balance:
        _lift_degenerate(root)
    ext = etree.Element("mujoco")
    etree.SubElement(
        ext,
        "compiler",
        discardvisual="true" if discard_visual else "false",
        fusestatic="false",
        balanceinertia="true" if balance else "false",
        inertiafromgeom="false",
        strippath="false",
        angle="radian",
    )
    root.insert(0, ext)
    return str(etree.tostring(root, encoding="unicode"))


#: Principal moments below this fraction of a link's largest (or below ``_FLOOR_ABS``) are
#: rounding, not physics: with ``balance_inertia`` they are raised to it (MuJoCo refuses a
#: tensor that is not positive definite; many URDFs give dummy or sensor links ``ixx = 0``).
_FLOOR_REL, _FLOOR_ABS = 1e-6, 1e-12


def _lift_degenerate(root: Any) -> None:
    """Raise principal moments within ``_FLOOR_REL`` of zero to it (a negative one: MuJoCo's)."""
    keys = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
    at = ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))
    for inertia in root.iterfind("link/inertial/inertia"):
        tensor = np.zeros((3, 3))
        try:
            for k, (i, j) in zip(keys, at):
                tensor[i, j] = tensor[j, i] = float(inertia.get(k, "0"))
        except ValueError:
            continue  # the gate reports unreadable numbers
        if not np.all(np.isfinite(tensor)):
            continue
        lam, vecs = np.linalg.eigh(tensor)
        floor = max(_FLOOR_REL * float(lam[-1]), _FLOOR_ABS)
        if lam[0] >= floor or lam[0] < -_FLOOR_REL * max(float(lam[-1]), _FLOOR_ABS):
            continue
        fixed = (vecs * np.maximum(lam, floor)) @ vecs.T
        for k, (i, j) in zip(keys, at):
            inertia.set(k, repr(float(fixed[i, j])))


def _set(elem: Any, key: str, values: Any) -> None:
    elem.set(key, vec(np.atleast_1d(np.asarray(values, dtype=float))))


def _patch(root: Any, model: Any, mujoco: Any) -> None:
    """Write the compiled model's numbers back into the saved MJCF with full precision."""
    body_type, joint_type = mujoco.mjtObj.mjOBJ_BODY, mujoco.mjtObj.mjOBJ_JOINT
    for body in root.iter("body"):
        b = mujoco.mj_name2id(model, body_type, body.get("name"))
        if b < 0:
            raise UrdfError(f"MJCF body {body.get('name')!r} is not in the compiled model")
        _set(body, "pos", model.body_pos[b])
        _set(body, "quat", model.body_quat[b])
        inertial = body.find("inertial")
        if inertial is not None:
            _set(inertial, "pos", model.body_ipos[b])
            _set(inertial, "quat", model.body_iquat[b])
            inertial.set("mass", num(model.body_mass[b]))
            _set(inertial, "diaginertia", model.body_inertia[b])
        for joint in body.findall("joint"):
            jid = mujoco.mj_name2id(model, joint_type, joint.get("name"))
            dof = model.jnt_dofadr[jid]
            _set(joint, "pos", model.jnt_pos[jid])
            _set(joint, "axis", model.jnt_axis[jid])
            if model.jnt_limited[jid]:
                _set(joint, "range", model.jnt_range[jid])
            if model.jnt_actfrclimited[jid]:
                _set(joint, "actuatorfrcrange", model.jnt_actfrcrange[jid])
            for key in ("damping", "frictionloss"):
                value = getattr(model, f"dof_{key}")[dof]
                if float(value) != 0.0 or joint.get(key) is not None:
                    joint.set(key, num(value))
        geoms = body.findall("geom")
        adr, n = int(model.body_geomadr[b]), int(model.body_geomnum[b])
        if len(geoms) != n:
            raise UrdfError(f"MJCF body {body.get('name')!r}: {len(geoms)} geoms, model has {n}")
        for g, geom in zip(range(adr, adr + n), geoms):
            if geom.get("type") == "mesh":
                continue  # MuJoCo re-centres meshes; their placement is kept as saved
            gtype = int(model.geom_type[g])
            size = model.geom_size[g]
            count = {
                int(mujoco.mjtGeom.mjGEOM_SPHERE): 1,
                int(mujoco.mjtGeom.mjGEOM_CAPSULE): 2,
                int(mujoco.mjtGeom.mjGEOM_CYLINDER): 2,
                int(mujoco.mjtGeom.mjGEOM_BOX): 3,
            }.get(gtype, 3)
            _set(geom, "size", size[:count])
            _set(geom, "pos", model.geom_pos[g])
            _set(geom, "quat", model.geom_quat[g])


def _exclude_adjacent(root: Any) -> None:
    """No contacts of a body with its parent and welded ancestors (MuJoCo: moving ones only)."""
    from lxml import etree

    def moves(body: Any) -> bool:
        return any(body.find(tag) is not None for tag in ("joint", "freejoint"))

    pairs: list[tuple[str, str]] = []
    for parent in root.iter("body"):
        for child in parent.findall("body"):
            pairs.append((parent.get("name"), child.get("name")))
            up = parent
            while not moves(up):
                up = up.getparent()
                if up is None or up.tag != "body":
                    break
                pairs.append((up.get("name"), child.get("name")))
    if not pairs:
        return
    contact = etree.Element("contact")
    for a, b in pairs:
        etree.SubElement(contact, "exclude", body1=a, body2=b)
    root.find("worldbody").addnext(contact)


def _compile(urdf_text: str, assets: dict[str, bytes]) -> tuple[str, Any, Any]:
    mujoco = need("mujoco")
    try:
        model = mujoco.MjModel.from_xml_string(urdf_text, assets)
    except ValueError as exc:
        raise UrdfError(f"MuJoCo's URDF compiler refused the model: {exc}") from None
    with tempfile.TemporaryDirectory(prefix="hexapod_kin_mjcf_") as tmp:
        path = os.path.join(tmp, "model.xml")
        mujoco.mj_saveLastXML(path, model)
        text = Path(path).read_text(encoding="utf-8")
    return text, model, mujoco


def _without_meshes(urdf: str) -> str:
    """The URDF without mesh geometry (MuJoCo cannot open ``package://`` ones); primitives stay."""
    from lxml import etree

    root = etree.fromstring(urdf.encode("utf-8"))
    for link in root.iter("link"):
        for elem in list(link):
            if elem.tag in ("visual", "collision") and elem.find("geometry/mesh") is not None:
                link.remove(elem)
    return str(etree.tostring(root, encoding="unicode"))


def to_mjcf(
    source: Any,
    *,
    meshes: bool = False,
    mesh_prefix: str = "meshes/",
    header: str | None = None,
    floor: bool = True,
    floor_z: float | None = None,
    timestep: float | None = None,
    integrator: str | None = None,
    floating: bool = False,
    balance_inertia: bool = False,
) -> MjcfExport:
    """Return the MJCF of a source, compiled by MuJoCo (deterministic).

    Args:
        source: What :func:`hexapod_kin.load` takes; a URDF without a parameter table is used
            without its mesh geometry (primitives, inertials and joints kept; no reach-based
            floor).
        meshes: STL visuals (trimesh) as non-colliding mesh geoms (group 1); the primitive
            collision geoms move to group 3.
        mesh_prefix: Folder of the mesh files relative to the MJCF file.
        header: Header comment line (the command that made it).
        floor: Add a floor plane and a light.
        floor_z: Floor height in [m]; default just below everything the robot can reach.
        timestep: ``<option timestep>`` in [s] (> 0); default MuJoCo's (0.002 s).
        integrator: ``<option integrator>``: one of :data:`INTEGRATORS`; default MuJoCo's.
        floating: A free joint ``floating_base`` on the root body (qpos ``x y z qw qx qy qz``
            first): the robot can fall, stand and walk (a Hexapod or a robot's URDF).
        balance_inertia: Mend rounded inertials: principal moments within 1e-6 of zero
            (relative to the link's largest) raised to that floor, and MuJoCo's
            ``balanceinertia`` for ``A + B >= C``. Off: such a URDF is refused.

    Raises:
        ParameterError: Invalid timestep, integrator, floor height or source; ``floating``
            for a chain (its base link has no mass).
        OptionalDependencyError: mujoco (or trimesh with meshes) not installed.
        UrdfError: MuJoCo refused the URDF.

    """
    from lxml import etree

    if timestep is not None:
        positive("timestep", timestep)
    if integrator is not None:
        one_of("integrator", integrator, INTEGRATORS)
    if floor_z is not None:
        finite("floor_z", floor_z)
    resolved = resolve_source(source)  # a chain or robot comes back as itself
    params = resolved.params
    if floating and isinstance(params, Chain):
        msg = (
            "floating=True needs a robot (a Hexapod or a legged robot's URDF) whose root body "
            "has a mass; a chain's base link has none"
        )
        raise ParameterError(msg, parameter="floating", value=floating)
    if params is None:
        urdf, default_floor, desc = _without_meshes(resolved.text), -1.0, resolved.name
        if meshes:
            raise ParameterError(
                "meshes=True needs a source with a parameter table, not a URDF", parameter="meshes"
            )
    else:
        urdf = to_urdf(params, header=header)
        default_floor = -math.ceil(110.0 * reach(params)) / 100.0
        desc = params.description or params.name
    assets: dict[str, bytes] = {}
    if meshes:
        meshed = mesh_visuals(urdf, mesh_prefix)
        urdf = meshed.urdf
        assets = {f"{mesh_prefix}{k}": v for k, v in meshed.files.items()}
    else:
        urdf = add_collisions(urdf)
    saved, model, mujoco = _compile(
        _with_compiler(urdf, discard_visual=not meshes, balance=balance_inertia), assets
    )
    root = etree.fromstring(saved.encode("utf-8"))
    _patch(root, model, mujoco)
    _exclude_adjacent(root)
    if floating:
        top = root.find("worldbody/body")
        free = etree.Element("freejoint", name="floating_base")
        inertial = top.find("inertial")
        if inertial is not None:
            inertial.addnext(free)
        else:
            top.insert(0, free)
    for geom in root.iter("geom") if meshes else ():
        if geom.get("type") != "mesh":
            geom.set("group", "3")
    if timestep is not None or integrator is not None:
        given = {"timestep": None if timestep is None else num(timestep), "integrator": integrator}
        root.find("compiler").addnext(
            etree.Element("option", {k: v for k, v in given.items() if v is not None})
        )
    if floor:
        world = root.find("worldbody")
        z = default_floor if floor_z is None else float(floor_z)
        pos = f"0 0 {num(z)}"
        plane = dict(name="floor", type="plane", size="0 0 0.05", pos=pos, rgba="0.8 0.8 0.8 1")
        light = dict(name="hk_light", pos=f"0 0 {num(z + 3.0)}", dir="0 0 -1", directional="true")
        world.insert(0, etree.Element("geom", **plane))
        world.insert(0, etree.Element("light", **light))
    root.insert(0, etree.Comment(" " + comment(f"MJCF of {desc}")[5:-4] + " "))
    if header:
        root.insert(1, etree.Comment(" " + comment(header)[5:-4] + " "))
    etree.indent(root, space="  ")
    text = etree.tostring(root, encoding="unicode")
    return MjcfExport(xml=text + "\n", assets=dict(sorted(assets.items())))


def write_mjcf(source: Any, path: str | os.PathLike[str], **options: Any) -> MjcfExport:
    """Write :func:`to_mjcf` to ``path`` (meshes into ``<stem>_meshes/`` beside it), atomically.

    ``options``: the keywords of :func:`to_mjcf` but ``mesh_prefix``. Meshes first, the MJCF
    last; a write stopped between two files removes what it created.

    Raises:
        ParameterError: As :func:`to_mjcf`, or when the directory does not exist.

    """
    dest = Path(path)
    parent = dest.parent if str(dest.parent) else Path(".")
    if not parent.is_dir():
        msg = f"path={str(dest)!r}: directory {str(parent)!r} does not exist"
        raise ParameterError(msg, parameter="path")
    stem = dest.name.split(".")[0] or "model"
    out = to_mjcf(source, mesh_prefix=f"{stem}_meshes/", **options)
    made: list[Path] = []  # files and folders this call creates: removed if it is stopped
    try:
        for rel, data in out.assets.items():
            target = parent / rel
            if not target.parent.exists():
                target.parent.mkdir(parents=True)
                made.append(target.parent)
            if not target.exists():
                made.append(target)
            atomic_write(target, data)
        atomic_write(dest, out.xml)
    except BaseException:  # a Ctrl-C or a full disk between two files: none of the new ones
        for path in reversed(made):
            with contextlib.suppress(OSError):
                path.rmdir() if path.is_dir() else path.unlink()
        raise
    return out
