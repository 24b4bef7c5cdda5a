"""The example notebooks run top to bottom (nbclient) and show the viewer inline."""

from __future__ import annotations

import html
import os
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((ROOT / "examples").glob("*.ipynb"))

pytestmark = pytest.mark.slow


def _needs(module: str):
    if os.environ.get("CI"):
        return __import__(module)
    return pytest.importorskip(module)


def test_two_notebooks_exist():
    assert {p.name for p in NOTEBOOKS} >= {"my_leg.ipynb", "hexapod_walk.ipynb"}


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_notebook_runs_and_shows_the_page_inline(path, tmp_path):
    nbformat = _needs("nbformat")
    nbclient = _needs("nbclient")
    _needs("ipykernel")
    nb = nbformat.read(path, as_version=4)
    client = nbclient.NotebookClient(
        nb, timeout=300, kernel_name="python3", resources={"metadata": {"path": str(tmp_path)}}
    )
    client.execute()
    errors = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])
              if o.get("output_type") == "error"]  # fmt: skip
    assert not errors
    frames = [o["data"]["text/html"] for c in nb.cells if c.cell_type == "code"
              for o in c.get("outputs", []) if "text/html" in o.get("data", {})]  # fmt: skip
    frames = [f for f in frames if f.startswith("<iframe srcdoc=")]
    assert len(frames) == 1
    page = html.unescape(re.search(r'srcdoc="([^"]*)"', frames[0]).group(1))
    assert page.startswith("<!DOCTYPE html>") and "Content-Security-Policy" in page


def test_notebook_view_escapes_the_page():
    from hexapod_kin.viewer.notebook import NotebookView

    page = "<html><body><p class=\"x\">a & b 'c'</p></body></html>"
    shown = NotebookView(page, height=300)._repr_html_()
    inner = re.fullmatch(r'<iframe srcdoc="([^"]*)" style="[^"]*300px[^"]*" '
                         r'sandbox="allow-scripts"></iframe>', shown)  # fmt: skip
    assert inner is not None and html.unescape(inner.group(1)) == page
