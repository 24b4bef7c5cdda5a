"""The ``timeline`` subcommand: a planned motion as a servo timeline (CSV, JSON, ROS 2 YAML).

``hexapod-kin timeline gait [SOURCE]`` walks a legged robot (default the hexapod; the ``gait``
command's options) and writes the joints' timeline; ``hexapod-kin timeline step [SOURCE]`` the
seeds' resolved-rate step of a leg; ``hexapod-kin timeline path FILE [SOURCE]`` takes any joint
path from a file (an IK path, a step's joint trajectory: CSV ``t,<joint>,...`` in [s] and [rad],
or JSON ``t``, ``q``, ``joint_names``; SOURCE's speed limits apply). All resample at ``--rate``
(``--interpolation linear|cubic``), map each joint through ``--calibration`` (YAML/TOML/JSON)
and stop at the first sample beyond a servo's limits or a joint's speed limit with one line
naming the joint, the time and the value (exit status 1: answered, not achieved; as when the
step or the walk reaches a joint limit or fails a check). The output format follows the suffix
of ``-o``: ``.csv``, ``.json``, ``.yaml``/``.yml`` (a ROS 2
``trajectory_msgs/JointTrajectory``).
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

from ..exceptions import ParameterError
from .common import (
    emit_json,
    load_source,
    margin_failures,
    not_achieved,
    output_path,
    pick,
    robot_args,
    robot_of,
    walk_args,
    walk_options,
)

__all__ = ["register"]

_SUFFIXES = (".csv", ".json", ".yaml", ".yml")


def _common(p: argparse.ArgumentParser) -> None:
    p.add_argument("--rate", type=float, default=50.0, help="timeline samples per second [Hz]")
    p.add_argument(
        "--interpolation",
        choices=("linear", "cubic"),
        default="linear",
        help="resampling: linear (positions and plan rates) or a cubic spline",
    )
    p.add_argument(
        "--calibration",
        metavar="FILE",
        help="servo calibration (.yaml/.toml/.json): offset, direction, units, limits "
        "(default: every joint in rad, unlimited)",
    )
    p.add_argument(
        "-o",
        "--output",
        required=True,
        metavar="FILE",
        help="output: .csv, .json or .yaml/.yml (ROS 2 JointTrajectory)",
    )
    p.add_argument("--json", action="store_true", help="print one JSON summary object")


def register(sub: Any) -> None:
    """Add the ``timeline`` subcommand to ``sub`` (an argparse subparsers object)."""
    p = sub.add_parser(
        "timeline",
        help="export a planned motion as a servo timeline (CSV, JSON, ROS 2 YAML)",
        description=__doc__.split("\n\n", 1)[1].strip() if __doc__ else None,
    )
    kinds = p.add_subparsers(dest="plan", required=True, metavar="PLAN")
    g = kinds.add_parser("gait", help="a walk of a legged robot (default the hexapod preset)")
    robot_args(g, kinds="legged", default="hexapod", inertia=True)
    walk_args(g, rate="--plan-rate")
    _common(g)
    g.set_defaults(func=_cmd_gait)
    st = kinds.add_parser(
        "step", help="the seeds' resolved-rate step v = [A sin(2 pi t/T), 0, 0] of a 3-joint leg"
    )
    robot_args(st, default="hexabot_leg", frames=True, tool=True)
    st.add_argument("--amplitude", type=float, default=0.05, help="A [m/s]")
    st.add_argument("--period", type=float, default=2.0, help="T [s]")
    st.add_argument("--dt", type=float, default=1e-3, help="integration step [s]")
    st.add_argument("--duration", type=float, default=4.0, help="[s]")
    _common(st)
    st.set_defaults(func=_cmd_step)
    f = kinds.add_parser(
        "path", help="a joint path from a file (IK path, a step): CSV t,<joint>,... or JSON"
    )
    f.add_argument("file", help="plan file: CSV (header t,<joint>,...; [s], [rad]) or JSON")
    robot_args(f, required=False)
    _common(f)
    f.set_defaults(func=_cmd_path)


def _cmd_gait(args: argparse.Namespace) -> int:
    from ..gait.robot import as_whole_body
    from ..params import Hexapod
    from .gait import planned_walk

    out = output_path(args.output, "-o", _SUFFIXES)
    robot = robot_of(args)
    model = robot.load()
    args.calibration = _calibration(args, model)
    wb = as_whole_body(model, feet=robot.feet, foot_radius=robot.foot_radius)
    options = walk_options(args, wb)
    if options["body_height"] is None and isinstance(model.params, Hexapod):
        options["body_height"] = 0.08  # the timelines' walk of the hexapod
    run = planned_walk(wb, options)
    return max(_write(run, args, out, None), not_achieved(margin_failures(run)))


def _cmd_step(args: argparse.Namespace) -> int:
    from ..seeds import seed_experiment

    out = output_path(args.output, "-o", _SUFFIXES)
    model = load_source(args)
    args.calibration = _calibration(args, model)
    run = seed_experiment(
        model, baseline=False, **pick(args, "amplitude", "period", "dt", "duration")
    )
    traj = run.trajectory
    limits = (model.lower, model.upper)
    status = _write((traj.t, traj.q), args, out, model.velocity_limit, model.joint_names, limits)
    limited = bool(traj.limited.any())  # as `step`: limits cut the motion
    return max(status, not_achieved(["joint or speed limits cut the step"] if limited else []))


def _cmd_path(args: argparse.Namespace) -> int:
    from ..export.timeline import read_plan

    out = output_path(args.output, "-o", _SUFFIXES)
    t, q, names = read_plan(args.file)
    vlim = plim = None
    if args.source:  # the plan is for this robot: its joints by name, their limits checked
        model = load_source(args)
        args.calibration = _calibration(args, model)
        unknown = [n for n in names if n not in model.joint_names]
        if unknown:
            msg = (
                f"plan {args.file!r}: joint(s) {', '.join(map(repr, unknown))} not in "
                f"{model.name!r}; its joints: {', '.join(model.joint_names)}"
            )
            allowed = tuple(model.joint_names)
            raise ParameterError(msg, parameter="file", value=unknown[0], allowed=allowed)
        idx = [model.joint_names.index(n) for n in names]
        vlim = [float(model.velocity_limit[i]) for i in idx]
        plim = ([float(model.lower[i]) for i in idx], [float(model.upper[i]) for i in idx])
    return _write((t, q), args, out, vlim, names, plim)


def _calibration(args: argparse.Namespace, model: Any) -> Any:
    """``--calibration`` read and held to ``model``'s joints and limits, before any planning."""
    from ..export.timeline import read_calibration

    return None if args.calibration is None else read_calibration(args.calibration, model)


def _write(
    plan: Any, args: argparse.Namespace, out: Any, vlim: Any, names: Any = None, plim: Any = None
) -> int:
    from ..export.timeline import timeline

    kw = pick(args, "rate", "interpolation", "calibration")
    tl = timeline(plan, joint_names=names, velocity_limit=vlim, position_limit=plim, **kw)
    path = tl.write(out)
    summary = {
        "path": str(path),
        "samples": len(tl.t),
        "duration": float(tl.t[-1] - tl.t[0]),
        "rate": tl.rate,
        "interpolation": tl.interpolation,
        "joints": list(tl.joint_names),
        "units": [s.units for s in tl.servos],
    }
    if args.json:
        emit_json(summary)
    else:
        print(
            f"{summary['samples']} samples of {len(tl.joint_names)} joints over "
            f"{summary['duration']:g} s at {tl.rate:g} Hz ({tl.interpolation}); every sample "
            f"within the servos' limits"
        )
        print(f"wrote {path}", file=sys.stderr)
    return 0
