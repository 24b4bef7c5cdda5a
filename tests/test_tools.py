"""Tools run as smoke tests: the benchmark harness in quick mode, section by section.

Every section of ``tools/bench.py`` must run, print JSON rows, and carry a comparison in
them: a ratio or speedup against a peer measured in the same run (or a figure beside its
target). Timing values are never asserted (they are the benchmark's output, not a test);
correctness columns that the sections compute against Pinocchio are.
"""

from __future__ import annotations

import json
import math
import re
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tools"))

import bench  # noqa: E402

COMPARISON = re.compile(r"ratio|speedup|peer|vs_|bare|raw_pin")


def _quick(section: str) -> list[dict[str, Any]]:
    res = subprocess.run(
        [sys.executable, str(ROOT / "tools" / "bench.py"), "--quick", "--json", "--only", section],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert res.returncode == 0, res.stderr[-2000:]
    assert "skipped" not in res.stderr, res.stderr[-2000:]
    rows = json.loads(res.stdout.strip().splitlines()[-1])
    assert rows, f"section {section} printed no rows"
    assert all(r["section"] == section for r in rows)
    return rows


def _positive_number(value: Any) -> bool:
    if isinstance(value, bool):
        return False
    if isinstance(value, (int, float)):
        return math.isfinite(value) and value > 0
    if isinstance(value, str):  # capped peers print '>1.8'
        m = re.fullmatch(r"[<>]?\s*([0-9.]+(?:e[+-]?\d+)?)", value.strip())
        return bool(m) and float(m.group(1)) > 0
    return False


@pytest.mark.parametrize("section", bench.SECTIONS)
def test_bench_quick_prints_ratios_for_every_section(section: str) -> None:
    rows = _quick(section)
    compared = [
        r for r in rows if any(COMPARISON.search(k) and _positive_number(v) for k, v in r.items())
    ]
    assert compared, f"no row of section {section} compares against a peer: {rows[:2]}"
    for row in rows:
        measured = [k for k, v in row.items() if k != "section" and _positive_number(v)]
        assert measured, f"row without a measured figure: {row}"
    if section == "spine":
        per_call = [r for r in rows if "raw_pin_fk+jac_us" in r]
        batch = [r for r in rows if "batch" in r]
        assert per_call and all(r["ratio"] > 0 and r["raw_pin_fk+jac_us"] > 0 for r in per_call)
        assert batch and all(r["speedup_fk"] > 0 and r["speedup_jac"] > 0 for r in batch)
        # the batch kernels agree with Pinocchio (a correctness column, not a timing)
        assert all(float(r["max_err_vs_pin"]) < 1e-9 for r in batch)
    if section == "startup":
        # every timed command really ran (a failing command would time its error message)
        assert all(r["exit"] == 0 for r in rows), [r for r in rows if r["exit"] != 0]
        assert {r["mode"] for r in rows} == {"cold", "warm"}
        assert all(r["min_s"] <= r["median_s"] <= r["max_s"] for r in rows)


def test_startup_commands_cover_every_subcommand() -> None:
    import argparse
    import importlib

    import bench_startup

    from hexapod_kin import cli

    parser = argparse.ArgumentParser(prog="hexapod-kin")
    sub = parser.add_subparsers(dest="command")
    for module in cli.MODULES:  # what cli.build_parser does: each area registers its commands
        importlib.import_module(f"hexapod_kin.cli.{module}").register(sub)
    names = list(sub.choices)
    assert names, "no subcommand registered"
    timed = {argv[0] for argv in bench_startup.COMMANDS.values()}  # keys may name variants
    assert set(names) - set(bench_startup.UNTIMED) <= timed
    assert timed <= set(names)
