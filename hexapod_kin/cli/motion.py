"""Subcommands ``ik`` (position, position + yaw, or 6-D pose targets) and ``step`` (resolved rate).

``--deg`` converts angles (revolute joints, rpy, yaw, angular velocities) from degrees; prismatic
joints stay in metres.
"""

from __future__ import annotations

import argparse
import math
import sys
from typing import Any, Literal

from .common import (
    check_outputs,
    emit_json,
    html_page,
    load_source,
    not_achieved,
    numbers,
    pick,
    q_args,
    q_from_args,
    refused,
    robot_args,
)

__all__ = ["register"]


def _angle(args: argparse.Namespace, v: float) -> float:
    return math.radians(v) if args.deg else v


def _add_ik(sub: Any) -> None:
    p = sub.add_parser(
        "ik", help="inverse kinematics: position, position + yaw or 6-D pose (closed form + DLS)"
    )
    robot_args(p, frames=True, tool=True)
    g = p.add_mutually_exclusive_group(required=True)
    numbers(g, "--target", "X Y Z", help="tip position in the base frame [m]")
    numbers(
        g,
        "--pose",
        "X Y Z ROLL PITCH YAW",
        help="tip pose: xyz [m] and URDF rpy [rad] (deg with --deg)",
    )
    p.add_argument(
        "--yaw",
        type=float,
        help="with --target: yaw of the tool's x axis in the base xy-plane [rad]",
    )
    w = p.add_mutually_exclusive_group()
    numbers(
        w, "--mask", "X Y Z WX WY WZ", kind=int, help="rows of the task to keep (1) or drop (0)"
    )
    numbers(w, "--weights", "X Y Z WX WY WZ", help="weight of each task row")
    p.add_argument(
        "--q0",
        nargs="+",
        type=float,
        help="start of the numerical solver (rad, m; revolute in deg with --deg)",
    )
    p.add_argument(
        "--deg",
        action="store_true",
        help="angles in degrees (rpy, yaw, revolute --q0); prismatic stay in m",
    )
    p.add_argument("--tol", type=float, default=1e-10, help="position tolerance [m]")
    p.add_argument("--rot-tol", type=float, default=1e-10, help="orientation tolerance [rad]")
    p.add_argument("--restarts", type=int, default=16, help="extra seeded starts")
    p.add_argument(
        "--numerical",
        action="store_true",
        help="run the numerical (DLS) solver too when the closed form answers (it always runs "
        "without a closed form, for an unreachable target, with --q0/--mask/--weights or --json)",
    )
    p.add_argument("--json", action="store_true", help="one JSON object on stdout")
    p.set_defaults(func=_cmd_ik)


def _target(args: argparse.Namespace) -> Any:
    import numpy as np

    if args.pose is not None:
        if args.yaw is not None:
            msg = "--yaw goes with --target, not --pose (the pose has its own rpy)"
            raise refused("--yaw", args.yaw, "only with --target", msg)
        from .._pose import Pose

        return Pose.of([*args.pose[:3], *(_angle(args, v) for v in args.pose[3:])], "--pose").matrix
    t = np.array(args.target, dtype=float)
    return t if args.yaw is None else np.append(t, _angle(args, args.yaw))


def _cmd_ik(args: argparse.Namespace) -> int:
    import numpy as np

    from .. import ik
    from ..exceptions import IKError

    model = load_source(args)
    target = _target(args)
    xyz = target[:3, 3] if target.shape == (4, 4) else target[:3]
    ik.check_within(model, xyz)  # the API's own check: a typo refused at once
    closed: list[list[float]] | None = None
    inside = 0  # closed-form solutions within the joint limits
    family = None
    if target.shape != (4, 4) and args.tool is None:
        try:
            family = ik.detect_family(model).family
        except IKError:
            family = None
    if family is not None and (target.size == 3 or family == "scara"):
        closed = ik.analytic(model, target)[0].tolist()
        inside = len(ik.analytic(model, target, within_limits=True)[0]) if closed else 0
    q0 = None if args.q0 is None else q_from_args(args, model, "q0")
    # The closed form answers first; the numerical solver runs only when needed or asked for.
    asked = any(v is not None for v in (q0, args.mask, args.weights))
    numerical = not inside or args.numerical or args.json or asked
    res = None
    if numerical:
        res = ik.solve(
            model, target, q0, **pick(args, "mask", "weights", "tol", "rot_tol", "restarts")
        )
    # the exit rule (cli docs): 0 the target is reached within the limits; 1 answered but not
    # achieved (unreachable: the nearest point is printed; or only beyond the joint limits)
    status = 0 if inside or (res is not None and res.status == "converged") else 1
    if args.json:
        emit_json(
            {
                "source": model.name,
                "tip": model.tip,
                "joint_names": list(model.joint_names),
                "target": target.tolist(),
                "family": family,
                "analytic": closed,
                "numerical": None if res is None else res.to_dict(),
            }
        )
        return status
    what = "pose" if target.shape == (4, 4) else "target"
    print(
        f"{model.name} (tip {model.tip}): {what} {np.round(target, 9).tolist()}, joints "
        f"{', '.join(model.joint_names)}"
    )
    if closed is not None:
        print(
            f"closed form ({family}): {len(closed)} solution(s), {inside} within the joint limits"
        )
        for sol in closed:
            print("  " + " ".join(f"{v: .9f}" for v in sol))
    elif target.shape != (4, 4):
        print("closed form: none for this chain")
    if res is None:
        print("numerical: not run (the closed form answered; --numerical runs it too)")
        return status
    print(f"numerical: {res.status} ({res.reason})")
    print("  q = " + " ".join(f"{v: .9f}" for v in res.q))
    print(
        f"  error = {res.error:.3e} m, {res.rotation_error:.3e} rad after {res.iterations} "
        f"steps, {res.attempts} start(s)"
    )
    if res.status in ("unreachable", "joint_limits"):
        print(
            f"  nearest reachable point {np.round(res.nearest, 9).tolist()} m, "
            f"distance {res.distance:.6g} m"
        )
    return status


def _add_step(sub: Any) -> None:
    p = sub.add_parser(
        "step",
        help="resolved rate: the seeds' experiment (v = [A sin(2πt/T), 0, 0]) or a constant "
        "velocity / 6-D twist",
    )
    robot_args(p, frames=True, tool=True)
    q_args(p)
    g = p.add_mutually_exclusive_group()
    numbers(g, "--velocity", "VX VY VZ", help="constant linear tip velocity [m/s] (base axes)")
    numbers(
        g,
        "--twist",
        "VX VY VZ WX WY WZ",
        help="constant twist [m/s, rad/s] (deg/s with --deg) in --frame",
    )
    p.add_argument(
        "--frame",
        choices=["base", "tip"],
        default="base",
        help="axes of --twist: base, or tip (body twist)",
    )
    p.add_argument("--amplitude", type=float, default=0.05, help="A [m/s] (seed experiment)")
    p.add_argument("--period", type=float, default=2.0, help="T [s] (seed experiment)")
    p.add_argument("--dt", type=float, default=1e-3, help="step [s]")
    p.add_argument("--duration", type=float, default=10.0, help="[s]")
    p.add_argument("--method", choices=["rk4", "euler"], default="rk4")
    p.add_argument("--gain", type=float, default=10.0, help="closed-loop gain [1/s] (0: open)")
    p.add_argument(
        "--no-baseline",
        action="store_true",
        help="skip the plain Euler + np.linalg.solve comparison",
    )
    p.add_argument("--json", action="store_true", help="one JSON object on stdout")
    p.add_argument(
        "--plot",
        metavar="FILE.png",
        help="the seeds' figures; with --velocity/--twist: joint values and rates, σ_min and "
        "the tip's drift from the exact motion",
    )
    p.add_argument("--html", metavar="FILE.html", help="write an animated 3-D page (HTML)")
    p.set_defaults(func=_cmd_step)


def _cmd_step(args: argparse.Namespace) -> int:
    check_outputs(args)
    model = load_source(args)
    q0 = None if args.q is None else q_from_args(args, model)
    if args.velocity is not None or args.twist is not None:
        return _constant(args, model, q0)
    from .. import seeds

    kw = pick(args, "amplitude", "period", "dt", "duration", "method", "gain")
    run = seeds.seed_experiment(model, q0=q0, baseline=not args.no_baseline, **kw)
    tr = run.trajectory
    written = []
    if args.plot:
        from ..plots import plot_motion

        written.append(str(plot_motion(run, args.plot)))
    if args.html:
        title = f"{model.name}: resolved-rate step (A={run.amplitude} m/s, T={run.period} s)"
        written.append(html_page(model, tr.t, tr.q, args.html, title, 0.02))
    status = _limited(tr)
    if args.json:
        emit_json({"source": model.name, **run.to_dict(), "written": written})
        return status
    print(
        f"{model.name}: v = [{run.amplitude} sin(2πt/{run.period}), 0, 0] m/s for "
        f"{tr.t[-1]:g} s, dt = {tr.dt:g} s, {tr.method}, gain {tr.gain:g} 1/s"
    )
    print("q0 = " + " ".join(f"{v:.6f}" for v in tr.q[0]))
    print(
        f"drift_y = {run.drift_y:.3e} m   drift_z = {run.drift_z:.3e} m   "
        f"error_x = {run.error_x:.3e} m"
    )
    if run.baseline_failure:
        print(f"plain Euler + np.linalg.solve: {run.baseline_failure}")
    if run.baseline:
        b = run.baseline
        print(
            f"plain Euler + np.linalg.solve: drift_y = {b['drift_y']:.3e} m   "
            f"drift_z = {b['drift_z']:.3e} m   error_x = {b['error_x']:.3e} m"
        )
    return _tail(tr, written, status)


def _tail(tr: Any, written: list[str], status: int) -> int:
    """The closest approach to a singularity, the files written; ``status``."""
    ca = tr.closest_approach
    print(
        f"closest approach to a singularity: σ_min = {ca.sigma_min:.4g} at t = "
        f"{ca.t:.3f} s (condition {ca.condition:.4g})"
    )
    for path in written:
        print(f"wrote {path}", file=sys.stderr)
    return status


def _limited(tr: Any) -> int:
    """Exit status of a motion: 1 (answered, not achieved) when limits cut it."""
    first = float(tr.t[tr.limited.argmax()]) if tr.limited.any() else None
    return not_achieved(
        [] if first is None else [f"joint or speed limits cut the motion at t={first:g} s"]
    )


def plot_constant(tr: Any, drift: Any, rot_drift: Any, path: str, title: str, model: Any) -> str:
    """Draw a constant velocity/twist run (2×2: q, q̇, σ_min, drift) to ``path``; return it.

    ``tr`` is the :class:`~hexapod_kin.motion.Trajectory`, ``drift`` (N,) the tip's distance [m]
    from the exact constant-twist motion, ``rot_drift`` (N,) its rotation [rad] (6-D runs) or
    None; ``model`` gives the joint names.
    """
    import numpy as np

    from ..plots import decimate, pyplot, save_figure

    plt = pyplot()
    fig, axes = plt.subplots(2, 2, figsize=(12, 8), sharex=True)
    names = list(model.joint_names)
    for k in range(tr.q.shape[1]):
        axes[0, 0].plot(*decimate(tr.t, tr.q[:, k]), label=names[k] if k < len(names) else k)
        axes[0, 1].plot(*decimate(tr.t, tr.qdot[:, k]))
    axes[0, 0].set_title("joint values")
    axes[0, 0].set_ylabel("q [rad] (prismatic: m)")
    if tr.q.shape[1] <= 12:
        axes[0, 0].legend(fontsize="small", ncol=2)
    axes[0, 1].set_title("joint rates (the control law)")
    axes[0, 1].set_ylabel("q̇ [rad/s] (prismatic: m/s)")
    ax = axes[1, 0]
    ax.plot(*decimate(tr.t, tr.sigma_min), color="tab:red", label="σ_min")
    ax.set_yscale("log")
    ax.set_title("smallest singular value of the task Jacobian")
    ax.set_ylabel("σ_min (m/rad or 1)")
    ca = tr.closest_approach
    ax.axvline(ca.t, color="0.5", ls=":", label=f"closest approach {ca.sigma_min:.3g}")
    ax.legend(fontsize="small")
    ax = axes[1, 1]
    floor = 1e-18  # a log axis needs positive values: exact samples drawn at the floor
    ax.plot(*decimate(tr.t, np.maximum(drift, floor)), label="position [m]")
    if rot_drift is not None:
        ax.plot(*decimate(tr.t, np.maximum(rot_drift, floor)), label="orientation [rad]")
    ax.set_yscale("log")
    ax.set_title("tip drift from the exact constant-twist motion")
    ax.set_ylabel("drift")
    ax.legend(fontsize="small")
    if tr.limited.any():
        first = float(tr.t[np.argmax(tr.limited)])
        for a in axes.ravel():
            a.axvline(first, color="tab:orange", ls="--", lw=0.8)
        ax.text(first, ax.get_ylim()[1], " limits hit", color="tab:orange", va="top", fontsize=8)
    for a in axes.ravel():
        a.grid(True, alpha=0.3)
    for a in axes[1]:
        a.set_xlabel("time t [s]")
    fig.suptitle(title)
    fig.tight_layout()
    return str(save_figure(fig, path, crop=False))


def _constant(args: argparse.Namespace, model: Any, q0: Any) -> int:
    """A constant linear velocity or twist: run it and compare with the exact motion."""
    import numpy as np

    from .. import motion

    vel = np.array(args.velocity if args.twist is None else args.twist, dtype=float)
    if args.twist is not None and args.deg:
        vel[3:] = np.radians(vel[3:])
    label = f"twist {vel.tolist()} m/s, rad/s in the {args.frame} frame"
    if args.twist is None:
        label = f"velocity {vel.tolist()} m/s (base axes)"
    kw = pick(args, "frame", "method", "gain")
    tr = motion.resolved_rate(model, vel, q0, args.dt, args.duration, **kw)
    twist = vel if vel.size == 6 else np.append(vel, np.zeros(3))
    frame: Literal["base", "tip"] = "tip" if vel.size == 6 and args.frame == "tip" else "base"
    exact = motion.constant_twist_pose(model.fk(tr.q[0]), twist, tr.t, frame)
    reached = tr.poses  # Pinocchio's FK of the joint trajectory, sample by sample
    from .._pose import rotation_angle

    drifts = np.linalg.norm(reached[:, :3, 3] - exact[:, :3, 3], axis=1)
    # ‖log(E Rᵀ)‖ of every sample, at once
    rot_drifts = rotation_angle(exact[:, :3, :3], reached[:, :3, :3]) if vel.size == 6 else None
    drift = float(np.max(drifts))
    rot = 0.0 if rot_drifts is None else float(np.max(rot_drifts))
    written = []
    if args.plot:
        written.append(
            plot_constant(tr, drifts, rot_drifts, args.plot, f"{model.name}: {label}", model)
        )
    if args.html:
        written.append(html_page(model, tr.t, tr.q, args.html, f"{model.name}: {label}", 0.02))
    if args.json:
        emit_json(
            {
                "source": model.name,
                "velocity": vel.tolist(),
                "frame": frame,
                "dt": tr.dt,
                "duration": float(tr.t[-1]),
                "method": tr.method,
                "gain": tr.gain,
                "q0": tr.q[0].tolist(),
                "q_end": tr.q[-1].tolist(),
                "position_drift": drift,
                "rotation_drift": rot,
                "limited": bool(tr.limited.any()),
                "closest_approach": tr.closest_approach.to_dict(),
                "written": written,
            }
        )
        return _limited(tr)
    print(
        f"{model.name} (tip {model.tip}): {label} for {tr.t[-1]:g} s, dt = {tr.dt:g} s, "
        f"{tr.method}, gain {tr.gain:g} 1/s"
    )
    print("q0 = " + " ".join(f"{v:.6f}" for v in tr.q[0]))
    print(
        f"drift from the exact motion: position {drift:.3e} m, orientation {rot:.3e} rad"
        + ("  (joint limits or speed limits were hit)" if tr.limited.any() else "")
    )
    return _tail(tr, written, _limited(tr))


def register(sub: Any) -> None:
    """Add ``ik`` and ``step`` to ``sub`` (an argparse subparsers object)."""
    _add_ik(sub)
    _add_step(sub)
