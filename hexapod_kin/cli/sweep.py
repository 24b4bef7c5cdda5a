"""The ``sweep`` subcommand: leg design sweeps on all local cores or a Dask cluster."""

from __future__ import annotations

import argparse
import math
from typing import Any

from .common import check_outputs, emit_json, pick, seed

__all__ = ["register"]

_OPTIONS = (
    ("l1", "coxa length [m]"),
    ("l2", "femur length [m]"),
    ("l3", "tibia length [m] (not with --total)"),
    ("mount_radius", "hip axis distance from the body centre [m]"),
    ("mount_yaw", "hip frame yaw on the body [rad, --deg: degrees]"),
    ("q1_lower", "hip lower limit [rad]"),
    ("q1_upper", "hip upper limit [rad]"),
    ("q2_lower", "knee lower limit [rad]"),
    ("q2_upper", "knee upper limit [rad]"),
    ("q3_lower", "ankle lower limit [rad]"),
    ("q3_upper", "ankle upper limit [rad]"),
    ("neutral", "neutral foot: fraction of the ground's radial reach (0..1)"),
)


def register(sub: Any) -> None:
    """Add the ``sweep`` subcommand to ``sub`` (an argparse subparsers object)."""
    p = sub.add_parser(
        "sweep",
        help="sweep leg designs (link lengths, height, mount, limits): stride, volume, σ_min",
        description=(
            "Score hexabot-leg designs: reachable volume (closed form where it exists, else "
            "Monte-Carlo with its standard error), longest straight stride at the body height, "
            "min σ_min/manipulability, singular distances and limit margin along it; Pareto "
            "front. Each parameter is VALUE, A:B or A:B:N (N grid points). Resumable: re-run "
            "the same command after an interruption."
        ),
    )
    for name, text in _OPTIONS:
        p.add_argument("--" + name.replace("_", "-"), dest=name, metavar="SPEC", help=text)
    p.add_argument(
        "--height",
        metavar="SPEC",
        help="body height [m] (default 0.10: the seed leg's standing height, robots.hexapod)",
    )
    p.add_argument("--total", type=float, help="fix l1+l2+l3 [m]; l3 = total - l1 - l2")
    p.add_argument("--deg", action="store_true", help="angle options are in degrees")
    p.add_argument("--method", choices=("grid", "random", "lhs"), default="grid")
    p.add_argument("--samples", type=int, default=100, help="designs for random/lhs")
    p.add_argument("--seed", type=seed, default=0, help="design sampling and Monte-Carlo seed")
    p.add_argument("--mc-samples", type=int, default=10_000, help="Monte-Carlo points/design")
    p.add_argument("--chunk-size", type=int, help="designs per chunk (default ~1/20 of all)")
    p.add_argument("--workers", type=int, help="local threads (default: all cores)")
    p.add_argument("--scheduler", metavar="ADDR", help="Dask scheduler, e.g. tcp://host:8786")
    p.add_argument(
        "--yes",
        action="store_true",
        help="run a sweep estimated beyond 1 h of scoring or 4 GB (refused otherwise)",
    )
    p.add_argument(
        "--out",
        default="sweep.csv",
        help="the table, its format by extension: .csv, .parquet or .json (summary + columns); "
        "resumable chunks live in a hidden .NAME.sweep-parts/ beside it until it is written",
    )
    p.add_argument("--plot", metavar="FILE.png", help="score maps and the Pareto front")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.set_defaults(func=_cmd_sweep)


def _fmt(d: dict[str, Any], name: str, unit: str, mc: int) -> str:
    v = d[name]
    if name == "volume" and d.get("volume_exact"):
        how = "± 0 (closed form)"
    elif name in ("volume", "volume_mc"):
        how = f"± {d[name + '_se']:.2g} (binomial SE, {mc} Monte-Carlo points)"
    elif name == "stride":
        how = "± 1e-12 (exact membership, bisection to rounding)"
    else:
        how = "(minimum over 64 points of the central 90 % of the stride)"
    return f"{name} = {v:.6g} {unit} {how}"


def _quiet_distributed() -> None:
    """Silence the log handler that ``import distributed`` installs (its levels are per logger)."""
    import logging

    try:
        import distributed  # noqa: F401 - installs its handler and levels
    except ImportError:
        return  # sweep() says how to install it
    for handler in logging.getLogger("distributed").handlers:
        handler.setLevel(logging.CRITICAL + 1)


def _cmd_sweep(args: argparse.Namespace) -> int:
    from ..sweep import DesignSpace, parse_range, plot_sweep, sweep
    from ..sweep.designs import ANGLES

    values: dict[str, Any] = {}
    for name in [n for n, _ in _OPTIONS] + ["height"]:
        text = getattr(args, name)
        if text is not None:
            scale = math.pi / 180 if (args.deg and name in ANGLES) else 1.0
            values[name] = parse_range("--" + name.replace("_", "-"), text, scale)
    space = DesignSpace(values, total=args.total)
    check_outputs(args)  # --plot checked before any work, not after the sweep
    if args.scheduler:  # a lost scheduler is one line (our error), not distributed's tracebacks
        _quiet_distributed()
    names = ("method", "samples", "seed", "mc_samples", "out", "chunk_size", "workers")
    progress = False if args.no_progress else None
    kw = pick(args, *names, "scheduler")
    res = sweep(space, progress=progress, allow_large=args.yes, **kw)
    if args.plot:
        res.files["plot"] = str(plot_sweep(res, args.plot))
    if args.json:
        emit_json(res.to_dict())
        return 0
    s = res.summary
    print(
        f"{s['n_designs']} designs ({s['n_feasible']} feasible), {res.scored} scored now, "
        f"{res.elapsed:.2f} s; Pareto front: {len(s['pareto_indices'])} designs"
    )
    b = s["best"]
    if b is None:
        print("no feasible design (the neutral foot is out of reach everywhere)")
    else:
        print(
            f"best (max stride): design {b['index']}: l1 = {b['l1']:.4g}, l2 = {b['l2']:.4g}, "
            f"l3 = {b['l3']:.4g} m, height = {b['height']:.4g} m"
        )
        for name, unit in (
            ("stride", "m"),
            ("volume", "m³"),
            ("volume_mc", "m³"),
            ("sigma_min", "m/rad"),
            ("manipulability", "m³/rad³"),
            ("axis_distance", "m"),
            ("q3_singular_margin", "rad"),
            ("limit_margin", "rad"),
        ):
            print("  " + _fmt(b, name, unit, args.mc_samples))
    for kind, path in res.files.items():
        print(f"{kind}: {path}")
    return 0
