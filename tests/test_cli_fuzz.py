"""Every subcommand × a battery of bad arguments: one error line, exit status 2, no traceback.

The subcommands are discovered from the parser, so a new command is fuzzed as soon as it is
registered. Runs in process (``main(argv)``) for speed, plus a few end-to-end runs of the
installed console script (closed pipe, unwritable paths).
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys

import pytest

from hexapod_kin.cli import build_parser, main

# Minimal valid arguments of commands that need more than a SOURCE (others: SOURCE = a preset).
BASE_ARGS: dict[str, list[str]] = {
    "ik": ["ik", "hexabot_leg", "--target", "0.15", "0.05", "-0.1"],
    # without --html, animate serves a live viewer until Ctrl-C
    "animate": ["animate", "hexabot_leg", "--html", "/tmp/hk-fuzz-animate.html"],
    "export-package": ["export-package", "hexabot_leg", "--out", "/tmp/hk-fuzz-pkg"],
    "mjcf": ["mjcf", "hexabot_leg", "-o", "/tmp/hk-fuzz.xml"],
    "sweep": [
        "sweep",
        "--l1",
        "0.04:0.06:2",
        "--l2",
        "0.1:0.1:1",
        "--l3",
        "0.1:0.1:1",
        "--height",
        "0.1",
    ],
}
# commands that serve or run long: only the parser-level checks
PARSER_ONLY = {"view", "drive", "reproduce", "sweep"}


def _subparsers() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser()
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    raise AssertionError("no subcommands")


SUBS = _subparsers()
COMMANDS = sorted(SUBS)


def _positionals(name: str) -> list[str]:
    return [
        a.dest
        for a in SUBS[name]._actions
        if not a.option_strings and a.dest != "help" and a.nargs != "?"
    ]


def _required_options(name: str) -> list[str]:
    return [a.dest for a in SUBS[name]._actions if a.option_strings and a.required]


def _base(name: str) -> list[str] | None:
    if name in BASE_ARGS:
        return list(BASE_ARGS[name])
    if _required_options(name):
        return None
    pos = _positionals(name)
    if not pos:
        return [name]
    if pos in (["source"], ["preset"]):
        return [name, "hexabot_leg"]
    return None


def _numeric_options(name: str) -> list[tuple[str, int]]:
    out = []
    for a in SUBS[name]._actions:
        if a.option_strings and a.type in (float, int):
            n = a.nargs if isinstance(a.nargs, int) else 1
            out.append((max(a.option_strings, key=len), n))
    return out


def _run(capsys, argv):
    code = main(argv)
    cap = capsys.readouterr()
    return code, cap.out, cap.err


def _assert_one_line_error(code, err, argv):
    assert code == 2, f"{argv}: exit {code}, stderr {err!r}"
    assert "Traceback" not in err, f"{argv}: traceback\n{err}"
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1, f"{argv}: expected one error line, got {lines}"
    assert "error" in lines[0]


def test_every_command_is_fuzzed():
    assert {"list", "urdf", "fk", "jacobian", "scan", "derive", "step", "ik"} <= set(COMMANDS)


@pytest.mark.parametrize("name", COMMANDS)
def test_unknown_option(capsys, name):
    argv = (_base(name) or [name]) + ["--no-such-option"]
    code, _, err = _run(capsys, argv)
    _assert_one_line_error(code, err, argv)


@pytest.mark.parametrize("name", [n for n in COMMANDS if _positionals(n)])
def test_missing_positional(capsys, name):
    code, _, err = _run(capsys, [name])
    _assert_one_line_error(code, err, [name])


@pytest.mark.parametrize(
    "name",
    [n for n in COMMANDS if _positionals(n) in (["source"], ["preset"]) and _base(n)],
)
def test_unknown_source(capsys, name):
    argv = [name, "no_such_robot_xyz"]
    if name in BASE_ARGS:
        argv += BASE_ARGS[name][2:]
    code, _, err = _run(capsys, argv)
    _assert_one_line_error(code, err, argv)
    assert "no_such_robot_xyz" in err


@pytest.mark.parametrize("name", [n for n in COMMANDS if _numeric_options(n)])
def test_non_numeric_values(capsys, name):
    base = _base(name) or [name]
    for option, n in _numeric_options(name):
        argv = base + [option] + ["abc"] * n
        code, _, err = _run(capsys, argv)
        _assert_one_line_error(code, err, argv)


@pytest.mark.parametrize(
    "name",
    [n for n in COMMANDS if _numeric_options(n) and n not in PARSER_ONLY and _base(n)],
)
def test_nan_values_refused(capsys, name):
    base = _base(name)
    assert base is not None
    for option, n in _numeric_options(name):
        if option in ("--seed",):
            continue
        argv = base + [option] + ["nan"] * n
        if option == "--q":
            argv = base + [option] + ["nan"] * 3
        code, out, err = _run(capsys, argv)
        _assert_one_line_error(code, err, argv)


def _path_options(name: str) -> list[str]:
    found = []
    for a in SUBS[name]._actions:
        for s in a.option_strings:
            if s in ("--plot", "--html", "-o", "--out", "--output"):
                found.append(s)
                break
    return found


@pytest.mark.parametrize(
    "name", [n for n in COMMANDS if _path_options(n) and n not in PARSER_ONLY and _base(n)]
)
def test_unwritable_outputs(capsys, name, tmp_path):
    base = _base(name)
    assert base is not None
    suffix = {"--plot": "x.png", "--html": "x.html"}
    for option in _path_options(name):
        target = str(tmp_path / "missing-dir" / suffix.get(option, "x.urdf"))
        if option == "--out" and name != "urdf":
            target = "/proc/no-such-dir/out"
        argv = base + [option, target]
        code, _, err = _run(capsys, argv)
        _assert_one_line_error(code, err, argv)
        assert ".tmp" not in err


def test_plot_format_refused(capsys):
    argv = ["scan", "hexabot_leg", "--grid", "5", "--plot", "map.bmpx"]
    code, _, err = _run(capsys, argv)
    _assert_one_line_error(code, err, argv)
    assert ".png" in err


def test_set_bad_value(capsys):
    argv = ["fk", "hexabot_leg", "--set", "l1=abc"]
    code, _, err = _run(capsys, argv)
    _assert_one_line_error(code, err, argv)
    assert "l1" in err


def test_help_exits_zero(capsys):
    for name in COMMANDS:
        assert main([name, "--help"]) == 0
        out = capsys.readouterr().out
        assert "usage" in out
        # each default said once, and never an empty "(default: None)"
        flat = " ".join(out.split())
        assert "(default: None)" not in flat, name
        assert not re.search(r"\(default: [^)]*\) \(default:", flat), name
        assert "--dt" not in flat or "(default: 0.001)" in flat, name


@pytest.mark.skipif(
    shutil.which("hexapod-kin") is None and not sys.executable,
    reason="console script not installed",
)
def test_closed_pipe_is_quiet():
    exe = [sys.executable, "-m", "hexapod_kin"]
    proc = subprocess.run(
        exe + ["fk", "hexabot_leg", "--q", "0.1", "0.2", "0.3"] + [],
        capture_output=True,
        timeout=600,
    )
    assert proc.returncode == 0
    # close stdout after the first line: `| head -1`
    shell = subprocess.run(
        " ".join(exe) + " fk hexapod --q " + " ".join(["0.1"] * 18) + " | head -1",
        shell=True,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert "Traceback" not in shell.stderr and "BrokenPipe" not in shell.stderr, shell.stderr


# --------------------------------------------------------------------- the exit-status rule
#: (argv, status): 0 achieved, 1 answered but not achieved, 2 bad input or failure.
EXIT_RULE = [
    (["ik", "hexabot_leg", "--target", "0.15", "0.05", "-0.1"], 0),  # reached (closed form)
    (["ik", "hexabot_leg", "--target", "1", "0", "0"], 1),  # unreachable: nearest printed
    (["ik", "hexabot_leg", "--target", "1", "0"], 2),  # bad input
    (["step", "hexabot_leg", "--duration", "0.3", "--no-baseline"], 0),
    (["step", "hexabot_leg", "--velocity", "0.5", "0", "0", "--duration", "1"], 1),  # limits
    (["step", "hexabot_leg", "--velocity", "0.5", "0"], 2),
    (["gait", "--duration", "1"], 0),
    (["gait", "--stride", "0.4", "--duration", "1"], 1),  # a check fails: not walkable
    (["gait", "--pattern", "gallop"], 2),
    (["fk", "hexabot_leg", "--q", "0", "0", "0"], 0),
    (["fk", "hexabot_leg", "--q", "0", "0"], 2),
]


@pytest.mark.parametrize(("argv", "status"), EXIT_RULE, ids=lambda v: str(v))
def test_exit_status_rule(capsys, argv, status):
    assert main(argv) == status
    cap = capsys.readouterr()
    err = [ln for ln in cap.err.splitlines() if ln.startswith("hexapod-kin")]
    if status == 2:  # one line on stderr says why
        assert len(err) == 1 and "error" in err[0], cap.err
    elif status == 1:  # the answer says what was not achieved
        said = (cap.out + cap.err).lower()
        assert any(w in said for w in ("unreachable", "limits", "not achieved")), said
