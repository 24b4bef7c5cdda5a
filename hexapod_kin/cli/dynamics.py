"""Dynamics subcommands: ``pendulum`` (seed 001 §1), ``torques`` (a leg), ``stand`` (the hexapod).

Heavy imports stay inside the runners. ``--json`` prints one JSON object on stdout.
"""

from __future__ import annotations

import argparse
import math
from typing import Any

from ..exceptions import ParameterError
from .common import (
    check_outputs,
    emit_json,
    html_page,
    knee_arg,
    load_source,
    not_achieved,
    numbers,
    pick,
    q_args,
    q_from_args,
    robot_args,
    robot_of,
)

__all__ = ["register"]


def _add_pendulum(sub: Any) -> None:
    p = sub.add_parser(
        "pendulum",
        help="the seed pendulum (ABA), undamped and damped, against the exact period and decay",
    )
    p.add_argument(
        "--theta0-deg",
        type=float,
        default=30.0,
        help="initial angle from the hanging equilibrium [deg], released at rest",
    )
    p.add_argument(
        "--damping",
        type=float,
        default=0.01,
        help="joint damping of the damped run [N m s/rad] (written into the URDF)",
    )
    p.add_argument("--dt", type=float, default=1e-3, help="integration step [s]")
    p.add_argument("--duration", type=float, default=20.0, help="simulated time [s]")
    p.add_argument(
        "--method", choices=("rk4", "symplectic_euler"), default="rk4", help="integrator"
    )
    p.add_argument(
        "--decay-theta0-deg",
        type=float,
        default=1.0,
        help="initial angle of the small-amplitude decay-rate run [deg]",
    )
    p.add_argument("--length", type=float, default=0.5, help="pendulum length [m]")
    p.add_argument("--mass", type=float, default=1.0, help="bob mass [kg]")
    p.add_argument("--json", action="store_true", help="one JSON object on stdout")
    p.add_argument("--plot", metavar="F", help="angle and angular velocity vs time (PNG)")
    p.add_argument("--html", metavar="F", help="the damped pendulum animated (offline HTML)")
    p.set_defaults(func=_cmd_pendulum)


def _cmd_pendulum(args: argparse.Namespace) -> int:
    check_outputs(args)
    for name in ("theta0_deg", "decay_theta0_deg"):
        value = getattr(args, name)
        if not (math.isfinite(value) and 0 < value < 180):
            opt = "--" + name.replace("_", "-")
            msg = (
                f"{opt}={value!r} is not allowed; an angle in (0, 180) degrees from the hanging "
                "equilibrium is needed"
            )
            raise ParameterError(msg, parameter=opt, value=value, allowed="(0, 180) deg")
    from ..dynamics import pendulum_experiment

    kw = pick(args, "dt", "duration", "method", "length", "mass")
    decay = math.radians(args.decay_theta0_deg)
    exp = pendulum_experiment(math.radians(args.theta0_deg), args.damping, decay_theta0=decay, **kw)
    written = []
    if args.plot:
        from ..report.figures import plot_pendulum

        written.append(str(plot_pendulum(exp, args.plot)))
    if args.html:
        written.append(_pendulum_html(exp, args))
    out = exp.to_dict()
    if args.json:
        emit_json({**out, "written": written})
        return 0
    p = out["pendulum"]
    print(
        f"pendulum: I = {p['inertia']:.9g} kg m^2 about the pivot, m = {p['mass']:g} kg, "
        f"l_c = {p['com_distance']:.9g} m; theta0 = {args.theta0_deg:g} deg; "
        f"{out['method']}, dt = {out['dt']:g} s, {out['duration']:g} s"
    )

    def num(x: Any, fmt: str, missing: str, unit: str = "") -> str:
        return missing if x is None else format(x, fmt) + unit

    short = "not measured (fewer than 2 periods)"
    print(
        f"undamped: period = {num(out['period'], '.12g', short, ' s')}; exact "
        f"4 sqrt(I/(m g l_c)) K(sin(theta0/2)) = {out['period_exact']:.12g} s; relative "
        f"error {num(out['period_error'], '.3e', '-')}"
    )
    print(f"undamped: energy drift max|E - E0|/E0 = {out['energy_drift']:.3e}")
    print(
        f"damped (b = {out['damping']:g}): energy monotone {out['damped_energy_monotone']} "
        f"(largest step increase {out['damped_energy_max_increase']:.3e} E0), lost "
        f"{100 * out['damped_energy_loss']:.2f}% in {out['duration']:g} s"
    )
    print(
        f"decay rate at {args.decay_theta0_deg:g} deg: "
        f"{num(out['decay_rate'], '.9g', 'not measured (fewer than 3 maxima)', ' 1/s')}; "
        f"b/(2I) = "
        f"{out['decay_rate_exact']:.9g} 1/s; relative error "
        f"{num(out['decay_rate_error'], '.3e', '-')}"
    )
    for path in written:
        print(f"wrote {path}")
    return 0


def _pendulum_html(exp: Any, args: argparse.Namespace) -> str:
    from ..kinematics import load

    run = exp.damped
    model = load("pendulum", damping=run.damping, length=args.length, mass=args.mass)
    title = (
        f"pendulum: theta0 = {math.degrees(run.theta0):g} deg, damping {run.damping:g} "
        "N m s/rad (Pinocchio ABA)"
    )
    return html_page(model, run.simulation.t, run.simulation.q, args.html, title, 1 / 30)


def _add_torques(sub: Any) -> None:
    p = sub.add_parser(
        "torques",
        help="joint torques of a leg under gravity and a foot force (J^T F, RNEA cross-check)",
    )
    robot_args(p, frames=True, inertia=True)
    q_args(p)
    numbers(
        p,
        "--force",
        "FX FY FZ",
        default=[0.0, 0.0, 0.0],
        help="force of the foot on its environment [N], base axes",
    )
    p.add_argument("--frame", help="frame where the force acts (default: the tip)")
    p.add_argument(
        "--step",
        action="store_true",
        help="along the seeds' resolved-rate step from --q (3-joint legs): peaks",
    )
    p.add_argument("--dt", type=float, default=1e-3, help="--step: step [s]")
    p.add_argument("--duration", type=float, default=10.0, help="--step: duration [s]")
    p.add_argument("--json", action="store_true", help="one JSON object on stdout")
    p.set_defaults(func=_cmd_torques)


def _cmd_torques(args: argparse.Namespace) -> int:
    from ..dynamics import leg_torques

    model = load_source(args)
    if args.step:
        from ..seeds import step_torques

        q0 = None if args.q is None else q_from_args(args, model)
        res = step_torques(model, args.force, q0=q0, **pick(args, "frame", "dt", "duration"))
        out = {"source": model.name, **res.to_dict()}
        if args.json:
            emit_json(out)
            return 0
        print(
            f"{model.name}: resolved-rate step, {out['duration']:g} s, {out['samples']} "
            f"samples, foot force {res.force.tolist()} N"
        )
        for i, name in enumerate(res.joint_names):
            print(
                f"  {name:<12} peak {res.peak[i]: .6f} N m   gravity peak "
                f"{res.peak_gravity[i]: .6f} N m"
            )
        print(f"J^T F vs RNEA with fext: max error {res.crosscheck_error:.3e} N m")
        return 0
    q = q_from_args(args, model)
    r = leg_torques(model, q, args.force, frame=args.frame)
    if args.json:
        emit_json({"source": model.name, **r.to_dict()})
        return 0
    print(f"{model.name}: force {r.force.tolist()} N at {r.frame!r} (base axes)")
    print(f"  {'joint':<12} {'gravity':>12} {'J^T F':>12} {'total':>12}   [N m]")
    for i, name in enumerate(r.joint_names):
        print(f"  {name:<12} {r.gravity[i]:12.6f} {r.force_torque[i]:12.6f} {r.total[i]:12.6f}")
    print(
        f"J^T F vs RNEA with fext: {r.crosscheck_error:.3e} N m; g(q) vs rnea(q,0,0): "
        f"{r.gravity_crosscheck_error:.3e} N m"
    )
    return 0


def _add_stand(sub: Any) -> None:
    p = sub.add_parser(
        "stand",
        help="a legged robot standing: contact forces holding its weight, joint torques",
        description=(
            "Stand a legged robot level on flat ground and print the contact forces that hold "
            "its weight and the joint torques (legs found from the kinematic tree). Exit "
            "status 1 when the forces are not feasible (a foot pulls, or slides beyond --mu)."
        ),
    )
    robot_args(p, kinds="legged", default="hexapod", inertia=True)
    p.add_argument(
        "--height",
        "--body-height",
        dest="height",
        type=float,
        help="body above the ground [m] (default: a Hexapod 0.10; other robots their own)",
    )
    p.add_argument(
        "--reach", type=float, help="mount to foot, horizontal [m] (default: l1 + l2 / own)"
    )
    numbers(p, "--shift", "DX DY", default=[0.0, 0.0], help="body shifted over the feet [m]")
    knee_arg(p)
    p.add_argument("--legs", nargs="+", help="stance legs (names or 1-based numbers); all")
    p.add_argument(
        "--method",
        choices=("min_norm", "friction"),
        default="min_norm",
        help="contact-force distribution",
    )
    p.add_argument("--mu", type=float, help="friction coefficient (needed by --method friction)")
    p.add_argument(
        "--gait",
        metavar="PATTERN",
        help="also walk with this gait (tripod, wave, ripple, crawl...): peak torque per joint",
    )
    p.add_argument("--gait-duration", type=float, default=4.0, help="--gait: walk length [s]")
    p.add_argument("--json", action="store_true", help="one JSON object on stdout")
    p.set_defaults(func=_cmd_stand)


def _cmd_stand(args: argparse.Namespace) -> int:
    from ..dynamics import stand
    from ..dynamics.standing import hexapod_model

    robot = robot_of(args)
    model = robot.load()
    hexa = hexapod_model(model)
    legs = None if args.legs is None else [int(v) if v.isdigit() else v for v in args.legs]
    given = pick(args, "height", "reach", "shift", "method", "mu", "knee")
    st = stand(model, legs=legs, feet=robot.feet, foot_radius=robot.foot_radius, **given)
    name = hexa.name if hexa is not None else robot.source
    out = {"source": name, **st.to_dict()}
    gt = None
    if args.gait:
        from ..dynamics import gait_torques
        from ..gait import as_whole_body, walk

        kw: dict[str, Any] = {"body_height": st.height}
        if args.reach is not None:
            kw["foot_reach"] = args.reach
        own = {} if hexa is not None else {"feet": robot.feet, "foot_radius": robot.foot_radius}
        wb = as_whole_body(hexa.params if hexa is not None else model, **own)
        run = walk(wb, pattern=args.gait, duration=args.gait_duration, knee=args.knee, **kw)
        gt = gait_torques(run, hexa, method=args.method, mu=args.mu)
        out["gait"] = {"walk": run.to_dict(), **gt.to_dict()}
    why = [] if st.feasible else ["standing: a foot pulls or slides (feasible False)"]
    if gt is not None and not gt.feasible:
        why.append(f"walking ({args.gait}): a foot pulls or slides (feasible False)")
    status = not_achieved(why)
    if args.json:
        emit_json(out)
        return status
    print(
        f"{name}: mass {st.mass:.6g} kg, weight {st.weight:.6g} N, CoM "
        f"{[round(v, 6) for v in st.com.tolist()]} m, body at {st.height:g} m"
    )
    print(
        f"contact forces ({st.method}{'' if st.mu is None else f', mu = {st.mu:g}'}), "
        "ground on foot [N]:"
    )
    for name, p_i, f in zip(st.stance_legs, st.feet, st.forces):
        print(f"  {name:<6} foot {p_i.round(4).tolist()}  f = {f.round(6).tolist()}")
    print(
        f"sum of forces - weight: {st.force_residual:.3e} N; moment about the CoM: "
        f"{st.moment_residual:.3e} N m; feasible {st.feasible}"
    )
    print("joint torques g(q) - sum J^T f [N m]:")
    for i, name in enumerate(st.joint_names):
        print(f"  {name:<12} {st.torque[i]: .6f}   (legs in the air: {st.gravity_torque[i]: .6f})")
    if gt is not None:
        print(
            f"walking ({args.gait}, {gt.t[-1] - gt.t[0]:g} s, {len(gt.t)} samples, quasi-static):"
            f" sum of forces - weight <= {gt.force_residual:.3e} N, moments <= "
            f"{gt.moment_residual:.3e} N m, feasible {gt.feasible}"
        )
        print("peak torque per joint [N m] (at t [s]):")
        for i, name in enumerate(gt.joint_names):
            print(f"  {name:<12} {gt.peak[i]: .6f}  ({gt.peak_time[i]:g})")
    return status


def register(sub: Any) -> None:
    """Add ``pendulum``, ``torques`` and ``stand`` to the subcommands ``sub``."""
    _add_pendulum(sub)
    _add_torques(sub)
    _add_stand(sub)
