"""What the controller is asked to do: a command, and a timeline of commands.

A :class:`Command` is a velocity twist in the robot's heading frame (``vx`` forward, ``vy``
left [m/s], ``wz`` yaw rate [rad/s]), a gait pattern (switched at the next cycle boundary)
and a mode: ``walk``, ``stand`` (feet down, body at its height; a zero twist while
walking also keeps stepping), ``sit`` (feet down, body lowered to :attr:`Command.height`
of its standing height). A :class:`Timeline` holds commands from given times; it reads
from a JSON or YAML file through the package's reader.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from .._fields import fields_dict
from .._reader import check_keys, clip, named, number, read_data, text
from ..exceptions import ParameterError, one_of

__all__ = ["MODES", "Command", "Timeline", "read_timeline", "timeline_of"]

#: The modes of a command.
MODES = ("walk", "stand", "sit")

#: Largest commanded speed [m/s] and yaw rate [rad/s]: beyond any legged robot (MIT Cheetah runs
#: at 3.7 m/s); a larger number is a typing slip, refused at once instead of ramped towards.
MAX_SPEED = 10.0
MAX_YAW_RATE = 10.0


@dataclass(frozen=True)
class Command:
    """One command (SI units).

    Attributes:
        vx: Forward speed in the heading frame [m/s].
        vy: Leftward speed [m/s].
        wz: Yaw rate [rad/s].
        pattern: Gait pattern name (None: keep the current one).
        mode: ``walk``, ``stand`` or ``sit``.
        height: In ``sit``, the body height as a fraction of the standing height (0.3 to 1).

    """

    vx: float = 0.0
    vy: float = 0.0
    wz: float = 0.0
    pattern: str | None = None
    mode: str = "walk"
    height: float = 0.6

    def __post_init__(self) -> None:
        for name, cap in (("vx", MAX_SPEED), ("vy", MAX_SPEED), ("wz", MAX_YAW_RATE)):
            x = number(getattr(self, name), name)
            if abs(x) > cap:
                unit = "rad/s" if name == "wz" else "m/s"
                raise ParameterError(
                    f"{name}={x:.6g} {unit}: at most {cap:g} {unit} either way",
                    parameter=name,
                    value=x,
                    allowed=[-cap, cap],
                )
            object.__setattr__(self, name, x)
        one_of("mode", self.mode, list(MODES))
        if self.pattern is not None:
            text(self.pattern, "pattern")  # a pattern's name
        h = number(self.height, "height")
        if not 0.3 <= h <= 1.0:
            raise ParameterError(
                f"height={self.height!r}: a fraction of the standing height from 0.3 to 1",
                parameter="height",
                value=self.height,
                allowed="[0.3, 1]",
            )

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready fields."""
        return fields_dict(self, "vx", "vy", "wz", "pattern", "mode", "height")


@dataclass(frozen=True)
class Timeline:
    """Commands from given times: ``entries[i] = (t_i [s], command)``, times increasing."""

    entries: tuple[tuple[float, Command], ...] = field(default_factory=tuple)

    def __post_init__(self) -> None:
        last = -math.inf
        for t, cmd in self.entries:
            if not (math.isfinite(t) and t >= 0 and t >= last) or not isinstance(cmd, Command):
                raise ParameterError(
                    f"timeline entry at t={t!r}: times >= 0 s in increasing order, each with "
                    "a Command",
                    parameter="timeline",
                    value=t,
                    allowed="increasing times >= 0",
                )
            last = t

    @classmethod
    def constant(cls, command: Command) -> Timeline:
        """One command from t = 0."""
        return cls(((0.0, command),))

    def at(self, t: float) -> Command:
        """The command in force at time ``t`` [s] (a zero-twist walk before the first)."""
        out = Command()
        for t0, cmd in self.entries:
            if t0 > t:
                break
            out = cmd
        return out

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: a list of ``{"t": ..., **command}``."""
        return {"commands": [{"t": t, **c.to_dict()} for t, c in self.entries]}


_KEYS = ("t", "vx", "vy", "wz", "pattern", "mode", "height")


def timeline_of(data: Any) -> Timeline:
    """A :class:`Timeline` from ``{"commands": [{"t": .., "vx": .., ...}, ...]}``.

    Raises:
        ParameterError: A missing list, an unknown key or a bad value (the key named).

    """
    rows = data.get("commands") if isinstance(data, dict) else None
    if not isinstance(rows, list) or not rows:
        raise ParameterError(
            "a command timeline is {'commands': [{'t': 0, 'vx': 0.3, ...}, ...]}",
            parameter="commands",
            value=type(rows).__name__,
        )
    out = []
    for i, row in enumerate(rows, start=1):
        if not isinstance(row, dict) or "t" not in row:
            raise ParameterError(
                f"command {i}={clip(row)}: a mapping with 't' and keys among {list(_KEYS)}",
                parameter="commands",
                value=clip(row),
                allowed=list(_KEYS),
            )
        check_keys(row, _KEYS, f"command {i}", parameter="commands")
        kw = {k: v for k, v in row.items() if k != "t"}
        out.append((number(row["t"], "t"), Command(**kw)))
    return Timeline(tuple(out))


def read_timeline(path: Any) -> Timeline:
    """Read a command timeline file (JSON or YAML, through :mod:`hexapod_kin._reader`)."""
    data = read_data(path, "command timeline", mapping="commands")
    with named(path, "command timeline"):
        return timeline_of(data)
