"""The one page builder (``hexapod_kin._page``): one skeleton, one escaping rule, one pass.

Every page kind (the viewer's page, a walk's, the simulation's, the seed report, a notebook
frame) is given hostile names and titles: template holes of every syntax this package ever
used (``__DATA__``, ``$data``, ``${x}``, ``$help``), ``</script>``, ``<!--``, quotes and ``&``.
The page is then read back by an HTML parser (:class:`html.parser.HTMLParser`, independent of
the builder): the title and the text show each name literally, the page has only the package's
own scripts and no comment, and the viewer's data (``var DATA = ...``) reads back equal to a
page built with a plain name, but for the title.
"""

from __future__ import annotations

import dataclasses
import json
import re
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

import hexapod_kin as hk
from hexapod_kin._page import Html, escape, fill, frame, page, script_json
from hexapod_kin.exceptions import ParameterError

#: Every way a name could be read as markup or as a template hole.
HOSTILE = "a __DATA__ $data ${x} $$ $help __TITLE__ </script> <!-- \"q\" 's' & <b>b</b> -->"


class _Read(HTMLParser):
    """The parts of a page a reader sees: title, text, scripts, comments, iframes' pages."""

    def __init__(self, doc: str) -> None:
        super().__init__(convert_charrefs=True)
        self.title = ""
        self.text: list[str] = []
        self.scripts: list[str] = []
        self.comments: list[str] = []
        self.frames: list[dict[str, str | None]] = []
        self._in: list[str] = []
        self.feed(doc)
        self.close()

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        if tag == "iframe":
            self.frames.append(dict(attrs))
        if tag in ("title", "script", "style"):
            self._in.append(tag)
            if tag == "script":
                self.scripts.append("")

    def handle_endtag(self, tag: str) -> None:
        if self._in and self._in[-1] == tag:
            self._in.pop()

    def handle_data(self, data: str) -> None:
        where = self._in[-1] if self._in else ""
        if where == "title":
            self.title += data
        elif where == "script":
            self.scripts[-1] += data
        elif where != "style":
            self.text.append(data)

    def handle_comment(self, data: str) -> None:
        self.comments.append(data)


def _data(doc: str) -> dict:
    """The viewer page's DATA, read from its one script (the same regex as test_viewer)."""
    seen = _Read(doc)
    assert len(seen.scripts) == 1 and not seen.comments
    m = re.search(r"var DATA = (\{.*?\});\n", seen.scripts[0])
    assert m, "no DATA in the script"
    return json.loads(m.group(1))


def _same_but_title(doc: str, plain: str, title: str) -> None:
    """``doc`` is ``plain``'s page with another title: every datum equal, the title literal."""
    got, ref = _data(doc), _data(plain)
    assert _Read(doc).title == got["title"] == title
    assert {k: v for k, v in got.items() if k != "title"} == {
        k: v for k, v in ref.items() if k != "title"
    }


# ---------------------------------------------------------------------------- the builder
def test_one_pass_never_reads_a_value_again() -> None:
    out = fill("<p>$a|$b</p>", a="$b ${b} __DATA__", b=Html("<i>x</i>"))
    assert out == "<p>$b ${b} __DATA__|<i>x</i></p>"
    assert fill("$a", a="$$") == "$$"


def test_the_one_escaping_rule() -> None:
    assert escape(HOSTILE) == (
        "a __DATA__ $data ${x} $$ $help __TITLE__ &lt;/script&gt; &lt;!-- &quot;q&quot; "
        "&#x27;s&#x27; &amp; &lt;b&gt;b&lt;/b&gt; --&gt;"
    )
    assert escape(Html("<b>")) == "<b>" and escape(3.5) == "3.5"
    assert isinstance(escape("x"), Html)


def test_script_json_cannot_close_its_script_and_reads_back_equal() -> None:
    value = {"t": HOSTILE, "n": [1.5, 2], "u": "é\u2028"}
    text = script_json(value)
    assert "<" not in text and ">" not in text and "&" not in text
    assert json.loads(text) == value
    with pytest.raises(ValueError):
        script_json({"x": float("nan")})


def test_the_skeleton_and_the_frame() -> None:
    doc = page(HOSTILE, fill("<p>$x</p>", x=HOSTILE), style="p{}", policy="default-src 'none'")
    seen = _Read(doc)
    assert doc.startswith("<!DOCTYPE html>\n") and doc.endswith("</body>\n</html>\n")
    assert seen.title == HOSTILE and HOSTILE in seen.text and not seen.comments
    assert not seen.scripts
    assert "content=\"default-src 'none'\"" in doc
    assert f'content="hexapod_kin {hk.__version__}"' in doc
    framed = _Read(frame(doc, height=300, title=HOSTILE))
    (attrs,) = framed.frames
    assert attrs["srcdoc"] == doc and attrs["title"] == HOSTILE
    assert attrs["sandbox"] == "allow-scripts" and "300px" in (attrs["style"] or "")
    assert not framed.text and not framed.comments
    for bad in (99, 4001, 300.0, True, "300"):
        with pytest.raises(ParameterError, match="height"):
            frame(doc, height=bad)  # type: ignore[arg-type]


# ---------------------------------------------------------------------------- every page
pytest.importorskip("meshcat")


@pytest.fixture(scope="module")
def hostile_urdf(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The leg's URDF in a file whose name is hostile (a model's name is its file's)."""
    folder = tmp_path_factory.mktemp("pages")
    path = folder / (HOSTILE.replace("/", "") + ".urdf")
    path.write_text(hk.to_urdf(hk.robots.hexabot_leg()), encoding="utf-8")
    return path


def test_viewer_page_with_a_hostile_title_and_robot_name(hostile_urdf: Path) -> None:
    from hexapod_kin import viewer

    plain = hk.load("hexabot_leg")
    hostile = hk.load(str(hostile_urdf))
    assert hostile.name == hostile_urdf.name  # what the default title shows
    t, q = np.array([0.0, 0.5]), np.array([[0.0, 0.1, 0.2], [0.3, 0.2, 0.1]])
    ref = viewer.render_html(plain, t, q, title="plain")
    _same_but_title(viewer.render_html(plain, t, q, title=HOSTILE), ref, HOSTILE)
    _same_but_title(viewer.render_html(hostile, t, q), ref, f"hexapod_kin: {hostile.name}")
    # the file and the notebook frame hold the same page
    out = viewer.export_html(plain, t, q, hostile_urdf.parent / "leg.html", title=HOSTILE)
    doc = out.read_text(encoding="utf-8")
    _same_but_title(doc, ref, HOSTILE)
    (attrs,) = _Read(viewer.iframe(out, height=300)).frames
    assert attrs["srcdoc"] == doc


def test_notebook_and_walk_pages_with_a_hostile_title() -> None:
    from hexapod_kin import viewer
    from hexapod_kin.viewer.notebook import show, show_walk

    plain = hk.load("hexabot_leg")
    ref = viewer.render_html(plain, np.zeros(1), plain.neutral(), title="plain")
    view = show(plain, title=HOSTILE, height=300)
    (attrs,) = _Read(view._repr_html_()).frames
    assert attrs["srcdoc"] == view.page
    _same_but_title(view.page, ref, HOSTILE)
    run = hk.gait.walk(duration=0.4, rate=25.0)
    walk_ref = viewer.walk_page(run, title="plain")
    _same_but_title(viewer.walk_page(run, title=HOSTILE), walk_ref, HOSTILE)
    nb = show_walk(run, title=HOSTILE, height=300)
    _same_but_title(nb.page, walk_ref, HOSTILE)


def test_simulation_page_with_a_hostile_pattern_name(tmp_path: Path) -> None:
    pytest.importorskip("mujoco")
    from hexapod_kin.simulate import simulate, simulation_html

    sim = simulate("hexapod", duration=0.5)
    run = dataclasses.replace(sim.run, table=dataclasses.replace(sim.run.table, name=HOSTILE))
    doc = simulation_html(dataclasses.replace(sim, run=run), tmp_path / "sim.html").read_text()
    seen = _Read(doc)
    title = f"hexapod_kin: {HOSTILE} plan and MuJoCo replay"
    assert seen.title == title and title in seen.text
    assert f"pattern {HOSTILE}, terrain flat, 0.5 s at 100 Hz" in seen.text
    # one script only, the fixed one keeping the two animations in step: nothing of the robot's
    from hexapod_kin.simulate.page import _SYNC

    assert seen.scripts == [_SYNC] and not seen.comments
    plan, replay = (_data(str(f["srcdoc"])) for f in seen.frames)
    assert plan["title"] == "plan" and replay["title"] == "MuJoCo"
    assert plan["bundle"] == replay["bundle"] and plan["scene"] != replay["scene"]


def test_report_page_with_hostile_texts(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from hexapod_kin.report import build
    from hexapod_kin.report.data import Verdict

    seed_text = tmp_path / "seed.txt"
    seed_text.write_text(f"line one\n{HOSTILE}\n", encoding="utf-8")
    monkeypatch.setattr(build, "seed_file", lambda title: seed_text)
    verdict = Verdict(
        claim="000-x", seed="000", where=HOSTILE, kind="value", claimed=HOSTILE,
        computed=HOSTILE, status="wrong", reason=HOSTILE, method=HOSTILE, lines="2-2",
    )  # fmt: skip
    f = {"drift_y": 1.0, "drift_z": 2.0, "error_x": 3.0}
    facts = {
        "scan_family_counts": {HOSTILE: {HOSTILE: 3}},
        "step": {**f, "baseline_euler_solve": f},
        "pendulum": dict.fromkeys(
            ("period", "period_exact", "damped_period", "decay_rate", "decay_rate_exact"), 1.0
        ),
        "hexapod": {HOSTILE: HOSTILE},
    }
    rep = build.Report(tmp_path, tmp_path / "r.md", tmp_path / "r.html", (verdict,), facts, 0.0)
    empty: dict[str, list[Path]] = {k: [] for k, _, _ in build.SECTIONS}
    doc = build._html(rep, {"000": HOSTILE}, empty, empty, {})
    seen = _Read(doc)
    assert seen.title == "hexapod_kin reproduces the seeds"
    assert len(seen.scripts) == 1 and not seen.comments  # the report's own script only
    text = "".join(seen.text)
    assert text.count(HOSTILE) >= 8  # seed title, claim fields, facts, the seed's line
    assert f"verdict: seed is wrong: {HOSTILE}" in text
