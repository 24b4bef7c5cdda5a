"""Screenshots of the cockpit (``hexapod-kin drive``) for the docs, one per mode.

Serves :func:`hexapod_kin.drive.drive` on 127.0.0.1, opens the page in headless Debian
Chromium (Playwright, software GL), drives each mode through the page and saves a PNG:

    python tools/drive_screenshots.py      # docs/img/drive_{joints,...,physics}.png,
                                           # drive_joints_legged.png, drive_physics_solo12.png
    python tools/drive_screenshots.py --out /tmp/img
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))
from headless import chromium  # noqa: E402

from hexapod_kin.drive import drive  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent


def _open(browser: Any, url: str) -> Any:
    page = browser.new_page(viewport={"width": 1100, "height": 680})
    page.goto(url)
    page.wait_for_function("() => window.hexapodKin && hexapodKin.ready && hexapodKin.state")
    page.evaluate("hexapodKin.fixResolution(1)")  # full resolution, not the adapted one
    return page


def _wait(page: Any, expr: str) -> None:
    page.wait_for_function(f"() => ({expr})", timeout=60000)


def _legged_with_families(source: str) -> Any:
    """The robot loaded, its legs' singular families derived (the cockpit only looks up)."""
    from hexapod_kin import load
    from hexapod_kin.drive import Cockpit
    from hexapod_kin.singularity import default_rows, families_for

    model = load(source)
    for view in Cockpit(model).leg_views:
        families_for(view, default_rows(view), derive=True)
    return model


def shoot(out: Path) -> list[Path]:
    """Write the seven screenshots to ``out``; return their paths."""
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    with chromium() as browser:
        with drive("hexabot_leg") as s:  # joints, then a target the leg stops short of
            page = _open(browser, s.url)
            _wait(page, "hexapodKin.state.readout.family !== null")
            for j, v in ((1, 0.7), (2, 0.15)):  # the ankle near q3 = 0: the family drawn
                page.evaluate(
                    "([j, v]) => { const k = document.getElementById('hk-joint-' + j);"
                    " k.value = v; k.dispatchEvent(new Event('input')); }",
                    [j, v],
                )
            time.sleep(1.5)
            paths.append(out / "drive_joints.png")
            page.screenshot(path=str(paths[-1]))
            limb = s.cockpit.limbs[0]
            s.set_target(limb.hip(s.cockpit.q, s.cockpit.base) + [0.2, 0.22, -0.12])
            _wait(page, "hexapodKin.state.readout.status !== 'moving'")
            time.sleep(1.0)
            paths.append(out / "drive_target.png")
            page.screenshot(path=str(paths[-1]))
        with drive("hexapod") as s:  # body pitched and rolled, feet held
            page = _open(browser, s.url)
            page.click("#hk-mode-body")
            for name, value in (("pitch", 0.2), ("roll", -0.12), ("z", 0.02)):
                page.evaluate(
                    "([n, v]) => { const k = document.getElementById('hk-body-' + n); k.value = v;"
                    " k.dispatchEvent(new Event('input')); }",
                    [name, value],
                )
            time.sleep(1.5)
            paths.append(out / "drive_body.png")
            page.screenshot(path=str(paths[-1]))
        legged = _legged_with_families("hexapod")
        with drive(legged) as s:  # a leg's knee/ankle near straight: its family drawn
            page = _open(browser, s.url)
            j = legged.joint_names.index("leg2_ankle")
            page.evaluate(
                "([j]) => { const k = document.getElementById('hk-joint-' + j);"
                " k.value = 0.12; k.dispatchEvent(new Event('input')); }",
                [j],
            )
            _wait(page, "hexapodKin.overlays.ghost.visible")
            time.sleep(1.0)
            paths.append(out / "drive_joints_legged.png")
            page.screenshot(path=str(paths[-1]))
        with drive("hexapod") as s:  # walking forward and turning
            page = _open(browser, s.url)
            page.keyboard.down("w")
            page.keyboard.down("q")
            time.sleep(2.5)
            paths.append(out / "drive_walk.png")
            page.screenshot(path=str(paths[-1]))
            page.keyboard.up("w")
            page.keyboard.up("q")
        for robot, name in (("hexapod", "drive_physics"), ("erd:solo12", "drive_physics_solo12")):
            with drive(robot) as s:  # physics: walking in MuJoCo, pushed by a click
                page = _open(browser, s.url)
                page.click("#hk-mode-physics")
                _wait(page, "hexapodKin.state.readout.mode === 'physics'")
                page.keyboard.down("w")
                time.sleep(1.5)
                page.mouse.click(700, 300)
                time.sleep(0.3)
                paths.append(out / f"{name}.png")
                page.screenshot(path=str(paths[-1]))
                page.keyboard.up("w")
    return paths


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "img")
    args = ap.parse_args(argv)
    for path in shoot(args.out):
        print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
