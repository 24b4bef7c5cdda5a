"""Export subcommands: ``xacro``, ``export-package``, ``mjcf`` (header: :func:`.common.made_by`)."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from ..exceptions import ParameterError
from .common import emit_json, made_by, output_path, pick, robot_args, robot_of

__all__ = ["register"]


def _add_xacro(sub: Any) -> None:
    p = sub.add_parser(
        "xacro", help="parametric xacro (a macro per leg family, a property per dimension)"
    )
    robot_args(p, kinds="table")
    p.add_argument("-l", "--leg", help="hexapod only: one leg with its mount")
    p.add_argument("-o", "--output", help="file to write (atomically); stdout if unset")
    p.add_argument(
        "-x", "--expand", action="store_true", help="print/write the expanded URDF instead"
    )
    p.set_defaults(func=_cmd_xacro)


def _cmd_xacro(args: argparse.Namespace) -> int:
    from .._io import atomic_write
    from ..export.xacro import expand_xacro, to_xacro

    if args.output:
        output_path(args.output, "--output", (".xacro", ".urdf"))
    src = robot_of(args).table()
    extra = ([f"-l {args.leg}"] if args.leg else []) + (["-x"] if args.expand else [])
    text = to_xacro(src, leg=args.leg, header=made_by(args, extra))
    if args.expand:
        text = expand_xacro(text)
    if args.output:
        path = atomic_write(args.output, text)
        print(f"wrote {path}", file=sys.stderr)
    else:
        sys.stdout.write(text)
    return 0


def _add_package(sub: Any) -> None:
    p = sub.add_parser(
        "export-package",
        help="ROS 2 description package (package.xml, CMakeLists, urdf/, launch/, rviz/, meshes/)",
    )
    robot_args(p, kinds="table")
    p.add_argument("-o", "--out", required=True, help="package folder to create")
    p.add_argument("-n", "--name", help="ROS package name (default <robot>_description)")
    p.add_argument("-m", "--meshes", action="store_true", help="STL visuals in meshes/ (trimesh)")
    p.add_argument("-f", "--force", action="store_true", help="replace a non-empty --out folder")
    p.add_argument("--maintainer", default="hexapod_kin user", help="package.xml maintainer")
    p.add_argument("--email", default="user@example.com", help="maintainer e-mail")
    p.add_argument("--license", default="BSD-3-Clause", help="package.xml license")
    p.add_argument("--json", action="store_true", help="print what was written as JSON")
    p.set_defaults(func=_cmd_package)


def _cmd_package(args: argparse.Namespace) -> int:
    from ..export.ros2 import export_package

    src = robot_of(args).table()
    extra = ([f"-n {args.name}"] if args.name else []) + (["-m"] if args.meshes else [])
    kw = pick(args, "name", "meshes", "force", "maintainer", "email", "license")
    result = export_package(src, args.out, header=made_by(args, extra), **kw)
    if args.json:
        emit_json(result.to_dict())
    else:
        print(
            f"wrote package {result.name} in {result.path} ({len(result.files)} files)",
            file=sys.stderr,
        )
    return 0


def _add_mjcf(sub: Any) -> None:
    p = sub.add_parser(
        "mjcf",
        help="MJCF for MuJoCo (its own URDF compiler), with damping, limits, inertials, a floor",
    )
    robot_args(p)
    p.add_argument("-o", "--output", help="MJCF file to write; stdout if unset")
    p.add_argument("-m", "--meshes", action="store_true", help="STL visuals in <stem>_meshes/")
    p.add_argument("--no-floor", action="store_true", help="no floor plane and light")
    p.add_argument("--floor-z", type=float, help="floor height [m] (default: below reach)")
    p.add_argument("--timestep", type=float, help="option timestep [s]")
    p.add_argument("--integrator", help="Euler, RK4, implicit or implicitfast")
    p.add_argument(
        "--floating", action="store_true", help="robots: a free joint on the body (it can fall)"
    )
    p.set_defaults(func=_cmd_mjcf)


def _cmd_mjcf(args: argparse.Namespace) -> int:
    from ..export.mjcf import to_mjcf, write_mjcf

    if args.output:
        output_path(args.output, "--output", (".xml", ".mjcf"))
    src = robot_of(args).table(urdf=True)
    flags = (("-m", args.meshes), ("(no floor)", args.no_floor), ("(floating)", args.floating))
    extra = [flag for flag, given in flags if given]
    for label in ("floor_z", "timestep", "integrator"):
        if getattr(args, label) is not None:
            extra.append(f"({label.replace('_', '-')} {getattr(args, label)})")
    kwargs = pick(args, "meshes", "floor_z", "timestep", "integrator", "floating")
    kwargs.update(header=made_by(args, extra), floor=not args.no_floor)
    if args.output:
        write_mjcf(src, args.output, **kwargs)
        print(f"wrote {args.output}", file=sys.stderr)
        return 0
    if args.meshes:
        msg = "--meshes writes mesh files beside the MJCF; give -o FILE"
        raise ParameterError(msg, parameter="meshes")
    sys.stdout.write(to_mjcf(src, **kwargs).xml)
    return 0


def register(sub: Any) -> None:
    """Add the export subcommands to the ``hexapod-kin`` parser."""
    _add_xacro(sub)
    _add_package(sub)
    _add_mjcf(sub)
