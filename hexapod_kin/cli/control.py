"""The ``control`` subcommand: closed-loop walking in MuJoCo under the controller."""

from __future__ import annotations

import argparse
import math
from typing import Any

from .common import not_achieved, pick, robot_args, robot_of, seed, velocity

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
    )
    robot_args(p, kinds="legged", default="hexapod")
    p.add_argument("--pattern", help="starting gait (default tripod on 6 legs, trot on 4)")
    p.add_argument(
        "--velocity",
        nargs="+",
        metavar="V",
        help="commanded twist in the heading frame: forward, sideways [m/s], yaw rate [rad/s] "
        "as three numbers or vx,vy,wz (default 0.2,0,0)",
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
    p.add_argument("--seed", type=seed, default=0, help="the bumps' random seed")
    p.add_argument("--friction", type=float, default=1.0, help="ground friction coefficient")
    p.add_argument(
        "--payload",
        metavar="KG[@X,Y,Z]",
        help="a load of KG kilograms fixed to the body at X,Y,Z [m] in the base frame "
        "(default its origin); the controller is not told of it",
    )
    p.add_argument(
        "--estimate",
        action="store_true",
        help="run on the state estimator's base position/velocity (IMU + legs), not MuJoCo's",
    )
    p.add_argument(
        "--lying", action="store_true", help="start lying on the body (it stands up first)"
    )
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=_cmd_control)


def _cmd_control(args: argparse.Namespace) -> int:
    from ..control import Command, Payload, Push, read_timeline, run
    from .common import emit_json

    pushes = [Push.parse(s) for s in (args.push or [])]
    payload = Payload.parse(args.payload) if args.payload is not None else None
    vx, vy, wz = velocity(args.velocity) or (0.2, 0.0, 0.0)
    command: Any = read_timeline(args.command) if args.command else Command(vx, vy, wz)
    robot = robot_of(args)
    model: Any = robot.load()
    if robot.feet is not None or robot.foot_radius is not None:  # --foot, --foot-radius
        from ..gait import as_whole_body

        model = as_whole_body(model, feet=robot.feet, foot_radius=robot.foot_radius)
    names = ("pattern", "duration", "kind", "bumps", "friction", "seed", "estimate", "lying")
    res = run(model, command=command, pushes=pushes, payload=payload, **pick(args, *names))
    out = res.to_dict()
    if args.json:
        emit_json(out)
    else:
        _print(out)
    why = ["the robot fell"] if res.fell else []
    if res.non_foot_contacts:
        why.append(f"{len(res.non_foot_contacts)} non-foot contact pair(s)")
    return not_achieved(why)


def simulate_control(
    args: argparse.Namespace, model: Any, options: dict[str, Any], html: Any
) -> int:
    """``simulate --control``: the plan open-loop and closed-loop, printed or as a page."""
    import sys

    from ..control.compare import compare, comparison_html
    from .common import emit_json

    opts = {k: v for k, v in options.items() if k != "stand"}
    kw = pick(args, "friction", "bumps", "seed", "payload")
    cmp = compare(model, pushes=args.push or (), **kw, **opts)
    out = cmp.to_dict()
    if html is not None:
        out["html"] = str(comparison_html(cmp, html))
    if args.json:
        emit_json(out)
    else:
        for name, a, b in cmp.rows():
            fa, fb = ("-" if v is None else f"{v:.4g}" for v in (a, b))
            print(f"{name:24s} open loop {fa:>10}   closed loop {fb:>10}")
        for k, r in enumerate(cmp.closed_loop.recovery_time):
            print(f"push {k + 1} (closed loop): back on the path in " + _seconds(r))
        if "html" in out:
            print(f"wrote {out['html']}", file=sys.stderr)
    res = cmp.closed_loop
    return not_achieved(["the robot fell under the controller"] if res.fell else [])


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
        print(f"push {k + 1}: back on the path in " + _seconds(r))
    print(
        f"tick {1e6 * out['tick_cpu']:.0f} us median (QP {1e6 * out['qp_cpu']:.0f} us mean); "
        f"{out['simulated']:g} s simulated in {out['cpu_time']:.2f} s CPU"
    )


def _seconds(r: float | None) -> str:
    return "never" if r is None else f"{r:.2f} s"
