"""``hexapod-kin drive SOURCE``: the browser cockpit (:func:`hexapod_kin.drive.drive`).

Serves the page on 127.0.0.1 until Ctrl-C (status 130), ``--serve-for`` seconds, or the last
page closes (``--until-closed``); the server stops with the command (nothing left running).
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

from .common import robot_args, robot_of
from .view import serve_end

__all__ = ["register"]


def register(sub: Any) -> None:
    """Declare ``drive``."""
    p = sub.add_parser(
        "drive", help="drive, pose and probe a robot live in the browser (127.0.0.1 only)"
    )
    robot_args(p, frames=True, feet=True)
    p.add_argument("--port", type=int, default=0, help="port on 127.0.0.1 (0: a free one)")
    p.add_argument("--no-open", action="store_true", help="do not open a browser")
    p.add_argument(
        "--serve-for", type=float, metavar="S", help="stop after S seconds (default: Ctrl-C)"
    )
    p.add_argument(
        "--until-closed",
        action="store_true",
        help="stop 2 s after the last page closes (once one has connected)",
    )
    p.add_argument(
        "--calibration",
        metavar="FILE",
        help="servo calibration of the downloaded timeline (as `timeline --calibration`)",
    )
    p.set_defaults(func=_cmd_drive)


def _cmd_drive(args: argparse.Namespace) -> int:
    import time
    import webbrowser

    from ..exceptions import ParameterError

    if not 0 <= args.port <= 65535:
        msg = f"--port {args.port!r} is not allowed; give 0 (a free port) or 1..65535"
        raise ParameterError(msg, parameter="--port", value=args.port, allowed="0..65535")
    end = serve_end(args)
    from ..drive import drive  # after the checks: a refusal imports no server

    robot = robot_of(args)
    with drive(
        robot.load(), feet=robot.feet, port=args.port, calibration=args.calibration
    ) as session:
        print(f"hexapod-kin drive {session.cockpit.model.name}: {session.url}", flush=True)
        print("serving on 127.0.0.1 only; press Ctrl-C to stop", file=sys.stderr, flush=True)
        if not args.no_open:
            webbrowser.open(session.url)
        server = session.server
        while end is None or time.monotonic() < end:
            if not session.running:
                return 1
            if args.until_closed and server.pages_seen and time.monotonic() - server.last_close > 2:
                break
            time.sleep(0.1)
    return 0
