"""The catalogue: the seed systems (``hexapod_kin/report/seeds/``) as named presets.

Each returns a validated :class:`~hexapod_kin.params.Chain` (or
:class:`~hexapod_kin.params.Hexapod`) from dimensions in SI units, its docstring naming its
seed and table; :data:`PRESETS` maps names to them (sorted).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

from .exceptions import HexapodKinError, ParameterError, choices, positive
from .params import Chain, Hexapod, Inertial, JointLimits, KhalilRow, LegMount

__all__ = ["PRESETS", "coxa_tibia_leg", "get", "hexabot_leg", "hexapod", "names",
           "pendulum", "scara"]  # fmt: skip


def hexabot_leg(
    l1: float = 0.05,
    l2: float = 0.10,
    l3: float = 0.10,
    alpha2: float = -math.pi / 2,
    *,
    name: str = "hexabot_leg",
    limits: tuple[JointLimits, ...] | None = None,
) -> Chain:
    """3-DOF hip/knee/ankle leg of seeds 000/001/003 (seed 001, Table 1).

    ===  =====  ======  ====  ===  ====
    j    σ      α       d     θ    r
    ===  =====  ======  ====  ===  ====
    1    0      0       0     q1   0
    2    0      α2      l1    q2   0
    3    0      0       l2    q3   0
    4    fixed  0       l3    0    0
    ===  =====  ======  ====  ===  ====

    With the default ``alpha2 = −π/2`` the foot is at
    ``Rz(q1)·[l1 + l2 c2 + l3 c23, 0, −(l2 s2 + l3 s23)]``: a positive knee angle moves the
    foot down (−z).

    ``l1``, ``l2``, ``l3``: coxa, femur, tibia lengths in [m]; ``alpha2``: row 2's twist
    [rad]; ``limits``: three (default ±π rad, 10 rad/s, 10 N·m). Joints ``hip, knee, ankle``,
    tip ``foot``.

    """
    l1, l2, l3 = positive("l1", l1), positive("l2", l2), positive("l3", l3)
    return Chain(
        rows=(KhalilRow(0), KhalilRow(0, alpha2, l1), KhalilRow(0, d=l2), KhalilRow(2, d=l3)),
        joint_names=("hip", "knee", "ankle"),
        limits=limits,
        link_names=("coxa", "femur", "tibia", "foot"),
        name=name,
        tip="foot",
        link_mass=0.05,
        link_radius=0.008,
        description=f"hexabot_leg(l1={l1}, l2={l2}, l3={l3}, alpha2={alpha2}) — seed 001 Table 1",
    )


def coxa_tibia_leg(
    l1: float = 10.0,
    l2: float = 5.0,
    *,
    name: str = "coxa_tibia_leg",
    limits: tuple[JointLimits, ...] | None = None,
) -> Chain:
    """2-DOF coxa/tibia leg of seed 002, in its convention (negative tibia angle lowers the foot).

    ===  =====  =====  ====  ===  ===
    j    σ      α      d     θ    r
    ===  =====  =====  ====  ===  ===
    1    0      0      0     θ1   0
    2    0      +π/2   l1    θ2   0
    3    fixed  0      l2    0    0
    ===  =====  =====  ====  ===  ===

    ``P = Rz(θ1)·[l1 + l2 cos θ2, 0, l2 sin θ2]``; with l1 = 10, l2 = 5: (0°, −30°) →
    (14.3301, 0, −2.5) and (20°, −30°) → (13.4659, 4.9012, −2.5).

    ``l1``, ``l2``: coxa and tibia lengths (the paper's numbers, read as metres); ``limits``:
    two (default ±π). Joints ``coxa, tibia``, tip ``foot``.

    """
    l1, l2 = positive("l1", l1), positive("l2", l2)
    scale = max(l1, l2)
    return Chain(
        rows=(KhalilRow(0), KhalilRow(0, math.pi / 2, l1), KhalilRow(2, d=l2)),
        joint_names=("coxa", "tibia"),
        limits=limits,
        link_names=("coxa_link", "tibia_link", "foot"),
        name=name,
        tip="foot",
        link_mass=0.05,
        link_radius=0.02 * scale,
        description=f"coxa_tibia_leg(l1={l1}, l2={l2}) — seed 002",
    )


def scara(
    r1: float = 0.4524,
    d2: float = 0.220,
    d3: float = 0.240,
    stroke: float = 0.2,
    *,
    name: str = "scara",
) -> Chain:
    """SCARA arm of seed 003 (Experiment 1) with its prismatic last joint.

    ===  =====  ===  ====  ===  ====
    j    σ      α    d     θ    r
    ===  =====  ===  ====  ===  ====
    1    0      0    0     θ1   r1
    2    0      0    d2    θ2   0
    3    0      0    d3    θ3   0
    4    1      π    0     0    q4
    5    fixed  0    0     0    0
    ===  =====  ===  ====  ===  ====

    The prismatic variable ``q4 ∈ [0, stroke]`` moves the tool down (α = π flips z).
    Singular when the arm is stretched or folded: ``θ2 = 0`` or ``θ2 = π``.

    ``r1``: height of the first joint frame, ``d2``, ``d3``: arm lengths, ``stroke``: the
    prismatic range [0, stroke], all in [m]. Joints ``theta1, theta2, theta3, q4``, tip ``tool``.

    """
    r1 = positive("r1", r1)
    d2, d3, stroke = positive("d2", d2), positive("d3", d3), positive("stroke", stroke)
    joints = (KhalilRow(0, r=r1), KhalilRow(0, d=d2), KhalilRow(0, d=d3), KhalilRow(1, math.pi))
    return Chain(
        rows=(*joints, KhalilRow(2)),
        joint_names=("theta1", "theta2", "theta3", "q4"),
        limits=(JointLimits(-math.pi, math.pi, 3.0, 50.0),) * 2
        + (JointLimits(-math.pi, math.pi, 5.0, 10.0), JointLimits(0.0, stroke, 0.5, 200.0)),
        link_names=("shoulder", "forearm", "wrist", "quill", "tool"),
        name=name,
        tip="tool",
        link_mass=1.0,
        link_radius=0.02,
        description=f"scara(r1={r1}, d2={d2}, d3={d3}, stroke={stroke}) — seed 003 Experiment 1",
    )


def pendulum(
    length: float = 0.5, mass: float = 1.0, damping: float = 0.01, *, name: str = "pendulum"
) -> Chain:
    """Simple pendulum of seed 001 §1: a point mass on a massless-like rod.

    Row 1 is a revolute joint whose axis ``z1`` is horizontal (α = π/2 turns it onto −y of the
    base); the rod lies along ``x1``; gravity acts along −z of the base. At ``q = 0`` the rod is
    horizontal; ``q = −π/2`` hangs it straight down. The seed's initial angle is 30° from the
    vertical, i.e. ``q0 = −π/2 + π/6``. Joint damping ``damping`` [N·m·s/rad] goes into the URDF.

    ``length`` of the rod [m], ``mass`` of the bob [kg]. Joint ``swing``, tip ``bob``.

    """
    length, mass = positive("length", length), positive("mass", mass)
    damping = positive("damping", damping, allow_zero=True)
    rod_r, bob_r, rod_m = 0.01 * length, 0.05 * length, 1e-3 * mass
    bob = Inertial(mass=mass, inertia=(0.4 * mass * bob_r**2,) * 3 + (0.0, 0.0, 0.0))
    i_t, i_a = rod_m * (3 * rod_r**2 + length**2) / 12.0, 0.5 * rod_m * rod_r**2
    rod = Inertial(mass=rod_m, com=(length / 2, 0.0, 0.0), inertia=(i_a, i_t, i_t, 0, 0, 0))
    return Chain(
        rows=(KhalilRow(0, math.pi / 2), KhalilRow(2, d=length)),
        joint_names=("swing",),
        limits=(JointLimits(-2 * math.pi, 2 * math.pi, 50.0, 10.0),),
        inertials=(rod, bob),
        link_names=("rod", "bob"),
        name=name,
        tip="bob",
        link_radius=rod_r,
        damping=damping,
        description=f"pendulum(length={length}, mass={mass}, damping={damping}) — seed 001 §1",
    )


#: Default mount yaw angles of the six legs [deg], counter-clockwise from front-left.
DEFAULT_MOUNT_YAW_DEG = (30.0, 90.0, 150.0, -150.0, -90.0, -30.0)


def hexapod(
    body_radius: float = 0.12,
    l1: float = 0.05,
    l2: float = 0.10,
    l3: float = 0.10,
    body_height: float = 0.05,
    body_mass: float = 1.0,
    mount_yaw_deg: tuple[float, ...] = DEFAULT_MOUNT_YAW_DEG,
    *,
    name: str = "hexapod",
) -> Hexapod:
    """The six-legged robot: a body with six ``hexabot_leg`` legs on fixed mounts.

    Default layout: legs ``leg1``..``leg6`` numbered counter-clockwise seen from above,
    starting front-left; leg *i* is mounted on a circle of radius ``body_radius`` in the body's
    xy-plane at yaw ``mount_yaw_deg[i]`` (30°, 90°, 150°, −150°, −90°, −30°) and points
    radially outward (its hip axis is the body z axis). Body x points forward, z up.

    ``body_radius``, ``body_height`` [m], ``body_mass`` [kg]; ``l1``, ``l2``, ``l3`` as
    :func:`hexabot_leg`; ``mount_yaw_deg``: one per leg. Joints ``leg<i>_hip/knee/ankle``,
    feet ``leg<i>_foot``.

    """
    body_radius = positive("body_radius", body_radius)
    body_height = positive("body_height", body_height)
    yaws = tuple(float(y) for y in mount_yaw_deg)
    if not yaws:
        raise ParameterError("mount_yaw_deg=() is empty; one yaw per leg is required")
    leg = hexabot_leg(l1, l2, l3)
    legs = tuple(
        LegMount(f"leg{i + 1}", leg, (body_radius * math.cos(a), body_radius * math.sin(a), 0.0), a)
        for i, a in enumerate(math.radians(y) for y in yaws)
    )
    return Hexapod(
        legs=legs,
        name=name,
        body_size=(2.2 * body_radius, 1.6 * body_radius, body_height),
        body_mass=body_mass,
        description=(
            f"hexapod(body_radius={body_radius}, l1={l1}, l2={l2}, l3={l3}, "
            f"mount_yaw_deg={list(yaws)})"
        ),
    )


#: Registry of presets by name (sorted; a test keeps it sorted).
PRESETS: dict[str, Callable[..., Any]] = {
    "coxa_tibia_leg": coxa_tibia_leg,
    "hexabot_leg": hexabot_leg,
    "hexapod": hexapod,
    "pendulum": pendulum,
    "scara": scara,
}


def names() -> list[str]:
    """Return the preset names, sorted."""
    return sorted(PRESETS)


def get(name: str, /, **params: Any) -> Chain | Hexapod:
    """Build the preset ``name`` with ``params`` overriding its defaults.

    Raises:
        ParameterError: If the name or a parameter is unknown (the message lists valid ones),
            or a number is beyond 1e9 (SI units: the loader's cap on any value).

    """
    if name not in PRESETS:
        raise ParameterError(f"preset={name!r} does not exist; presets are {choices(names())}")
    import inspect

    func = PRESETS[name]
    known = inspect.signature(func).parameters
    for key in params:
        if key not in known:
            raise ParameterError(
                f"{name}: parameter {key!r} does not exist; parameters are {choices(known)}"
            )
    for key, value in params.items():
        for v in value if isinstance(value, (list, tuple)) else (value,):
            if isinstance(v, (int, float)) and not isinstance(v, bool) and not abs(v) <= 1e9:
                text = f"{v:g}" if isinstance(v, float) else f"an integer of {v.bit_length()} bits"
                raise ParameterError(
                    f"{name}: {key}={text} is beyond 1e9 (SI units), the loader's cap on any value",
                    parameter=key,
                    value=text,
                    allowed="|value| <= 1e9",
                )
    try:
        return func(**params)  # type: ignore[no-any-return,unused-ignore]
    except HexapodKinError:
        raise
    except (TypeError, ValueError) as exc:
        bad = {k: v for k, v in params.items() if not isinstance(v, (int, float, list, tuple))}
        raise ParameterError(
            f"{name}: {exc}"
            + (f" (non-numeric: {bad}; dimensions are numbers in SI units)" if bad else ""),
            parameter=next(iter(bad), None),
            value=next(iter(bad.values()), None),
            allowed="a number (SI units)",
        ) from None
