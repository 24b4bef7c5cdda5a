"""The ``gait`` subcommand: a legged robot walks; stability, slip and limits checked."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from ..exceptions import ParameterError
from .dynamics import add_feet_args, feet_arg

__all__ = ["register"]


def register(sub: Any) -> None:
    """Add the ``gait`` subcommand to ``sub`` (an argparse subparsers object)."""
    p = sub.add_parser(
        "gait",
        help="walk a legged robot (tripod, wave, ripple, ...) and check every sample",
        description=(
            "Walk a legged robot (SOURCE: the hexapod preset by default, a URDF path or "
            "erd:NAME; name the feet with --foot when the URDF has no foot links) with a phase "
            "table and report, over every sample: the "
            "minimum static stability margin (signed distance of the projected centre of mass "
            "to the support polygon's edge), the worst stance-foot slip and the smallest "
            "joint-limit margin (SI units). An infeasible walk (a foot out of reach, off the "
            "terrain, a joint beyond its limit, legs colliding, the CoM outside the support "
            "polygon) stops with an error naming the leg, the time and the check."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument("source", nargs="?", metavar="SOURCE", help="the robot (default: hexapod)")
    p.add_argument(
        "-s",
        "--set",
        action="append",
        metavar="NAME=VALUE",
        help="hexapod preset parameter (SI units), e.g. -s body_radius=0.14",
    )
    p.add_argument(
        "--pattern", default="tripod", help="phase table: tripod, wave, ripple (6 legs), ..."
    )
    add_feet_args(p)
    p.add_argument(
        "--foot-reach",
        type=float,
        default=None,
        help="mount to neutral foot point, horizontal [m] (default: the robot's own)",
    )
    p.add_argument(
        "--stride",
        type=float,
        default=None,
        help="foot stroke in stance [m] for a straight walk (default 0.05; not with --velocity)",
    )
    p.add_argument("--height", type=float, default=0.03, help="step height [m]")
    p.add_argument("--period", type=float, default=1.0, help="cycle time [s]")
    p.add_argument(
        "--duty-factor",
        type=float,
        default=None,
        help="stance fraction in (0, 1) (default: the pattern's)",
    )
    p.add_argument(
        "--velocity",
        type=float,
        nargs=3,
        metavar=("VX", "VY", "WZ"),
        default=None,
        help="body twist: forward, sideways [m/s], yaw rate [rad/s] (not with --stride)",
    )
    p.add_argument(
        "--body-height",
        type=float,
        default=None,
        help="body above the mean ground height of the feet [m] (default: the robot's own)",
    )
    p.add_argument(
        "--terrain",
        choices=("flat", "slope", "step"),
        default="flat",
        help="slope: 8 degrees uphill along x; step: 0.02 m up at x = 0.25 m",
    )
    p.add_argument("--rate", type=float, default=100.0, help="sample rate [Hz]")
    p.add_argument("--duration", type=float, default=10.0, help="length of the walk [s]")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument(
        "--plot",
        metavar="FILE.png",
        help="gait diagram, margin over time and foot paths from above",
    )
    p.add_argument(
        "--html",
        metavar="FILE.html",
        help="self-contained animation (support polygon and projected CoM per frame)",
    )
    p.add_argument(
        "--view",
        action="store_true",
        help="play the walk in the live viewer (127.0.0.1) until Ctrl-C",
    )
    p.set_defaults(func=_cmd_gait)


def _cmd_gait(args: argparse.Namespace) -> int:
    from .. import robots
    from ..gait.robot import GaitError, as_whole_body
    from ..gait.walk import walk
    from .common import PLOT_SUFFIXES, emit_json, output_path, set_params

    plot = output_path(args.plot, "--plot", PLOT_SUFFIXES) if args.plot else None
    source = args.source or "hexapod"
    params = set_params(args.set, source=source)
    robot: Any = None
    if params:  # robots.get checks the names and values (one error naming the parameter)
        if source not in robots.PRESETS:
            raise ParameterError(
                f"-s/--set is for the presets; {source!r} is not one",
                parameter="set",
                value=sorted(params),
            )
        built = robots.get(source, **params)
        if not isinstance(built, robots.Hexapod):
            raise ParameterError(
                f"{source!r} is not a legged robot preset", parameter="source", value=source
            )
        robot = as_whole_body(built, foot_radius=args.foot_radius)
    elif args.source is not None or args.foot or args.foot_radius is not None:
        robot = as_whole_body(source, feet=feet_arg(args), foot_radius=args.foot_radius)
    html = output_path(args.html, "--html", (".html", ".htm")) if args.html else None
    try:
        run = walk(
            robot,
            pattern=args.pattern,
            stride=args.stride,
            step_height=args.height,
            period=args.period,
            duty_factor=args.duty_factor,
            velocity=args.velocity,
            body_height=args.body_height,
            foot_reach=args.foot_reach,
            terrain=args.terrain,
            rate=args.rate,
            duration=args.duration,
        )
    except GaitError as exc:  # a check failed: answered, not achieved (exit status 1)
        print(f"hexapod-kin: not walkable: {' '.join(str(exc).split())}", file=sys.stderr)
        return 1
    out = run.to_dict()
    if plot is not None:
        from ..gait.plots import plot_gait

        out["plot"] = str(plot_gait(run, plot))
    if html is not None:
        from ..viewer import walk_html

        out["html"] = str(walk_html(run, html))  # the run's own robot
    if args.json:
        emit_json(out)
    else:
        _print(out)
    if args.view:
        if args.source not in (None, "hexapod") or params:
            raise ParameterError(
                "--view plays the built-in hexapod; use --html for other robots",
                parameter="view",
            )
        _view(run)
    return 0


def _view(run: Any) -> None:
    import time

    from .. import load
    from ..exceptions import ViewerError
    from ..viewer import Viewer, walk_live

    with Viewer(load("hexapod")) as viewer:
        walk_live(run, viewer)
        print(f"meshcat viewer of the walk: {viewer.url}", file=sys.stderr, flush=True)
        print("serving on 127.0.0.1 only; press Ctrl-C to stop", file=sys.stderr, flush=True)
        while viewer.server.running:  # Ctrl-C: the one line of main, status 130
            time.sleep(0.2)
        raise ViewerError(f"the meshcat server (pid {viewer.pid}) stopped")


def _print(out: dict[str, Any]) -> None:
    vx, vy, wz = out["velocity"]
    print(
        f"{out['pattern']['name']} gait on {out['terrain']} terrain, {out['samples']} samples "
        f"over {out['duration']:g} s (v = {vx:.4g}, {vy:.4g} m/s, wz = {wz:.4g} rad/s, "
        f"stride {out['stride']:.4g} m)"
    )
    print(f"min stability margin   {out['min_margin']:.6g} m")
    print(f"min ZMP margin         {out['min_zmp_margin']:.6g} m (dynamic; reported)")
    print(f"max stance slip        {out['max_slip']:.3g} m")
    print(f"min joint-limit margin {out['min_limit_margin']:.6g} rad")
    print(f"min leg clearance      {out['min_clearance']:.6g} m")
    for key in ("plot", "html"):
        if key in out:
            print(f"wrote {out[key]}", file=sys.stderr)
