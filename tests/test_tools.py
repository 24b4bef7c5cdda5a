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


def _number(value: Any) -> float | None:
    """A measured figure as a float (capped peers print '>1.8'); None for anything else."""
    if isinstance(value, bool):
        return None
    if isinstance(value, (int, float)):
        return float(value) if math.isfinite(value) else None
    if isinstance(value, str):
        m = re.fullmatch(r"[<>]?\s*([0-9.]+(?:e[+-]?\d+)?)", value.strip())
        return float(m.group(1)) if m else None
    return None


#: A row's own time, by the name the sections give it (first present wins).
OWN_TIME = ("solve_per_call_median_us", "median_us", "s", "best_s", "median_s")


def _speedup_parts(row: dict[str, Any]) -> tuple[float, float] | None:
    """(peer, own) times of a row with one peer time and its own, in the same unit."""
    own_key = next((k for k in OWN_TIME if _number(row.get(k)) is not None), None)
    if own_key is None:
        return None
    unit = "_us" if own_key.endswith("_us") else "_s"
    peers = [
        k
        for k, v in row.items()
        if k.startswith("peer_") and k.endswith(unit) and _number(v) is not None
    ]
    if len(peers) != 1 or isinstance(row[peers[0]], str):  # a capped peer ('>1.8') has no value
        return None
    return float(row[peers[0]]), float(row[own_key])


def check_rows(section: str, rows: list[dict[str, Any]]) -> int:
    """Every figure a row states, checked against what it is made of; the ratios checked."""
    checked = 0
    for row in rows:
        assert "error" not in row, f"a row of {section} failed: {row}"
        measured = {k: _number(v) for k, v in row.items() if k not in ("section", "row")}
        assert any(v is not None for v in measured.values()), f"row without a figure: {row}"
        # a rate is a fraction of the poses, and never below the row's own target
        for key, value in measured.items():
            if value is not None and key.endswith("success") and not key.startswith("target"):
                assert 0.0 <= value <= 1.0, (key, row)
        if "success" in row and "target_success" in row:
            assert row["success"] >= row["target_success"], row
        # a speedup is the peer's time over the row's own time (both as rounded in the row)
        parts = _speedup_parts(row)
        speedup = _number(row.get("speedup"))
        if parts is not None and speedup is not None and parts[1] > 0:
            peer, own = parts
            assert speedup == pytest.approx(peer / own, rel=0.1, abs=0.1), row
            checked += 1
    return checked


def test_check_rows_refuses_wrong_figures() -> None:
    """The row check fails on a wrong ratio, a failed row, a rate out of [0, 1] (self-test)."""
    good = {"row": "x", "s": 0.02, "peer_pinocchio_loop_s": 0.5, "speedup": 25.0}
    assert check_rows("t", [good]) == 1
    for bad in (
        good | {"speedup": 2.5},  # ratio not peer / own
        good | {"error": "boom"},
        {"row": "ik", "median_us": 9.0, "success": 1.7, "target_success": 0.99},
        {"row": "ik", "median_us": 9.0, "success": 0.9, "target_success": 0.999},
        {"row": "nothing", "note": "not measured"},
    ):
        with pytest.raises(AssertionError):
            check_rows("t", [bad])


@pytest.mark.slow
@pytest.mark.parametrize("section", bench.SECTIONS)
def test_bench_quick_prints_ratios_for_every_section(section: str) -> None:
    if section == "percall":  # its only peer is Robotics Toolbox (the `bench` extra; .ci/run)
        pytest.importorskip("roboticstoolbox", reason="the bench extra is not installed")
    rows = _quick(section)
    compared = [
        r for r in rows if any(COMPARISON.search(k) and (_number(v) or 0) > 0 for k, v in r.items())
    ]
    assert compared, f"no row of section {section} compares against a peer: {rows[:2]}"
    check_rows(section, rows)
    if section == "spine":
        per_call = [r for r in rows if "raw_pin_fk+jac_us" in r]
        batch = [r for r in rows if "batch" in r]
        assert per_call and batch
        # each ratio is the quotient of the row's own two times (as rounded in the row)
        for r in per_call:
            raw = r["raw_pin_fk+jac_us"]
            assert r["ratio"] == pytest.approx(r["hexapod_kin_fk+jacobian_us"] / raw, rel=0.02)
            assert r["ratio_fused"] == pytest.approx(
                r["hexapod_kin_fk_jacobian_fused_us"] / raw, rel=0.02
            )
        for r in batch:
            assert r["speedup_fk"] == pytest.approx(
                r["raw_pin_loop_fk_s"] / r["fk_batch_s"], rel=0.05
            )
            assert r["speedup_jac"] == pytest.approx(
                r["raw_pin_loop_jac_s"] / r["jacobian_batch_s"], rel=0.05
            )
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
