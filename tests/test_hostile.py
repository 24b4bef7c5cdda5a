"""Hostile table files, in process: ``main`` returns 2 with one line naming the file.

The corpus of issue 25 (alias bombs, huge integers, non-UTF-8, deep nesting, duplicate keys,
absurd magnitudes) and a table that names its links but not its tip. The same files (and
devices, named pipes, sweeps, damaged chunks) run as real child processes, timed and with
their peak memory measured, in ``test_hostile_cli.py``.
"""

from __future__ import annotations

import math
import os
import subprocess
from pathlib import Path

import pytest
from test_hostile_cli import cli, here

import hexapod_kin as hk
from hexapod_kin.cli import main

ROWS = "\n".join(f"[[row]]\nalpha = 0.0\nd = {0.1 if i else 0}\nr = 0\n" for i in range(3))


def _bomb() -> str:
    """The "billion laughs": 9 levels of 9 aliases each (9⁹ strings when expanded)."""
    lines = ["a: &a [x, x, x, x, x, x, x, x, x]"]
    for i in range(8):
        prev, cur = chr(97 + i), chr(98 + i)
        lines.append(f"{cur}: &{cur} [" + ", ".join([f"*{prev}"] * 9) + "]")
    return "\n".join(lines) + "\nname: *i\nrow: [{alpha: 0}]\n"


def _few_alias_bomb() -> str:
    """Fewer aliases (6 per level, 60 in all) that still expand to 6¹⁰ values."""
    lines = ["a: &a [x, x, x, x, x, x]"]
    for i in range(10):
        prev, cur = chr(97 + i), chr(98 + i)
        lines.append(f"{cur}: &{cur} [" + ", ".join([f"*{prev}"] * 6) + "]")
    return "\n".join(lines) + "\nrow: [{alpha: 0}]\n"


CASES: dict[str, tuple[str, bytes | str, str]] = {
    # name: (file name, content, a phrase the one-line error must contain)
    "alias-bomb": ("bomb.yaml", _bomb(), "aliases"),
    "alias-bomb-few": ("bomb6.yaml", _few_alias_bomb(), "after alias expansion"),
    "int-401": ("int401.yaml", "row:\n  - d: " + "9" * 401 + "\n", "401 digits"),
    "int-5001-yaml": ("int5001.yaml", "row:\n  - d: " + "9" * 5001 + "\n", "integers"),
    "int-5001-toml": ("int5001.toml", "[[row]]\nd = " + "9" * 5001 + "\n", "integers"),
    "not-utf8": ("latin1.yaml", "name: caf\xe9\nrow: [{d: 0}]\n".encode("latin-1"), "UTF-8"),
    "deep-yaml": ("deep.yaml", "row: " + "[" * 50_000 + "]" * 50_000 + "\n", "nest"),
    "deep-toml": ("deep.toml", "row = " + "[" * 50_000 + "]" * 50_000 + "\n", "nest"),
    "deep-yaml-maps": ("deepm.yaml", "row: " + "{a: " * 5_000 + "1" + "}" * 5_000, "nest"),
    "dup-row-key": ("dup.yaml", "row:\n  - {d: 0.1, d: 0.5}\n", "'d' given twice"),
    "dup-top-key": ("dup2.yaml", "angles: deg\nangles: rad\nrow: [{d: 0.1}]\n", "'angles'"),
    "d-1e300": ("big.toml", "[[row]]\nd = 1e300\n", "out of range"),
    "d-1e12": ("big12.toml", "[[row]]\nd = 1e12\n", "out of range"),
    "long-string": ("long.yaml", "name: " + "x" * 20_000 + "\nrow: [{d: 0}]\n", "characters"),
    "not-a-mapping": ("list.yaml", "- 1\n- 2\n", "mapping"),
    "yaml-python-tag": ("tag.yaml", "name: !!python/object/apply:os.system [echo hi]\n", "YAML"),
}


def _one_clear_line(res: subprocess.CompletedProcess[str]) -> str:
    lines = res.stderr.strip().splitlines()
    assert res.returncode == 2, res.stderr
    assert len(lines) == 1, res.stderr
    assert lines[0].startswith("hexapod-kin: error: "), lines[0]
    assert "a bug" not in lines[0] and "Traceback" not in res.stderr
    assert len(lines[0]) < 400, lines[0]
    return lines[0]


def _write(tmp_path: Path, case: str) -> tuple[Path, str]:
    name, content, phrase = CASES[case]
    path = tmp_path / name
    if isinstance(content, bytes):
        path.write_bytes(content)
    else:
        path.write_text(content)
    return path, phrase


@pytest.mark.parametrize("case", sorted(CASES))
def test_hostile_table_file(tmp_path: Path, case: str, capsys: pytest.CaptureFixture[str]) -> None:
    """In process (fast): ``main`` returns 2 with one line naming the file and the refusal."""
    path, phrase = _write(tmp_path, case)
    rc = main(["fk", str(path)])
    err = capsys.readouterr().err
    line = _one_clear_line(subprocess.CompletedProcess([], rc, "", err))
    assert phrase in line, line
    assert path.name in line, line  # the file is named


def test_growing_file_capped_while_reading(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The cap holds on the bytes read, not the size the file system reports.

    The file really grows after it is opened and ``fstat``-ed (another writer appends on the
    first read): a reader trusting the reported size (1,000 bytes, under the cap) would pass.
    """
    from hexapod_kin._io import read_regular
    from hexapod_kin.exceptions import SourceError

    path = tmp_path / "t.yaml"
    real_read = os.read

    def grow_then_read(extra: int):
        grown: list[int] = []

        def read(fd: int, n: int) -> bytes:
            if not grown:  # the writer appends between fstat and the first read
                with open(path, "ab") as fh:
                    fh.write(b"+" * extra)
                grown.append(extra)
            return real_read(fd, n)

        return read, grown

    # under the cap after growing: every byte read, the appended ones included
    path.write_bytes(b"#" * 1000)
    read, grown = grow_then_read(500)
    monkeypatch.setattr(os, "read", read)
    assert read_regular(path, 1999) == b"#" * 1000 + b"+" * 500
    assert grown == [500]
    # over the cap after growing: refused although fstat said 1,000 bytes
    path.write_bytes(b"#" * 1000)
    read, grown = grow_then_read(2000)
    monkeypatch.setattr(os, "read", read)
    with pytest.raises(SourceError, match="more than 1999 bytes"):
        read_regular(path, 1999)
    assert grown == [2000] and path.stat().st_size == 3000
    monkeypatch.undo()
    # the plain cap, at and one byte under the file's size
    path.write_bytes(b"#" * 2000)
    assert read_regular(path, 2000) == b"#" * 2000
    with pytest.raises(SourceError, match="more than 1999 bytes"):
        read_regular(path, 1999)


def test_links_named_without_tip(tmp_path: Path) -> None:
    """A table naming every link and no tip ends at its last link (FK by hand: 3 × 0.1 m)."""
    path = tmp_path / "named.toml"
    path.write_text(
        "".join(f'[[row]]\nd = 0.1\nlink = "l{i}"\n' for i in range(3)), encoding="utf-8"
    )
    model = hk.load(str(path))
    assert model.tip == "l2"
    p = model.fk([0.4, -0.3, 0.2])[:3, 3]
    # Khalil rows with d = 0.1 and alpha = 0: planar 3R, tip at the third frame's origin
    x = 0.1 * (1 + math.cos(0.4) + math.cos(0.4 - 0.3))
    y = 0.1 * (math.sin(0.4) + math.sin(0.4 - 0.3))
    assert abs(p[0] - x) < 1e-12 and abs(p[1] - y) < 1e-12 and abs(p[2]) < 1e-12


def test_good_table_still_reads(tmp_path: Path) -> None:
    path = tmp_path / "ok.toml"
    path.write_text('name = "ok"\n' + ROWS, encoding="utf-8")
    assert hk.load(str(path)).nq == 3


@pytest.mark.parametrize("l1, ok", [(1e4, True), (1e8, False)])
def test_urdf_never_writes_what_its_loader_refuses(l1: float, ok: bool) -> None:
    """A 0.1 kg rod of 1e8 m has an inertia of 8e13 kg m² (the loader caps at 1e9): refused."""
    from hexapod_kin import robots
    from hexapod_kin.exceptions import ParameterError
    from hexapod_kin.urdf import to_urdf

    chain = robots.get("hexabot_leg", l1=l1)
    if not ok:
        with pytest.raises(ParameterError, match="beyond 1e\\+09"):
            to_urdf(chain)
        return
    model = hk.load(to_urdf(chain))
    assert abs(model.fk([0.0, 0.0, 0.0])[0, 3] - (l1 + 0.2)) < 1e-6 * l1


def test_table_caps_are_the_loaders(tmp_path: Path) -> None:
    """The table's caps are the URDF gate's, in the table's terms: the largest table loads."""
    from hexapod_kin import _gate, tables

    assert tables.MAX_JOINTS == _gate.MAX_DOF and tables.MAX_NUMBER == _gate.MAX_ABS
    path = tmp_path / "long.toml"
    pose = "{ xyz = [0, 0, 0.1], rpy = [0, 0, 0] }"
    path.write_text(
        f'convention = "dh"\nbase_pose = {pose}\ntool = {pose}\n'
        + "[[row]]\na = 0.001\n"
        + '[[row]]\ntype = "fixed"\na = 0.001\n' * (tables.MAX_ROWS - 1),
        encoding="utf-8",
    )
    model = hk.load(str(path))
    assert model.nq == 1
    path.write_text(path.read_text() + '[[row]]\ntype = "fixed"\n', encoding="utf-8")
    with pytest.raises(hk.exceptions.ParameterError, match=f"{tables.MAX_ROWS + 1} rows"):
        hk.load(str(path))


ODD_VALUES = [None, True, -1, 0, 1e300, -1e300, 1e-300, "x", "", [], [1], [1, 2, 3],
              [1, 2, 3, 4, 5, 6], {}, {"a": 1}, {"xyz": [0, 0, 1e300]}, {"rpy": "a"}, [[1]],
              ["a", "b", "c"], 2**70, -(2**70), math.nan]  # fmt: skip


@pytest.mark.parametrize("convention", ["khalil", "dh"])
def test_every_key_with_odd_values(convention: str) -> None:
    """Any value under any key gives a chain or the package's error, never another exception."""
    from hexapod_kin.exceptions import HexapodKinError
    from hexapod_kin.params import Chain
    from hexapod_kin.tables import ROW_KEYS, TOP_KEYS, chain_from_table

    good = {"khalil": {"d": 0.1, "alpha": 1.0}, "dh": {"a": 0.1, "alpha": 1.0}}[convention]
    geometry = ("alpha", "d", "theta", "r", "a")
    tables = [
        {"convention": convention, key: value, "row": [{"d": 0.1}, dict(good)]}
        for key in TOP_KEYS
        if key != "convention"
        for value in ODD_VALUES
    ] + [
        {"convention": convention, "row": [{key: value}, dict(good)]}
        for key in (*geometry, *ROW_KEYS)
        for value in ODD_VALUES
    ]
    refused = 0
    for table in tables:
        try:
            assert isinstance(chain_from_table(table), Chain)
        except HexapodKinError as exc:
            assert "\n" not in str(exc) and len(str(exc)) < 400, str(exc)
            refused += 1
    assert 0.5 * len(tables) < refused < len(tables)  # most are refused, some are fine


def test_a_preset_parameter_called_name(capsys: pytest.CaptureFixture[str]) -> None:
    """``-s name=...`` is the preset's own ``name`` parameter (was a clash with get's name)."""
    assert main(["fk", "hexabot_leg", "-s", "name=front", "--json"]) == 0
    assert hk.robots.get("hexabot_leg", name="front").name == "front"
    assert "position" in capsys.readouterr().out


# ------------------------------------------- hostile feet files and calibrations, real children
PHX = Path(__file__).parent / "data" / "phantomx" / "phantomx.urdf"


def _laughs() -> str:
    """The probe's 424-byte "billion laughs" (9 levels of 9 aliases)."""
    lines = ['a: &a ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"]']
    for i in range(8):
        prev, cur = chr(97 + i), chr(98 + i)
        lines.append(f"{cur}: &{cur} [" + ", ".join([f"*{prev}"] * 9) + "]")
    return "\n".join(lines) + "\n"


def _make(tmp_path: Path, case: str, suffix: str) -> Path:
    """A hostile user file: its name ends in ``suffix`` whatever it is."""
    path = tmp_path / f"{case}{suffix}"
    if case == "pipe":
        os.mkfifo(path)
    elif case == "device":
        os.symlink("/dev/zero", path)
    elif case == "folder":
        path.mkdir()
    elif case == "huge":  # 100 MB (sparse): read up to the cap only
        with open(path, "wb") as f:
            f.truncate(100 << 20)
    elif case == "not-utf8":
        path.write_bytes("caf\xe9: [0, 0, 0]\n".encode("latin-1"))
    elif case == "bomb":
        path.write_text(_laughs())
    elif case == "duplicate-foot":
        path.write_text("tibia_lf: [0, 0.16, 0.029]\ntibia_lf: [0, 0.2, 0]\n")
    elif case == "duplicate-offset":
        path.write_text("defaults: {units: rad}\njoints:\n  j1: {offset: 0.1, offset: 0.3}\n")
    elif case == "offset-text":
        path.write_text("defaults: {units: rad}\njoints:\n  j1: {offset: '0.3'}\n")
    elif case == "us-per-rad-1e308":
        path.write_text("defaults: {units: us, us_per_rad: 1e308, centre: 1500}\n")
    elif case == "resolution-1e-320":
        path.write_text("defaults: {units: ticks, ticks_per_revolution: 4096, centre: 2048, "
                        "resolution: 1e-320}\n")  # fmt: skip
    elif case == "duplicate-json":
        path.write_text('{"t": [0, 1], "q": [[0], [1]], "t": [0, 2]}')
    return path


PHRASES = {
    "pipe": "is a named pipe",
    "device": "is a device",
    "folder": "is a folder",
    "huge": "more than",
    "not-utf8": "not UTF-8 text",
    "bomb": "more than 64 YAML aliases",
    "duplicate-foot": "key 'tibia_lf' given twice",
    "duplicate-offset": "key 'offset' given twice",
    "offset-text": "offset='0.3' is not a finite number",
    "duplicate-json": "key 't' given twice",
    "us-per-rad-1e308": "us_per_rad 1e+308 maps two turns to inf us",
    "resolution-1e-320": "resolution 1e-320 is too fine",
}
COMMANDS = {
    # name: (hostile cases, suffix, the command line with {f} the hostile file)
    "stand --foot": (
        ("pipe", "device", "folder", "huge", "not-utf8", "bomb", "duplicate-foot"),
        ".yaml",
        ("stand", str(PHX), "--foot", "{f}"),
    ),
    "gait --foot": (("bomb", "pipe"), ".yaml", ("gait", str(PHX), "--foot", "{f}")),
    "simulate --foot": (("bomb", "device"), ".yaml", ("simulate", str(PHX), "--foot", "{f}")),
    "timeline --calibration": (
        (
            "pipe",
            "device",
            "not-utf8",
            "bomb",
            "duplicate-offset",
            "offset-text",
            "us-per-rad-1e308",
            "resolution-1e-320",
        ),  # fmt: skip
        ".yaml",
        ("timeline", "path", "plan.csv", "--calibration", "{f}", "-o", "out.csv"),
    ),
    "timeline path": (
        ("pipe", "folder", "not-utf8", "duplicate-json"),
        ".json",
        ("timeline", "path", "{f}", "-o", "out.csv"),
    ),
}
CHILD_CASES = [(cmd, case) for cmd, (cases, _, _) in COMMANDS.items() for case in cases]


@pytest.mark.slow
@pytest.mark.parametrize(("command", "case"), CHILD_CASES, ids=[f"{c}-{k}" for c, k in CHILD_CASES])
def test_hostile_user_file_on_the_command_line(tmp_path: Path, command: str, case: str) -> None:
    """One line, exit 2, within 1 s of CPU and 1 GB (the probe: 23.6 s and 2.3 GB for a bomb).

    In this process (``main(argv)``, :func:`test_hostile_cli.here`), but a named pipe in a
    child: were it opened, it would wait for a writer, and the child is killed past 60 s.
    """
    _, suffix, argv = COMMANDS[command]
    (tmp_path / "plan.csv").write_text("t,j1\n0,0\n1,0.1\n")
    path = _make(tmp_path, case, suffix)
    args = [a.format(f=path.name) for a in argv]
    run = cli(*args, cwd=tmp_path, timeout=60.0) if case == "pipe" else here(*args, cwd=tmp_path)
    status, err, cpu, peak = run.status, run.stderr, run.cpu, run.peak
    lines = err.strip().splitlines()
    assert status == 2 and len(lines) == 1, err
    assert lines[0].startswith("hexapod-kin: error: ") and PHRASES[case] in lines[0], lines[0]
    assert path.name in lines[0] and "a bug" not in err, lines[0]
    assert cpu < 1.0, f"{cpu:.2f} s of CPU"
    assert peak < 1 << 30, f"peak RSS {peak / 2**20:.0f} MB"
