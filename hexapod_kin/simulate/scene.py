"""The MuJoCo scene of a walk (:func:`scene_mjcf`) and the engine reading its contacts."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._fields import fields_dict
from ..exceptions import ConfigurationError, ParameterError, one_of, positive

__all__ = ["MAX_FRICTION", "SCENE_TERRAINS", "SimScene", "check_friction", "check_steps",
           "scene_mjcf"]  # fmt: skip

#: The largest sliding friction coefficient a scene takes (a coefficient of 100 is glue).
MAX_FRICTION = 100.0

#: The default (and largest automatic) physics step [s].
MAX_TIMESTEP = 1e-3

#: The largest ``ω dt`` of a servo (ω its natural frequency) the automatic timestep allows
#: (accuracy, not only stability: at the stability limit, 0.4, travel and slip are off by 2 %).
STABLE_OMEGA_DT = 0.2

#: The automatic timestep is at least ``MAX_TIMESTEP / MAX_SPLIT`` (bounded work).
MAX_SPLIT = 10

#: The largest bump amplitude [m] of a scene's ground.
MAX_BUMPS = 0.05

#: Cell size [m] of the bumps' height field, and its half-sizes along x and y [m].
_BUMP_CELL, _BUMP_HALF = 0.05, (8.0, 4.0)

#: Terrains the scene can build (the named ones of :mod:`hexapod_kin.gait.terrain`).
SCENE_TERRAINS = ("flat", "slope", "step")

_SLOPE = math.radians(8.0)
_STEP_RISE, _STEP_AT = 0.02, 0.25


def _mujoco() -> Any:
    try:
        import mujoco
    except ImportError:
        from ..exceptions import OptionalDependencyError

        raise OptionalDependencyError(
            "mujoco is not installed; `pip install 'hexapod-kin[export]'` installs it "
            "(MuJoCo >= 3.14)",
            parameter="module",
            value="mujoco",
        ) from None
    return mujoco


# ----------------------------------------------------------------------------- the robot
def _robot(robot: Any, feet: Any = None) -> Any:
    """The whole-body model of ``robot`` (None: the built-in hexapod), ``feet`` its foot spec."""
    from ..gait import as_whole_body

    return as_whole_body(robot, feet=feet)


#: Radius [m] of the spheres that stand for point feet (a robot whose foot radius is 0).
POINT_FOOT = 0.001


def scene_foot_radius(robot: Any) -> float:
    """The feet's contact radius [m] the scene gives a robot when none is asked.

    The robot's own ``foot_radius`` when it has one; else the radius of its foot links'
    collision shapes (:func:`.collision.foot_radius_of`: a sphere's, a cylinder's, a mesh's
    half-size); else :data:`POINT_FOOT`.
    """
    from .collision import foot_radius_of

    wb = _robot(robot, None)
    r = float(wb.foot_radius)
    if r > 0:
        return r
    found = foot_radius_of(wb)
    return float(found) if found is not None and found > 0 else POINT_FOOT


def _robot_mjcf(wb: Any, source: Any = None) -> str:
    """The robot's MJCF with a free base: from its Hexapod table, else from its URDF.

    The URDF: the robot's ``urdf``, else that of ``source``, else of its ``source`` label.
    """
    import os

    from ..exceptions import HexapodKinError
    from ..export.mjcf import to_mjcf
    from ..params import Hexapod
    from ..sources import resolve_source

    params = getattr(wb, "params", None)
    if isinstance(params, Hexapod):
        return to_mjcf(params, floating=True, floor=False).xml
    repair = getattr(getattr(wb, "kinematic", None), "inertia_repair", None)
    urdf = getattr(wb, "urdf", None) if repair is None else repair.text
    for src in (source, getattr(wb, "source", None)):
        if isinstance(urdf, str) or not isinstance(src, (str, os.PathLike)):
            continue
        try:
            urdf = resolve_source(src).text
        except HexapodKinError:
            continue
    if isinstance(urdf, str):
        return to_mjcf(urdf, floating=True, floor=False, balance_inertia=True).xml
    raise ParameterError(
        f"robot {getattr(wb, 'source', wb)!r}: no Hexapod table or URDF text to export to "
        "MJCF; give its URDF path or erd:NAME as the robot",
        parameter="robot",
        value=repr(getattr(wb, "source", wb)),
    )


def _leg_ends(wb: Any) -> list[int]:
    """Per leg, the column of the deepest joint moving its foot (each joint moved 1e-3 rad)."""
    q0 = np.asarray(wb.neutral_q(), dtype=float)
    eye = np.eye(4)[None]
    f0 = wb.feet(q0[None], eye)[0]
    qs = q0[None] + 1e-3 * np.eye(wb.nq)
    moved = np.linalg.norm(wb.feet(qs, np.repeat(eye, wb.nq, axis=0)) - f0, axis=-1) > 1e-9
    parents = np.asarray(wb.model.parents)
    names = list(wb.model.names)
    depth = []
    for name in wb.joint_names:
        j, d = names.index(name), 0
        while j > 0:
            j, d = int(parents[j]), d + 1
        depth.append(d)
    out = []
    for leg in range(wb.n_legs):
        cols = np.flatnonzero(moved[:, leg])
        if not len(cols):
            raise ConfigurationError(f"leg {wb.leg_names[leg]}: no joint moves its foot")
        out.append(int(max(cols, key=lambda c: depth[c])))
    return out


# ----------------------------------------------------------------------------- the scene
@dataclass(frozen=True)
class SimScene:
    """The MJCF of a robot on a terrain, ready to simulate.

    ``xml``: the MJCF text (robot, terrain, foot spheres, actuators, options);
    ``foot_geoms`` per leg (``leg_names``), ``actuators`` per leg joint (``joint_names``
    order): their names. The settings as :func:`scene_mjcf` takes them, in SI units.
    """

    xml: str
    terrain: str
    foot_radius: float
    foot_geoms: tuple[str, ...]
    actuators: tuple[str, ...]
    joint_names: tuple[str, ...]
    leg_names: tuple[str, ...]
    kp: float
    kv: float
    friction: float
    timestep: float
    armature: float = 0.0
    contact_time: float = 0.02
    bumps: float = 0.0
    seed: int = 0
    flat_start: float = 0.0

    def ground(self, x: Any, y: Any) -> np.ndarray:
        """Ground height [m] at ``x``, ``y`` [m] with the bumps (:meth:`height` without)."""
        h = self.height(x, y)
        if not self.bumps:
            return h
        field = self.bumps * (2.0 * _bump_field(self.seed, self.flat_start) - 1.0)
        ny, nx = field.shape
        # MuJoCo's height field, bilinear here (two triangles per cell there: equal at nodes)
        u = np.clip((np.asarray(x) + _BUMP_HALF[0]) / _BUMP_CELL, 0, nx - 1.000001)
        v = np.clip((np.asarray(y) + _BUMP_HALF[1]) / _BUMP_CELL, 0, ny - 1.000001)
        j, i = np.floor(u).astype(int), np.floor(v).astype(int)
        fu, fv = u - j, v - i
        z = (field[i, j] * (1 - fu) * (1 - fv) + field[i, j + 1] * fu * (1 - fv)) + (
            field[i + 1, j] * (1 - fu) * fv + field[i + 1, j + 1] * fu * fv
        )
        return np.asarray(h + z)

    def height(self, x: Any, y: Any) -> np.ndarray:
        """Ground height [m] of the scene at ``x``, ``y`` [m]."""
        x = np.asarray(x, dtype=float)
        if self.terrain == "slope":
            return np.asarray(math.tan(_SLOPE) * x + 0.0 * np.asarray(y))
        if self.terrain == "step":
            return np.asarray(np.where(x >= _STEP_AT, _STEP_RISE, 0.0) + 0.0 * np.asarray(y))
        return np.asarray(0.0 * x + 0.0 * np.asarray(y))

    @property
    def normal_z(self) -> float:
        """The z component of the ground normal (1 on flat ground and steps)."""
        return math.cos(_SLOPE) if self.terrain == "slope" else 1.0

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready settings (SI units)."""
        names = ("terrain", "foot_radius", "kp", "kv", "friction", "timestep", "armature")
        return fields_dict(self, *names, "contact_time", "bumps", "seed", "flat_start")


#: The built-in hexapod's ``m ℓ`` [kg·m] and ``m ℓ²`` [kg·m²], for its AX-12-class servos.
_REF_ML, _REF_ML2 = 1.96 * 0.25, 1.96 * 0.25**2


def servo_defaults(robot: Any) -> tuple[float, float, float]:
    """Default servo ``(kp, kv, armature)`` for a robot, scaled to its weight and size.

    The same sag under the robot's weight for every robot: ``kp = 300 N·m/rad × m ℓ /
    (1.96 kg × 0.25 m)`` (``m`` the mass, ``ℓ`` the mean leg span), ``kv = 0.01 s × kp``, the
    armature ``0.002 kg·m² × m ℓ² / (1.96 kg × (0.25 m)²)``; three significant digits.
    """
    wb = _robot(robot, None)
    span = wb.leg_span
    m = float(wb.mass)
    if not (m > 0 and span > 0):
        return 300.0, 3.0, 0.002
    kp = float(f"{300.0 * m * span / _REF_ML:.3g}")
    arm = float(f"{0.002 * m * span**2 / _REF_ML2:.3g}")
    return kp, float(f"{0.01 * kp:.3g}"), arm


def check_friction(friction: float) -> float:
    """``friction`` if in (0, :data:`MAX_FRICTION`] (beyond, MuJoCo's solver crawls)."""
    if (mu := positive("friction", friction)) > MAX_FRICTION:
        msg = f"friction={friction!r} is not allowed; a coefficient from 0 to {MAX_FRICTION:g}"
        raise ParameterError(
            msg, parameter="friction", value=friction, allowed=f"(0, {MAX_FRICTION:g}]"
        )
    return mu


def scene_mjcf(
    robot: Any = None,
    *,
    feet: Any = None,
    source: Any = None,
    terrain: str = "flat",
    foot_radius: float | None = None,
    friction: float = 1.0,
    kp: float | None = None,
    kv: float | None = None,
    armature: float | None = None,
    contact_time: float = 0.005,
    timestep: float | None = None,
    bumps: float = 0.0,
    seed: int = 0,
    flat_start: float = 0.0,
) -> SimScene:
    """The robot on a terrain, with foot spheres and position actuators, as MJCF.

    Args:
        robot: The robot (a :class:`~hexapod_kin.gait.robot.WholeBody`, or what the gait
            accepts; None: the built-in hexapod).
        feet: The feet of a URDF robot without foot links (as the gait takes them).
        source: Where a built robot's URDF comes from (its path, text or ``erd:NAME``; a
            robot given by path or name is its own source).
        terrain: ``flat``, ``slope`` (8° up along +x) or ``step`` (0.02 m up at x = 0.25 m).
        foot_radius: Foot sphere radius [m] (default the robot's ``foot_radius``; point
            feet, radius 0, are :data:`POINT_FOOT` spheres).
        friction: Sliding friction coefficient of every geom (> 0, <= :data:`MAX_FRICTION`).
        kp: Position gain [N·m/rad] (> 0); the force is clamped to the joints' effort limits.
            Default :func:`servo_defaults` (scaled to the robot's weight and size).
        kv: Velocity gain [N·m·s/rad] (> 0); default ``0.01 s × kp``.
        armature: Rotor inertia of each leg joint's servo [kg·m²] (≥ 0; MuJoCo's
            ``armature``). Default :func:`servo_defaults`.
        contact_time: Contact stiffness as MuJoCo's ``solref`` time constant [s] (critically
            damped; at least twice the time step).
        timestep: Physics time step [s] (> 0). Default: :data:`MAX_TIMESTEP`, divided by
            the smallest whole number that keeps every servo's ``ω dt`` within
            :data:`STABLE_OMEGA_DT` (``ω = sqrt(kp / I)``, ``I = 1 / (M⁻¹)_jj`` at the
            neutral pose, armature included; the position gain is explicit in MuJoCo's
            integrator). At least ``MAX_TIMESTEP / MAX_SPLIT``.
        bumps: Amplitude [m] of random bumps on flat ground (0: none; at most
            :data:`MAX_BUMPS`): a height field of 5 cm cells, 16 m × 8 m, heights uniform in
            ``[-bumps, bumps]`` (seeded).
        seed: The bumps' random seed.
        flat_start: Half-width [m] (>= 0) of a flat square at height 0 around the origin
            amid the bumps, where a robot can be set down at rest.

    Returns:
        A :class:`SimScene`.

    Raises:
        ParameterError: A bad value, or a terrain that is not one of :data:`SCENE_TERRAINS`.
        OptionalDependencyError: MuJoCo is not installed.

    """
    from lxml import etree

    from ..export._common import num, vec
    from .collision import add_hulls, mjcf_asset

    one_of("terrain", terrain, list(SCENE_TERRAINS))
    wb = _robot(robot, feet)
    auto = servo_defaults(wb)
    kp = auto[0] if kp is None else kp
    kv = auto[1] if kv is None else kv
    armature = auto[2] if armature is None else armature
    mu, kp, kv, dt, tc = (
        positive(n, v)
        for n, v in (
            ("friction", friction),
            ("kp", kp),
            ("kv", kv),
            ("timestep", MAX_TIMESTEP if timestep is None else timestep),
            ("contact_time", contact_time),
        )
    )
    check_friction(mu)
    arm = 0.0 if armature == 0 else positive("armature", armature)
    if tc < 2 * dt:
        raise ParameterError(
            f"contact_time={contact_time!r} s is below twice the timestep ({2 * dt:g} s)",
            parameter="contact_time",
            value=contact_time,
            allowed=f">= {2 * dt:g}",
        )
    bump = 0.0 if bumps == 0 else positive("bumps", bumps)
    if bump > MAX_BUMPS or (bump and terrain != "flat"):
        raise ParameterError(
            f"bumps={bumps!r} m on {terrain!r} ground; bumps from 0 to {MAX_BUMPS:g} m, on "
            "flat ground only",
            parameter="bumps",
            value=bumps,
            allowed=f"[0, {MAX_BUMPS:g}] on flat ground",
        )
    mujoco = _mujoco()
    r = scene_foot_radius(wb) if foot_radius is None else positive("foot_radius", foot_radius)
    xml = _robot_mjcf(wb, robot if source is None else source)
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    # the robot at its neutral pose, base at the origin: where each foot is, in which body
    q0 = np.asarray(wb.neutral_q(), dtype=float)
    jids = _joints(mujoco, model, wb.joint_names)
    data.qpos[:] = 0.0
    data.qpos[3] = 1.0
    data.qpos[model.jnt_qposadr[jids]] = q0
    mujoco.mj_kinematics(model, data)
    feet = wb.feet(q0[None], np.eye(4)[None])[0]
    ends = _leg_ends(wb)
    root = etree.fromstring(xml.encode("utf-8"))
    bodies = {b.get("name"): b for b in root.iter("body")}
    foot_geoms = []
    for leg, (name, col) in enumerate(zip(wb.leg_names, ends)):
        bid = int(model.jnt_bodyid[jids[col]])
        R, x = data.xmat[bid].reshape(3, 3), data.xpos[bid]
        local = R.T @ (feet[leg] - x)
        # drop the export's spheres at the foot point (this body or bodies welded to it)
        for b in range(model.nbody):
            welded, up = b == bid, b
            while not welded and model.body_jntnum[up] == 0 and up > 0:
                up = int(model.body_parentid[up])
                welded = up == bid
            if not welded:
                continue
            elems = bodies[mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b)].findall("geom")
            adr = int(model.body_geomadr[b])
            for k, g in enumerate(range(adr, adr + len(elems))):
                kind = int(model.geom_type[g])
                if kind == int(mujoco.mjtGeom.mjGEOM_SPHERE) and (
                    np.linalg.norm(data.geom_xpos[g] - feet[leg]) < 1e-9
                ):
                    elems[k].getparent().remove(elems[k])
                elif kind == int(mujoco.mjtGeom.mjGEOM_CYLINDER):
                    _trim(elems[k], model, data, g, feet[leg], r)
        gname = f"{name}_foot_contact"
        etree.SubElement(
            bodies[mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, bid)],
            "geom",
            name=gname,
            type="sphere",
            size=num(r),
            pos=vec(local),
            rgba="0.8 0.15 0.15 1",
        )
        foot_geoms.append(gname)
    add_hulls(root, bodies, wb, r)
    world = root.find("worldbody")
    default = etree.Element("default")
    etree.SubElement(default, "geom", friction=f"{num(mu)} 0 0", solref=f"{num(tc)} 1")
    etree.SubElement(default, "joint", armature=num(arm))
    root.find("compiler").addnext(default)
    option = etree.Element(
        "option", timestep=num(dt), integrator="implicitfast", cone="elliptic", impratio="10"
    )
    root.find("compiler").addnext(option)
    grounds = [dict(name="ground", type="plane", size="0 0 0.05", pos="0 0 0")]
    if terrain == "slope":
        a = -_SLOPE / 2.0  # about y by -8°: the normal (−sin 8°, 0, cos 8°)
        grounds[0]["quat"] = f"{num(math.cos(a))} 0 {num(math.sin(a))} 0"
    if terrain == "step":
        half = 5.0
        grounds.append(
            dict(
                name="step",
                type="box",
                size=f"{num(half)} {num(half)} {num(_STEP_RISE / 2)}",
                pos=f"{num(_STEP_AT + half)} 0 {num(_STEP_RISE / 2)}",
            )
        )
    flat = 0.0 if not flat_start else positive("flat_start", flat_start)
    if bump:
        field = _bump_field(seed, flat)
        etree.SubElement(
            mjcf_asset(root),
            "hfield",
            name="bumps",
            nrow=str(field.shape[0]),
            ncol=str(field.shape[1]),
            size=f"{num(_BUMP_HALF[0])} {num(_BUMP_HALF[1])} {num(2 * bump)} {num(0.05)}",
            elevation=" ".join(num(v) for v in field[::-1].ravel()),  # MJCF: the top row first
        )
        grounds = [dict(name="ground", type="hfield", hfield="bumps", pos=f"0 0 {num(-bump)}")]
    for k, spec in enumerate(grounds):
        world.insert(k, etree.Element("geom", rgba="0.8 0.8 0.8 1", **spec))
    world.insert(
        0, etree.Element("light", name="hk_light", pos="0 0 3", dir="0 0 -1", directional="true")
    )
    act = etree.SubElement(root, "actuator")
    names = []
    for jn, jid in zip(wb.joint_names, jids):
        attrs = dict(name=f"{jn}_servo", joint=jn, kp=num(kp), kv=num(kv))
        frc = model.jnt_actfrcrange[jid] if model.jnt_actfrclimited[jid] else (-np.inf, np.inf)
        lim = float(min(abs(frc[0]), abs(frc[1])))
        if math.isfinite(lim):
            attrs.update(forcerange=f"{num(-lim)} {num(lim)}", forcelimited="true")
        etree.SubElement(act, "position", **attrs)
        names.append(attrs["name"])
    _exclude_touching(root, mujoco, wb, q0)
    if timestep is None:
        dt = _stable_timestep(mujoco, root, wb, q0, kp)
        option.set("timestep", num(dt))
    etree.indent(root, space="  ")
    text = etree.tostring(root, encoding="unicode") + "\n"
    return SimScene(
        xml=text,
        terrain=terrain,
        foot_radius=r,
        foot_geoms=tuple(foot_geoms),
        actuators=tuple(names),
        joint_names=tuple(wb.joint_names),
        leg_names=tuple(wb.leg_names),
        kp=kp,
        kv=kv,
        friction=mu,
        timestep=dt,
        armature=arm,
        contact_time=tc,
        bumps=bump,
        seed=int(seed),
        flat_start=flat,
    )


def _stable_timestep(mujoco: Any, root: Any, wb: Any, q0: np.ndarray, kp: float) -> float:
    """:data:`MAX_TIMESTEP` / k, the smallest whole k with ``ω dt <= STABLE_OMEGA_DT``."""
    from lxml import etree

    model = mujoco.MjModel.from_xml_string(etree.tostring(root, encoding="unicode"))
    data = mujoco.MjData(model)
    data.qpos[3] = 1.0
    jids = _joints(mujoco, model, wb.joint_names)
    data.qpos[model.jnt_qposadr[jids]] = q0
    mujoco.mj_forward(model, data)
    full = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, full)
    dofs = model.jnt_dofadr[jids]
    inertia = 1.0 / np.diag(np.linalg.inv(full))[dofs]
    omega = float(np.sqrt(kp / inertia).max())
    k = math.ceil(MAX_TIMESTEP * omega / STABLE_OMEGA_DT)
    return MAX_TIMESTEP / min(MAX_SPLIT, max(1, k))


def _bump_field(seed: int, flat: float = 0.0) -> np.ndarray:
    """(ny, nx) the bumps' elevations in [0, 1], seeded, MuJoCo's ``hfield_data`` order.

    0.5 (height 0) on the square ``|x|, |y| <= flat`` [m]; the far corners exactly 0 and 1, so
    MuJoCo's rescaling to [0, 1] keeps them.
    """
    nx, ny = (int(round(2 * h / _BUMP_CELL)) + 1 for h in _BUMP_HALF)
    grid = np.random.default_rng(seed).uniform(0.0, 1.0, ny * nx).reshape(ny, nx)
    if flat > 0:
        k, cy, cx = int(round(flat / _BUMP_CELL)), ny // 2, nx // 2
        grid[cy - k : cy + k + 1, cx - k : cx + k + 1] = 0.5
    grid[0, 0], grid[-1, -1] = 0.0, 1.0
    return grid


def _exclude_touching(root: Any, mujoco: Any, wb: Any, q0: np.ndarray) -> None:
    """Exclude contacts between robot bodies whose collision shapes touch in the neutral pose.

    A URDF's modelling artefact (ANYmal's thigh boxes cross its base box), found with the
    robot held in the air.
    """
    from lxml import etree

    model = mujoco.MjModel.from_xml_string(etree.tostring(root, encoding="unicode"))
    data = mujoco.MjData(model)
    data.qpos[:] = 0.0
    data.qpos[2], data.qpos[3] = 100.0, 1.0
    data.qpos[_joint_qpos(mujoco, model, wb.joint_names)] = q0
    mujoco.mj_forward(model, data)

    def name(b: int) -> str:
        return str(mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b))

    pairs: set[tuple[str, str]] = set()
    for c in data.contact[: data.ncon]:
        b1, b2 = int(model.geom_bodyid[c.geom1]), int(model.geom_bodyid[c.geom2])
        if b1 and b2 and b1 != b2:
            a, b = sorted((name(b1), name(b2)))
            pairs.add((a, b))
    if not pairs:
        return
    contact = root.find("contact")
    if contact is None:
        contact = etree.Element("contact")
        root.find("worldbody").addnext(contact)
    for a, b in sorted(pairs):
        etree.SubElement(contact, "exclude", body1=a, body2=b)


def _trim(elem: Any, model: Any, data: Any, g: int, foot: np.ndarray, r: float) -> None:
    """Shorten a link cylinder that ends at the foot point: the foot sphere alone is its tip.

    The flat end's rim (radius ρ) would touch the ground beside the sphere; the end moves back
    by ρ along the axis (at most half the cylinder).
    """
    from ..export._common import num, vec

    rho, half = float(model.geom_size[g, 0]), float(model.geom_size[g, 1])
    axis = data.geom_xmat[g].reshape(3, 3)[:, 2]
    for sign in (1.0, -1.0):
        if np.linalg.norm(data.geom_xpos[g] + sign * half * axis - foot) < 1e-9:
            cut = min(rho, half)
            local = model.geom_quat[g]
            mat = np.empty(9)
            mujoco = _mujoco()

            mujoco.mju_quat2Mat(mat, local)
            shift = -sign * 0.5 * cut * mat.reshape(3, 3)[:, 2]
            elem.set("size", f"{num(rho)} {num(half - 0.5 * cut)}")
            elem.set("pos", vec(np.asarray(model.geom_pos[g]) + shift))
            return


def _joints(mujoco: Any, model: Any, names: Any) -> np.ndarray:
    """The MuJoCo ids of the joints ``names`` (ConfigurationError for one not in the MJCF)."""
    ids = np.array([mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, n) for n in names], int)
    missing = [n for n, i in zip(names, ids) if i < 0]
    if missing:
        raise ConfigurationError(f"joint {missing[0]!r} is not in the robot's MJCF")
    return ids


def _joint_qpos(mujoco: Any, model: Any, names: Any) -> np.ndarray:
    """The ``qpos`` addresses of the joints ``names``."""
    return np.asarray(model.jnt_qposadr[_joints(mujoco, model, names)])


# ----------------------------------------------------------------------------- the engine
class _Engine:
    """A compiled scene: ids of the joints, actuators, feet and the ground."""

    def __init__(self, scene: SimScene) -> None:
        mujoco = _mujoco()
        self.mj = mujoco
        self.scene = scene
        self.model = m = mujoco.MjModel.from_xml_string(scene.xml)
        self.data = mujoco.MjData(m)
        self.jq = _joint_qpos(mujoco, m, scene.joint_names)
        self.act = np.array(
            [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, a) for a in scene.actuators]
        )
        geom = mujoco.mjtObj.mjOBJ_GEOM
        self.feet = np.array([mujoco.mj_name2id(m, geom, g) for g in scene.foot_geoms])
        self.leg_of = np.full(m.ngeom, -1)
        self.leg_of[self.feet] = np.arange(len(self.feet))
        self.ground = np.zeros(m.ngeom, dtype=bool)
        for name in ("ground", "step"):
            g = mujoco.mj_name2id(m, geom, name)
            if g >= 0:
                self.ground[g] = True
        self._vel = np.zeros(6)
        self._force = np.zeros(6)
        self._leg_list = [int(v) for v in self.leg_of]
        self._ground_list = [bool(v) for v in self.ground]
        self._geom_type = mujoco.mjtObj.mjOBJ_GEOM

    def label(self, g: int) -> str:
        """A geom's name, or ``body/index`` for an unnamed one."""
        m, mj = self.model, self.mj
        name = mj.mj_id2name(m, mj.mjtObj.mjOBJ_GEOM, g)
        if name:
            return str(name)
        b = int(m.geom_bodyid[g])
        return f"{mj.mj_id2name(m, mj.mjtObj.mjOBJ_BODY, b)}/{g - int(m.body_geomadr[b])}"

    def place(self, pose: np.ndarray, q: np.ndarray) -> None:
        """Base at ``pose`` (4×4), joints at ``q``, at rest."""
        mj, d = self.mj, self.data
        mj.mj_resetData(self.model, d)
        d.qpos[:3] = pose[:3, 3]
        quat = np.empty(4)
        mj.mju_mat2Quat(quat, np.ascontiguousarray(pose[:3, :3]).reshape(-1))
        d.qpos[3:7] = quat
        d.qpos[self.jq] = q
        d.ctrl[self.act] = q
        mj.mj_forward(self.model, d)

    def base_pose(self) -> np.ndarray:
        """The free base's 4×4 world pose."""
        d = self.data
        out = np.eye(4)
        mat = np.empty(9)
        self.mj.mju_quat2Mat(mat, d.qpos[3:7])
        out[:3, :3] = mat.reshape(3, 3)
        out[:3, 3] = d.qpos[:3]
        return out

    def contacts(self) -> tuple[np.ndarray, np.ndarray]:
        """(ncon, 2) geom pairs in contact, and (ncon,) True where one is a foot on the ground."""
        d = self.data
        nc = int(d.ncon)
        if nc == 0:
            return np.zeros((0, 2), dtype=int), np.zeros(0, dtype=bool)
        g = np.asarray(d.contact.geom[:nc]).reshape(nc, 2)
        feet = self.leg_of[g] >= 0
        ground = self.ground[g]
        ok = (feet[:, 0] & ground[:, 1]) | (feet[:, 1] & ground[:, 0])
        return g, ok

    def normal_forces(self) -> np.ndarray:
        """(L,) normal force of the ground on each foot now [N]."""
        out = np.zeros(len(self.feet))
        g, ok = self.contacts()
        for c in np.flatnonzero(ok):
            self.mj.mj_contactForce(self.model, self.data, int(c), self._force)
            out[self.leg_of[g[c]].max()] += self._force[0]
        return out

    def contact_forces(self) -> np.ndarray:
        """(L, 3) force of the ground on each foot now, world frame [N]."""
        out = np.zeros((len(self.feet), 3))
        g, ok = self.contacts()
        frames = self.data.contact.frame
        for c in np.flatnonzero(ok):
            self.mj.mj_contactForce(self.model, self.data, int(c), self._force)
            world = np.asarray(frames[c]).reshape(3, 3).T @ self._force[:3]
            foot_second = self.leg_of[g[c, 1]] >= 0  # the force acts on geom2 along +normal
            out[self.leg_of[g[c]].max()] += world if foot_second else -world
        return out

    def bottom_speed(self, leg: int, normal: tuple[float, float, float]) -> float:
        """Tangential speed [m/s] of a foot sphere's lowest point: ``v + ω × (−r n)`` ⟂ ``n``."""
        foot = int(self.feet[leg])
        self.mj.mj_objectVelocity(self.model, self.data, self._geom_type, foot, self._vel, 0)
        w, v = self._vel[:3], self._vel[3:]
        n = np.asarray(normal)
        u = v + np.cross(w, -self.scene.foot_radius * n)
        return float(np.linalg.norm(u - (u @ n) * n))

    def scan(self) -> tuple[list[tuple[int, int]], list[tuple[int, float, int]]]:
        """The contacts now: ``(others, feet)``.

        ``others``: the geom pairs that are not a foot on the ground; ``feet``: ``(leg, speed
        [m/s], contact index)``, the tangential speed of the foot's material point at the
        contact, ``v + ω × (p_c − c)`` less its normal part (zero for a rolling foot). Plain
        Python: a step has few contacts.
        """
        mj, m, d = self.mj, self.model, self.data
        nc = int(d.ncon)
        if nc == 0:
            return [], []
        con = d.contact
        pairs = con.geom[:nc].tolist()
        leg_of, ground = self._leg_list, self._ground_list
        others: list[tuple[int, int]] = []
        feet: list[tuple[int, float, int]] = []
        vel = self._vel
        xpos = d.geom_xpos
        for c, (g0, g1) in enumerate(pairs):
            if leg_of[g0] >= 0 and ground[g1]:
                foot = g0
            elif leg_of[g1] >= 0 and ground[g0]:
                foot = g1
            else:
                others.append((g0, g1))
                continue
            mj.mj_objectVelocity(m, d, self._geom_type, foot, vel, 0)
            wx, wy, wz, vx, vy, vz = vel.tolist()
            px, py, pz = con.pos[c].tolist()
            cx, cy, cz = xpos[foot].tolist()
            ax, ay, az = px - cx, py - cy, pz - cz
            vx += wy * az - wz * ay
            vy += wz * ax - wx * az
            vz += wx * ay - wy * ax
            nx, ny, nz = con.frame[c][:3].tolist()
            vn = vx * nx + vy * ny + vz * nz
            tx, ty, tz = vx - vn * nx, vy - vn * ny, vz - vn * nz
            feet.append((leg_of[foot], math.sqrt(tx * tx + ty * ty + tz * tz), c))
        return others, feet


def check_steps(timestep: Any, spans: dict[str, float], default_timestep: float = 1e-3) -> float:
    """Refuse a simulation of more than ``dynamics.MAX_STEPS`` physics steps; the timestep [s].

    ``spans`` maps each option to the simulated time it adds [s]; past the cap the refusal
    names the option adding the most, or ``timestep`` when the spans fit at ``default_timestep``.

    Raises:
        ParameterError: A timestep that is not > 0, a span not finite >= 0, too many steps.

    """
    from ..dynamics.forward import MAX_STEPS

    dt = positive("timestep", timestep)
    for name, span in spans.items():
        if not (isinstance(span, (int, float)) and math.isfinite(span) and span >= 0):
            raise ParameterError(
                f"{name}={span!r}: a time >= 0 s", parameter=name, value=span, allowed=">= 0"
            )
    total = sum(spans.values())
    if total / dt <= MAX_STEPS:
        return dt
    name = max(spans, key=lambda k: spans[k])
    if dt < default_timestep and total / default_timestep <= MAX_STEPS:
        name = "timestep"
    value = dt if name == "timestep" else spans[name]
    raise ParameterError(
        f"{name}={value!r}: {' + '.join(f'{k} {v:g} s' for k, v in spans.items())} at "
        f"timestep {dt:g} s is {total / dt:.3g} physics steps; at most {MAX_STEPS} (a larger "
        f"timestep or less simulated time)",
        parameter=name,
        value=value,
        allowed=f"(simulated time) / timestep <= {MAX_STEPS}",
    )
