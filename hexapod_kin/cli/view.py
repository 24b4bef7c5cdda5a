"""The viewer subcommands: ``view`` (a model in the browser) and ``animate`` (a demo motion).

Both serve meshcat on 127.0.0.1 until Ctrl-C, ``--serve-for`` or ``--no-wait``; ``animate
--html FILE`` writes a self-contained page instead.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

from .common import check_outputs, emit_json, load_source, q_args, q_from_args, refused, robot_args

__all__ = ["register", "serve_end", "serve_until", "wait_args"]


def wait_args(p: argparse.ArgumentParser) -> None:
    """``--serve-for S`` or ``--no-wait``: how long a live viewer serves (default until Ctrl-C)."""
    g = p.add_mutually_exclusive_group()
    g.add_argument(
        "--serve-for",
        type=float,
        metavar="S",
        help="serve for S seconds, then stop (default: until Ctrl-C)",
    )
    g.add_argument(
        "--no-wait",
        action="store_true",
        help="stop the server right after showing (scripts, tests)",
    )


def serve_end(args: argparse.Namespace) -> float | None:
    """When to stop serving (:func:`time.monotonic` [s]; None: at Ctrl-C): ``--serve-for``.

    Raises:
        ParameterError: ``--serve-for`` outside [0, 1e7] s.

    """
    import time

    if args.serve_for is not None and not (0.0 <= args.serve_for <= 1e7):
        msg = f"--serve-for {args.serve_for!r} is not allowed; give seconds in [0, 1e7]"
        raise refused("--serve-for", args.serve_for, "seconds in [0, 1e7]", msg)
    return None if args.serve_for is None else time.monotonic() + args.serve_for


def serve_until(viewer: Any, args: argparse.Namespace) -> int:
    """Print the viewer's URL and serve until Ctrl-C, ``--serve-for`` seconds or not at all."""
    import time

    from ..exceptions import ViewerError

    end = serve_end(args)
    print(f"meshcat viewer of {viewer.model.name}: {viewer.url}", flush=True)
    if args.no_wait:
        return 0
    print("serving on 127.0.0.1 only; press Ctrl-C to stop", file=sys.stderr, flush=True)
    while end is None or time.monotonic() < end:  # Ctrl-C: the one line of main, status 130
        if not viewer.server.running:
            raise ViewerError(f"the meshcat server (pid {viewer.pid}) stopped")
        time.sleep(0.2 if end is None else max(0.0, min(0.2, end - time.monotonic())))
    return 0


def _add_view(sub: Any) -> None:
    p = sub.add_parser("view", help="show a model in the browser (meshcat server on 127.0.0.1)")
    robot_args(p, frames=True)
    q_args(p)
    wait_args(p)
    p.add_argument("--triads", action="store_true", help="draw the Khalil frames (labelled j)")
    p.set_defaults(func=_cmd_view)


def _cmd_view(args: argparse.Namespace) -> int:
    serve_end(args)  # a bad --serve-for is refused before the robot loads and the server starts
    import numpy as np

    from ..gait import default_configuration
    from ..viewer import Viewer

    model = load_source(args)
    q = default_configuration(model) if args.q is None else q_from_args(args, model)
    with Viewer(model, q=q) as viewer:
        if args.triads:
            viewer.animate([0.0], np.asarray(q)[None, :], trace_frame=False, frame_triads=True)
        return serve_until(viewer, args)


def _add_animate(sub: Any) -> None:
    p = sub.add_parser(
        "animate",
        help="animate a demo motion (joint sweep; hexapod: body sway with feet on the ground)",
    )
    robot_args(p, frames=True)
    p.add_argument(
        "--html",
        metavar="FILE",
        help="write a self-contained HTML file (no server); else serve it live",
    )
    p.add_argument("--length", type=float, default=4.0, metavar="S", help="motion length in s")
    p.add_argument("--samples", type=int, default=121, help="number of samples")
    p.add_argument("--fps", type=float, help="resample the animation at this frame rate")
    p.add_argument("--speed", type=float, default=1.0, help="playback speed factor")
    p.add_argument("--no-loop", action="store_true", help="play once")
    p.add_argument("--triads", action="store_true", help="draw the Khalil frames (labelled j)")
    p.add_argument(
        "--sigma-min",
        type=float,
        metavar="S",
        help="mark samples whose smallest singular value of the tip's position "
        "Jacobian is below S (m/rad)",
    )
    p.add_argument("--title", help="page title")
    p.add_argument("--json", action="store_true", help="one JSON object on stdout")
    wait_args(p)
    p.set_defaults(func=_cmd_animate)


def _cmd_animate(args: argparse.Namespace) -> int:
    if args.html:
        check_outputs(args)
    else:
        serve_end(args)  # refused before the robot loads and the server starts
    import numpy as np

    from ..gait import demo_trajectory
    from ..viewer import Viewer, export_html

    model = load_source(args)
    times, qs, base = demo_trajectory(model, args.length, args.samples)
    mask = None
    if args.sigma_min is not None:
        sv = np.array([np.linalg.svd(model.position_jacobian(q), compute_uv=False)[-1] for q in qs])
        mask = sv < args.sigma_min
    common = dict(base_poses=base, frame_triads=args.triads, singular_mask=mask, fps=args.fps)
    common["loop"] = not args.no_loop
    if args.html:
        path = export_html(
            model, times, qs, args.html, title=args.title, speed=args.speed, **common
        )
        if args.json:
            emit_json(
                {
                    "source": model.name,
                    "html": str(path),
                    "samples": int(len(times)),
                    "duration": float(times[-1] - times[0]),
                    "singular_samples": int(mask.sum()) if mask is not None else 0,
                }
            )
        else:
            print(f"wrote {path} ({len(times)} samples, {times[-1] - times[0]:.3g} s)")
        return 0
    with Viewer(model, q=qs[0]) as viewer:
        viewer.animate(times, qs, **common)
        return serve_until(viewer, args)


def register(sub: Any) -> None:
    """Add ``view`` and ``animate`` to ``sub`` (an argparse subparsers object)."""
    _add_view(sub)
    _add_animate(sub)
