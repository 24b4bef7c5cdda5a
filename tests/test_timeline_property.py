"""Property (issue 35): nothing unchecked reaches a servo.

For random calibrations (every key, plausible and absurd numbers: 1e308, 1e-320, subnormal,
zero steps) and random motions (a few joints, uneven times, angles up to 1e308 rad, with and
without joint limits), :func:`hexapod_kin.export.timeline.timeline` either refuses or returns a
timeline whose every value is finite and inside the servos' and joints' ranges; the files it
writes are valid JSON (no ``Infinity``/``NaN``), CSV and ROS 2 YAML that read back to the same
commands. A refusal of a sample names the joint and the time; a refusal of a calibration names
the joint and the key. The commands are recomputed here from the servo map itself,
:math:`u = c + d\\,s\\,(q - q_0)` rounded to the resolution, with ``s`` from the units.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from hexapod_kin.exceptions import ConfigurationError, HexapodKinError, LimitError, ParameterError
from hexapod_kin.export.servos import Calibration
from hexapod_kin.export.timeline import read_timeline, timeline

#: Numbers a calibration or a plan may hold: ordinary ones and the probe's absurd ones.
_WILD = st.one_of(
    st.sampled_from([0.0, 1.0, -1.0, 1e308, -1e308, 1e-320, 5e-324, 1e9, 1e-9, 2.0**53]),
    st.floats(-1e4, 1e4, allow_nan=False, allow_infinity=False),
    st.floats(allow_nan=False, allow_infinity=False),
)
_POSITIVE = st.one_of(
    st.sampled_from([1e308, 1e-320, 5e-324, 1e-6, 1e9]),
    st.floats(1e-3, 1e4),
    st.floats(min_value=0.0, exclude_min=True, allow_infinity=False),
)


@st.composite
def _servo_entry(draw: st.DrawFn) -> dict[str, object]:
    units = draw(st.sampled_from(["rad", "deg", "ticks", "us"]))
    entry: dict[str, object] = {"units": units}
    if draw(st.booleans()):
        entry["offset"] = draw(st.one_of(st.floats(-4.0, 4.0), _WILD))
    if draw(st.booleans()):
        entry["direction"] = draw(st.sampled_from([1, -1]))
    if units == "ticks":
        entry["ticks_per_revolution"] = draw(st.one_of(st.sampled_from([1228.8, 4096]), _POSITIVE))
    if units == "us":
        entry["us_per_rad"] = draw(st.one_of(st.sampled_from([500.0, 636.6]), _POSITIVE))
    if units in ("ticks", "us") and draw(st.booleans()):
        entry["centre"] = draw(st.one_of(st.sampled_from([512.0, 1500.0, 2048.0]), _WILD))
    if draw(st.booleans()):
        lo, hi = sorted(draw(st.lists(_WILD, min_size=2, max_size=2, unique=True)))
        entry["limits"] = [lo, hi]
    if draw(st.booleans()):
        entry["velocity_limit"] = draw(_POSITIVE)
    if draw(st.booleans()):
        entry["resolution"] = draw(st.one_of(st.just(0.0), _POSITIVE))
    return entry


@st.composite
def _case(draw: st.DrawFn) -> tuple[dict[str, object], np.ndarray, np.ndarray, object, float]:
    n_joints = draw(st.integers(1, 3))
    names = [f"j{k}" for k in range(n_joints)]
    data: dict[str, object] = {"defaults": draw(_servo_entry())}
    listed = draw(st.lists(st.sampled_from(names), unique=True, max_size=n_joints))
    data["joints"] = {j: draw(_servo_entry()) for j in listed}
    n = draw(st.integers(2, 6))
    steps = draw(st.lists(st.floats(1e-3, 0.5), min_size=n - 1, max_size=n - 1))
    t = np.concatenate([[0.0], np.cumsum(steps)])
    scale = draw(st.sampled_from([0.1, 1.0, 10.0, 1e300]))
    q = (
        np.array(
            draw(st.lists(st.floats(-1.0, 1.0), min_size=n * n_joints, max_size=n * n_joints))
        ).reshape(n, n_joints)
        * scale
    )
    limits = None
    if draw(st.booleans()):
        half = draw(st.sampled_from([0.5, 1.0, 2.6, 1e300]))
        limits = (np.full(n_joints, -half), np.full(n_joints, half))
    rate = draw(st.sampled_from([5.0, 20.0, 50.0, 1000.0]))
    return data, t, q, limits, rate


def _strict_json(text: str) -> object:
    def refuse(name: str) -> object:
        raise AssertionError(f"{name} in a JSON timeline")

    return json.loads(text, parse_constant=refuse)


def _expected_commands(cal: Calibration, names: tuple[str, ...], q: np.ndarray) -> np.ndarray:
    """The servo map by hand (not :meth:`Servo.command`): units → units per radian."""
    out = np.empty_like(q)
    for j, name in enumerate(names):
        s = cal.servo(name)
        per_rad = {
            "rad": 1.0,
            "deg": 180.0 / math.pi,
            "ticks": (s.ticks_per_revolution or 0.0) / (2.0 * math.pi),
            "us": s.us_per_rad or 0.0,
        }[s.units]
        centre = s.centre if s.units in ("ticks", "us") else 0.0
        u = centre + s.direction * per_rad * (q[:, j] - s.offset)
        step = s.resolution if s.resolution is not None else float(s.units in ("ticks", "us"))
        out[:, j] = np.round(u / step) * step if step > 0 else u
    return out


@pytest.mark.slow
@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(case=_case())
def test_every_timeline_is_finite_and_within_every_range(case, tmp_path_factory) -> None:
    data, t, q, limits, rate = case
    names = tuple(f"j{k}" for k in range(q.shape[1]))
    try:
        cal = Calibration.from_dict(data, "cal.yaml")
        tl = timeline((t, q), rate=rate, calibration=cal, joint_names=names, position_limit=limits)
    except (LimitError, ConfigurationError) as exc:  # a sample refused: joint and time named
        message = str(exc)
        event(f"refused: {type(exc).__name__}")
        if isinstance(exc, LimitError) or "not finite" in message or "±1e+09" in message:
            assert re.match(r"joint j\d at t=-?\d+\.\d{4} s: ", message), message
            assert exc.parameter in names, exc.parameter
        else:  # a plan of more samples than allowed
            assert exc.parameter == "rate", message
        return
    except ParameterError as exc:  # a calibration refused: the joint (or '*') and the key
        message = str(exc)
        event(f"calibration refused: {exc.parameter}")
        assert re.search(r"(calibration of (j\d|\*)|joint '(j\d|\*)')", message), message
        assert exc.parameter in {
            "units", "offset", "direction", "ticks_per_revolution", "centre", "us_per_rad",
            "limits", "velocity_limit", "resolution",
        }, (exc.parameter, message)  # fmt: skip
        return
    except HexapodKinError as exc:  # no other refusal is expected of these inputs
        pytest.fail(f"{type(exc).__name__}: {exc}")

    event("written")
    for arr in (tl.t, tl.q, tl.qdot, tl.command, tl.speed):
        assert np.all(np.isfinite(arr))
    assert np.abs(tl.command).max() <= 1e9 and np.abs(tl.speed).max() <= 1e9  # plausible
    qs = np.column_stack([np.interp(tl.t, t, q[:, j]) for j in range(q.shape[1])])
    assert np.array_equal(tl.command, _expected_commands(cal, names, qs))
    for j, servo in enumerate(tl.servos):
        if servo.limits is not None:
            assert servo.limits[0] <= tl.command[:, j].min()
            assert tl.command[:, j].max() <= servo.limits[1]
        if limits is not None:
            assert np.all(qs[:, j] >= limits[0][j] - 1e-9)
            assert np.all(qs[:, j] <= limits[1][j] + 1e-9)
        if servo.velocity_limit is not None:
            assert np.all(np.abs(tl.qdot[:, j]) <= servo.velocity_limit)
    folder = tmp_path_factory.mktemp("tl")
    for suffix in (".json", ".csv", ".yaml"):
        path = tl.write(folder / f"t{suffix}")
        text = Path(path).read_text()
        assert not re.search(r"\b(inf|infinity|nan)\b", text, re.IGNORECASE), suffix
        if suffix == ".json":
            _strict_json(text)
        back = read_timeline(path)
        if suffix != ".yaml":  # commands, in the servos' units, exactly
            assert np.array_equal(back.command, tl.command), suffix
