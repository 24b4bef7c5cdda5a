"""Hostile robot names in every page the command line writes (issue 35), as real children.

A URDF whose file name (the model's name, the pages' default title) holds every template hole
and markup this package ever used is shown by ``animate --html``, walked by ``gait --html``,
simulated by ``simulate --html`` and animated by ``step --html``. Each is one
``python -m hexapod_kin`` child measured with ``os.wait4`` (peak RSS, CPU time): exit 0, at
most two stderr lines (the gate's own warnings about the robot), no traceback and no
catch-all; the page read back by an independent HTML parser shows the name literally in its
title and carries no comment and no script but the package's own.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from test_hostile_cli import CATCH_ALL, LIMIT_BYTES, cli
from test_pages import HOSTILE, _Read

import hexapod_kin as hk

pytest.importorskip("meshcat")
DATA = Path(__file__).parent / "data" / "phantomx" / "phantomx.urdf"
FEET = [
    a for s in ("lf", "lm", "lr", "rf", "rm", "rr") for a in ("--foot", f"tibia_{s}:0,0.16,0.029")
]
NAME = HOSTILE.replace("/", "")
#: Only a guard against a hang (the machine may be busy): nothing asserts wall time.
HANG = 300.0


def _clean(run, page: Path, name: str) -> None:
    assert run.status == 0, run.stderr
    assert run.peak < LIMIT_BYTES, f"peak RSS {run.peak / 2**20:.0f} MB"
    assert CATCH_ALL not in run.stderr and "Traceback" not in run.stderr, run.stderr
    warnings = [ln for ln in run.lines if not ln.startswith("wrote ")]
    assert len(warnings) <= 2, run.stderr
    seen = _Read(page.read_text(encoding="utf-8"))
    assert name in seen.title, seen.title
    assert not seen.comments
    for attrs in seen.frames:  # a page inside a frame is held to the same rule
        inner = _Read(attrs.get("srcdoc") or "")
        assert not inner.comments


@pytest.fixture()
def leg(tmp_path: Path) -> Path:
    path = tmp_path / f"{NAME}.urdf"
    path.write_text(hk.to_urdf(hk.robots.hexabot_leg()), encoding="utf-8")
    return path


@pytest.fixture()
def hexapod(tmp_path: Path) -> Path:
    path = tmp_path / f"{NAME}.urdf"
    shutil.copy(DATA, path)
    return path


def test_animate_page_of_a_hostile_name(leg: Path, tmp_path: Path) -> None:
    run = cli(
        "animate", leg.name, "--samples", "11", "--html", "v.html", cwd=tmp_path, timeout=HANG
    )
    _clean(run, tmp_path / "v.html", leg.name)


def test_step_page_of_a_hostile_name(leg: Path, tmp_path: Path) -> None:
    run = cli(
        "step",
        leg.name,
        "--q",
        "0",
        "0.3",
        "1.2",
        "--duration",
        "0.2",
        "--html",
        "s.html",
        cwd=tmp_path,
        timeout=HANG,
    )
    _clean(run, tmp_path / "s.html", leg.name)


def test_gait_page_of_a_hostile_name(hexapod: Path, tmp_path: Path) -> None:
    run = cli(
        "gait",
        hexapod.name,
        *FEET,
        "--duration",
        "0.5",
        "--html",
        "g.html",
        cwd=tmp_path,
        timeout=HANG,
    )
    _clean(run, tmp_path / "g.html", "")


@pytest.mark.slow
def test_simulate_page_of_a_hostile_name(hexapod: Path, tmp_path: Path) -> None:
    run = cli(
        "simulate",
        hexapod.name,
        *FEET,
        "--duration",
        "0.5",
        "--html",
        "m.html",
        cwd=tmp_path,
        timeout=HANG,
    )
    _clean(run, tmp_path / "m.html", "")
