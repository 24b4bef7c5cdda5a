"""The ``gait`` subcommand: a legged robot walks; stability, slip and limits checked."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from ..exceptions import HexapodKinError, ParameterError
from .common import robot_args, robot_of, walk_args, walk_options
from .view import wait_args

__all__ = ["SPEED_CHECKS", "planned_walk", "register"]


def register(sub: Any) -> None:
    """Add the ``gait`` subcommand to ``sub`` (an argparse subparsers object)."""
    p = sub.add_parser(
        "gait",
        help="walk a legged robot (tripod, wave, ripple, ...) and check every sample",
        description=(
            "Walk a legged robot with a phase table and report, over every sample: the "
            "minimum static stability margin (signed distance of the projected centre of mass "
            "to the support polygon's edge), the worst stance-foot slip and the smallest "
            "joint-limit margin (SI units). An infeasible walk (a foot out of reach, off the "
            "terrain, a joint beyond its limit, legs colliding, the CoM outside the support "
            "polygon) stops with one line naming the leg, the time and the check, exit status "
            "1; so does a walk whose minimum static or ZMP margin is negative."
        ),
    )
    robot_args(p, kinds="legged", default="hexapod", inertia=True)
    walk_args(p)
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
        help="play the walk in the live viewer (127.0.0.1) until Ctrl-C (the hexapod preset)",
    )
    wait_args(p)
    p.set_defaults(func=_cmd_gait)


def _cmd_gait(args: argparse.Namespace) -> int:
    from ..gait.robot import as_whole_body
    from .common import check_outputs, emit_json, margin_failures, not_achieved

    check_outputs(args)
    robot = robot_of(args)
    if args.view and (args.source != "hexapod" or robot.params):
        msg = "--view plays the built-in hexapod; use --html for other robots"
        raise ParameterError(msg, parameter="view")
    model = robot.load()
    wb = as_whole_body(model, feet=robot.feet, foot_radius=robot.foot_radius)
    # a check that fails raises GaitError: one line, exit status 1 (cli.main)
    run = planned_walk(wb, walk_options(args, wb))
    out = run.to_dict()
    if args.plot:
        from ..gait.plots import plot_gait

        out["plot"] = str(plot_gait(run, args.plot))
    if args.html:
        from ..viewer import walk_html

        out["html"] = str(walk_html(run, args.html, model=model))  # the robot as loaded here
    if args.json:
        emit_json(out)
    else:
        _print(out)
    status = not_achieved(margin_failures(run))
    if args.view:
        status = max(status, _view(run, args))
    return status


#: The checks a slower or shorter walk would pass: their message shows the top speed.
SPEED_CHECKS = ("joint speed", "joint acceleration", "reach")


def planned_walk(wb: Any, options: dict[str, Any]) -> Any:
    """:func:`~hexapod_kin.gait.walk.walk` with the options of :func:`.common.walk_options`.

    A walk asking more than the robot can fails with its pattern's highest straight speed
    (:func:`~hexapod_kin.gait.walk.highest_speed`) in the message.

    Raises:
        GaitError: A check fails (exit status 1).

    """
    from ..gait.legs import GaitError
    from ..gait.walk import highest_speed, walk

    try:
        return walk(wb, **options)
    except GaitError as exc:
        if exc.check not in SPEED_CHECKS:
            raise
        try:
            v, stride, period = highest_speed(wb, **options)
        except HexapodKinError:  # pragma: no cover - the search plans what walk planned
            raise exc from None
        top = f"no stride of {options.get('pattern')!s} is within this robot's reach"
        if v > 0:
            top = f"the highest straight speed of {options.get('pattern')!s} for this robot is "
            top += f"{v:.3g} m/s (--stride {stride:.3g} --period {period:.3g})"
        exc.message = f"{exc}; {top}"  # the same error (check, leg, time...), told more
        exc.args = (exc.message,)
        raise exc from None


def _view(run: Any, args: argparse.Namespace) -> int:
    from .. import load
    from ..viewer import Viewer, walk_live
    from .view import serve_until

    with Viewer(load("hexapod")) as viewer:
        walk_live(run, viewer)
        return serve_until(viewer, args)


def _print(out: dict[str, Any]) -> None:
    vx, vy, wz = out["velocity"]
    print(
        f"{out['pattern']['name']} gait on {out['terrain']} terrain, {out['samples']} samples "
        f"over {out['duration']:g} s (v = {vx:.4g}, {vy:.4g} m/s, wz = {wz:.4g} rad/s, "
        f"stride {out['stride']:.4g} m, period {out['period']:.4g} s)"
    )
    print(f"min stability margin   {out['min_margin']:.6g} m")
    print(f"min ZMP margin         {out['min_zmp_margin']:.6g} m (dynamic)")
    print(f"max stance slip        {out['max_slip']:.3g} m")
    print(f"min joint-limit margin {out['min_limit_margin']:.6g} rad")
    print(f"min leg clearance      {out['min_clearance']:.6g} m")
    print(f"knees point            {', '.join(out['knees'])} (the IK branch; --knee)")
    for key in ("plot", "html"):
        if key in out:
            print(f"wrote {out[key]}", file=sys.stderr)
