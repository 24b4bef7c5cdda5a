r"""Joint timelines for hardware: a planned motion resampled for servos, CSV, JSON, ROS 2 YAML.

A *plan* is any motion with sample times and joint angles: a
:class:`~hexapod_kin.gait.walk.GaitRun` (``gait.walk``), a
:class:`~hexapod_kin.motion.rate.Trajectory` (``motion.resolved_rate``, a step), or an IK path
given as ``(times, q)`` arrays. :func:`timeline` resamples it at a chosen rate and maps every
joint to its servo through a :class:`Calibration`:

.. math::

    \theta_s = d\,(q - q_0), \qquad
    u = \begin{cases}
      \theta_s & \text{rad} \\
      \theta_s \cdot 180/\pi & \text{deg} \\
      c + \theta_s \, T / (2\pi) & \text{ticks (T ticks per revolution, centre c)} \\
      c_{\mu s} + \theta_s \, k & \text{us (k µs per rad, centre } c_{\mu s})
    \end{cases}

with ``q0`` the joint angle at the servo's centre (``offset``) and ``d = ±1`` the direction,
rounded to the servo's resolution. Every sample is checked (finite, commands and speeds per
second within ±1e9 servo units; the joint's limits; the servo's limits; the speed limit
[rad/s]); the first one beyond is refused naming the joint,
the time and the value. Interpolation: ``"linear"`` (velocities the plan's own or its
second-order finite difference) or ``"cubic"`` (a not-a-knot spline and its derivative).
Files: CSV (``# key: value`` header, ``t [s]``, commands and speeds in servo units), JSON (the
same), ROS 2 ``JointTrajectory`` YAML (commanded angles [rad]); read back to half a step.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np

from .._fields import read_only
from .._io import atomic_write
from .._reader import (
    check_keys,
    csv_table,
    named,
    number,
    numbers,
    parse_data,
    read_text,
    text,
    texts,
)
from ..exceptions import ConfigurationError, HexapodKinError, LimitError, SourceError, choices
from .servos import MAX_COMMAND, UNITS, Calibration, Servo, _bad, read_calibration

__all__ = [
    "UNITS",
    "Calibration",
    "Servo",
    "Timeline",
    "read_calibration",
    "read_plan",
    "read_timeline",
    "timeline",
]

#: Most samples of a timeline (a day at 100 Hz is 8.6e6).
MAX_SAMPLES = 1e7
#: Interpolations understood by :func:`timeline`.
INTERPOLATIONS: tuple[str, ...] = ("linear", "cubic")
FORMAT = "hexapod-kin timeline"
#: Byte cap of a timeline or plan file (parsing one takes some ten times its size in memory).
_MAX_TIMELINE_BYTES = 64 << 20
#: Most values of a timeline or plan file (no more than its bytes: a value takes one or more).
_MAX_TIMELINE_VALUES = _MAX_TIMELINE_BYTES

Interpolation = Literal["linear", "cubic"]


def _identity() -> Calibration:
    """Every joint in rad, unlimited (a plan without calibration; a ROS 2 file read back)."""
    return Calibration(default=Servo(joint="*"))


@dataclass(frozen=True)
class Timeline:
    """A plan resampled for servos (arrays read-only), its ``calibration``, rate and interpolation.

    Attributes:
        t: (N,) sample times [s], ``k / rate``.
        q: (N, J) joint angles of the commands sent [rad] (the servo values mapped back);
            ``qdot`` (N, J) their rates [rad/s]; columns in ``joint_names`` order.
        command: (N, J) servo commands in each servo's units (rounded to its resolution);
            ``speed`` (N, J) in servo units per second.

    """

    t: np.ndarray
    joint_names: tuple[str, ...]
    q: np.ndarray
    qdot: np.ndarray
    command: np.ndarray
    speed: np.ndarray
    calibration: Calibration
    rate: float
    interpolation: str

    @property
    def servos(self) -> tuple[Servo, ...]:
        """The servo of each column."""
        return tuple(self.calibration.servo(j) for j in self.joint_names)

    def to_dict(self) -> dict[str, Any]:
        """The timeline as JSON-ready data (the JSON file's content)."""
        return {
            "format": FORMAT,
            "version": 1,
            "rate": self.rate,
            "interpolation": self.interpolation,
            "joint_names": list(self.joint_names),
            "units": [s.units for s in self.servos],
            "calibration": self.calibration.to_dict(),
            "t": self.t.tolist(),
            "command": self.command.tolist(),
            "speed": self.speed.tolist(),
        }

    def to_csv(self) -> str:
        """CSV text: header lines, then ``t [s]``, the commands and the speeds."""
        units = [s.units for s in self.servos]
        cal = self.calibration.to_dict()
        lines = [
            f"# format: {FORMAT} 1",
            f"# rate: {self.rate!r}",
            f"# interpolation: {self.interpolation}",
            "# calibration: " + json.dumps(cal, sort_keys=True, allow_nan=False),
            ",".join(
                ["t [s]"]
                + [f"{j} [{u}]" for j, u in zip(self.joint_names, units)]
                + [f"{j} speed [{u}/s]" for j, u in zip(self.joint_names, units)]
            ),
        ]
        for k in range(len(self.t)):
            row = [self.t[k], *self.command[k], *self.speed[k]]
            lines.append(",".join(_num(v) for v in row))
        return "\n".join(lines) + "\n"

    def to_ros2_yaml(self, frame_id: str = "") -> str:
        """A ROS 2 ``trajectory_msgs/msg/JointTrajectory`` as YAML (positions in [rad])."""
        out = [
            "# trajectory_msgs/msg/JointTrajectory, written by hexapod-kin "
            f"({self.interpolation} resampling at {self.rate:g} Hz)",
            "header:",
            "  stamp: {sec: 0, nanosec: 0}",
            f"  frame_id: {json.dumps(frame_id)}",
            "joint_names: [" + ", ".join(json.dumps(j) for j in self.joint_names) + "]",
            "points:",
        ]
        for k in range(len(self.t)):
            sec, nanosec = divmod(int(round(float(self.t[k]) * 1e9)), 1_000_000_000)
            out += [
                "- positions: [" + ", ".join(_num(v) for v in self.q[k]) + "]",
                "  velocities: [" + ", ".join(_num(v) for v in self.qdot[k]) + "]",
                "  accelerations: []",
                "  effort: []",
                f"  time_from_start: {{sec: {sec}, nanosec: {nanosec}}}",
            ]
        return "\n".join(out) + "\n"

    def write(self, path: str | os.PathLike[str], fmt: str | None = None) -> Path:
        """Write the timeline atomically; ``fmt`` = ``"csv"``, ``"json"`` or ``"ros2"``.

        The format defaults to the suffix: ``.csv``, ``.json``, ``.yaml``/``.yml`` (ROS 2).

        Raises:
            ParameterError: Unknown format or suffix.

        """
        kind = _format(Path(path), fmt)
        if kind == "json":
            text = json.dumps(self.to_dict(), separators=(",", ":"), allow_nan=False) + "\n"
            return atomic_write(path, text)
        return atomic_write(path, self.to_csv() if kind == "csv" else self.to_ros2_yaml())


def _num(v: float) -> str:
    return repr(float(v))


FORMATS: tuple[str, ...] = ("csv", "json", "ros2")


def _format(path: Path, fmt: str | None) -> str:
    if fmt is not None:
        if fmt not in FORMATS:
            raise _bad(f"format {fmt!r} unknown; {choices(FORMATS)}", "format", fmt, FORMATS)
        return fmt
    suffix = path.suffix.lower()
    kinds = {".csv": "csv", ".json": "json", ".yaml": "ros2", ".yml": "ros2"}
    if suffix not in kinds:
        msg = f"{path.name}: suffix {suffix or '(none)'!r} unknown; allowed: .csv, .json, "
        raise _bad(msg + ".yaml/.yml (ROS 2 JointTrajectory)", "path", str(path), sorted(kinds))
    return kinds[suffix]


def _malformed(text: str, parameter: str, value: Any, allowed: Any) -> ConfigurationError:
    return ConfigurationError(text, parameter=parameter, value=value, allowed=allowed)


def _plan_arrays(
    plan: Any, times: Any, joint_names: Sequence[str] | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, tuple[str, ...]]:
    if isinstance(plan, tuple) and len(plan) == 2 and times is None:
        times, plan = plan
    if hasattr(plan, "t") and hasattr(plan, "q"):
        t = np.asarray(plan.t, dtype=float)
        q = np.asarray(plan.q, dtype=float)
        qd = getattr(plan, "qdot", None)
        qdot = None if qd is None else np.asarray(qd, dtype=float)
        names = joint_names or getattr(plan, "joint_names", None)
    else:
        if times is None:
            text = "an IK path needs its sample times: timeline((times, q)) or times="
            raise _malformed(text, "times", None, "(N,) increasing times [s]")
        t = np.asarray(times, dtype=float)
        q = np.asarray(plan, dtype=float)
        qdot = None
        names = joint_names
    if q.ndim != 2 or t.ndim != 1 or len(t) != len(q) or len(t) < 2:
        text = f"a plan needs (N,) times and (N, J) joint angles with N >= 2, got times {t.shape}"
        raise _malformed(f"{text} and q {q.shape}", "q", q.shape, "(N, J), N >= 2")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(q))):
        text = "the plan's times and joint angles must be finite"
        raise _malformed(text, "q", "non-finite", "finite")
    if not np.all(np.diff(t) > 0):
        text = "the plan's times must increase strictly"
        raise _malformed(text, "times", None, "strictly increasing")
    if names is None:
        names = tuple(f"joint{i + 1}" for i in range(q.shape[1]))
    names = tuple(str(n) for n in names)
    if len(names) != q.shape[1] or len(set(names)) != len(names):
        text = f"{len(names)} joint names for {q.shape[1]} columns (names must be distinct)"
        raise _malformed(text, "joint_names", list(names), f"{q.shape[1]} distinct names")
    if qdot is not None and qdot.shape != q.shape:
        qdot = None
    return t, q, qdot, names


def _model_speed_limits(plan: Any, velocity_limit: Any, n: int) -> np.ndarray:
    if velocity_limit is not None:
        v = np.broadcast_to(np.asarray(velocity_limit, dtype=float), (n,)).copy()
    else:
        robot = getattr(plan, "robot", None)
        v = np.array(getattr(robot, "velocity_limit", np.full(n, np.inf)), dtype=float)
        if v.shape != (n,):
            v = np.full(n, np.inf)
    v[~(v > 0)] = np.inf  # Pinocchio's 0 = not given
    return v


def _model_position_limits(plan: Any, position_limit: Any, n: int) -> np.ndarray:
    """(2, n) joint limits [rad or m]: given, else the plan's robot's ``lower``/``upper``."""
    robot = getattr(plan, "robot", None)
    own = (getattr(robot, "lower", None), getattr(robot, "upper", None))
    lo, hi = own if position_limit is None else position_limit
    out = np.array([np.full(n, -np.inf), np.full(n, np.inf)])
    if lo is None or hi is None:
        return out
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    if lo.shape == hi.shape == (n,):
        out[0] = np.where(np.isnan(lo), -np.inf, lo)
        out[1] = np.where(np.isnan(hi), np.inf, hi)
    return out


def _first(bad: np.ndarray) -> int | None:
    """The first sample where ``bad`` holds (None: none)."""
    hits = np.flatnonzero(bad)
    return int(hits[0]) if hits.size else None


def _beyond(joint: str, t: float, what: str, value: Any, allowed: Any) -> LimitError:
    """The refusal of a sample beyond a limit, naming the joint and the time [s]."""
    text = f"joint {joint} at t={t:.4f} s: {what}"
    return LimitError(text, parameter=joint, value=float(value), allowed=allowed)


def _refuse_implausible(
    s: Servo, j: int, ts: Any, qs: Any, command: Any, speed: Any, ok: Any
) -> None:
    """Refuse the first sample of column ``j`` not ``ok`` (not finite, or beyond ±1e9)."""
    k = _first(~ok)
    if k is None:  # e.g. a scale of 1e308 µs/rad, a resolution of 1e-320, a 1e308 rad plan
        return
    u, v = float(command[k, j]), float(speed[k, j])
    finite = math.isfinite(u) and math.isfinite(v)
    why = f"beyond ±{MAX_COMMAND:g} (no servo's)" if finite else "not finite"
    text = (
        f"joint {s.joint} at t={ts[k]:.4f} s: command {u:g} {s.units}, speed {v:g} "
        f"{s.units}/s (q = {qs[k, j]:.6g} rad): {why}; check the calibration's scale and "
        "resolution and the plan"
    )
    allowed = f"finite commands and speeds within ±{MAX_COMMAND:g}"
    raise _malformed(text, s.joint, u, allowed)


@np.errstate(over="ignore", invalid="ignore", divide="ignore")  # non-finite results refused
def timeline(
    plan: Any,
    *,
    rate: float,
    interpolation: Interpolation = "linear",
    calibration: Calibration | str | os.PathLike[str] | None = None,
    times: Any = None,
    joint_names: Sequence[str] | None = None,
    velocity_limit: Any = None,
    position_limit: Any = None,
) -> Timeline:
    """Resample a plan at ``rate`` and map it to the servos, checking every sample.

    Args:
        plan: A ``GaitRun``, a resolved-rate ``Trajectory``, anything with ``t`` and ``q``
            (optionally ``qdot``, ``joint_names``, ``robot``), a ``(times, q)`` pair or (N, J)
            joint angles [rad] with ``times`` (an IK path).
        times: (N,) times [s] of an array plan.
        rate: Samples per second [Hz]; samples at ``t0 + k / rate`` up to the plan's end.
        interpolation: ``"linear"`` or ``"cubic"`` (see the module doc).
        calibration: A :class:`Calibration`, a file, or None (every joint in rad, unlimited).
        joint_names: The plan's joint names (default: the plan's own, else joint1..J).
        velocity_limit: Speed limits [rad/s], scalar or (J,), where the calibration gives
            none (default: the plan's robot's, else unlimited).
        position_limit: ``(lower, upper)``, each (J,) [rad or m] (default: the plan's robot's,
            else none): every sample within them (1e-9 of slack).

    Raises:
        LimitError: A sample beyond a servo's limits, a joint's limits or its speed limit
            (naming the joint, the time [s] and the value; ``parameter`` is the joint).
        ConfigurationError: A malformed plan.
        ParameterError: Bad rate, interpolation or calibration (checked against the joints'
            limits before any sample: :meth:`Calibration.check_joints`).

    """
    if interpolation not in INTERPOLATIONS:
        msg = f"interpolation {interpolation!r} unknown; {choices(INTERPOLATIONS)}"
        raise _bad(msg, "interpolation", interpolation, INTERPOLATIONS)
    if not (isinstance(rate, (int, float)) and math.isfinite(rate) and rate > 0):
        raise _bad(f"rate {rate!r} must be a positive number [Hz]", "rate", rate, "> 0")
    t, q, qdot, names = _plan_arrays(plan, times, joint_names)
    cal = calibration
    if not isinstance(cal, Calibration):
        cal = _identity() if cal is None else read_calibration(cal)
    plim = _model_position_limits(plan, position_limit, len(names))
    cal.check_joints(names, plim[0], plim[1])
    servos = [cal.servo(j) for j in names]

    samples = float(np.floor((t[-1] - t[0]) * rate * (1 + 1e-12))) + 1.0
    if not samples <= MAX_SAMPLES:  # bounded work: no allocation of an absurd size
        most = f"at most {MAX_SAMPLES:g}"
        text = f"{samples:.3g} samples ({t[-1] - t[0]:.6g} s at {rate:g} Hz); allowed: {most}"
        raise _malformed(
            f"{text}: lower the rate or shorten the plan", "rate", rate, f"{most} samples"
        )
    n = int(samples)
    ts = t[0] + np.arange(n) / float(rate)
    ts = np.minimum(ts, t[-1])
    if interpolation == "cubic":
        from scipy.interpolate import CubicSpline

        spline = CubicSpline(t, q, axis=0)
        qs = spline(ts)
        vs = spline(ts, 1)
    else:
        # the plan's own rates, else a second-order difference (first order for two samples)
        qd = qdot
        if qd is None:
            qd = np.gradient(q, t, axis=0, edge_order=2 if len(t) > 2 else 1)
        qs = np.column_stack([np.interp(ts, t, q[:, j]) for j in range(q.shape[1])])
        vs = np.column_stack([np.interp(ts, t, qd[:, j]) for j in range(q.shape[1])])

    vlim = _model_speed_limits(plan, velocity_limit, len(names))
    command = np.empty_like(qs)
    speed = np.empty_like(vs)
    q_sent = np.empty_like(qs)
    for j, s in enumerate(servos):
        exact = s.command_exact(qs[:, j])
        command[:, j] = s.command(qs[:, j])
        speed[:, j] = s.direction * s.scale * vs[:, j]
        q_sent[:, j] = s.angle(command[:, j])
        finite = np.isfinite(command[:, j]) & np.isfinite(speed[:, j]) & np.isfinite(q_sent[:, j])
        _refuse_implausible(s, j, ts, qs, command, speed, finite)
        k = _first((qs[:, j] < plim[0, j] - 1e-9) | (qs[:, j] > plim[1, j] + 1e-9))
        if k is not None:
            lo, hi = float(plim[0, j]), float(plim[1, j])
            what = f"q = {qs[k, j]:.6g} is beyond the joint's limits [{lo:.6g}, {hi:.6g}]"
            raise _beyond(s.joint, ts[k], what, qs[k, j], (lo, hi))
        if s.limits is not None:
            lo, hi = s.limits
            k = _first((command[:, j] < lo) | (command[:, j] > hi))
            if k is not None:
                what = (
                    f"{exact[k]:.6g} {s.units} (q = {qs[k, j]:.6g} rad) is beyond its servo's "
                    f"limits [{lo:g}, {hi:g}] {s.units}"
                )
                raise _beyond(s.joint, ts[k], what, exact[k], (lo, hi))
        # plausible: no servo takes a command (or a speed per second) beyond ±MAX_COMMAND
        sane = (np.abs(command[:, j]) <= MAX_COMMAND) & (np.abs(speed[:, j]) <= MAX_COMMAND)
        _refuse_implausible(s, j, ts, qs, command, speed, sane)
        lim = s.velocity_limit if s.velocity_limit is not None else float(vlim[j])
        k = _first(np.abs(vs[:, j]) > lim)
        if k is not None:
            what = f"speed {vs[k, j]:.6g} rad/s is beyond its limit {lim:g} rad/s"
            raise _beyond(s.joint, ts[k], what, vs[k, j], (-lim, lim))
    read_only(ts, q_sent, vs, command, speed)
    return Timeline(ts, names, q_sent, vs, command, speed, cal, float(rate), interpolation)


#: What a malformed file's content raises while it is read (the package's own errors pass).
_MALFORMED = (KeyError, ValueError, TypeError, IndexError, AttributeError)


def _not_a(exc: Exception, kind: str, p: Path, what: str) -> Exception:
    """The error of a file that is not ``what``; the reader's and calibration's own as they are."""
    if isinstance(exc, HexapodKinError):
        return exc
    why = f"{type(exc).__name__}: {' '.join(str(exc).split())[:120]}"
    return SourceError(f"{kind}={str(p)!r}: not {what} ({why})", parameter=kind, value=str(p))


def _from_commands(
    t: Any, names: Any, command: Any, speed: Any, cal: Any, rate: float, how: str
) -> Timeline:
    """The timeline of servo ``command`` and ``speed`` columns mapped back through ``cal``."""
    servos = [cal.servo(j) for j in names]
    q = np.column_stack([s.angle(command[:, j]) for j, s in enumerate(servos)])
    qdot = np.column_stack([speed[:, j] / (s.direction * s.scale) for j, s in enumerate(servos)])
    read_only(t, q, qdot, command, speed)
    return Timeline(t, names, q, qdot, command, speed, cal, rate, how)


def read_timeline(path: str | os.PathLike[str], fmt: str | None = None) -> Timeline:
    """Read a timeline written by :meth:`Timeline.write` (CSV, JSON or ROS 2 YAML).

    CSV and JSON carry their calibration, so the joint angles ``q`` are the servo commands
    mapped back (the plan's angles to half the servo's resolution). A ROS 2 file holds
    angles [rad] and rates [rad/s]; it reads back with an identity (rad) calibration.

    Raises:
        SourceError: The file cannot be read or is not a timeline.

    """
    p = Path(path)
    kind = _format(p, fmt)
    raw = read_text(p, "timeline", _MAX_TIMELINE_BYTES)
    try:
        with named(p, "timeline", SourceError):
            return {"json": _read_json, "csv": _read_csv, "ros2": _read_ros2}[kind](raw, p)
    except _MALFORMED as exc:
        raise _not_a(exc, "timeline", p, f"a hexapod-kin {kind} timeline") from None


def _read_json(raw: str, p: Path) -> Timeline:
    d = parse_data(raw, str(p), "json", "timeline", _MAX_TIMELINE_VALUES)
    if d.get("format") != FORMAT:
        raise KeyError("format")
    t = np.asarray(numbers(d["t"], "t"), dtype=float)
    n, names = len(t), texts(d["joint_names"], "joint_names")
    cmd, speed = (np.asarray(numbers(d[k], k), float).reshape(n, -1) for k in ("command", "speed"))
    cal = Calibration.from_dict(d["calibration"])
    how = (number(d["rate"], "rate"), text(d["interpolation"], "interpolation"))
    return _from_commands(t, names, cmd, speed, cal, *how)


def _csv(text: str, name: str, what: str) -> tuple[dict[str, str], tuple[str, ...], np.ndarray]:
    """``# key: value`` lines, the column names (units dropped) and the numbers (csv_table's)."""
    meta, header, rows = csv_table(text, name, what)
    names = tuple(h.rsplit(" [", 1)[0] for h in header)
    return meta, names, np.array(rows, dtype=float).reshape(len(rows), len(header))


def _read_csv(text: str, p: Path) -> Timeline:
    meta, columns, data = _csv(text, str(p), "timeline")
    if not meta.get("format", "").startswith(FORMAT):
        raise KeyError("format")
    n = (len(columns) - 1) // 2
    names = columns[1 : 1 + n]
    cal = Calibration.from_dict(parse_data(meta["calibration"], str(p), "json", "timeline"))
    cols = (data[:, 0].copy(), names, data[:, 1 : 1 + n].copy(), data[:, 1 + n :].copy())
    return _from_commands(*cols, cal, float(meta["rate"]), meta["interpolation"])


def _read_ros2(text: str, p: Path) -> Timeline:
    d = parse_data(text, str(p), "yaml", "timeline", _MAX_TIMELINE_VALUES)
    names = texts(d["joint_names"], "joint_names")
    pts = d["points"]
    stamps = [[pt["time_from_start"]["sec"], pt["time_from_start"]["nanosec"]] for pt in pts]
    sec = np.asarray(numbers(stamps, "time_from_start"), dtype=float).reshape(-1, 2)
    t = sec[:, 0] + sec[:, 1] * 1e-9
    q = np.asarray(numbers([pt["positions"] for pt in pts], "positions"), dtype=float)
    v = np.asarray(numbers([pt["velocities"] for pt in pts], "velocities"), dtype=float)
    q, v = q.reshape(len(pts), len(names)), v.reshape(len(pts), len(names))
    rate = 1.0 / float(np.median(np.diff(t))) if len(t) > 1 else 0.0
    head = text.splitlines()[0] if text else ""
    interp = "cubic" if "cubic" in head else "linear"
    return _from_commands(t, names, q, v, _identity(), rate, interp)


def read_plan(path: str | os.PathLike[str]) -> tuple[np.ndarray, np.ndarray, tuple[str, ...]]:
    """Read a plan (an IK path, a step's joint trajectory) from a file: ``(t, q, joint_names)``.

    CSV: a header row ``t,<joint>,<joint>,...`` then one row per sample (times [s], angles
    [rad]); lines starting with ``#`` are ignored. JSON: ``{"t": [...], "q": [[...], ...],
    "joint_names": [...]}``.

    Raises:
        SourceError: The file cannot be read or is malformed.

    """
    p = Path(path)
    raw = read_text(p, "plan", _MAX_TIMELINE_BYTES)
    try:
        if p.suffix.lower() == ".json":
            d = parse_data(raw, str(p), "json", "plan", _MAX_TIMELINE_VALUES)
            with named(p, "plan", SourceError):
                if not isinstance(d, dict):
                    raise TypeError(f"a JSON object is needed, not a {type(d).__name__}")
                check_keys(d, ("t", "q", "joint_names"), "plan")
                t = np.asarray(numbers(d["t"], "t"), dtype=float)
                q = np.asarray(numbers(d["q"], "q"), dtype=float)
                names = d.get("joint_names") or [f"joint{i + 1}" for i in range(q.shape[-1])]
                return t, q.reshape(len(t), -1), texts(names, "joint_names")
        _, columns, data = _csv(raw, str(p), "plan")
        return data[:, 0].copy(), data[:, 1:].copy(), columns[1:]
    except _MALFORMED as exc:
        what = "a plan (CSV: a header t,<joint>,... then rows; JSON: t, q, joint_names)"
        raise _not_a(exc, "plan", p, what) from None
