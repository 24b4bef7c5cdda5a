"""Helpers shared by the subcommand modules: sources, joint values, output, argument groups.

Every subcommand module imports from here; nothing here imports the heavy parts of the
package at module level.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NoReturn

from ..exceptions import ParameterError

#: Image formats that ``--plot`` accepts (matplotlib writes each natively).
PLOT_SUFFIXES = (".png", ".jpg", ".jpeg", ".svg", ".pdf")


class DefaultsFormatter(argparse.ArgumentDefaultsHelpFormatter):
    """Every option's default in its help, once: not when the help already says it, not None."""

    def _get_help_string(self, action: argparse.Action) -> str | None:
        text = action.help or ""
        if action.default is None or "default" in text.lower():
            return text
        return super()._get_help_string(action)


class OneLineParser(argparse.ArgumentParser):
    """An ``ArgumentParser`` whose usage errors are one line on stderr and exit status 2.

    Help shows every option's default (:class:`DefaultsFormatter`) unless a subcommand
    picks another formatter.
    """

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("formatter_class", DefaultsFormatter)
        super().__init__(*args, **kwargs)

    def error(self, message: str) -> NoReturn:
        """Print ``hexapod-kin: error: <message>`` (with the subcommand) and exit 2."""
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def refused(option: str, value: Any, allowed: Any, msg: str) -> ParameterError:
    """The :class:`ParameterError` of a bad ``option`` ``value`` (``msg``; what is ``allowed``)."""
    return ParameterError(msg, parameter=option, value=value, allowed=allowed)


def seed(text: str) -> int:
    """An argparse ``type`` for ``--seed``: an integer in [0, 2**63) (numpy's seeds)."""
    try:
        value = int(text)
    except ValueError:
        value = -1
    if not 0 <= value < 2**63:
        raise argparse.ArgumentTypeError(f"{text!r}: expected an integer in [0, 2**63)")
    return value


def set_params(pairs: Sequence[str] | None, source: Any = None) -> dict[str, Any]:
    """``-s NAME=VALUE`` pairs as a dict, fitted to a preset ``source``'s parameters.

    A value is JSON, else comma-separated numbers (a tuple; ``45,`` is one item), else text.

    Raises:
        ParameterError: A pair without ``=``, a list item not a finite number, a list for a
            parameter that takes one number.

    """
    out: dict[str, Any] = {}
    for pair in pairs or ():
        if "=" not in pair:
            msg = f"--set {pair!r}: expected NAME=VALUE (e.g. --set l1=0.06)"
            raise ParameterError(msg, parameter="--set", value=pair, allowed="NAME=VALUE")
        key, value = pair.split("=", 1)
        key = key.strip()
        out[key] = _set_value(key, value.strip())
    if isinstance(source, str):
        out = _fit_to_preset(source, out)
    return out


def _set_value(key: str, text: str) -> Any:
    """One ``-s`` value: JSON, else comma-separated numbers, else the text itself."""
    import math

    try:
        parsed: Any = json.loads(text)
    except json.JSONDecodeError:
        parsed = None
        if "," not in text:
            return text
    except ValueError:  # an integer beyond Python's digit limit
        msg = f"-s {key}=...: a number of {len(text)} characters; numbers are SI values of a robot"
        raise refused(key, f"{text[:20]}...", "a number of at most 15 digits", msg) from None
    else:
        return tuple(parsed) if isinstance(parsed, list) else parsed
    items = [t.strip() for t in text.split(",")]
    if len(items) > 1 and items[-1] == "":  # "45," : a one-item list
        items.pop()
    values = []
    for i, item in enumerate(items, start=1):
        try:
            v = float(item)
        except ValueError:
            v = math.nan
        if not math.isfinite(v):
            shown = text if len(text) <= 60 else f"{text[:40]}...({len(text)} characters)"
            one = item if len(item) <= 30 else f"{item[:20]}...({len(item)} characters)"
            msg = (
                f"-s {key}={shown}: item {i} ({one!r}) is not a finite number; a list value "
                f"is comma-separated numbers in SI units (e.g. -s {key}=30,90,150)"
            )
            raise refused(key, text, "comma-separated finite numbers", msg)
        values.append(v)
    return tuple(values)


def _fit_to_preset(source: str, params: dict[str, Any]) -> dict[str, Any]:
    """One number for a list parameter as a 1-tuple; a list for a one-number one refused."""
    import inspect

    from .. import robots

    if source not in robots.PRESETS:
        return params
    sig = inspect.signature(robots.PRESETS[source])
    out = dict(params)
    for key, value in params.items():
        if key not in sig.parameters:
            continue  # robots.get names the valid parameters
        default = sig.parameters[key].default
        takes_list = isinstance(default, (tuple, list))
        takes_number = isinstance(default, (int, float)) and not isinstance(default, bool)
        is_number = isinstance(value, (int, float)) and not isinstance(value, bool)
        if takes_list and is_number:
            out[key] = (value,)
        elif takes_number and isinstance(value, tuple):
            msg = (
                f"-s {key}={','.join(f'{v:g}' for v in value)}: {source} parameter {key!r} "
                f"takes one number (SI units), not a list of {len(value)}"
            )
            raise ParameterError(msg, parameter=key, value=list(value), allowed="one number")
    return out


#: What SOURCE may be, said once for every command that takes a robot (``kinds`` of
#: :func:`robot_args`); the ``--help`` test holds each command to what it offers.
SOURCE_KINDS: dict[str, str] = {
    "any": "a preset name (hexapod-kin list), a table file (.toml/.yaml), a URDF path or "
    "erd:NAME (example-robot-data)",
    "table": "a preset name (hexapod-kin list) or a table file (.toml/.yaml): what "
    "hexapod_kin builds (a URDF is already a URDF)",
    "legged": "a legged robot: a Hexapod preset, a URDF path or erd:NAME (name the feet with "
    "--foot when the URDF has no foot links)",
}


def robot_args(
    p: argparse.ArgumentParser,
    *,
    kinds: str = "any",
    default: str | None = None,
    required: bool = True,
    frames: bool = False,
    tool: bool = False,
    inertia: bool = False,
    feet: bool = False,
) -> None:
    """Declare SOURCE, ``-s``, ``--package-dir`` and what is asked for (read by robot_of)."""
    help_ = SOURCE_KINDS[kinds] + ("" if default is None else f" (default {default})")
    if default is None and required:
        p.add_argument("source", metavar="SOURCE", help=help_)
    else:
        p.add_argument("source", nargs="?", default=default, metavar="SOURCE", help=help_)
    p.add_argument(
        "-s",
        "--set",
        action="append",
        metavar="NAME=VALUE",
        help="a parameter of a preset or table file (SI units; repeatable); a list as "
        "comma-separated numbers, e.g. -s mount_yaw_deg=45,90,135,-135,-90,-45",
    )
    if kinds != "table":
        p.add_argument(
            "--package-dir",
            action="append",
            metavar="DIR|NAME=PATH",
            help="a folder where package:// meshes resolve, or NAME=PATH: ROS package NAME is the "
            "folder PATH (a .xacro's $(find NAME)); repeatable; before ROS_PACKAGE_PATH",
        )
    if frames:
        p.add_argument("--base", help="base frame of the sub-chain (default: the root link)")
        p.add_argument(
            "--tip",
            help="tip frame of the sub-chain (default: a chain's last frame; an arm's TCP or "
            "flange with the gripper joints locked; every limb's end of a legged robot)",
        )
    if tool:
        numbers(
            p,
            "--tool",
            "X Y Z ROLL PITCH YAW",
            help="rigid offset of the tip frame: xyz [m] and URDF rpy [rad] (deg with --deg), "
            "e.g. a foot point on a tibia link: --tip tibia_lf --tool 0.00155 0.1535 0.0288 0 0 0",
        )
    if kinds == "legged" or feet:
        p.add_argument(
            "--foot",
            action="append",
            metavar="FRAME:X,Y,Z",
            help="a foot as a frame plus an offset in it [m], once per leg (appended; or "
            "several space-separated, or a .yaml/.toml/.json file), for a URDF without foot "
            "links; e.g. --foot tibia_lf:0,0.16,0.029",
        )
    if kinds == "legged":
        p.add_argument(
            "--foot-radius",
            type=float,
            help="contact radius of the feet [m] (default: the robot's)",
        )
    if inertia:
        p.add_argument(
            "--inertia",
            choices=("urdf", "collision", "point"),
            default="urdf",
            help="inertias: the URDF's; recomputed from each link's collision shapes; or point "
            "masses (1 cm spheres). Both repairs keep every mass and centre of mass",
        )


@dataclass(frozen=True)
class Robot:
    """The robot a command line names: SOURCE, ``-s``, keywords of :func:`hexapod_kin.load`."""

    source: str
    params: dict[str, Any]
    options: dict[str, Any]
    feet: Any = None
    foot_radius: float | None = None

    def load(self) -> Any:
        """The loaded model (:func:`hexapod_kin.load`) with every option given."""
        from ..kinematics import load

        return load(self.source, **self.options, **self.params)

    def table(self, urdf: bool = False) -> Any:
        """The table (Chain or Hexapod) of a preset or table file; with ``urdf`` a URDF's source.

        Raises:
            ParameterError: SOURCE is a URDF and not ``urdf``.

        """
        from ..sources import resolve_source

        dirs = self.options.get("package_dirs", ())
        resolved = resolve_source(self.source, package_dirs=dirs, **self.params)
        if resolved.params is None and urdf:
            return self.source
        if resolved.params is None:
            msg = (
                f"SOURCE {self.source!r} is a URDF without a parameter table; this command "
                f"exports what hexapod_kin builds: {SOURCE_KINDS['table'].split(':')[0]}"
            )
            allowed = "a preset name or a .toml/.yaml table"
            raise ParameterError(msg, parameter="SOURCE", value=self.source, allowed=allowed)
        return resolved.params

    def legged(self, model: Any = None) -> Any:
        """The legged robot (:func:`hexapod_kin.gait.robot.as_whole_body`) of ``model`` (loaded)."""
        from ..gait.robot import as_whole_body

        mdl = self.load() if model is None else model
        return as_whole_body(mdl, feet=self.feet, foot_radius=self.foot_radius)


def robot_of(args: argparse.Namespace) -> Robot:
    """Read the arguments of :func:`robot_args` back (ParameterError: a bad ``-s``)."""
    import math

    source = args.source
    keys = ("base", "tip", "inertia")
    options = {k: getattr(args, k) for k in keys if getattr(args, k, None) is not None}
    tool = getattr(args, "tool", None)
    if tool is not None:
        rpy = [math.radians(v) if getattr(args, "deg", False) else v for v in tool[3:]]
        options["tool"] = (tuple(tool[:3]), tuple(rpy))
    dirs = getattr(args, "package_dir", None)
    if dirs:
        options["package_dirs"] = tuple(dirs)
    feet = getattr(args, "foot", None)
    if feet:  # a bad feet spec or file is refused before the robot is loaded
        from ..gait.legs import parse_feet

        feet = parse_feet(" ".join(feet))
    params = set_params(getattr(args, "set", None), source=source)
    return Robot(source, params, options, feet or None, getattr(args, "foot_radius", None))


def load_source(args: argparse.Namespace) -> Any:
    """The loaded model of the command line's robot; the default tips said on one line."""
    model = robot_of(args).load()
    chosen = getattr(model, "default_tips", None)
    if chosen is not None and chosen.note:  # the default a user would pick, said on one line
        print(f"hexapod-kin: {model.name}: {chosen.note}", file=sys.stderr)
    return model


def q_from_args(args: argparse.Namespace, model: Any, attr: str = "q") -> Any:
    """``--q`` for ``model`` (zeros when absent; ``--deg`` converts the revolute joints only).

    Raises:
        ParameterError: Wrong number of values.

    """
    import numpy as np

    values = getattr(args, attr, None)
    if values is None:
        return np.zeros(model.nq)
    q = np.array(values, dtype=float)
    if q.shape != (model.nq,):
        msg = (
            f"--{attr} has {q.size} values; {model.name} has {model.nq} joints "
            f"({', '.join(model.joint_names)})"
        )
        raise refused(f"--{attr}", list(values), f"{model.nq} values", msg)
    if getattr(args, "deg", False):
        prismatic = np.asarray(model.is_prismatic, dtype=bool)
        q = np.where(prismatic, q, np.radians(q))
    return q


def output_path(path: str | os.PathLike[str], option: str, suffixes: Sequence[str]) -> Path:
    """Check an output file before any work (ParameterError: suffix, missing or unwritable)."""
    p = Path(path)
    parent = p.parent if str(p.parent) else Path(".")

    def refuse(why: str, allowed: Any) -> NoReturn:
        raise refused(option, str(path), allowed, f"{option} {str(path)!r}: {why}")

    if p.suffix.lower() not in suffixes:
        refuse(
            f"unknown file type {p.suffix or '(none)'!r}; use one of {', '.join(suffixes)}",
            list(suffixes),
        )
    if not parent.is_dir():
        refuse(f"directory {str(parent)!r} does not exist", "a path in an existing directory")
    if not os.access(parent, os.W_OK) or p.is_dir():
        refuse("cannot write there (permission denied or a directory)", "a writable file path")
    return p


def made_by(args: argparse.Namespace, extra: Sequence[str] = ()) -> str:
    """An exported file's header: the command, short options (no ``--``), no output path."""
    words = [args.command, args.source, *(f"-s {s}" for s in args.set or ()), *extra]
    return "made by: hexapod-kin " + " ".join(words)


def not_achieved(why: Sequence[str]) -> int:
    """Exit status 0 when ``why`` is empty, else 1 (answered, not achieved) and one line why."""
    if not why:
        return 0
    print(f"hexapod-kin: not achieved: {'; '.join(why)}", file=sys.stderr)
    return 1


def walk_args(p: argparse.ArgumentParser, rate: str = "--rate") -> None:
    """The options of a planned walk (``rate``: the flag of its sample rate); see walk_options."""
    p.add_argument(
        "--pattern",
        help="phase table: tripod, wave, ripple (6 legs); crawl (4 legs); wave, ripple "
        "(8 legs) (default: tripod for six legs, crawl for four, else wave); trot and pace "
        "(4 legs) are not statically stable: refused open loop (exit 1), they need a balance "
        "controller",
    )
    p.add_argument(
        "--stride",
        type=float,
        help="foot stroke in stance [m] for a straight walk (default 0.05; not with --velocity)",
    )
    p.add_argument(
        "--height",
        type=float,
        help="step height [m] (default 0.03, or 0.15 x the leg span of a short leg)",
    )
    p.add_argument(
        "--period",
        type=float,
        help="cycle time [s] (default 1, or longer when a joint would exceed its speed limit)",
    )
    p.add_argument(
        "--duty-factor", type=float, help="stance fraction in (0, 1) (default: the pattern's)"
    )
    p.add_argument(
        "--velocity",
        nargs="+",
        metavar="V",
        help="body twist: forward, sideways [m/s], yaw rate [rad/s] as three numbers or "
        "vx,vy,wz (not with --stride)",
    )
    p.add_argument(
        "--body-height",
        type=float,
        help="body above the mean ground height of the feet [m] (default: the robot's own)",
    )
    p.add_argument(
        "--foot-reach",
        type=float,
        help="mount to neutral foot point, horizontal [m] (default: the robot's own)",
    )
    p.add_argument(
        "--terrain",
        choices=("flat", "slope", "step"),
        default="flat",
        help="slope: 8 degrees uphill along x; step: 0.02 m up at x = 0.25 m",
    )
    p.add_argument(
        rate, dest="walk_rate", metavar="HZ", type=float, default=100.0, help="the walk's rate [Hz]"
    )
    p.add_argument("--duration", type=float, default=10.0, help="length of the walk [s]")
    knee_arg(p)


def knee_arg(p: argparse.ArgumentParser) -> None:
    """``--knee``: where the closed-form legs' knees point (the IK branch)."""
    p.add_argument(
        "--knee",
        choices=("up", "down", "forward", "backward", "out", "in"),
        help="the IK branch: where the legs' knees point (default: the branch inside the "
        "joint limits nearest the robot's neutral pose; the one taken is reported)",
    )


def velocity(values: Sequence[str] | None) -> tuple[float, ...] | None:
    """``--velocity``: three finite numbers, given apart or as ``vx,vy,wz``."""
    import math

    if values is None:
        return None
    parts = [v for item in values for v in item.replace(",", " ").split()]
    try:
        vel = [float(v) for v in parts]
    except ValueError:
        vel = []
    if len(vel) != 3 or not all(math.isfinite(v) for v in vel):
        msg = f"--velocity {' '.join(values)!r}: three finite numbers vx,vy,wz [m/s, m/s, rad/s]"
        raise refused("--velocity", " ".join(values), "vx,vy,wz", msg)
    return tuple(vel)


def walk_options(args: argparse.Namespace, wb: Any) -> dict[str, Any]:
    """The keywords of :func:`hexapod_kin.gait.walk.walk` from :func:`walk_args`'s options."""
    from ..gait.tables import default_pattern

    return {
        **pick(args, "stride", "period", "duty_factor", "body_height", "foot_reach", "terrain"),
        **pick(args, "duration", "knee"),
        "pattern": args.pattern or default_pattern(wb.n_legs),
        "step_height": args.height,
        "velocity": velocity(args.velocity),
        "rate": args.walk_rate,
    }


def pick(args: argparse.Namespace, *names: str) -> dict[str, Any]:
    """The options ``names`` of the command line, by name: keywords of the call they go to."""
    return {name: getattr(args, name) for name in names}


def margin_failures(run: Any) -> list[str]:
    """Why a planned walk is not achieved: a static or ZMP margin below 0 [m]."""
    why = []
    for attr, what, point in (
        ("min_margin", "static stability", "projected centre of mass"),
        ("min_zmp_margin", "ZMP", "zero-moment point"),
    ):
        value = float(getattr(run, attr))
        if value < 0:
            why.append(
                f"min {what} margin {value:.6g} m < 0 (the {point} leaves the support: the "
                "plan needs a balance controller, or a longer --period or shorter --stride)"
            )
    return why


def check_outputs(args: argparse.Namespace) -> None:
    """Refuse bad ``--plot``/``--html`` paths before any computation (:func:`output_path`)."""
    if getattr(args, "plot", None):
        output_path(args.plot, "--plot", PLOT_SUFFIXES)
    if getattr(args, "html", None):
        output_path(args.html, "--html", (".html", ".htm"))


def html_page(model: Any, t: Any, q: Any, path: str, title: str, every: float) -> str:
    """``--html``: ``q`` at ``t`` [s] as an offline page, a frame per ``every`` s."""
    try:
        from ..viewer import export_html
    except ImportError as exc:
        msg = f"--html needs the viewer (hexapod_kin.viewer): {exc}"
        raise refused("--html", path, "install hexapod-kin[viewer]", msg) from None
    stride = max(1, int(round(every / float(t[1] - t[0])))) if len(t) > 1 else 1
    return str(export_html(model, t[::stride], q[::stride], path, title=title))


def matrix_text(m: Any, indent: str = "  ") -> str:
    """Rows of a matrix, 6 decimals, one line each."""
    return "\n".join(indent + " ".join(f"{v: .6f}" for v in row) for row in m)


def emit_json(obj: dict[str, Any]) -> None:
    """Write one JSON object (no NaN) and a newline on stdout."""
    sys.stdout.write(json.dumps(obj, allow_nan=False) + "\n")


def numbers(p: Any, flag: str, names: str, kind: type = float, **kw: Any) -> None:
    """An option of as many numbers (``kind``) as ``names`` (its metavar, space-separated)."""
    metavar = tuple(names.split())
    p.add_argument(flag, nargs=len(metavar), type=kind, metavar=metavar, **kw)


def q_args(p: argparse.ArgumentParser, what: str = "joint values") -> None:
    """``--q`` (``what``: rad for revolute, m for prismatic joints) and ``--deg``."""
    p.add_argument("--q", nargs="+", type=float, help=f"{what} (rad for revolute, m for prismatic)")
    p.add_argument(
        "--deg", action="store_true", help="revolute --q values in degrees (prismatic stay in m)"
    )
