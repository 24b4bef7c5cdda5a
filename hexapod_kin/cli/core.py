"""The core subcommands: list, urdf, fk, jacobian, demo, derive, scan.

Each has an ``_add_<name>(sub)`` declaring its arguments and a ``_cmd_<name>(args)`` running it.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Iterator
from typing import Any

from ..exceptions import ParameterError
from .common import (
    check_outputs,
    emit_json,
    load_source,
    made_by,
    matrix_text,
    output_path,
    pick,
    q_args,
    q_from_args,
    refused,
    robot_args,
    robot_of,
    seed,
)

__all__ = ["COMMANDS", "register"]


def _add_list(sub: Any) -> None:
    p = sub.add_parser("list", help="list the presets")
    p.add_argument("--json", action="store_true")
    p.add_argument("--erd", action="store_true", help="also list example-robot-data robots")


def _cmd_list(args: argparse.Namespace) -> int:
    from .. import robots

    docs = {n: (robots.PRESETS[n].__doc__ or "").strip().splitlines()[0] for n in robots.names()}
    rows = [{"name": name, "summary": doc.replace("``", "")} for name, doc in docs.items()]
    out: dict[str, Any] = {"presets": rows}
    if args.erd:
        from ..sources import erd_names

        out["erd"] = erd_names()
    if args.json:
        emit_json(out)
        return 0
    for row in rows:
        print(f"{row['name']:<16} {row['summary']}")
    if args.erd:
        print("\nexample-robot-data (use erd:NAME): " + ", ".join(out["erd"]))
    return 0


def _add_urdf(sub: Any) -> None:
    p = sub.add_parser("urdf", help="export the URDF of a preset or a table file")
    robot_args(p, kinds="table")
    p.add_argument("-l", "--leg", help="hexapod only: one leg with its mount (e.g. leg1)")
    p.add_argument("-o", "--output", help="file to write (atomically); default stdout")


def _cmd_urdf(args: argparse.Namespace) -> int:
    from ..urdf import to_urdf, write_urdf

    if args.output:
        output_path(args.output, "-o/--output", (".urdf", ".xml"))
    built = robot_of(args).table()
    header = made_by(args, [f"-l {args.leg}"] if args.leg else [])
    if args.output:
        path = write_urdf(built, args.output, leg=args.leg, header=header)
        print(f"wrote {path}", file=sys.stderr)
    else:
        sys.stdout.write(to_urdf(built, leg=args.leg, header=header))
    return 0


def _add_fk(sub: Any) -> None:
    p = sub.add_parser("fk", help="tip transform and every intermediate transform")
    robot_args(p, frames=True, tool=True)
    q_args(p)
    p.add_argument("--json", action="store_true", help="one JSON object on stdout")


def _cmd_fk(args: argparse.Namespace) -> int:
    model = load_source(args)
    q = q_from_args(args, model)
    tip = model.fk(q)
    rel = model.transforms(q)
    cum = model.cumulative_transforms(q)
    frames = list(model.path_frames)
    chosen = model.default_tips
    limbs = chosen.tips if chosen is not None and chosen.kind == "limbs" else ()
    ends = {name: model.placement(q, name) for name in limbs}  # every limb's end
    if args.json:
        emit_json(
            {
                "source": model.name,
                "joint_names": list(model.joint_names),
                "q": [float(v) for v in model.check_q(q)],
                "base": model.base,
                "tip": model.tip,
                "frames": frames,
                "T_tip": tip.tolist(),
                "position": tip[:3, 3].tolist(),
                "transforms": [t.tolist() for t in rel],
                "cumulative": [t.tolist() for t in cum],
                "ends": {name: T.tolist() for name, T in ends.items()},
            }
        )
        return 0
    print(
        f"{model.name}: q = {[round(float(v), 6) for v in model.check_q(q)]} "
        f"({', '.join(model.joint_names)})"
    )
    for name, T in ends.items():  # a tree robot: every limb's end, not one leaf
        _placement(f"T  ({model.base} -> {name}):", T)
    if ends:
        return 0
    n = len(rel)
    for j, (t, c) in enumerate(zip(rel, cum), start=1):
        print(f"^{j - 1}T_{j}  ({frames[j - 1]} -> {frames[j]}):\n{matrix_text(t)}")
        if 1 < j < n:  # ^0T_1 = ^0T_1 above; ^0T_n is the tip, printed last
            print(f"^0T_{j}  ({frames[0]} -> {frames[j]}):\n{matrix_text(c)}")
    _placement(f"^0T_{n} = T tip  ({model.base} -> {model.tip}):", tip)
    return 0


def _placement(title: str, T: Any) -> None:
    """A placement printed: its title, the 4x4 matrix, the position [m]."""
    print(f"{title}\n{matrix_text(T)}\nposition [m]: " + " ".join(f"{v:.6f}" for v in T[:3, 3]))


def _add_jacobian(sub: Any) -> None:
    p = sub.add_parser("jacobian", help="frame Jacobian of the tip")
    robot_args(p, frames=True, tool=True)
    q_args(p)
    p.add_argument(
        "--reference",
        default="local_world_aligned",
        choices=["local", "world", "local_world_aligned"],
    )
    p.add_argument("--json", action="store_true", help="one JSON object on stdout")


def _cmd_jacobian(args: argparse.Namespace) -> int:
    import numpy as np

    model = load_source(args)
    q = q_from_args(args, model)
    jac = model.jacobian(q, args.reference)
    # position measures from the tip's linear velocity (LOCAL_WORLD_ALIGNED rows), whatever
    # reference is printed: WORLD's linear rows are the velocity of the point at the world origin
    jp = model.jacobian(q, "local_world_aligned")[:3]
    det = float(np.linalg.det(jp)) if jp.shape[0] == jp.shape[1] else None
    sv = np.linalg.svd(jp, compute_uv=False)
    if args.json:
        emit_json(
            {
                "source": model.name,
                "joint_names": list(model.joint_names),
                "q": [float(v) for v in model.check_q(q)],
                "reference": args.reference,
                "tip": model.tip,
                "jacobian": jac.tolist(),
                "det_position": det,
                "singular_values_position": sv.tolist(),
            }
        )
        return 0
    tips = model.default_tips.tips if model.default_tips is not None else ()
    if args.tip is None and len(getattr(model.params, "foot_frames", ())) > 1:
        tips = model.params.foot_frames  # a legged preset: its first foot
    which = f" of {len(tips)} limbs' ends, --tip picks another" if len(tips) > 1 else ""
    print(f"J of frame {model.tip!r} (the first{which})" if which else f"J of frame {model.tip!r}")
    print(f"({args.reference}, rows vx vy vz wx wy wz; columns {', '.join(model.joint_names)}):")
    print(matrix_text(jac))
    if det is not None:
        print(f"det(J_position) = {det:.6e}  (tip linear velocity, base-aligned)")
    print("singular values (position): " + " ".join(f"{v:.6e}" for v in sv))
    return 0


def _add_demo(sub: Any) -> None:
    p = sub.add_parser("demo", help="export the leg URDF, print its FK and Jacobian")
    p.add_argument("--out", default="out", help="directory for the exported URDF")


def _cmd_demo(args: argparse.Namespace) -> int:
    from pathlib import Path

    import numpy as np

    from .. import robots
    from ..kinematics import load
    from ..urdf import write_urdf

    leg = robots.hexabot_leg()
    out = Path(args.out)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        msg = f"--out {args.out!r}: cannot create the directory ({exc.strerror})"
        raise refused("--out", args.out, "a writable directory", msg) from None
    output_path(out / "hexabot_leg.urdf", "--out", (".urdf",))
    path = write_urdf(leg, out / "hexabot_leg.urdf", header="made by: hexapod-kin demo")
    print(f"wrote {path}")
    model = load(path)
    q_deg = (20.0, 30.0, 45.0)
    q = np.radians(q_deg)
    print(f"q = ({', '.join(f'{v:g}' for v in q_deg)}) deg  (hip, knee, ankle)")
    print(f"T foot in base:\n{matrix_text(model.fk(q))}")
    print(f"J (local_world_aligned):\n{matrix_text(model.jacobian(q))}")
    print(f"det(J_position) = {np.linalg.det(model.position_jacobian(q)):.6e}")
    return 0


def _add_derive(sub: Any) -> None:
    p = sub.add_parser(
        "derive", help="symbolic T, p, J (direct/indirect), det J factored, singular families"
    )
    robot_args(p, frames=True, tool=True)
    p.add_argument("--rows", nargs="+", help="rows of J for det (x y z wx wy wz; default auto)")
    p.add_argument("--latex", action="store_true", help="print LaTeX instead of text")
    from ..symbolic import DEFAULT_BUDGET  # a constant: no sympy

    p.add_argument(
        "--budget",
        type=float,
        help=f"CPU time budget [s] (default: derive()'s, {DEFAULT_BUDGET:g} s): what is not "
        "done by then is reported, never waited on",
    )
    p.add_argument("--json", action="store_true", help="one JSON object on stdout")


#: CPU seconds of ``--budget`` kept for what follows the derivation (formulas as text, check):
#: the text until half of it is left, the check until :data:`_WRITE` is left.
_AFTER = 0.6

#: CPU seconds before the end of ``--budget`` by which the output is ready.
_WRITE = 0.05

#: CPU seconds the child may spend past ``--budget`` on linear work (the unfinished
#: derivation's plain products): its own limit, never reached by the work it bounds.
_SLACK = 1.0

_CHECK_LABELS = {
    "max_abs_J_sym_minus_J_pinocchio": "max |J_sym - J_pin|",
    "max_abs_det_sym_minus_det_pinocchio": "max |det_sym - det_pin|",
}


def _phase(end: float, make: Callable[[], Iterator[Any]]) -> tuple[list[Any], bool]:
    """The items of ``make()`` until ``end`` (:func:`time.process_time`); whether all came."""
    import time

    from .._budget import BudgetReached, cpu_limit

    out: list[Any] = []
    try:
        with cpu_limit(end - time.process_time()):
            out.extend(make())
    except BudgetReached:
        return out, False
    return out, True


def _derive_job(
    rows: Any, fmt: str, budget: float, jac_pin: Any, qs: Any, pinned: tuple[Any, str, str]
) -> Iterator[tuple[str, Any]]:  # pragma: no cover - runs in the child process
    """``derive``'s work within ``budget`` CPU seconds, in one child process (no Pinocchio).

    Yields the derivation (until :data:`_AFTER` is left), the formulas as ``fmt`` (until half
    of it) and what was cut, the check against the parent's ``jac_pin`` at ``qs`` and why
    it is incomplete.
    """
    import dataclasses
    import json
    import pickle
    import time

    import numpy as np

    from ..jacobian_rows import ROW_NAMES
    from ..symbolic import derive
    from ..symbolic.checks import evaluate, evaluate_matrix

    end = time.process_time() + budget
    chain, reference, tip = pinned
    deriv = derive(chain, rows=rows, budget=budget, within=budget - _AFTER)
    # as a budgeted derive() returns it: through pickle (sympy rebuilds -(a + b) as -a - b)
    deriv = pickle.loads(pickle.dumps(dataclasses.replace(deriv, reference=reference, tip=tip)))
    # what the parent needs of it, without sympy objects (the parent imports no sympy)
    yield "derivation", (deriv.incomplete, deriv.chain.description, deriv.reference)
    ran_out = "the budget ran out"
    if fmt == "json":
        made, whole = _phase(end - _AFTER / 2, lambda: iter([json.dumps(deriv.to_dict())]))
        if not whole:
            short = dataclasses.replace(deriv, det=None, gram=None).to_dict()
            short["incomplete"].append(f"det and gram as text ({ran_out})")
            made = [json.dumps(short)]
    elif fmt == "latex":
        made, whole = _phase(end - _AFTER / 2, lambda: iter([deriv.latex()]))
        if not whole:
            made = [f"% {deriv.chain.name}\n% NOT DONE: the LaTeX of the formulas ({ran_out})"]
    else:
        made, whole = _phase(end - _AFTER / 2, deriv.text_parts)
        if not whole:  # what the derivation did not reach is said in any case
            made.append(f"NOT DONE: printing the formulas after the {len(made)} first ({ran_out})")
            made.extend(f"NOT DONE: {what}" for what in deriv.incomplete)
    yield "text", ("\n".join(made), "" if whole else ran_out)

    def check() -> Iterator[tuple[str, float]]:
        at = {**deriv.lengths, **{sym: qs[:, k] for k, sym in enumerate(deriv.q)}}
        jac = jac_pin[:, [ROW_NAMES.index(r) for r in deriv.rows]]
        jac_sym = evaluate_matrix(deriv.J_rows, at, len(qs))
        yield "max_abs_J_sym_minus_J_pinocchio", float(np.abs(jac_sym - jac).max())
        if deriv.det is not None and jac.shape[1] == jac.shape[2]:
            det_sym = np.broadcast_to(evaluate(deriv.det, at), (len(qs),))
            yield (
                "max_abs_det_sym_minus_det_pinocchio",
                float(np.abs(det_sym - np.linalg.det(jac)).max()),
            )

    if end - _WRITE - time.process_time() <= 0.05:
        yield "check", ({}, "no time left in the budget")
        return
    got, whole = _phase(end - _WRITE, check)
    yield "check", (dict(got), "" if whole else ran_out)


def _cmd_derive(args: argparse.Namespace) -> int:
    import dataclasses
    import json
    import math

    if args.budget is not None and not (math.isfinite(args.budget) and args.budget > 0):
        msg = f"--budget {args.budget!r} is not allowed; a time in seconds > 0"
        raise ParameterError(msg, parameter="--budget", value=args.budget, allowed="> 0 s")
    from .._budget import prestart, run

    prestart(("hexapod_kin.cli.core", *_SYMPY))  # sympy there, Pinocchio here
    import numpy as np

    from ..symbolic import DEFAULT_BUDGET  # no sympy in this process unless the child fails
    from ..symbolic.sources import chain_of

    budget = DEFAULT_BUDGET if args.budget is None else float(args.budget)
    model = load_source(args)
    chain, reference, tip = chain_of(model, None, None)
    qs = model.random_q(100, seed=0)
    jac_pin = np.array([model.jacobian(q) for q in qs])  # Pinocchio here, sympy in the child
    fmt = "json" if args.json else "latex" if args.latex else "text"
    job = (args.rows, fmt, budget, jac_pin, qs, (chain, reference, tip))
    done, reason = run(_derive_job, job, budget + _SLACK)
    if "derivation" not in done:
        if reason is None or not reason.startswith("budget of"):
            raise RuntimeError(f"derive: the derivation process failed: {reason}")
        # the budget ran out before anything came back: the plain products, nothing printed
        from ..symbolic import derive

        deriv = derive(chain, rows=args.rows, budget=budget, within=0.0, cache=False)
        deriv = dataclasses.replace(deriv, reference=reference, tip=tip)
        summary = (deriv.incomplete, deriv.chain.description, deriv.reference)
        lines = [f"NOT DONE: {what}" for what in deriv.incomplete]
        done["text"] = (
            json.dumps(deriv.to_dict())
            if fmt == "json"
            else "\n".join(("% " if fmt == "latex" else "") + line for line in lines),
            "the budget ran out",
        )
    else:
        summary = done["derivation"]
    incomplete, description, reference = summary
    text, cut = done.get("text", ("", "the budget ran out"))
    check, why = done.get("check", ({}, "the budget ran out"))
    recovered = description.startswith("Khalil table recovered")
    status = 1 if incomplete or why or cut else 0  # answered, not all of it
    if args.json:
        out = {**json.loads(text), "check_vs_pinocchio_100_random_q": check}
        if why:
            out["check_incomplete"] = why
        if recovered:
            out["table_from_urdf"] = description
        emit_json(out)
        return status
    print(text)
    if args.latex:
        return status
    if recovered:  # the URDF's table: what was snapped, one line
        print(f"table: {description}")
    if check:
        print(
            f"check vs Pinocchio at 100 random q (reference {reference}): "
            + ", ".join(f"{_CHECK_LABELS[k]} = {v:.2e}" for k, v in check.items())
        )
    if why:
        print(f"NOT DONE: check vs Pinocchio at 100 random q ({why})")
    return status


#: ``--families`` choice -> ``scan(families=...)``.
_FAMILIES: dict[str, bool | str] = {"derive": True, "cached": "cached", "off": False}


def _add_scan(sub: Any) -> None:
    p = sub.add_parser("scan", help="singularity measures over a joint grid; singular families")
    robot_args(p, frames=True, tool=True)
    p.add_argument("--grid", type=int, help="points per scanned joint (default: scan()'s, 61)")
    p.add_argument("--samples", type=int, help="random configurations instead of a grid")
    p.add_argument(
        "--joints",
        nargs="+",
        help="joints to scan, or 'all' (default: the two that change sigma_min most)",
    )
    p.add_argument("--rows", nargs="+", help="rows of J (x y z wx wy wz; default auto)")
    q_args(p, "values of the joints not scanned")
    p.add_argument("--threshold", type=float, help="sigma_min threshold (default 1%% of reach)")
    p.add_argument("--seed", type=seed, help="seed of --samples (default: scan()'s, 0)")
    p.add_argument(
        "--families",
        choices=list(_FAMILIES),
        help="singular families: derive them within --family-budget (cached on disk after the "
        "first time; scan()'s default), only use cached ones, or none",
    )
    p.add_argument("--family-budget", type=float, help="time budget [s] for deriving the families")
    p.add_argument("--json", action="store_true", help="one JSON object on stdout")
    p.add_argument(
        "--plot", metavar="FILE.png", help="heat map (2 scanned joints, grid): .png .jpg .svg .pdf"
    )


#: What a derivation's child imports besides its job's module.
_SYMPY = ("hexapod_kin.symbolic.derivation", "hexapod_kin.symbolic.checks", "sympy.tensor.tensor")


def _cmd_scan(args: argparse.Namespace) -> int:
    check_outputs(args)
    from .._budget import prestart
    from .._cache import folder

    fresh = args.families in (None, "derive") and "sympy" not in sys.modules
    if fresh and not any(folder("families").glob("*.json")):  # no family derived yet
        prestart(("hexapod_kin.singularity.families", *_SYMPY))  # the derivation's child
    import numpy as np

    from ..singularity import scan

    model = load_source(args)
    joints: Any = args.joints
    if joints == ["all"]:
        joints = "all"
    elif joints:
        joints = [int(j) if str(j).isdigit() else j for j in joints]
    given = {  # only what was given: every default is scan()'s own
        **pick(args, "grid", "samples", "rows", "threshold", "seed", "family_budget"),
        "joints": joints,
        "q_fixed": q_from_args(args, model) if args.q is not None else None,
        "families": None if args.families is None else _FAMILIES[args.families],
        "progress": False if args.json else None,
    }
    result = scan(model, **{k: v for k, v in given.items() if v is not None})
    reason = result.family_reason
    if args.plot:
        from ..plots import plot_singularity_map

        path = plot_singularity_map(result, args.plot)
        print(f"wrote {path}", file=sys.stderr)
    # families asked for (the default) but not all derived in --family-budget: answered, not all
    status = int(
        args.families in (None, "derive")
        and ("derivation incomplete" in reason or reason.startswith("derivation failed"))
    )
    if args.json:
        emit_json(result.to_dict())
        return status
    n = result.q.shape[0]
    how = f"grid {result.grid_shape}" if result.grid_shape else "random samples"
    over = ", ".join(result.joint_names[j] for j in result.joints)
    print(f"{result.source}: {n} configurations over {over} ({how})")
    print(f"rows of J: {', '.join(result.rows)}; singular when sigma_min < {result.threshold:.3g}")
    print(f"singular: {int(result.singular.sum())}  unexplained: {int(result.unexplained.sum())}")
    for name, count in result.family_counts.items():
        print(f"  family {name}: {count}")
    if reason:
        print(f"  {'NOT DONE' if result.families else 'no families'}: {reason}")
    finite = np.isfinite(result.condition)
    print(
        f"manipulability: min {result.manipulability.min():.4g}  max "
        f"{result.manipulability.max():.4g}; condition (finite) max "
        f"{result.condition[finite].max() if finite.any() else float('nan'):.4g}"
    )
    return status


Command = tuple[Callable[[Any], None], Callable[[argparse.Namespace], int]]

#: Subcommands in help order: (declare arguments, run).
COMMANDS: dict[str, Command] = {
    "list": (_add_list, _cmd_list),
    "urdf": (_add_urdf, _cmd_urdf),
    "fk": (_add_fk, _cmd_fk),
    "jacobian": (_add_jacobian, _cmd_jacobian),
    "demo": (_add_demo, _cmd_demo),
    "derive": (_add_derive, _cmd_derive),
    "scan": (_add_scan, _cmd_scan),
}


def register(sub: Any) -> None:
    """Add the core subcommands to ``sub`` (an argparse subparsers object)."""
    for name, (add, run) in COMMANDS.items():
        add(sub)
        sub.choices[name].set_defaults(func=run)
