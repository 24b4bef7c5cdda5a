r"""Servo calibration: how each joint's angle maps to its servo's command, and the servo's limits.

A calibration file (``.yaml``/``.yml``, ``.toml`` or ``.json``) has a ``defaults`` table (the
settings of every joint not listed) and a ``joints`` table (per joint, overriding the
defaults). Keys: ``units`` (``rad``, ``deg``, ``ticks``, ``us``), ``offset`` (joint angle at
the servo's centre [rad]), ``direction`` (±1), ``ticks_per_revolution`` and ``centre``
(ticks), ``us_per_rad`` and ``centre`` (PWM pulse width, µs), ``limits`` ([lowest, highest]
in the servo's units), ``velocity_limit`` [rad/s], ``resolution`` (the command's step in its
units). The map is :math:`u = c + d\,s\,(q - q_0)` with ``s`` the servo units per radian.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from contextlib import nullcontext
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np

from .._reader import check_keys, named, number, numbers, read_data, text
from ..exceptions import ParameterError, choices

__all__ = ["UNITS", "Calibration", "Servo", "read_calibration"]

#: Servo units understood by :class:`Servo`.
UNITS: tuple[str, ...] = ("rad", "deg", "ticks", "us")
#: Largest magnitude of a servo command in its units (any real servo is far inside).
MAX_COMMAND = 1e9
#: Slowest plausible speed limit of a servo [rad/s] (a turn in some 70 days).
MIN_SPEED = 1e-6


#: The least fraction of a joint's range [lower, upper] its servo's limits must sweep.
MIN_COVER = 0.1


def _bad(message: str, parameter: str, value: Any, allowed: Any) -> ParameterError:
    return ParameterError(message, parameter=parameter, value=value, allowed=allowed)


@dataclass(frozen=True)
class Servo:
    """The servo that drives one joint, and how its command maps to the joint angle.

    Attributes:
        joint: The joint's name.
        units: ``"rad"``, ``"deg"``, ``"ticks"`` or ``"us"`` (PWM pulse width in µs).
        offset: Joint angle at the servo's centre (zero for rad/deg) [rad].
        direction: +1 or -1 (servo angle = ``direction * (q - offset)``).
        ticks_per_revolution: Ticks per turn (``"ticks"``; e.g. 1228.8 for 1024 ticks over
            300°, an AX-12).
        centre: The command at the centre: ticks (``"ticks"``) or µs (``"us"``; e.g. 1500).
        us_per_rad: Pulse width per radian [µs/rad] (``"us"``).
        limits: The servo's own (lowest, highest) command, in its units (None: unlimited).
        velocity_limit: The joint's speed limit [rad/s] (None: the model's, or unlimited).
        resolution: The command's step, in its units (1 for ticks and µs; 0 = exact).

    """

    joint: str
    units: str = "rad"
    offset: float = 0.0
    direction: int = 1
    ticks_per_revolution: float | None = None
    centre: float = 0.0
    us_per_rad: float | None = None
    limits: tuple[float, float] | None = None
    velocity_limit: float | None = None
    resolution: float | None = None

    def __post_init__(self) -> None:
        where = f"calibration of {self.joint}"

        def need(ok: bool, key: str, text: str, allowed: Any, value: Any = None) -> None:
            if not ok:
                shown = getattr(self, key) if value is None else value
                raise _bad(f"{where}: {text}", key, shown, allowed)

        need(self.units in UNITS, "units", f"units {self.units!r} unknown; {choices(UNITS)}", UNITS)
        sign = self.direction
        need(sign in (1, -1), "direction", f"direction {sign!r}; allowed: 1 or -1", (1, -1))
        for name in ("offset", "centre"):
            need(math.isfinite(getattr(self, name)), name, f"{name} must be finite", "finite")
        for unit, key, e_g in (
            ("ticks", "ticks_per_revolution", "e.g. 1228.8 for 1024 ticks over 300°"),
            ("us", "us_per_rad", "a PWM servo: some 500 to 650"),
        ):
            v = getattr(self, key)
            ok = self.units != unit or (v is not None and math.isfinite(v) and v >= 1)
            need(ok, key, f"units {unit!r} need {key} >= 1 ({e_g}), got {v!r}", ">= 1")
        if self.limits is not None:
            lo, hi = self.limits
            text = f"limits {list(self.limits)} must be finite with lowest < highest"
            ok = math.isfinite(lo) and math.isfinite(hi) and lo < hi
            need(ok, "limits", text, "[lowest, highest]")
        vel, res = self.velocity_limit, self.resolution
        text = (
            f"velocity_limit {vel!r} rad/s is not a servo's speed; allowed: >= {MIN_SPEED:g} rad/s"
        )
        need(vel is None or vel >= MIN_SPEED, "velocity_limit", text, f">= {MIN_SPEED:g}")
        ok = res is None or (math.isfinite(res) and res >= 0)
        need(ok, "resolution", f"resolution {res!r} must be >= 0", ">= 0")
        # plausible: two turns either side of the centre stay within MAX_COMMAND, in whole steps
        key = {"ticks": "ticks_per_revolution", "us": "us_per_rad"}.get(self.units, "centre")
        key = "centre" if not abs(self.zero) <= MAX_COMMAND else key
        reach = abs(self.zero) + self.scale * 4.0 * math.pi
        within = f"commands within ±{MAX_COMMAND:g}"
        text = f"{key} {getattr(self, key)!r} maps two turns to {reach:g} {self.units}"
        need(reach <= MAX_COMMAND, key, f"{text}; allowed: {within}", within)
        ok = not self.step > 0 or self.step / self.scale <= 2.0 * math.pi
        text = f"{key} {getattr(self, key)!r} makes one step of {self.step:g} {self.units}"
        turn = "at most one turn"
        need(ok, key, f"{text} {self.step / self.scale:g} rad; allowed: {turn}", f"{turn} per step")
        ok = not self.step > 0 or reach / self.step < 2.0**52
        text = f"resolution {self.step!r} is too fine for commands up to {reach:g} {self.units}"
        least = f">= {reach / 2.0**52:.3g}" if self.step > 0 else ""
        need(ok, "resolution", f"{text} (more than 2^52 steps)", least, value=self.step)

    @property
    def scale(self) -> float:
        """Servo units per radian of servo angle."""
        if self.units == "ticks":
            return float(self.ticks_per_revolution) / (2.0 * math.pi)  # type: ignore[arg-type]
        if self.units == "us":
            return float(self.us_per_rad)  # type: ignore[arg-type]
        return 180.0 / math.pi if self.units == "deg" else 1.0

    @property
    def step(self) -> float:
        """The command's resolution in its units (0: not rounded)."""
        if self.resolution is not None:
            return float(self.resolution)
        return 1.0 if self.units in ("ticks", "us") else 0.0

    @property
    def zero(self) -> float:
        """The command at the centre (0 for rad and deg)."""
        return self.centre if self.units in ("ticks", "us") else 0.0

    def command_exact(self, q: Any) -> np.ndarray:
        """Servo commands for joint angles ``q`` [rad], not rounded."""
        return self.zero + self.direction * self.scale * (np.asarray(q, dtype=float) - self.offset)

    def command(self, q: Any) -> np.ndarray:
        """Servo commands for joint angles ``q`` [rad], rounded to the resolution."""
        u = self.command_exact(q)
        s = self.step
        return np.round(u / s) * s if s > 0 else u

    def angle(self, u: Any) -> np.ndarray:
        """Joint angles [rad] for servo commands ``u`` (the inverse of :meth:`command`)."""
        u = np.asarray(u, dtype=float)
        return self.offset + self.direction * (u - self.zero) / self.scale

    def check_range(self, lower: float, upper: float) -> None:
        """Refuse a servo that cannot drive a joint of limits [lower, upper] [rad or m].

        The ``offset`` within a turn of the joint's range, the angles the servo's ``limits``
        reach overlapping it, a step of the ``resolution`` within that (infinite limits: no
        check).

        Raises:
            ParameterError: Naming the joint, the key, the value and the allowed range.

        """
        lo, hi = float(lower), float(upper)
        if not (math.isfinite(lo) and math.isfinite(hi) and lo <= hi):
            return
        where, turn = f"calibration of {self.joint}", 2.0 * math.pi
        if not lo - turn <= self.offset <= hi + turn:
            span = (lo - turn, hi + turn)
            msg = (
                f"{where}: offset {self.offset:g} is more than a turn outside the joint's limits "
                f"[{lo:.6g}, {hi:.6g}]; allowed: [{span[0]:.6g}, {span[1]:.6g}]"
            )
            raise _bad(msg, "offset", self.offset, span)
        if self.limits is not None:
            a, b = sorted(float(x) for x in self.angle(self.limits))
            if b < lo or a > hi:
                u = sorted(float(x) for x in self.command_exact([lo, hi]))
                msg = (
                    f"{where}: limits {list(self.limits)} {self.units} reach the joint only at "
                    f"[{a:.6g}, {b:.6g}] (centre {self.zero:g} {self.units}, offset "
                    f"{self.offset:g} rad, {self.scale:g} {self.units}/rad), outside its limits "
                    f"[{lo:.6g}, {hi:.6g}]; allowed: "
                    f"servo limits overlapping [{u[0]:.6g}, {u[1]:.6g}] {self.units}"
                )
                raise _bad(msg, "limits", list(self.limits), (u[0], u[1]))
            self._check_cover(lo, hi, b - a)
            self._check_steps(lo, hi)

    def _check_cover(self, lower: float, upper: float, reach: float) -> None:
        """Refuse a µs/ticks scale whose limits sweep ``reach`` < MIN_COVER of the joint's range."""
        span = upper - lower
        key = {"ticks": "ticks_per_revolution", "us": "us_per_rad"}.get(self.units)
        if key is None or self.limits is None or not (span > 0 and reach < MIN_COVER * span):
            return  # limits in rad or deg are the servo's own words: a narrow one is allowed
        width = float(self.limits[1] - self.limits[0])
        most = width / (MIN_COVER * span) * (2.0 * math.pi if self.units == "ticks" else 1.0)
        allowed = f"<= {most:.6g}"
        msg = (
            f"calibration of {self.joint}: {key} {getattr(self, key)!r} lets the servo's limits "
            f"{list(self.limits)} {self.units} sweep only {reach:.6g} of the joint's range "
            f"[{lower:.6g}, {upper:.6g}] (less than {MIN_COVER:g} of it); allowed: {allowed}"
        )
        raise _bad(msg, key, getattr(self, key), allowed)

    def _check_steps(self, lower: float, upper: float) -> None:
        """Refuse a resolution with no step inside both the servo's limits and the joint's."""
        s = self.step
        if self.limits is None or not s > 0:
            return
        u = sorted(float(x) for x in self.command_exact([lower, upper]))
        a, b = max(u[0], self.limits[0]), min(u[1], self.limits[1])
        if math.ceil(a / s - 1e-9) * s > b + 1e-9 * s:
            msg = (
                f"calibration of {self.joint}: resolution {s:g} {self.units} has no step within "
                f"[{a:.6g}, {b:.6g}] {self.units} (the servo's limits {list(self.limits)} on the "
                f"joint's limits [{lower:.6g}, {upper:.6g}]); allowed: at most {b - a:.6g}"
            )
            raise _bad(msg, "resolution", s, f"<= {b - a:.6g}")

    def to_dict(self) -> dict[str, Any]:
        """The servo as a calibration-file entry (only the keys that matter for its units)."""
        scale = {"ticks": ["ticks_per_revolution", "centre"], "us": ["us_per_rad", "centre"]}
        keys = ["units", "offset", "direction", *scale.get(self.units, [])]
        keys += [
            k for k in ("limits", "velocity_limit", "resolution") if getattr(self, k) is not None
        ]
        d = {k: getattr(self, k) for k in keys}
        if self.limits is not None:
            d["limits"] = list(self.limits)
        return d


#: The keys of a servo's entry in a calibration file: its fields but ``joint``.
_SERVO_KEYS = tuple(f.name for f in fields(Servo) if f.name != "joint")


@dataclass(frozen=True)
class Calibration:
    """Each joint's servo (see :class:`Servo`); joints not listed use ``default``.

    Attributes:
        servos: The listed joints' servos, by joint name.
        default: The servo settings of joints not listed (its ``joint`` is ``"*"``), or None:
            then every joint of a plan must be listed.

    """

    servos: Mapping[str, Servo] = field(default_factory=dict)
    default: Servo | None = None

    def servo(self, joint: str) -> Servo:
        """The servo of ``joint`` (the default's settings under the joint's name)."""
        if joint in self.servos:
            return self.servos[joint]
        if self.default is None:
            listed = sorted(self.servos)
            msg = f"calibration: no servo for joint {joint!r} and no 'defaults'; listed: {listed}"
            raise _bad(msg, "calibration", joint, listed)
        return Servo(**{**self.default.__dict__, "joint": joint})

    def check_joints(
        self, joint_names: Sequence[str], lower: Any = None, upper: Any = None, of: str = "the plan"
    ) -> None:
        """Refuse a listed joint not in ``joint_names`` and a servo that cannot drive its joint.

        With the joints' ``lower``/``upper`` limits [rad or m] every joint's servo is held to
        :meth:`Servo.check_range`.

        Raises:
            ParameterError: An unknown joint (naming the joints allowed); a servo unfit.

        """
        extra = [j for j in self.servos if j not in joint_names]
        if extra:
            msg = f"calibration: joint {extra[0]!r} is not in {of}; {choices(joint_names)}"
            raise _bad(msg, "calibration", extra[0], list(joint_names))
        if lower is None or upper is None:
            return
        for joint, lo, hi in zip(joint_names, lower, upper):
            if joint in self.servos or self.default is not None:
                self.servo(joint).check_range(lo, hi)

    def to_dict(self) -> dict[str, Any]:
        """The calibration as a file's data: ``{"defaults": {...}, "joints": {...}}``."""
        out = {} if self.default is None else {"defaults": self.default.to_dict()}
        return {**out, "joints": {k: s.to_dict() for k, s in self.servos.items()}}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], name: str | None = None) -> Calibration:
        """Build from a file's data (see the module doc); ``name``: the file, named in errors."""

        def refuse(why: str, value: Any, allowed: Any) -> ParameterError:
            return _bad(why, "calibration", value, allowed)

        with named(name, "calibration") if name is not None else nullcontext():
            if not isinstance(data, Mapping):
                raise refuse("must be a mapping", type(data).__name__, "mapping")
            check_keys(data, ("defaults", "joints"), "calibration", parameter="calibration")
            base = data.get("defaults") or {}
            joints = data.get("joints") or {}
            if not isinstance(base, Mapping) or not isinstance(joints, Mapping):
                raise refuse("'defaults' and 'joints' must be tables", None, "tables")
            default = _servo("*", base) if "defaults" in data else None
            servos = {}
            for joint, entry in joints.items():
                if not isinstance(entry, Mapping):
                    why = f"joint {joint!r} must be a table of servo settings"
                    raise refuse(why, joint, _SERVO_KEYS)
                servos[str(joint)] = _servo(str(joint), {**base, **entry})
            return cls(servos=servos, default=default)


def _servo(joint: str, entry: Mapping[str, Any]) -> Servo:
    where = f"joint {joint!r}"
    check_keys(entry, _SERVO_KEYS, where, parameter="calibration")
    kw: dict[str, Any] = {}
    for key, value in entry.items():
        if key == "units":
            kw[key] = text(value, f"{where}: units", parameter=key)
        elif key == "limits":
            pair = numbers(value, f"{where}: limits", 2, parameter=key)
            kw[key] = (pair[0], pair[1])
        else:
            kw[key] = number(value, f"{where}: {key}", parameter=key)
    if "direction" in kw and kw["direction"] in (1.0, -1.0):
        kw["direction"] = int(kw["direction"])
    return Servo(joint=joint, **kw)


def read_calibration(path: str | os.PathLike[str], robot: Any = None) -> Calibration:
    """Read a calibration file (``.yaml``/``.yml``, ``.toml`` or ``.json``).

    Through the strict reader (:mod:`hexapod_kin._reader`); with ``robot`` (``joint_names``,
    ``lower``, ``upper``) every entry must fit one of its joints (:meth:`Calibration.check_joints`).

    Example (AX-12-like servos: 1024 ticks over 300°, centre 512)::

        defaults: {units: ticks, ticks_per_revolution: 1228.8, centre: 512,
                   limits: [0, 1023], velocity_limit: 11.9}
        joints:
          leg1_knee: {direction: -1, offset: -0.3}

    Raises:
        SourceError: The file cannot be read or parsed, or is refused by the reader.
        ParameterError: An unknown key or unit, a bad number; with ``robot``, an unknown
            joint or a servo that does not fit its joint's limits.

    """
    cal = Calibration.from_dict(read_data(path, "calibration"), str(path))
    if robot is not None:
        with named(path, "calibration"):
            cal.check_joints(robot.joint_names, robot.lower, robot.upper, of=repr(robot.name))
    return cal
