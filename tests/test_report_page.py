"""The report page as a reader sees it: headless Chromium, with and without WebGL.

Every fact is read from the rendered DOM (layout, visibility, text), never from the HTML
source: matrices laid out as tables with the differing entries marked, no Markdown or Python
``repr`` in the visible text, every claim linked to its lines of the shipped seed text, and
without WebGL a message and the still frame in place of each animation. The page must load
nothing from the network.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from hexapod_kin.report import load_claims, reproduce
from hexapod_kin.report.data import seed_file

pytestmark = [pytest.mark.browser, pytest.mark.slow]

#: Flags that take WebGL away (as in a browser or VM without a GPU or software fallback).
NO_WEBGL = ("--disable-webgl", "--disable-3d-apis")


@pytest.fixture(scope="module")
def report(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict]:
    out = tmp_path_factory.mktemp("page")
    rep = reproduce(out, quick=True)  # replays test_report's build when this worker made it
    assert rep.counts["error"] == 0
    return out / "report.html", json.loads((out / "verdicts.json").read_text())


def _open(playwright_api, page_path: Path, extra: tuple[str, ...] = ()):
    from headless import launch_chromium

    browser = launch_chromium(*playwright_api, extra)
    page = browser.new_page(viewport={"width": 1200, "height": 900})
    requests: list[str] = []
    page.on("request", lambda r: requests.append(r.url))
    page.goto(page_path.as_uri())
    page.wait_for_load_state("load")
    return browser, page, requests


def _visible_text(page) -> str:
    """The page's rendered text but the seeds' own texts (quoted verbatim, Markdown included)."""
    return page.evaluate(
        "() => { const c = document.body.cloneNode(true);"
        " c.querySelectorAll('pre.seed').forEach(e => e.remove());"
        " document.body.appendChild(c); const t = c.innerText; c.remove(); return t; }"
    )


def test_page_without_webgl(playwright_api, report) -> None:
    page_path, data = report
    browser, page, requests = _open(playwright_api, page_path, NO_WEBGL)
    try:
        assert page.evaluate("document.documentElement.dataset.webgl") == "no"
        anims = page.locator(".anim")
        assert anims.count() == 2
        for i in range(2):
            a = anims.nth(i)
            msg = a.locator(".nogl")
            assert msg.is_visible()
            assert "This browser has no WebGL: showing a still frame" in msg.inner_text()
            still = a.locator("img.still")
            assert still.is_visible()
            box = still.bounding_box()
            assert box["width"] > 300 and box["height"] > 200
            assert page.evaluate(
                "(e) => e.complete && e.naturalWidth > 300", still.element_handle()
            )
            assert a.locator("iframe").count() == 0 and not a.locator("button.play").is_visible()
        assert not [u for u in requests if not u.startswith(("file:", "data:", "blob:", "about:"))]
    finally:
        browser.close()


def test_page_with_webgl_matrices_text_and_links(playwright_api, report) -> None:
    page_path, data = report
    browser, page, requests = _open(playwright_api, page_path)
    try:
        assert page.evaluate("document.documentElement.dataset.webgl") == "yes"
        # --- matrices: two tables per verdict with cells, the seed's shape, marks where they differ
        for v in data["verdicts"]:
            cells = v["cells"]
            item = page.locator(f"[id='{v['claim']}']")
            tables = item.locator("table.mat")
            if cells is None:
                assert tables.count() == 0, v["claim"]
                continue
            assert tables.count() == 2, v["claim"]
            header = 1 if cells.get("header") else 0
            for k, rows in enumerate((cells["seed"], cells["ours"])):
                t = tables.nth(k)
                assert t.locator("tr").count() == len(rows) + header, v["claim"]
                # laid out: the rows stack (each row lower than the one before)
                ys = [t.locator("tr").nth(r).bounding_box()["y"] for r in range(len(rows))]
                assert ys == sorted(ys) and len(set(ys)) == len(ys)
                marked = t.locator("td.diff")
                assert marked.count() == len(cells["differ"]), v["claim"]
                for i, j in sorted(map(tuple, cells["differ"])):
                    cell = t.locator("tr").nth(i + header).locator("td").nth(j)
                    assert "diff" in (cell.get_attribute("class") or "")
                    bg = page.evaluate(
                        "(e) => getComputedStyle(e).backgroundColor", cell.element_handle()
                    )
                    assert bg not in ("rgba(0, 0, 0, 0)", "transparent")
        assert page.locator("td.diff").count() == 2 * sum(
            len(v["cells"]["differ"]) for v in data["verdicts"] if v["cells"]
        )
        # --- no Markdown, no Python repr in what a reader sees
        text = _visible_text(page)
        assert "`" not in text and "{'" not in text and not re.search(r"\*\*[A-Za-z]", text)
        assert "standing height [m]" in text and "stand_height_m" not in text
        # --- the legend explains and the summary counts the underdetermined verdicts
        assert "underdetermined" in page.locator("dl.legend").inner_text()
        n = sum(v["status"] == "underdetermined" for v in data["verdicts"])
        assert f"{n} underdetermined" in page.locator("body > p").first.inner_text()
        # --- every claim links to its passage; following a link opens the seed at that line
        claims, seeds = load_claims()
        for c in claims:
            first, last = c.lines
            assert first >= 1
            text_lines = seed_file(seeds[c.seed]).read_text(encoding="utf-8").split("\n")
            assert last <= len(text_lines) and text_lines[first - 1].strip(), c.id
            link = page.locator(f"[id='{c.id}'] h3 a[href='#seed-{c.seed}-L{first}']")
            assert link.count() == 1, c.id
        page.locator("[id='000-T04'] h3 a").click()
        target = page.locator("#seed-000-L75")
        assert target.is_visible() and "0_4T" in target.inner_text()
        # --- the animations start only when asked
        anims = page.locator(".anim")
        assert anims.count() == 2 and not anims.first.locator(".nogl").is_visible()
        assert anims.first.locator("img.still").is_visible()
        anims.first.locator("button.play").click()
        frame = anims.first.locator("iframe")
        assert frame.count() == 1 and frame.is_visible()
        assert frame.get_attribute("sandbox") == "allow-scripts"  # the page cannot reach ours
        inner = frame.element_handle().content_frame()
        assert inner is not None  # the animation runs inside its sandbox
        inner.wait_for_function("() => window.hexapodKin && window.hexapodKin.ready", timeout=60000)
        assert not [u for u in requests if not u.startswith(("file:", "data:", "blob:", "about:"))]
    finally:
        browser.close()
