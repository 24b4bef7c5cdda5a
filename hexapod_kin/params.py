"""Parameter tables: Khalil–Kleinfinger (modified DH) and standard DH rows, chains, robots.

Conventions, defined once here and used everywhere:

* **Khalil–Kleinfinger (modified DH)**, the lab reports' convention: row ``j`` gives
  ``^{j-1}T_j = Rx(alpha_j) · Tx(d_j) · Rz(theta_j) · Tz(r_j)``; ``q_j`` adds to ``theta_j``
  (revolute, ``sigma = 0``) or ``r_j`` (prismatic, ``sigma = 1``); a fixed row (``sigma = 2``)
  has none: it attaches the foot or tool frame.
* **Standard (Denavit–Hartenberg 1955) DH**, columns ``(theta, d, a, alpha)``:
  ``^{i-1}T_i = Rz(theta_i) · Tz(d_i) · Tx(a_i) · Rx(alpha_i)``; ``q`` adds to ``theta_i``
  or ``d_i``. Khalil's ``d`` and ``alpha`` are standard DH's ``a`` and ``alpha`` of the
  *previous* row, Khalil's ``r`` its ``d``: :meth:`Chain.from_dh` converts exactly.
* **Poses**: ``T_a_b`` maps frame ``b`` coordinates to frame ``a`` (``p_a = T_a_b · p_b``), a 4×4
  matrix or ``(xyz [m], rpy [rad])``, fixed-axis X-Y-Z as URDF's ``<origin>``:
  ``R = Rz(yaw)·Ry(pitch)·Rx(roll)``. :class:`Pose` holds one; :func:`rpy_to_matrix` /
  :func:`matrix_to_rpy` are the only RPY conversions.
* **Base and tool** of a :class:`Chain`: ``T_base_tip = base · ^0T_1 ··· ^{n-1}T_n · tool``
  (:func:`hexapod_kin.table_fk`), ``base`` Khalil frame 0 in the base link, ``tool`` the tip
  frame in the last row's.

All lengths are in metres, angles in radians, masses in kg, inertias in kg·m².
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from ._pose import Pose, matrix_to_rpy, rpy_to_matrix
from .exceptions import ParameterError, choices, finite, positive

__all__ = ["KhalilRow", "DHRow", "JointLimits", "Inertial", "Chain", "LegMount",
           "Hexapod", "khalil_transform", "dh_transform", "rod_inertial",
           "chain_from_rows", "Pose", "rpy_to_matrix", "matrix_to_rpy"]  # fmt: skip

SigmaName = Literal["revolute", "prismatic", "fixed"]
_SIGMA: dict[Any, SigmaName] = {
    0: "revolute", 1: "prismatic", 2: "fixed",
    "revolute": "revolute", "prismatic": "prismatic", "fixed": "fixed",
    "r": "revolute", "p": "prismatic", "f": "fixed",
}  # fmt: skip

_NAME_OK = set("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-.")


def _sigma(value: Any, where: str) -> SigmaName:
    key = value.lower() if isinstance(value, str) else value
    if isinstance(key, bool) or key not in _SIGMA:
        raise ParameterError(
            f"{where}.sigma={value!r} is not allowed; use 'revolute' (0), 'prismatic' (1) or "
            "'fixed' (2)"
        )
    return _SIGMA[key]


def _name(value: Any, where: str) -> str:
    if not isinstance(value, str) or not value or not set(value) <= _NAME_OK:
        raise ParameterError(
            f"{where}={value!r} is not a valid name; use a non-empty string of letters, digits, "
            "'_', '-' or '.'"
        )
    return value


def _check_row(row: Any, fields: tuple[str, ...]) -> None:
    """Validate a table row in place: its ``sigma`` and finite ``fields``."""
    where = type(row).__name__
    object.__setattr__(row, "sigma", _sigma(row.sigma, where))
    for f in fields:
        object.__setattr__(row, f, finite(f"{where}.{f}", getattr(row, f)))


def _xyz(values: Any, where: str, named: str = "") -> tuple[float, ...]:
    """Three finite numbers, checked (``where`` names them in messages)."""
    if len(tuple(values)) != 3:
        raise ParameterError(f"{where}={values!r}: three numbers{named} required")
    return tuple(finite(f"{where}[{i}]", v) for i, v in enumerate(values))


def _names(names: tuple[str, ...], count: int, field: str, what: str) -> tuple[str, ...]:
    if len(names) != count:
        raise ParameterError(f"Chain.{field} has {len(names)} names; the table has {count} {what}")
    for i, n in enumerate(names):
        _name(n, f"Chain.{field}[{i}]")
    return names


def khalil_transform(alpha: float, d: float, theta: float, r: float) -> np.ndarray:
    """``^{j-1}T_j = Rx(alpha)·Tx(d)·Rz(theta)·Tz(r)`` (4×4, closed form; [rad], [m])."""
    ca, sa, ct, st = math.cos(alpha), math.sin(alpha), math.cos(theta), math.sin(theta)
    return np.array(
        [
            [ct, -st, 0.0, d],
            [ca * st, ca * ct, -sa, -r * sa],
            [sa * st, sa * ct, ca, r * ca],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


def dh_transform(theta: float, d: float, a: float, alpha: float) -> np.ndarray:
    """The standard-DH ``^{i-1}T_i = Rz(theta)·Tz(d)·Tx(a)·Rx(alpha)`` (4×4; [rad], [m])."""
    ca, sa, ct, st = math.cos(alpha), math.sin(alpha), math.cos(theta), math.sin(theta)
    return np.array(
        [
            [ct, -st * ca, st * sa, a * ct],
            [st, ct * ca, -ct * sa, a * st],
            [0.0, sa, ca, d],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


@dataclass(frozen=True)
class KhalilRow:
    """One Khalil–Kleinfinger row: ``^{j-1}T_j = Rx(alpha)·Tx(d)·Rz(theta)·Tz(r)``, ``q`` added.

    Attributes:
        sigma: ``"revolute"`` (0), ``"prismatic"`` (1) or ``"fixed"`` (2).
        alpha: Twist about ``x_{j-1}`` in [rad].
        d: Distance along ``x_{j-1}`` in [m].
        theta: Angle about ``z_j`` in [rad] (offset added to ``q`` for a revolute joint).
        r: Distance along ``z_j`` in [m] (offset added to ``q`` for a prismatic joint).

    """

    sigma: SigmaName | int | str
    alpha: float = 0.0
    d: float = 0.0
    theta: float = 0.0
    r: float = 0.0

    def __post_init__(self) -> None:
        _check_row(self, ("alpha", "d", "theta", "r"))

    @property
    def is_joint(self) -> bool:
        """True when the row carries a joint variable (revolute or prismatic)."""
        return self.sigma != "fixed"

    def transform(self, q: float = 0.0) -> np.ndarray:
        """Return ``^{j-1}T_j`` at joint value ``q`` ([rad] or [m]; ignored when fixed)."""
        theta = self.theta + q if self.sigma == "revolute" else self.theta
        r = self.r + q if self.sigma == "prismatic" else self.r
        return khalil_transform(self.alpha, self.d, theta, r)


@dataclass(frozen=True)
class DHRow:
    """One row of a standard DH table: ``Rz(theta)·Tz(d)·Tx(a)·Rx(alpha)``.

    Attributes:
        theta: Angle about ``z_{i-1}`` in [rad] (offset added to ``q`` when revolute).
        d: Offset along ``z_{i-1}`` in [m] (offset added to ``q`` when prismatic).
        a: Link length along ``x_i`` in [m].
        alpha: Link twist about ``x_i`` in [rad].
        sigma: ``"revolute"`` (0), ``"prismatic"`` (1) or ``"fixed"`` (2).

    """

    theta: float = 0.0
    d: float = 0.0
    a: float = 0.0
    alpha: float = 0.0
    sigma: SigmaName | int | str = "revolute"

    def __post_init__(self) -> None:
        _check_row(self, ("theta", "d", "a", "alpha"))

    def transform(self, q: float = 0.0) -> np.ndarray:
        """Return ``^{i-1}T_i`` at joint value ``q``."""
        theta = self.theta + q if self.sigma == "revolute" else self.theta
        d = self.d + q if self.sigma == "prismatic" else self.d
        return dh_transform(theta, d, self.a, self.alpha)


@dataclass(frozen=True)
class JointLimits:
    """Limits of one joint, in the units of its variable.

    ``lower <= upper`` in [rad] or [m]; maximum ``velocity`` [rad/s] or [m/s] and ``effort``
    (torque [N·m] or force [N]), both ``>= 0``.
    """

    lower: float = -math.pi
    upper: float = math.pi
    velocity: float = 10.0
    effort: float = 10.0

    def __post_init__(self) -> None:
        for f in ("lower", "upper", "velocity", "effort"):
            object.__setattr__(self, f, finite(f"JointLimits.{f}", getattr(self, f)))
        if self.lower > self.upper:
            raise ParameterError(
                f"JointLimits: lower={self.lower} > upper={self.upper}; lower <= upper required"
            )
        if self.velocity < 0 or self.effort < 0:
            raise ParameterError(
                f"JointLimits: velocity={self.velocity}, effort={self.effort}; both must be >= 0"
            )


@dataclass(frozen=True)
class Inertial:
    """Mass properties of a link, in the link's (Khalil) frame.

    ``mass`` > 0 [kg]; centre of mass ``com`` [m]; ``inertia`` ``(ixx, iyy, izz, ixy, ixz,
    iyz)`` about it [kg·m²], positive definite, obeying the triangle inequality.
    """

    mass: float
    com: tuple[float, float, float] = (0.0, 0.0, 0.0)
    inertia: tuple[float, float, float, float, float, float] = (1e-6, 1e-6, 1e-6, 0, 0, 0)

    def __post_init__(self) -> None:
        object.__setattr__(self, "mass", positive("Inertial.mass", self.mass))
        object.__setattr__(self, "com", _xyz(self.com, "Inertial.com", " (x, y, z)"))
        if len(tuple(self.inertia)) != 6:
            raise ParameterError(
                f"Inertial.inertia={self.inertia!r}: six numbers (ixx, iyy, izz, ixy, ixz, iyz)"
            )
        ii = tuple(finite(f"Inertial.inertia[{i}]", v) for i, v in enumerate(self.inertia))
        object.__setattr__(self, "inertia", ii)
        mat = self.matrix()
        eig = np.linalg.eigvalsh(mat)
        if eig[0] <= 0:
            raise ParameterError(
                f"Inertial.inertia={ii}: not positive definite (eigenvalues {eig.tolist()})"
            )
        a, b, c = eig
        tol = 1e-12 * max(1.0, c)
        if a + b < c - tol:
            raise ParameterError(
                f"Inertial.inertia={ii}: principal moments {eig.tolist()} violate the triangle "
                "inequality (I1 + I2 >= I3)"
            )

    def matrix(self) -> np.ndarray:
        """Return the 3×3 inertia matrix about the centre of mass in [kg·m²]."""
        ixx, iyy, izz, ixy, ixz, iyz = self.inertia
        return np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]], dtype=float)


def rod_inertial(start: np.ndarray, end: np.ndarray, mass: float, radius: float) -> Inertial:
    """Inertial of a solid rod from ``start`` to ``end`` ([m], link frame), com at its middle.

    ``mass`` in [kg], ``radius`` in [m]; a zero-length rod is a solid sphere of ``radius``.
    """
    start, end = np.asarray(start, float), np.asarray(end, float)
    vec = end - start
    length = float(np.linalg.norm(vec))
    com = 0.5 * (start + end)
    if length < 1e-9:
        mat = np.eye(3) * (0.4 * mass * radius**2)
    else:
        u = vec / length
        axial = 0.5 * mass * radius**2
        transverse = mass * (3 * radius**2 + length**2) / 12.0
        mat = transverse * (np.eye(3) - np.outer(u, u)) + axial * np.outer(u, u)
    inertia = (mat[0, 0], mat[1, 1], mat[2, 2], mat[0, 1], mat[0, 2], mat[1, 2])
    return Inertial(mass=mass, com=(float(com[0]), float(com[1]), float(com[2])), inertia=inertia)


def default_limits(sigma: str) -> JointLimits:
    """The limits a joint row gets when none are given: ±π rad, or ±0.1 m when prismatic."""
    if sigma == "prismatic":
        return JointLimits(lower=-0.1, upper=0.1, velocity=0.5, effort=100.0)
    return JointLimits()


@dataclass(frozen=True)
class Chain:
    """A serial chain by a Khalil–Kleinfinger table: frame 0 the base, ``j`` row ``j``'s frame.

    Attributes:
        rows: The Khalil rows, in order from the base.
        joint_names: One name per *joint* row (revolute/prismatic); default ``q1, q2, ...``.
        limits: One :class:`JointLimits` per joint row; default ±π rad (revolute),
            ±0.1 m (prismatic).
        inertials: One :class:`Inertial` per row (the link carried by that row's frame) or
            ``None`` for a default: a rod of ``link_mass`` from the frame origin to the next
            frame's origin (the tip link gets a small sphere).
        name: Robot name in the URDF; ``description`` (free text, the preset's source) goes into
            its header.
        base: Name of the base link. A pose (4×4 or ``(xyz, rpy)``) may be given here
            instead: it becomes :attr:`base_pose` and the link keeps the name ``"base"``.
        tip: Name of the tip frame: the last row's link, or the tool link when :attr:`tool`
            is set.
        link_names: Names of the links of frames 1..n; default ``link1, ...``, the last one
            ``tip`` (with a tool: ``link<n>``, the tool link is ``tip``).
        link_mass: Default link mass in [kg] when ``inertials`` is ``None``.
        link_radius: Radius in [m] of the visual cylinders and default rod inertia.
        damping: Joint viscous damping ([N·m·s/rad] or [N·s/m]) and ``friction`` (dry), one
            value or one per joint.
        base_pose: ``T_base_0``: Khalil frame 0 in the base link (anything :meth:`Pose.of`
            takes; ``None``: identity).
        tool: ``T_n_tool``: the tool frame in the last row's (``None``: no tool link).

    """

    rows: tuple[KhalilRow, ...]
    joint_names: tuple[str, ...] | None = None
    limits: tuple[JointLimits, ...] | None = None
    inertials: tuple[Inertial | None, ...] | None = None
    name: str = "chain"
    base: str = "base"
    tip: str = "foot"
    link_names: tuple[str, ...] | None = None
    link_mass: float = 0.1
    link_radius: float = 0.01
    damping: float | tuple[float, ...] = 0.0
    friction: float | tuple[float, ...] = 0.0
    description: str = ""
    base_pose: Pose | None = None
    tool: Pose | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.base, str):
            if self.base_pose is not None:
                raise ParameterError(
                    "Chain: base= is a pose and base_pose= is given too; give the pose once"
                )
            object.__setattr__(self, "base_pose", Pose.of(self.base, "Chain.base"))
            object.__setattr__(self, "base", "base")
        for f in ("base_pose", "tool"):
            v = getattr(self, f)
            if v is not None:
                pose = Pose.of(v, f"Chain.{f}")
                object.__setattr__(self, f, None if pose.is_identity and f == "base_pose" else pose)
        rows = tuple(self.rows)
        if not rows:
            raise ParameterError("Chain.rows=() is empty; at least one KhalilRow is required")
        for i, row in enumerate(rows, start=1):
            if not isinstance(row, KhalilRow):
                raise ParameterError(
                    f"Chain.rows[{i}]={row!r} is not a KhalilRow (convert DH tables with "
                    "Chain.from_dh)"
                )
        object.__setattr__(self, "rows", rows)
        joint_rows = [r for r in rows if r.is_joint]
        nj = len(joint_rows)
        if nj == 0:
            raise ParameterError("Chain.rows has no revolute or prismatic row; nothing moves")
        default_names = tuple(f"q{i}" for i in range(1, nj + 1))
        names = default_names if self.joint_names is None else tuple(self.joint_names)
        object.__setattr__(self, "joint_names", _names(names, nj, "joint_names", "joint rows"))
        defaults = tuple(default_limits(str(r.sigma)) for r in joint_rows)
        limits = defaults if self.limits is None else tuple(self.limits)
        if len(limits) != nj or not all(isinstance(x, JointLimits) for x in limits):
            raise ParameterError(
                f"Chain.limits: {nj} JointLimits required (one per joint row), got {len(limits)}"
            )
        object.__setattr__(self, "limits", limits)
        for f in ("name", "base", "tip"):
            _name(getattr(self, f), f"Chain.{f}")
        if self.link_names is not None:
            links = tuple(self.link_names)
        elif self.tool is not None:
            links = tuple(f"link{j}" for j in range(1, len(rows) + 1))
        else:
            links = tuple(f"link{j}" for j in range(1, len(rows))) + (self.tip,)
        object.__setattr__(self, "link_names", _names(links, len(rows), "link_names", "rows"))
        all_names: tuple[str, ...] = (self.base, *links)
        if self.base_pose is not None:
            all_names += (self.frame0_link,)
        if self.tool is not None:
            all_names += (self.tip,)
        if len(set(all_names)) != len(all_names):
            raise ParameterError(f"Chain link names must be unique, got {all_names}")
        if len(set(names)) != len(names):
            raise ParameterError(f"Chain.joint_names must be unique, got {names}")
        positive("Chain.link_mass", self.link_mass)
        positive("Chain.link_radius", self.link_radius)
        if self.inertials is not None:
            inn = tuple(self.inertials)
            if len(inn) != len(rows) or not all(x is None or isinstance(x, Inertial) for x in inn):
                raise ParameterError(
                    f"Chain.inertials: {len(rows)} entries (Inertial or None) required, one per row"
                )
            object.__setattr__(self, "inertials", inn)
        for f in ("damping", "friction"):
            v = getattr(self, f)
            vals = (v,) * nj if isinstance(v, (int, float)) else tuple(v)
            if len(vals) != nj:
                raise ParameterError(f"Chain.{f}: one value or {nj} values required, got {v!r}")
            vals = tuple(finite(f"Chain.{f}", x) for x in vals)
            if any(x < 0 for x in vals):
                raise ParameterError(f"Chain.{f}={v!r}: values must be >= 0")
            object.__setattr__(self, f, vals if not isinstance(v, (int, float)) else float(v))

    # ----------------------------------------------------------------- derived facts
    @property
    def frame0_link(self) -> str:
        """Name of the link of Khalil frame 0: the base link, or ``<base>_frame0`` when offset."""
        return self.base if self.base_pose is None else f"{self.base}_frame0"

    @property
    def base_matrix(self) -> np.ndarray:
        """``T_base_0`` as a 4×4 array (identity when no base pose)."""
        return np.eye(4) if self.base_pose is None else self.base_pose.matrix

    @property
    def tool_matrix(self) -> np.ndarray:
        """``T_n_tool`` as a 4×4 array (identity when no tool)."""
        return np.eye(4) if self.tool is None else self.tool.matrix

    @property
    def nq(self) -> int:
        """Number of joint variables."""
        return len(self.joint_names or ())

    @property
    def joint_rows(self) -> tuple[int, ...]:
        """Indices (0-based) of the rows carrying a joint variable."""
        return tuple(i for i, r in enumerate(self.rows) if r.is_joint)

    @property
    def sigmas(self) -> tuple[str, ...]:
        """Joint types of the joint rows, in order."""
        return tuple(str(self.rows[i].sigma) for i in self.joint_rows)

    def _per_joint(self, v: float | tuple[float, ...]) -> tuple[float, ...]:
        return (float(v),) * self.nq if isinstance(v, (int, float)) else tuple(v)

    def joint_damping(self) -> tuple[float, ...]:
        """Damping per joint."""
        return self._per_joint(self.damping)

    def joint_friction(self) -> tuple[float, ...]:
        """Dry friction per joint."""
        return self._per_joint(self.friction)

    def lower(self) -> np.ndarray:
        """Lower joint bounds (n,)."""
        return np.array([lim.lower for lim in self.limits or ()])

    def upper(self) -> np.ndarray:
        """Upper joint bounds (n,)."""
        return np.array([lim.upper for lim in self.limits or ()])

    def link_inertial(self, j: int) -> Inertial:
        """Inertial of the link of row ``j`` (0-based), the given one or the default rod."""
        inertial = None if self.inertials is None else self.inertials[j]
        if inertial is not None:
            return inertial
        if j + 1 < len(self.rows):
            nxt, mass = self.rows[j + 1].transform(0.0)[:3, 3], self.link_mass
        else:
            nxt, mass = np.zeros(3), 0.2 * self.link_mass
        return rod_inertial(np.zeros(3), nxt, mass, self.link_radius)

    def replace(self, **changes: Any) -> Chain:
        """Return a copy with fields replaced (validated again)."""
        from dataclasses import replace

        return replace(self, **changes)

    # ----------------------------------------------------------------- constructors
    @classmethod
    def from_dh(
        cls, dh_rows: Sequence[DHRow], *, base: Any = None, tool: Any = None, **kwargs: Any
    ) -> Chain:
        """Build a chain from a standard-DH table, exactly (the same FK to rounding).

        ``Π Rz(θi)Tz(di)Tx(ai)Rx(αi)`` regrouped (``Tx`` and ``Rx`` commute) into Khalil rows
        ``(α_{i-1}, a_{i-1}, θ_i, d_i)`` plus a fixed last row ``(α_n, a_n, 0, 0)``: the tip.

        Args:
            dh_rows: Standard-DH rows from the base.
            base: ``T_base_0`` (pose: 4×4 or ``(xyz, rpy)``) or a base link name; ``None``
                keeps the defaults.
            tool: ``T_n_tool`` in the last DH frame (pose), ``None`` for none.
            **kwargs: Other :class:`Chain` fields (names, limits, tip, ...). ``link_names``
                and ``inertials``, if given, must have ``len(dh_rows) + 1`` entries.

        Raises:
            ParameterError: Empty table, a non-DHRow entry, or invalid chain fields.

        """
        kwargs |= {k: v for k, v in (("base", base), ("tool", tool)) if v is not None}
        dh = list(dh_rows)
        if not dh or not all(isinstance(r, DHRow) for r in dh):
            raise ParameterError("Chain.from_dh: a non-empty sequence of DHRow is required")
        rows = []
        prev_alpha, prev_a = 0.0, 0.0
        for row in dh:
            rows.append(KhalilRow(row.sigma, prev_alpha, prev_a, row.theta, row.d))
            prev_alpha, prev_a = row.alpha, row.a
        rows.append(KhalilRow("fixed", prev_alpha, prev_a, 0.0, 0.0))
        return cls(rows=tuple(rows), **kwargs)


def chain_from_rows(rows: Sequence[Sequence[Any]], **kwargs: Any) -> Chain:
    """Build a :class:`Chain` from plain tuples ``(sigma, alpha, d, theta, r)``, one per row.

    Raises:
        ParameterError: A malformed row or value (naming the row, 1-based, and the field).

    """
    built = []
    for j, row in enumerate(rows, start=1):
        try:
            values = tuple(row)
            if len(values) != 5:
                raise ParameterError(f"{len(values)} values; (sigma, alpha, d, theta, r) required")
            built.append(KhalilRow(*values))
        except ParameterError as exc:
            raise ParameterError(f"row {j}: {exc}") from None
        except TypeError:
            raise ParameterError(f"row {j}: {row!r} is not a sequence of 5 values") from None
    return Chain(rows=tuple(built), **kwargs)


@dataclass(frozen=True)
class LegMount:
    """A leg fixed to the body: a chain and its mount pose on the body.

    ``chain``'s frame 0 is the mount frame, at ``xyz`` [m] in the body frame, turned by ``yaw``
    [rad] about the body z axis; ``name`` prefixes its joints and links (``"leg1"``).
    """

    name: str
    chain: Chain
    xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    yaw: float = 0.0

    def __post_init__(self) -> None:
        _name(self.name, "LegMount.name")
        if not isinstance(self.chain, Chain):
            raise ParameterError(f"LegMount.chain={self.chain!r} is not a Chain")
        object.__setattr__(self, "xyz", _xyz(self.xyz, "LegMount.xyz"))
        object.__setattr__(self, "yaw", finite("LegMount.yaw", self.yaw))

    def transform(self) -> np.ndarray:
        """Return ``^{body}T_{mount}`` (4×4)."""
        t = khalil_transform(0.0, 0.0, self.yaw, 0.0)  # Rz(yaw)
        t[:3, 3] = self.xyz
        return t


@dataclass(frozen=True)
class Hexapod:
    """A body carrying ``legs`` (six :class:`LegMount` for a hexapod), its link ``body``.

    ``body_size``: the body box ``(x, y, z)`` [m] (visual and inertia), ``body_mass`` [kg];
    ``name`` and ``description`` go into the URDF.
    """

    legs: tuple[LegMount, ...]
    name: str = "hexapod"
    body: str = "body"
    body_size: tuple[float, float, float] = (0.30, 0.20, 0.05)
    body_mass: float = 1.0
    description: str = ""

    def __post_init__(self) -> None:
        legs = tuple(self.legs)
        if not legs or not all(isinstance(x, LegMount) for x in legs):
            raise ParameterError("Hexapod.legs: a non-empty sequence of LegMount is required")
        object.__setattr__(self, "legs", legs)
        _name(self.name, "Hexapod.name")
        _name(self.body, "Hexapod.body")
        names = [x.name for x in legs]
        if len(set(names)) != len(names):
            raise ParameterError(f"Hexapod.legs names must be unique, got {names}")
        size = tuple(finite("Hexapod.body_size", v) for v in self.body_size)
        if len(size) != 3 or min(size) <= 0:
            raise ParameterError(f"Hexapod.body_size={self.body_size!r}: three lengths > 0 m")
        object.__setattr__(self, "body_size", size)
        object.__setattr__(self, "body_mass", positive("Hexapod.body_mass", self.body_mass))

    @property
    def nq(self) -> int:
        """Total number of joint variables."""
        return sum(leg.chain.nq for leg in self.legs)

    @property
    def joint_names(self) -> tuple[str, ...]:
        """Joint names ``<leg>_<joint>`` in leg order."""
        return tuple(f"{leg.name}_{j}" for leg in self.legs for j in (leg.chain.joint_names or ()))

    @property
    def foot_frames(self) -> tuple[str, ...]:
        """Tip frame names ``<leg>_<tip>`` in leg order."""
        return tuple(f"{leg.name}_{leg.chain.tip}" for leg in self.legs)

    def leg(self, name: str) -> LegMount:
        """Return the leg mount called ``name``."""
        for leg in self.legs:
            if leg.name == name:
                return leg
        raise ParameterError(
            f"leg={name!r} does not exist; legs are {choices(x.name for x in self.legs)}"
        )
