"""Tools run as smoke tests: the benchmark harness in quick mode prints its ratios."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_bench_quick_prints_ratios_for_every_section():
    res = subprocess.run(
        [sys.executable, str(ROOT / "tools" / "bench.py"), "--quick", "--json"],
        capture_output=True, text=True, timeout=600,
    )
    assert res.returncode == 0, res.stderr
    rows = json.loads(res.stdout.strip().splitlines()[-1])
    sections = {r["section"] for r in rows}
    assert {"spine", "singularity", "ik", "viewer"} <= sections
    spine = [r for r in rows if r["section"] == "spine"]
    assert all(r["ratio"] > 0 and r["raw_pin_fk+jac_us"] > 0 for r in spine)
