"""A walk's physics verdict over a small ensemble of simulator settings (``simulate --robust``).

One replay in MuJoCo (:func:`hexapod_kin.simulate.simulate`) passes or fails under settings
the robot's data do not fix: the contact's softness, the servos' rotor inertia (a URDF has
no armature), the friction of the floor, the floor's flatness. :func:`simulate_robust`
plans the walk once and replays it under each member of :data:`ENSEMBLE`:

* contact: the project's (``solref`` time constant 5 ms) and MuJoCo's default (20 ms);
* armature: as given (the robot's data, else :func:`~hexapod_kin.simulate.scene.servo_defaults`)
  and zero;
* friction: 0.6 and 1.0 (the eight corners of these three);
* bumps: random ±3 mm bumps on the floor (a height field of 5 cm cells, friction 0.8),
  three seeds (flat terrain only: on a slope or a step the bumpy members are left out).

The eight flat members replay the plan open-loop (mode ``replay``). The three bumpy ones are
``controlled``: an open-loop replay cannot react to bumps it was not told about (on them every
example-robot-data quadruped's stance feet slid 5.5–25.5 mm, whatever the plan), and a walking
robot meets unknown ground with feedback, so they walk the plan's pattern for its duration,
commanded its mean twist (:func:`~.controlled.plan_command`: the controller's path ends where
the plan's tracked point does), under the closed-loop controller
(:func:`hexapod_kin.control.run`, as ``simulate --control --bumps 0.003 --seed K``), judged by
:meth:`~.controlled.ControlledRun.checks`: travel along the plan within 1 % of the plan's
distance, heading, no fall, no non-foot contact (:data:`~.controlled.CONTROL_LIMITS`).

The verdict is every member's checks (:meth:`~hexapod_kin.simulate.SimRun.checks` for a
replay); the worst member (a failing one first, then the largest travel error) is the one
printed.

The members without armature are replayed at :data:`ROBUST_TIMESTEP` (unless ``timestep`` is
given), a quarter of the smallest automatic step of :func:`~hexapod_kin.simulate.scene_mjcf`:
the automatic step keeps the servos stable, not the figures converged, and without armature
on MuJoCo's soft contact they are not (the verdict would then be the integrator's, not the
robot's). With the armature as given the automatic step is within 0.1 point of it (anymal's
nominal crawl: +0.32 % at 500 µs, +0.24 % at 25 µs), so those seven members keep it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from .controlled import CONTROL_LIMITS, ControlledRun, finite

__all__ = [
    "CONTROL_LIMITS",
    "ENSEMBLE",
    "ROBUST_TIMESTEP",
    "ControlledRun",
    "Member",
    "RobustRun",
    "simulate_robust",
]

#: The ensemble's physics step [s] (``MAX_TIMESTEP / 40``; it divides every plan interval that
#: the automatic step divides). erd:anymal's 4 s crawl, MuJoCo's contact, zero armature:
#: travel +3.9 % at the automatic 167 µs, +2.7 % at 100 µs, +1.4 % at 50 µs, +0.9 % at 25 µs
#: (→ about +0.5 % as the step → 0); with armature, 500 µs is already within 0.1 point.
ROBUST_TIMESTEP = 2.5e-5


@dataclass(frozen=True)
class Member:
    """One setting of the ensemble.

    Attributes:
        name: A short label.
        contact_time: Contact ``solref`` time constant [s].
        zero_armature: The servos without rotor inertia (else the armature as given).
        friction: Sliding friction coefficient.
        bumps: Amplitude of the floor's random bumps [m].
        seed: The bumps' seed.
        controlled: Walked under the closed-loop controller (else the plan replayed; the
            controller's scene has the project's contact and the armature as given).

    """

    name: str
    contact_time: float
    zero_armature: bool
    friction: float
    bumps: float = 0.0
    seed: int = 0
    controlled: bool = False

    @property
    def mode(self) -> str:
        """``controlled`` or ``replay``."""
        return "controlled" if self.controlled else "replay"

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (SI units)."""
        return {
            "name": self.name,
            "mode": self.mode,
            "contact_time": self.contact_time,
            "armature": "zero" if self.zero_armature else "as given",
            "friction": self.friction,
            "bumps": self.bumps,
            "seed": self.seed,
        }


def _corners() -> tuple[Member, ...]:
    out = []
    for mu in (1.0, 0.6):
        for tc, contact in ((0.005, "project contact"), (0.02, "MuJoCo contact")):
            for zero in (False, True):
                arm = "armature 0" if zero else "armature as given"
                out.append(Member(f"{contact}, {arm}, friction {mu:g}", tc, zero, mu))
    return tuple(out)


#: The ensemble: the eight corners of contact × armature × friction (replayed), then three
#: bumpy floors (walked under the controller).
ENSEMBLE: tuple[Member, ...] = _corners() + tuple(
    Member(f"bumps 3 mm seed {s}, friction 0.8", 0.005, False, 0.8, 0.003, s, True)
    for s in range(3)
)


@dataclass(frozen=True)
class RobustRun:
    """The ensemble's replays of one plan.

    Attributes:
        members: The settings, in :data:`ENSEMBLE` order.
        runs: One per member: a :class:`~hexapod_kin.simulate.SimRun` (replayed) or a
            :class:`~.controlled.ControlledRun` (``controlled``).

    """

    members: tuple[Member, ...]
    runs: tuple[Any, ...]

    @property
    def failures(self) -> list[tuple[Member, list[str]]]:
        """The members that fail and their failing checks."""
        out = []
        for m, r in zip(self.members, self.runs):
            bad = [k for k, row in r.checks().items() if not row["ok"]]
            if bad:
                out.append((m, bad))
        return out

    @property
    def ok(self) -> bool:
        """Every member passes every check."""
        return not self.failures

    @property
    def worst(self) -> int:
        """The index of the worst member: failing checks first, then the travel error."""
        return max(range(len(self.runs)), key=self._key)

    @property
    def nominal(self) -> Any:
        """The first replayed member's run (in :data:`ENSEMBLE`: the project's settings)."""
        return next(r for m, r in zip(self.members, self.runs) if not m.controlled)

    @property
    def worst_replay(self) -> Any:
        """The worst of the replayed members' runs (for a page or a scene), as :attr:`worst`."""
        replays = [i for i, m in enumerate(self.members) if not m.controlled]
        return self.runs[max(replays, key=self._key)]

    def _key(self, i: int) -> tuple[int, float]:
        c = self.runs[i].checks()
        return sum(not row["ok"] for row in c.values()), float(c["travel"]["value"])

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: per member its settings and figures; the worst; the verdict."""
        rows = []
        for m, r in zip(self.members, self.runs):
            c = r.checks()
            row = {
                **m.to_dict(),
                **(r.to_dict() if m.controlled else {}),
                "distance_error": r.distance_error,
                "heading_error": float(r.checks()["heading"]["value"]),
                "turn_error": r.turn_error,
                "direction": r.direction,
                "failed": [k for k, check in c.items() if not check["ok"]],
                "checks": c,
            }
            rows.append(finite(row) if m.controlled else row)
        return {"members": rows, "worst": self.worst, "ok": self.ok}


def simulate_robust(
    run_or_robot: Any = None,
    *,
    members: tuple[Member, ...] = ENSEMBLE,
    stand: bool = True,
    **options: Any,
) -> RobustRun:
    """Plan a walk once, replay it under each member of the ensemble, walk the controlled ones.

    The replayed members run first (the first of them plans the walk); each controlled
    member then walks the plan's pattern for its duration, commanded the plan's mean twist,
    under the controller
    (:func:`~.controlled.controlled_run`; the servo keywords below are the replay's only).

    Args:
        run_or_robot: As :func:`hexapod_kin.simulate.simulate` (a run, or a robot to plan).
        members: The settings (default :data:`ENSEMBLE`; at least one replayed).
        stand: Run the standing check (once, with the first replayed member).
        **options: Keywords of :func:`~hexapod_kin.simulate.simulate` (the walk's, the
            feet's, the servos'; not ``friction``, ``contact_time``, ``bumps``, ``seed``:
            the members set them; ``armature`` is the "as given" value; ``timestep``
            default: the automatic step, :data:`ROBUST_TIMESTEP` without armature).

    Returns:
        A :class:`RobustRun`.

    Raises:
        ParameterError: Bad values (as :func:`~hexapod_kin.simulate.simulate`), an option
            the members set, no members, no replayed member.
        GaitError: The plan fails (as :func:`~hexapod_kin.gait.walk.walk`).
        OptionalDependencyError: MuJoCo is not installed.

    """
    from ..exceptions import ParameterError
    from ..simulate import simulate
    from .controlled import controlled_run

    taken = sorted({"friction", "contact_time", "bumps", "seed"} & set(options))
    if taken:
        raise ParameterError(
            f"{taken[0]}= is set by each member of the ensemble; leave it out",
            parameter=taken[0],
            allowed="the ensemble's own values",
        )
    if (options.get("terrain") or "flat") != "flat":  # bumps are for flat ground
        members = tuple(m for m in members if not m.bumps)
    if not members:
        raise ParameterError("members=(): at least one setting", parameter="members")
    if all(m.controlled for m in members):
        raise ParameterError(
            "members: every one controlled; at least one replays the plan (its figures are "
            "the controlled members' reference)",
            parameter="members",
            allowed="at least one Member with controlled=False",
        )
    fine = options.get("timestep") is None  # the zero-armature members' own step
    runs: dict[int, Any] = {}
    first = None
    for k, m in sorted(enumerate(members), key=lambda km: km[1].controlled):
        if m.controlled:  # after the replays: walked under the controller
            assert first is not None
            robot = getattr(first.run, "robot", None) if _is_run(run_or_robot) else run_or_robot
            feet, radius = options.get("feet"), options.get("foot_radius")
            runs[k] = controlled_run(first, robot, m, feet, radius)
            continue
        opts = dict(options)
        if m.zero_armature:
            opts["armature"] = 0.0
            if fine:
                opts["timestep"] = ROBUST_TIMESTEP
        target = run_or_robot if first is None else first.run
        if first is not None:  # the plan is made once; its keywords are spent
            opts = {key: v for key, v in opts.items() if key in _REPLAY_KEYS}
        sim = simulate(
            target,
            friction=m.friction,
            contact_time=m.contact_time,
            bumps=m.bumps,
            seed=m.seed,
            stand=stand and first is None,
            **opts,
        )
        if first is None:
            first = sim
        runs[k] = sim
    return RobustRun(members=tuple(members), runs=tuple(runs[k] for k in range(len(members))))


def _is_run(obj: Any) -> bool:
    from ..gait.walk import GaitRun

    return isinstance(obj, GaitRun)


#: The keywords of :func:`~hexapod_kin.simulate.simulate` that concern the replay, not the plan.
_REPLAY_KEYS = frozenset(
    ("foot_radius", "kp", "kv", "armature", "timestep", "settle", "terrain", "feedforward")
)
