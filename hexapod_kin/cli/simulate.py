"""The ``simulate`` subcommand: a planned walk replayed open-loop in MuJoCo, checked."""

from __future__ import annotations

import argparse
import math
import sys
from typing import Any

from .common import (
    margin_failures,
    not_achieved,
    refused,
    robot_args,
    robot_of,
    seed,
    walk_args,
    walk_options,
)

__all__ = ["register"]


def register(sub: Any) -> None:
    """Add the ``simulate`` subcommand to ``sub`` (an argparse subparsers object)."""
    p = sub.add_parser(
        "simulate",
        help="plan a walk, replay it in MuJoCo and compare (distance, heading, tilt, slip)",
        description=(
            "Plan a walk (as the gait command does), export the robot to MJCF with the "
            "terrain, foot contact spheres and stiff position servos on every leg joint, "
            "replay the planned joint angles open-loop in MuJoCo and report: distance and "
            "turn vs the plan, heading error, max roll and pitch, body height error, "
            "stance-foot slip, any contact that is not a foot on the ground, and the "
            "standing per-foot contact forces vs dynamics.stand(). With --robust the plan is "
            "judged under an ensemble of settings the robot's data do not fix: replayed with "
            "MuJoCo's default contact and the project's, armature as given and zero, friction "
            "0.6 and 1.0; on three floors with random 3 mm bumps its twist is walked under the "
            "closed-loop controller (a replay cannot react to unknown ground), judged by travel "
            "within 1 % of the plan's distance, heading, no fall, no non-foot contact; each "
            "member listed with its mode (replay, controlled) and the worst printed. "
            "Exit status 0 when every check passes (of every member), 1 when "
            "one fails (the plan's, as gait, or the physics'), 2 on bad input. Needs MuJoCo "
            "(pip install 'hexapod-kin[export]'; --robust and --control also proxsuite: "
            "'hexapod-kin[export,control]')."
        ),
    )
    robot_args(p, kinds="legged", default="hexapod", inertia=True)
    walk_args(p)
    p.add_argument("--friction", type=float, default=1.0, help="sliding friction coefficient")
    p.add_argument(
        "--no-stand", action="store_true", help="skip the standing foot-force comparison"
    )
    p.add_argument(
        "--robust",
        action="store_true",
        help="the verdict over the ensemble of hexapod_kin.robust.ENSEMBLE (8 replays on flat "
        "ground, 3 closed-loop walks over 3 mm bumps: about 15 times the CPU time of one "
        "replay, more for the members without armature)",
    )
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument(
        "--html", metavar="FILE.html", help="plan and simulation side by side (self-contained)"
    )
    p.add_argument("--mjcf", metavar="FILE.xml", help="also write the simulated scene's MJCF")
    p.add_argument(
        "--control",
        action="store_true",
        help="also walk the plan's twist closed-loop (hexapod_kin.control) and compare; "
        "--html writes the two side by side; exit 1 when the closed loop falls (not with "
        "--robust or --mjcf)",
    )
    p.add_argument(
        "--bumps",
        type=float,
        default=0.0,
        help="with --control: random ground bumps of this amplitude [m] (0 to 0.05, flat "
        "terrain) under both the replay and the closed loop",
    )
    p.add_argument("--seed", type=seed, default=0, help="with --control: the bumps' random seed")
    p.add_argument(
        "--push",
        action="append",
        metavar="F@T,D",
        help="with --control: a lateral push on the closed loop of F newtons at T s for D s "
        "(repeatable; negative: rightward)",
    )
    p.add_argument(
        "--payload",
        metavar="KG[@X,Y,Z]",
        help="with --control: a load of KG kilograms fixed to the body at X,Y,Z [m] in the "
        "base frame (default its origin); the controller is not told of it",
    )
    p.set_defaults(func=_cmd_simulate)


def _cmd_simulate(args: argparse.Namespace) -> int:
    from .._io import atomic_write
    from ..simulate import simulate, simulation_html
    from ..simulate.scene import check_friction
    from .common import emit_json, output_path

    check_friction(args.friction)  # before the robot is loaded and the walk planned
    _check_control_options(args)
    html = output_path(args.html, "--html", (".html", ".htm")) if args.html else None
    mjcf = output_path(args.mjcf, "--mjcf", (".xml", ".mjcf")) if args.mjcf else None
    robot = robot_of(args)
    model = robot.load()
    walk = walk_options(args, robot.legged(model) if args.pattern is None else None)
    options = dict(feet=robot.feet, foot_radius=robot.foot_radius, stand=not args.no_stand, **walk)
    if args.control:  # open loop beside closed loop (hexapod_kin.control)
        from .control import simulate_control

        return simulate_control(args, model, options, html)
    ensemble = None
    if args.robust:
        from ..robust import simulate_robust

        ensemble = simulate_robust(model, **options)
        sim = ensemble.worst_replay  # the page, the scene and the full print
    else:
        sim = simulate(model, friction=args.friction, **options)
    out = sim.to_dict()
    if ensemble is not None:
        out["robust"] = ensemble.to_dict()
        out["stand"] = out["stand"] or ensemble.nominal.to_dict()["stand"]
    if mjcf is not None:
        out["mjcf"] = str(atomic_write(mjcf, sim.scene.xml))
    if html is not None:
        out["html"] = str(simulation_html(sim, html))
    if args.json:
        emit_json(out)
    else:
        if ensemble is not None:
            _print_members(out["robust"])
        _print(out)
    why = margin_failures(sim.run)
    if ensemble is not None:
        bad = ensemble.failures
        if bad:
            worst = ensemble.members[ensemble.worst]
            failed = out["robust"]["members"][ensemble.worst]["failed"]
            why.append(
                f"{len(bad)} of {len(ensemble.members)} ensemble members fail the physics "
                f"checks; worst {worst.name!r}: {', '.join(failed)}"
            )
        return not_achieved(why)
    failed = [k for k, row in out["checks"].items() if not row["ok"]]
    return not_achieved(
        why + ([f"the physics check(s) {', '.join(failed)} fail"] if failed else [])
    )


def _check_control_options(args: argparse.Namespace) -> None:
    """Refuse ``--control`` with a second verdict, and its own options without it."""
    if args.control and (args.robust or args.mjcf):
        other = "--robust" if args.robust else "--mjcf"
        msg = f"--control cannot be combined with {other}"
        raise refused("--control", other, "--control alone, or with --html", msg)
    extra = (args.bumps != 0.0, args.seed != 0, bool(args.push), args.payload is not None)
    given = [name for name, on in zip(("--bumps", "--seed", "--push", "--payload"), extra) if on]
    if given and not args.control:
        msg = "needs --control (the open-loop replay alone takes neither bumps nor pushes here)"
        raise refused(given[0], given[0], "with --control", f"{given[0]} {msg}")
    if args.control:
        from ..control import Payload, Push
        from ..simulate.scene import MAX_BUMPS

        if not (math.isfinite(args.bumps) and 0.0 <= args.bumps <= MAX_BUMPS):
            msg = f"--bumps {args.bumps!r}: an amplitude from 0 to {MAX_BUMPS:g} m"
            raise refused("--bumps", args.bumps, f"[0, {MAX_BUMPS:g}]", msg)
        args.push = [Push.parse(text) for text in args.push or []]
        if args.payload is not None:
            args.payload = Payload.parse(args.payload)
        if args.bumps and args.terrain not in (None, "flat"):
            msg = f"--bumps {args.bumps!r} on --terrain {args.terrain}: bumps on flat ground only"
            raise refused("--bumps", args.bumps, "--terrain flat", msg)


def _print_members(rob: dict[str, Any]) -> None:
    print("ensemble (mode, travel along the plan, heading error, failed checks):")
    for k, row in enumerate(rob["members"]):
        mark = "worst " if k == rob["worst"] else "      "
        bad = ", ".join(row["failed"]) or "pass"
        print(
            f"  {mark}{row['name']:<52} {row['mode']:<10} {_pct(row['distance_error']):>10} "
            f"{_deg(row['heading_error']):>7} deg  {bad}"
        )
    worst = rob["members"][rob["worst"]]
    if worst["mode"] == "controlled":
        c, along = worst["control"], worst["distance_along"]
        print(
            f"worst member: {worst['name']}, walked under the controller ({c['kind']}, "
            f"{c['pattern']}): {'-' if along is None else f'{along:.5f}'} m along the plan vs "
            f"{worst['distance_planned']:.5f} m planned ({_pct(worst['distance_error'])}), "
            f"direction {worst['direction']}, heading error "
            f"{_deg(c['heading_error'])} deg, max roll / pitch "
            f"{_deg(c['max_roll'])} / {_deg(c['max_pitch'])} deg, "
            f"fell: {c['fell']}, non-foot contacts {len(c['non_foot_contacts'])}, swing strikes "
            f"{len(c['swing_strikes'])}"
        )
        print("worst replayed member, in full:")
    else:
        print(f"worst member, in full: {worst['name']}")


def _deg(v: float | None) -> str:
    return "-" if v is None else f"{math.degrees(v):.3f}"


def _pct(v: float | None) -> str:
    return "-" if v is None else f"{100 * v:+.3f} %"


def _print(out: dict[str, Any]) -> None:
    plan, sc = out["plan"], out["scene"]
    print(
        f"{plan['pattern']['name']} walk on {sc['terrain']} terrain, {plan['duration']:g} s, "
        f"replayed in MuJoCo (feet {1e3 * sc['foot_radius']:.3g} mm, friction "
        f"{sc['friction']:g}, kp {sc['kp']:g} N·m/rad, armature {sc['armature']:g} kg·m², "
        f"contact time {1e3 * sc['contact_time']:g} ms, timestep {1e3 * sc['timestep']:g} ms"
        + (f", bumps {1e3 * sc['bumps']:g} mm seed {sc['seed']}" if sc["bumps"] else "")
        + ")"
    )
    print(
        f"distance  {out['distance_along']:.5f} m along the plan vs "
        f"{out['distance_planned']:.5f} m planned ({_pct(out['distance_error'])})"
    )
    print(f"direction {out['direction']}")
    print(
        f"turn      {math.degrees(out['turn']):.4f} deg vs "
        f"{math.degrees(out['turn_planned']):.4f} deg planned ({_pct(out['turn_error'])})"
    )
    print(f"heading error      {out['heading_error_deg']:.4f} deg")
    print(f"max roll / pitch   {out['max_roll_deg']:.4f} / {out['max_pitch_deg']:.4f} deg")
    print(f"body height error  {1e3 * out['height_error']:.3f} mm")
    print(
        f"stance slip        {1e3 * out['max_slip']:.3f} mm per stance "
        f"(max {out['max_slip_speed']:.4f} m/s)"
    )
    contacts = out["non_foot_contacts"]
    print(
        "non-foot contacts  "
        + (", ".join(f"{a}-{b} at {w:.3f} s" for a, b, w in contacts) if contacts else "none")
    )
    strikes = out["swing_strikes"]
    print(
        "swing foot strikes "
        + (", ".join(f"{leg} at {w:.3f} s" for leg, w in strikes) if strikes else "none")
    )
    stand = out["stand"]
    if stand is not None:
        print(
            f"standing forces    max |MuJoCo - stand()| = {stand['max_error']:.3g} N "
            f"(3-D; vertical {stand['max_normal_error']:.3g} N; per foot vertical "
            f"{', '.join(f'{f[2]:.4f}' for f in stand['forces'])} N vs "
            f"{', '.join(f'{f[2]:.4f}' for f in stand['expected'])} N)"
        )
    failed = [k for k, row in out["checks"].items() if not row["ok"]]
    print("checks             " + ("pass" if not failed else "FAIL: " + ", ".join(failed)))
    for key in ("html", "mjcf"):
        if key in out:
            print(f"wrote {out[key]}", file=sys.stderr)
