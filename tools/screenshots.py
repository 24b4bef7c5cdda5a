"""Screenshots of the viewer for the docs: the hexapod standing, and a leg mid-step.

Exports each scene with :func:`hexapod_kin.viewer.export_html`, opens it from disk in headless
Debian Chromium (Playwright, every network request blocked), seeks the animation and saves
the page as a PNG.

    python tools/screenshots.py                 # writes docs/img/hexapod.png, docs/img/leg_step.png
    python tools/screenshots.py --out /tmp/img --keep-html
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from hexapod_kin import gait, load, viewer

sys.path.insert(0, str(Path(__file__).resolve().parent))
from headless import chromium  # noqa: E402

from hexapod_kin._io import atomic_write

ROOT = Path(__file__).resolve().parent.parent


def hexapod_scene(out: Path) -> tuple[Path, float]:
    """The hexapod standing on its six feet, body swaying (feet fixed by the leg IK)."""
    model = load("hexapod")
    times, qs, base = gait.demo_trajectory(model, duration=4.0, samples=81)
    path = viewer.export_html(
        model,
        times,
        qs,
        out / "hexapod.html",
        base_poses=base,
        trace_frame=False,
        title="hexapod_kin: hexapod (body sway)",
    )
    return path, 0.6


def leg_step_scene(out: Path) -> tuple[Path, float]:
    """The 3-DOF leg in mid-swing of a foot step (stance line + half-ellipse swing)."""
    model = load("hexabot_leg")
    step = gait.foot_step(model, length=0.06, height=0.04, duration=1.0, dt=0.01)
    sigma = np.array(
        [np.linalg.svd(model.position_jacobian(q), compute_uv=False)[-1] for q in step.q]
    )
    path = viewer.export_html(
        model,
        step.t,
        step.q,
        out / "leg_step.html",
        frame_triads=True,
        singular_mask=sigma < 1e-3,
        title="hexapod_kin: hexabot_leg, foot step (mid-swing)",
    )
    return path, 0.75  # duty factor 0.5: swing from t = 0.5 s to 1 s, top at 0.75 s


def shoot(
    html: Path, png: Path, t: float, size: tuple[int, int] = (1000, 700), browser: Any = None
) -> Path:
    """Open ``html`` offline in headless Chromium, seek to ``t`` [s], save a PNG.

    ``browser``: a Playwright browser to reuse (default: launch Debian's ``chromium``).
    """
    if browser is None:
        with chromium() as own:
            return shoot(html, png, t, size, own)
    blocked: list[str] = []
    page = browser.new_page(viewport={"width": size[0], "height": size[1]})
    try:

        def route(r: Any) -> None:
            if r.request.url.startswith("file://"):
                r.continue_()
            else:
                blocked.append(r.request.url)
                r.abort()

        page.route("**/*", route)
        page.goto(html.resolve().as_uri())
        page.wait_for_function("() => window.hexapodKin && window.hexapodKin.ready", timeout=60000)
        page.evaluate(
            "document.querySelector('.dg.main') && "
            "(document.querySelector('.dg.main').style.display = 'none')"
        )
        page.evaluate(f"hexapodKin.seek({t})")
        page.wait_for_timeout(400)
        data = page.screenshot()
    finally:
        page.close()
    if blocked:
        raise SystemExit(f"screenshots: the page requested {blocked}")
    return atomic_write(png, data)


def main(argv: list[str] | None = None, browser: Any = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(ROOT / "docs" / "img"), help="output directory")
    parser.add_argument("--keep-html", action="store_true", help="also keep the HTML pages")
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        pages = Path(args.out) if args.keep_html else Path(tmp)
        for scene, name in ((hexapod_scene, "hexapod.png"), (leg_step_scene, "leg_step.png")):
            html, t = scene(pages)
            png = shoot(html, out / name, t, browser=browser)
            print(f"wrote {png}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
