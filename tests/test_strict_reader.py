"""The one strict reader of user files (``hexapod_kin._reader``), and every reader going through it.

Each hostile case is refused with a :class:`SourceError` naming the kind of file and the file,
for every kind of user file: tables, feet files, calibrations, plans, timelines, claims.
"""

from __future__ import annotations

import json
import os
import re
import resource
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import hexapod_kin as hk
from hexapod_kin import _reader
from hexapod_kin.exceptions import (
    HexapodKinError,
    OptionalDependencyError,
    ParameterError,
    SourceError,
)


def _cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def billion_laughs() -> str:
    """The 424-byte "billion laughs" of the probe: 9 levels of 9 aliases (9⁹ strings)."""
    lines = ['a: &a ["lol","lol","lol","lol","lol","lol","lol","lol","lol"]']
    for i in range(8):
        prev, cur = chr(97 + i), chr(98 + i)
        lines.append(f"{cur}: &{cur} [" + ",".join([f"*{prev}"] * 9) + "]")
    return "\n".join(lines) + "\n"


# ------------------------------------------------------------------ the reader itself
def test_billion_laughs_refused_at_once(tmp_path: Path) -> None:
    path = tmp_path / "bomb.yaml"
    path.write_text(billion_laughs())
    assert path.stat().st_size < 450
    cpu = _cpu()
    with pytest.raises(SourceError, match="more than 64 YAML aliases") as info:
        _reader.read_data(path, "feet")
    assert _cpu() - cpu < 0.5
    assert info.value.parameter == "feet" and str(path) in str(info.value)


def test_aliases_under_the_cap_that_expand_are_refused(tmp_path: Path) -> None:
    """60 aliases (under the cap) expanding to 6¹⁰ values: the walk stops at the value cap."""
    lines = ["a: &a [x, x, x, x, x, x]"]
    for i in range(10):
        prev, cur = chr(97 + i), chr(98 + i)
        lines.append(f"{cur}: &{cur} [" + ", ".join([f"*{prev}"] * 6) + "]")
    path = tmp_path / "b.yaml"
    path.write_text("\n".join(lines) + "\n")
    cpu = _cpu()
    with pytest.raises(SourceError, match="after alias expansion"):
        _reader.read_data(path)
    assert _cpu() - cpu < 1.0


@pytest.mark.parametrize(
    ("name", "text", "phrase"),
    [
        ("d.json", '{"offset": 1, "offset": 2}', "key 'offset' given twice"),
        ("d.yaml", "offset: 1\noffset: 2\n", "key 'offset' given twice (line 2)"),
        ("d.toml", "offset = 1\noffset = 2\n", "not valid TOML"),
        ("n.json", '{"a": NaN}', "NaN is not a JSON number"),
        ("i.json", '{"a": [1, Infinity]}', "Infinity is not a JSON number"),
        ("big.json", '{"a": ' + "9" * 5001 + "}", "an integer of 5001 digits"),
        ("big.yaml", "a: " + "9" * 401 + "\n", "an integer of 401 digits"),
        ("deep.json", "[" * 100_000 + "]" * 100_000, "nest"),
        ("deep2.json", "[" * 20 + "]" * 20, "nested deeper than 16 levels"),
        ("deep.yaml", "a: " + "[" * 50_000 + "]" * 50_000, "nest"),
        ("deep.toml", "a = " + "[" * 50_000 + "]" * 50_000, "nest"),
        ("key.yaml", "5: [0, 0, 0]\n", "the key 5 is not a string"),
        ("key2.yaml", "true: 1\n", "the key True is not a string"),
        ("tag.yaml", "a: !!python/object/apply:os.system [echo hi]\n", "the YAML tag"),
        ("date.yaml", "a: 2024-01-01\n", "a value of type date"),
        ("long.json", '{"a": "' + "x" * 20_000 + '"}', "a string of 20000 characters"),
        ("bad.json", "{", "not valid JSON"),
        ("bad.yaml", "a: [", "not valid YAML"),
    ],
)
def test_hostile_contents(tmp_path: Path, name: str, text: str, phrase: str) -> None:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    cpu = _cpu()
    with pytest.raises(SourceError) as info:
        _reader.read_data(path, "calibration")
    assert _cpu() - cpu < 1.0
    message = str(info.value)
    assert phrase in message and str(path) in message and "\n" not in message, message
    assert info.value.parameter == "calibration"


def test_files_that_are_not_regular(tmp_path: Path) -> None:
    os.mkfifo(tmp_path / "pipe.yaml")  # no writer: a blocking open would hang
    os.symlink("/dev/zero", tmp_path / "zero.yaml")
    (tmp_path / "dir.yaml").mkdir()
    for name, kind in [("pipe.yaml", "a named pipe"), ("zero.yaml", "a device"),
                       ("dir.yaml", "a folder")]:  # fmt: skip
        with pytest.raises(SourceError, match=f"is {kind}; only regular files are read"):
            _reader.read_data(tmp_path / name, "feet")
    with pytest.raises(SourceError, match=r"cannot read it \(No such file"):
        _reader.read_data(tmp_path / "none.yaml", "feet")


def test_byte_cap_and_utf8(tmp_path: Path) -> None:
    path = tmp_path / "big.yaml"
    path.write_bytes(b"#" * 1001)
    assert _reader.read_data(path, max_bytes=1001) is None  # a YAML file of comments only
    with pytest.raises(SourceError, match="more than 1000 bytes"):
        _reader.read_data(path, max_bytes=1000)
    path.write_bytes("name: caf\xe9\n".encode("latin-1"))
    with pytest.raises(SourceError, match=r"not UTF-8 text \(byte 9: invalid"):
        _reader.read_data(path)


def test_the_same_values_from_json_toml_and_yaml(tmp_path: Path) -> None:
    data = {"defaults": {"units": "ticks", "limits": [0, 1023], "centre": 512.0},
            "joints": {"j1": {"direction": -1, "offset": -0.25}}}  # fmt: skip
    (tmp_path / "c.json").write_text(json.dumps(data))
    (tmp_path / "c.yaml").write_text(
        "defaults: {units: ticks, limits: [0, 1023], centre: 512.0}\n"
        "joints:\n  j1: {direction: -1, offset: -0.25}\n"
    )
    (tmp_path / "c.toml").write_text(
        '[defaults]\nunits = "ticks"\nlimits = [0, 1023]\ncentre = 512.0\n'
        "[joints.j1]\ndirection = -1\noffset = -0.25\n"
    )
    for suffix in ("json", "yaml", "toml"):
        assert _reader.read_data(tmp_path / f"c.{suffix}") == data


def test_toml_on_python_310_uses_tomli(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    """Without ``tomllib`` (3.10) the reader takes ``tomli`` (same API), else says to install it."""
    tomllib = pytest.importorskip("tomllib")  # the same API as tomli
    path = tmp_path / "t.toml"
    path.write_text("a = 1\n")
    monkeypatch.setitem(sys.modules, "tomllib", None)  # as on 3.10: no such module
    monkeypatch.setitem(sys.modules, "tomli", tomllib)  # tomli installed (same API)
    assert _reader.read_data(path) == {"a": 1}
    monkeypatch.setitem(sys.modules, "tomli", None)
    with pytest.raises(OptionalDependencyError, match="tomli"):
        _reader.read_data(path)


# ------------------------------------------------------------ every reader uses it
def _table(path: Path) -> Any:
    return hk.load(path)


def _feet(path: Path) -> Any:
    from hexapod_kin.gait.legs import parse_feet

    return parse_feet(str(path))


def _calibration(path: Path) -> Any:
    from hexapod_kin.export.timeline import read_calibration

    return read_calibration(path)


def _plan(path: Path) -> Any:
    from hexapod_kin.export.timeline import read_plan

    return read_plan(path)


def _timeline(path: Path) -> Any:
    from hexapod_kin.export.timeline import read_timeline

    return read_timeline(path)


def _claims(path: Path) -> Any:
    from hexapod_kin.report.data import load_claims

    return load_claims(path)


def _sweep(path: Path) -> Any:
    from hexapod_kin.sweep import read_results

    return read_results(path)


READERS: dict[str, tuple[Callable[[Path], Any], str, str]] = {
    # kind: (reader, parameter of its errors, suffix it reads)
    "table": (_table, "source", ".yaml"),
    "feet": (_feet, "feet", ".yaml"),
    "calibration": (_calibration, "calibration", ".yaml"),
    "plan": (_plan, "plan", ".json"),
    "timeline": (_timeline, "timeline", ".json"),
    "claims": (_claims, "claims", ".toml"),
    "sweep table": (_sweep, "path", ".json"),
}
HOSTILE = {
    "pipe": "is a named pipe",
    "folder": "is a folder",
    "not-utf8": "not UTF-8 text",
    "duplicate": "given twice",
}


def _hostile(tmp_path: Path, case: str, suffix: str) -> Path:
    path = tmp_path / f"f{suffix}"
    if case == "pipe":
        os.mkfifo(path)
    elif case == "folder":
        path.mkdir()
    elif case == "not-utf8":
        path.write_bytes(b"\xff\xfe")
    elif suffix == ".toml":
        path.write_text("[a]\nb = 1\n[a]\nb = 2\n")
    elif suffix == ".json":
        path.write_text('{"t": [0], "t": [1]}')
    else:
        path.write_text("a: 1\na: 2\n")
    return path


@pytest.mark.parametrize("case", sorted(HOSTILE))
@pytest.mark.parametrize("kind", sorted(READERS))
def test_every_user_file_goes_through_the_reader(tmp_path: Path, kind: str, case: str) -> None:
    read, parameter, suffix = READERS[kind]
    path = _hostile(tmp_path, case, suffix)
    with pytest.raises(SourceError) as info:
        read(path)
    phrase = "not valid TOML" if case == "duplicate" and suffix == ".toml" else HOSTILE[case]
    assert phrase in str(info.value) and info.value.parameter == parameter, str(info.value)


def test_yaml_alias_bomb_in_every_yaml_reader(tmp_path: Path) -> None:
    path = tmp_path / "bomb.yaml"
    path.write_text(billion_laughs())
    for kind in ("table", "feet", "calibration"):
        cpu = _cpu()
        with pytest.raises(SourceError, match="YAML aliases"):
            READERS[kind][0](path)
        assert _cpu() - cpu < 0.5, kind
    from hexapod_kin.export.timeline import read_timeline

    with pytest.raises(SourceError, match="YAML aliases"):
        read_timeline(path, fmt="ros2")


# ------------------------------------------------------------ the readers' own values
def test_calibration_key_twice_is_refused_not_the_last(tmp_path: Path) -> None:
    from hexapod_kin.export.timeline import read_calibration

    path = tmp_path / "cal.yaml"
    path.write_text("joints:\n  knee: {offset: 0.1, offset: 0.3}\n")
    with pytest.raises(SourceError, match=r"key 'offset' given twice \(line 2\)"):
        read_calibration(path)
    path.write_text("joints:\n  knee: {offset: 0.3}\n")
    assert read_calibration(path).servo("knee").offset == 0.3


@pytest.mark.parametrize(
    ("entry", "phrase"),
    [
        ("{offset: '0.5'}", "offset='0.5' is not a finite number"),
        ("{direction: true}", "direction=True is not a finite number"),
        ("{offset: .inf}", "offset=inf is not a finite number"),
        ("{units: 5}", "units=5 must be a string"),
        ("{limits: 5}", "limits=5: a list of 2 numbers is required"),
        ("{limits: [0, .nan]}", "limits[1]=nan is not a finite number"),
    ],
)
def test_calibration_values_are_numbers(tmp_path: Path, entry: str, phrase: str) -> None:
    from hexapod_kin.export.timeline import read_calibration

    path = tmp_path / "cal.yaml"
    path.write_text(f"joints:\n  knee: {entry}\n")
    with pytest.raises(ParameterError, match=re.escape(phrase)):
        read_calibration(path)


@pytest.mark.parametrize(
    ("row", "phrase"),
    [("link = true", "row 1.link=True must be a string"),
     ("name = 5", "row 1.name=5 must be a string")],
)  # fmt: skip
def test_non_string_names_in_a_table_are_refused(tmp_path: Path, row: str, phrase: str) -> None:
    path = tmp_path / "t.toml"
    path.write_text(f"[[row]]\nd = 0.1\n{row}\n[[row]]\nd = 0.1\n{row.split()[0]} = 'b'\n")
    with pytest.raises(ParameterError, match=phrase):
        hk.load(path)


def test_a_feet_file_holding_a_file_name_is_not_followed(tmp_path: Path) -> None:
    """A feet file whose content is the name of a file (itself) is a spec, not a path."""
    from hexapod_kin.gait.legs import parse_feet

    path = tmp_path / "self.yaml"
    path.write_text(f"{path}\n")
    (foot,) = parse_feet(str(path))  # a frame of that name (refused later by the robot)
    assert foot.frame == str(path) and foot.offset == (0.0, 0.0, 0.0)


def test_a_good_feet_file_in_every_format(tmp_path: Path) -> None:
    from hexapod_kin.gait.legs import FootSpec, parse_feet

    want = (FootSpec("tibia_lf", (0.0, 0.16, 0.029)),)
    (tmp_path / "f.json").write_text('{"feet": {"tibia_lf": [0, 0.16, 0.029]}}')
    (tmp_path / "f.toml").write_text('[[feet]]\nframe = "tibia_lf"\noffset = [0, 0.16, 0.029]\n')
    (tmp_path / "f.yml").write_text("tibia_lf: [0, 0.16, 0.029]\n")
    for name in ("f.json", "f.toml", "f.yml"):
        assert parse_feet(str(tmp_path / name)) == want


def test_timeline_files_still_read_back(tmp_path: Path) -> None:
    """A written timeline (CSV with its calibration, JSON, ROS 2 YAML) reads back exactly."""
    from hexapod_kin.export.timeline import read_timeline, timeline

    t = np.linspace(0.0, 1.0, 11)
    q = np.column_stack([0.3 * np.sin(t), -0.2 * t])
    tl = timeline((t, q), rate=20, joint_names=["j1", "j2"])
    for suffix in ("csv", "json", "yaml"):
        path = tl.write(tmp_path / f"w.{suffix}")
        back = read_timeline(path)
        np.testing.assert_allclose(back.q, tl.q, atol=1e-12)
        np.testing.assert_allclose(back.t, tl.t, atol=1e-12)


# ------------------------------------------------ YAML 1.2 numbers, calibrations, timelines
def test_yaml_exponents_are_numbers(tmp_path: Path) -> None:
    """PyYAML alone reads ``1e-3`` as text (YAML 1.1); the reader reads it as YAML 1.2 does."""
    data = _reader.parse_data("a: [1e-3, 1.5e3, -2E5, 1.0e+3, 12, x1e3, '1e3']", "x", "yaml")
    assert data == {"a": [0.001, 1500.0, -200000.0, 1000.0, 12, "x1e3", "1e3"]}
    path = tmp_path / "t.yaml"
    path.write_text("row:\n  - {d: 1e-1}\n  - {d: 2e-1}\n")
    p = hk.load(path).fk([0.0, 0.0])[:3, 3]
    np.testing.assert_allclose(p, [0.3, 0.0, 0.0], atol=1e-15)  # two rows along x: 0.1 + 0.2


@pytest.mark.parametrize(
    ("entry", "key"),
    [
        ("{units: us, us_per_rad: 1e308, centre: 1500}", "us_per_rad"),
        ("{units: ticks, ticks_per_revolution: 1e308, centre: 0}", "ticks_per_revolution"),
        ("{units: us, us_per_rad: 600, centre: 1e12}", "centre"),
        ("{units: ticks, ticks_per_revolution: 4096, centre: 2048, resolution: 1e-320}",
         "resolution"),
        ("{units: ticks, ticks_per_revolution: 1e-300, centre: 0.5}", "ticks_per_revolution"),
    ],
)  # fmt: skip
def test_implausible_calibrations_are_refused(tmp_path: Path, entry: str, key: str) -> None:
    from hexapod_kin.export.timeline import read_calibration

    path = tmp_path / "cal.yaml"
    path.write_text(f"defaults: {entry}\n")
    with pytest.raises(ParameterError) as info:
        read_calibration(path)
    assert info.value.parameter == key, str(info.value)


def test_a_two_sample_plan_has_its_finite_difference_speed() -> None:
    from hexapod_kin.export.timeline import timeline

    tl = timeline((np.array([0.0, 2.0]), np.array([[0.0], [0.5]])), rate=4)
    np.testing.assert_allclose(tl.qdot[:, 0], 0.25, rtol=1e-15)  # 0.5 rad over 2 s
    np.testing.assert_allclose(tl.q[:, 0], 0.25 * tl.t, atol=1e-15)


def test_non_finite_commands_are_refused_naming_joint_and_time() -> None:
    from hexapod_kin.exceptions import ConfigurationError
    from hexapod_kin.export.timeline import timeline

    t = np.array([0.0, 0.5, 1.0])
    with pytest.raises(ConfigurationError, match=r"joint j1 at t=0\.\d+ s: .*not finite"):
        timeline((t, np.array([[0.0], [1.0], [1e308]])), rate=10, joint_names=["j1"])
    with pytest.raises(ConfigurationError, match="samples"):
        timeline((np.array([0.0, 1e300]), np.zeros((2, 1))), rate=50)


def _servo_entry(draw: Any) -> dict[str, Any]:
    from hypothesis import strategies as st

    units = draw(st.sampled_from(["rad", "deg", "ticks", "us"]))
    big = st.floats(1e-320, 1e308, allow_nan=False)
    entry: dict[str, Any] = {"units": units, "offset": draw(st.floats(-4, 4)),
                             "direction": draw(st.sampled_from([1, -1]))}  # fmt: skip
    if units == "ticks":
        entry.update(ticks_per_revolution=draw(big), centre=draw(st.floats(-1e12, 1e12)))
    if units == "us":
        entry.update(us_per_rad=draw(big), centre=draw(st.floats(-1e12, 1e12)))
    if draw(st.booleans()):
        entry["resolution"] = draw(st.floats(0, 1e3) | big)
    if draw(st.booleans()):
        lo = draw(st.floats(-1e4, 1e4))
        entry["limits"] = [lo, lo + draw(st.floats(1e-3, 1e4))]
    return entry


def test_every_timeline_is_finite_within_range_or_refused_by_name() -> None:
    """Random calibrations and motions: a timeline holds only finite commands and speeds
    inside the servos' limits, written as valid JSON; or it is refused naming the joint."""
    from hypothesis import HealthCheck, given, settings
    from hypothesis import strategies as st

    from hexapod_kin.exceptions import ConfigurationError
    from hexapod_kin.export.timeline import Calibration, timeline

    seen: set[str] = set()

    @settings(max_examples=150, deadline=None, suppress_health_check=list(HealthCheck))
    @given(st.data())
    def check(data: Any) -> None:
        try:
            cal = Calibration.from_dict({"joints": {"j1": _servo_entry(data.draw)}})
        except ParameterError:
            return  # refused before any command is made
        n = data.draw(st.integers(2, 6))
        t = np.cumsum([0.0] + [data.draw(st.floats(1e-3, 10.0)) for _ in range(n - 1)])
        angle = st.floats(-4.0, 4.0) | st.floats(-1e308, 1e308)
        q = np.array([[data.draw(angle)] for _ in range(n)])
        try:
            tl = timeline((t, q), rate=data.draw(st.floats(1.0, 50.0)), joint_names=["j1"],
                          calibration=cal)  # fmt: skip
        except ConfigurationError as exc:
            assert str(exc).startswith("joint j1 at t="), str(exc)
            seen.add("refused")
            return
        seen.add("written")
        assert all(np.all(np.isfinite(a)) for a in (tl.command, tl.speed, tl.q, tl.qdot))
        limits = cal.servo("j1").limits
        if limits is not None:
            assert np.all((tl.command >= limits[0]) & (tl.command <= limits[1]))
        text = json.dumps(tl.to_dict(), allow_nan=False)  # valid JSON: no Infinity, no NaN
        assert json.loads(text)["joint_names"] == ["j1"]

    check()
    assert seen == {"refused", "written"}  # both outcomes drawn: the test can fail


def _command_timeline(path: Path) -> Any:
    from hexapod_kin.control.commands import read_timeline

    return read_timeline(path)


_TL = (
    '{"format": "hexapod-kin timeline", "calibration": {"defaults": {"units": "rad"}}, '
    '"joint_names": ["j"], "t": [0, 0.1], "command": [[0], [0]], "speed": [[0], [0]], '
    '"rate": 10, "interpolation": "linear"}'
)
#: kind -> (reader, suffix, {case: (file text, the shared phrase)}): every reader's values go
#: through _reader's number/numbers, text/texts and check_keys, with the file named (named).
VALUES: dict[str, tuple[Callable[[Path], Any], str, dict[str, tuple[str, str]]]] = {
    "table": (_table, ".yaml", {
        "text-number": ("row:\n  - {d: '0.1'}\n", "row 1.d='0.1' is not a finite number"),
        "boolean": ("row:\n  - {d: true}\n", "row 1.d=True is not a finite number"),
        "unknown-key": ("row:\n  - {dd: 0.1}\n", "unknown key 'dd' (did you mean 'd'?)"),
        "name": ("row:\n  - {name: 5}\n", "row 1.name=5 must be a string"),
    }),
    "feet": (_feet, ".yaml", {
        "text-number": ("a: ['0', 0, 0]\n", "foot a: offset[0]='0' is not a finite number"),
        "boolean": ("a: [0, true, 0]\n", "foot a: offset[1]=True is not a finite number"),
        "unknown-key": ("feet: [{frame: a, offst: [0, 0, 0]}]\n", "unknown key 'offst'"),
        "name": ("feet: [{frame: 5}]\n", "foot frame=5 must be a string"),
    }),
    "calibration": (_calibration, ".yaml", {
        "text-number": ("joints: {k: {offset: '0.5'}}\n", "offset='0.5' is not a finite number"),
        "boolean": ("joints: {k: {direction: true}}\n", "direction=True is not a finite number"),
        "unknown-key": ("joints: {k: {ofset: 0}}\n", "unknown key 'ofset'"),
        "name": ("joints: {k: {units: 5}}\n", "units=5 must be a string"),
    }),
    "plan": (_plan, ".json", {
        "text-number": ('{"t": ["0"], "q": [[0]]}', "t[0]='0' is not a finite number"),
        "boolean": ('{"t": [0], "q": [[false]]}', "q[0][0]=False is not a finite number"),
        "unknown-key": ('{"t": [0], "q": [[0]], "qq": 1}', "unknown key 'qq'"),
        "name": ('{"t": [0], "q": [[0]], "joint_names": [5]}', "joint_names[0]=5 must be a string"),
    }),
    "timeline": (_timeline, ".json", {
        "text-number": (_TL.replace("[0, 0.1]", '[0, "0.1"]'), "t[1]='0.1' is not a finite number"),
        "boolean": (_TL.replace('"rate": 10', '"rate": true'), "rate=True is not a finite number"),
        "unknown-key": (_TL.replace('"units"', '"unit"'), "unknown key 'unit'"),
        "name": (_TL.replace('["j"]', "[5]"), "joint_names[0]=5 must be a string"),
    }),
    "command timeline": (_command_timeline, ".json", {
        "text-number": ('{"commands": [{"t": 0, "vx": "1"}]}', "vx='1' is not a finite number"),
        "boolean": ('{"commands": [{"t": true}]}', "t=True is not a finite number"),
        "unknown-key": ('{"commands": [{"t": 0, "speed": 1}]}', "unknown key 'speed'"),
        "name": ('{"commands": [{"t": 0, "pattern": 5}]}', "pattern=5 must be a string"),
    }),
    "claims": (_claims, ".toml", {
        "unknown-key": ("claimz = 1\n", "unknown key 'claimz'"),
        "name": ('[[claim]]\nid = 5\nseed = "0"\nwhere = "x"\nkind = "y"\n', "claim id=5 must"),
    }),
}  # fmt: skip
VALUE_CASES = [(kind, case) for kind, (_, _, cases) in VALUES.items() for case in cases]


@pytest.mark.parametrize(("kind", "case"), VALUE_CASES, ids=[f"{k}-{c}" for k, c in VALUE_CASES])
def test_every_reader_checks_values_with_the_same_words(tmp_path: Path, kind: str, case: str):
    """A text for a number, a boolean, a misspelt key, a number for a name: one message each
    whatever the file, the file named in front (``kind='path': ...``)."""
    read, suffix, cases = VALUES[kind]
    text, phrase = cases[case]
    path = tmp_path / f"f{suffix}"
    path.write_text(text)
    with pytest.raises(HexapodKinError) as info:
        read(path)
    message = str(info.value)
    assert phrase in message, message
    assert f"={str(path)!r}: " in message and message.count("\n") == 0, message
