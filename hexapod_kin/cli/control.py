"""The ``control`` subcommand: closed-loop walking in MuJoCo under the controller."""

from __future__ import annotations

import argparse
import math
from typing import Any

from .common import not_achieved, robot_args, robot_of

__all__ = ["register"]


def register(sub: Any) -> None:
    """Add the ``control`` subcommand to ``sub`` (an argparse subparsers object)."""
    p = sub.add_parser(
        "control",
        help="walk closed-loop in MuJoCo under the controller (pushes, bumps, commands)",
        description=(
            "Run the walking controller (hexapod_kin.control) on the robot in MuJoCo: "
            "stance forces by a QP for torque motors, body posing for position servos, "
            "Raibert foot placement. Reports travel, heading, roll/pitch, falls, non-foot "
            "contacts, swing strikes and recovery from pushes. Exit status 0 when it did not "
            "fall and nothing but feet touched, 1 otherwise, 2 on bad input. Needs MuJoCo "
            "and proxsuite (pip install 'hexapod-kin[export,control]')."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    robot_args(p, kinds="legged", default="hexapod")
    p.add_argument("--pattern", help="starting gait (default tripod on 6 legs, trot on 4)")
    p.add_argument(
        "--velocity",
        nargs=3,
        type=float,
        default=(0.2, 0.0, 0.0),
        metavar=("VX", "VY", "WZ"),
        help="commanded twist in the heading frame [m/s, m/s, rad/s]",
    )
    p.add_argument("--command", metavar="FILE", help="a command timeline (JSON or YAML)")
    p.add_argument("--duration", type=float, default=10.0, help="walking time [s]")
    p.add_argument("--kind", choices=("torque", "servo"), help="actuators (default by robot)")
    p.add_argument(
        "--push",
        action="append",
        metavar="F@T,D",
        help="a lateral push of F newtons at T s for D s (repeatable; negative: rightward)",
    )
    p.add_argument("--bumps", type=float, default=0.0, help="bump amplitude [m] (0: flat)")
    p.add_argument("--seed", type=int, default=0, help="the bumps' random seed")
    p.add_argument("--friction", type=float, default=1.0, help="ground friction coefficient")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=_cmd_control)


def _cmd_control(args: argparse.Namespace) -> int:
    from ..control import Command, Push, read_timeline, run
    from .common import emit_json

    pushes = [Push.parse(s) for s in (args.push or [])]
    command: Any = read_timeline(args.command) if args.command else Command(*args.velocity)
    robot = robot_of(args)
    model: Any = robot.load()
    if robot.feet is not None or robot.foot_radius is not None:  # --foot, --foot-radius
        from ..gait import as_whole_body

        model = as_whole_body(model, feet=robot.feet, foot_radius=robot.foot_radius)
    res = run(
        model,
        pattern=args.pattern,
        command=command,
        duration=args.duration,
        kind=args.kind,
        pushes=pushes,
        bumps=args.bumps,
        friction=args.friction,
        seed=args.seed,
    )
    out = res.to_dict()
    if args.json:
        emit_json(out)
    else:
        _print(out)
    why = []
    if res.fell:
        why.append("the robot fell")
    if res.non_foot_contacts:
        why.append(f"{len(res.non_foot_contacts)} non-foot contact pair(s)")
    return not_achieved(why)


def _print(out: dict[str, Any]) -> None:
    err = out["travel_error"]
    print(
        f"{out['kind']} control, {out['pattern']}: travel {out['travel']:.4f} m vs "
        f"{out['travel_planned']:.4f} m ({'-' if err is None else f'{100 * err:+.2f} %'})"
    )
    print(f"heading error      {math.degrees(out['heading_error']):.3f} deg")
    print(
        f"max roll / pitch   {math.degrees(out['max_roll']):.3f} / "
        f"{math.degrees(out['max_pitch']):.3f} deg"
    )
    print(f"max path error     {1e3 * out['max_path_error']:.2f} mm; fell: {out['fell']}")
    contacts = out["non_foot_contacts"]
    print(
        "non-foot contacts  "
        + (", ".join(f"{a}-{b} at {t:.2f} s" for a, b, t in contacts[:5]) if contacts else "none")
    )
    for k, r in enumerate(out["recovery_time"]):
        print(f"push {k + 1}: back on the path in {'never' if r is None else f'{r:.2f} s'}")
    print(
        f"tick {1e6 * out['tick_cpu']:.0f} us median (QP {1e6 * out['qp_cpu']:.0f} us mean); "
        f"{out['simulated']:g} s simulated in {out['cpu_time']:.2f} s CPU"
    )
