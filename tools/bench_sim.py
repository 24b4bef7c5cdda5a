"""Benchmark: a planned walk replayed open-loop in MuJoCo (issue 22, ``hexapod_kin.simulate``).

Target: the MuJoCo replay of 10 s of walk (1 kHz physics, the scene's contacts, slip and
non-foot checks at every step) in <= 10 s of wall time. Timed: the replay alone
(``SimRun.wall_time``: placing, settling 0.5 s, replaying), the whole ``simulate()`` call
(planning, scene export, replay, standing forces) and the standing check alone.

``rows()`` returns ``(label, seconds, target text)``; ``python tools/bench_sim.py`` prints
them with the figures of each walk (distance vs plan, heading, roll/pitch, slip).
"""

from __future__ import annotations

import time

TARGET_S = 10.0


def rows(patterns: tuple[str, ...] = ("tripod", "wave", "ripple")) -> list[tuple[str, float, str]]:
    """(label, seconds, target) per timed case."""
    from hexapod_kin.gait import walk
    from hexapod_kin.simulate import simulate, stand_forces

    out: list[tuple[str, float, str]] = []
    for pattern in patterns:
        run = walk(pattern=pattern, duration=10.0)
        t0, c0 = time.perf_counter(), time.process_time()
        sim = simulate(run, stand=False)
        total, cpu = time.perf_counter() - t0, time.process_time() - c0
        out.append((f"MuJoCo replay, {pattern} 10 s @ 1 kHz", sim.wall_time, f"<= {TARGET_S:g} s"))
        out.append((f"simulate({pattern}) incl. scene export", total, "informative"))
        out.append((f"simulate({pattern}), CPU time of this process", cpu, "informative"))
    t0 = time.perf_counter()
    stand_forces()
    out.append(("standing forces (2 s settle)", time.perf_counter() - t0, "informative"))
    return out


def _figures() -> None:
    from hexapod_kin.simulate import simulate

    cases = {
        "tripod": {"pattern": "tripod"},
        "wave": {"pattern": "wave"},
        "ripple": {"pattern": "ripple"},
        "turn": {"pattern": "tripod", "velocity": (0.0, 0.0, 0.2)},
        "slope": {"pattern": "tripod", "terrain": "slope"},
        "step": {"pattern": "tripod", "terrain": "step"},
    }
    from hexapod_kin.simulate import stand_forces

    st = stand_forces()
    print(f"standing: max |MuJoCo - stand()| = {st.max_error:.3g} N per foot, forces {st.forces}")
    for radius in (0.001, None):
        for name, kw in cases.items():
            s = simulate(foot_radius=radius, stand=False, **kw)
            d = s.to_dict()
            dist = "-" if d["distance_error"] is None else f"{100 * d['distance_error']:+.2f} %"
            turn = "-" if d["turn_error"] is None else f"{100 * d['turn_error']:+.2f} %"
            print(
                f"{name:7s} feet {1e3 * s.scene.foot_radius:4.1f} mm: distance {dist:>8s} "
                f"turn {turn:>8s} heading {d['heading_error_deg']:.3f} deg roll "
                f"{d['max_roll_deg']:.3f} pitch {d['max_pitch_deg']:.3f} deg slip "
                f"{1e3 * s.max_slip:.2f} mm height {1e3 * s.height_error:.2f} mm "
                f"non-foot {len(s.non_foot_contacts)} {'ok' if s.ok else 'FAIL'}"
            )


if __name__ == "__main__":
    import mujoco

    print(f"MuJoCo {mujoco.__version__}")
    for label, seconds, target in rows():
        print(f"{label:45s} {seconds:8.3f} s   target {target}")
    _figures()
