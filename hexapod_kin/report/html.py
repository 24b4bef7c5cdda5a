"""The report's pieces of HTML (the page is :func:`hexapod_kin._page.page`; one escaping rule)."""

from __future__ import annotations

import base64
import json
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from .._page import escape as e
from .._page import frame

__all__ = [
    "CSS",
    "SCRIPT",
    "animation",
    "derivation_html",
    "derivation_layout",
    "image",
    "inline",
    "line_anchor",
    "matrix_pair",
    "pretty_entry",
    "seed_notation",
    "seed_texts",
    "verdict_html",
]

#: The page's style and script (package data): the script opens the ``<details>`` around a
#: linked seed line and flags animations when WebGL is missing.
CSS = Path(__file__).with_name("report.css").read_text(encoding="utf-8").removesuffix("\n")
SCRIPT = Path(__file__).with_name("report.js").read_text(encoding="utf-8").removesuffix("\n")

_CODE = re.compile(r"`([^`]+)`")
_BOLD = re.compile(r"\*\*(.+?)\*\*")


def inline(text: str) -> str:
    """Escaped prose with Markdown code spans and bold rendered (``<code>``, ``<b>``)."""
    out: str = e(text)
    out = _CODE.sub(lambda m: f"<code>{m.group(1)}</code>", out)
    return _BOLD.sub(lambda m: f"<b>{m.group(1)}</b>", out)


_POW = {"2": "²", "3": "³", "4": "⁴"}
_SUP = str.maketrans("0123456789", "⁰¹²³⁴⁵⁶⁷⁸⁹")
_SUB = str.maketrans("0123456789", "₀₁₂₃₄₅₆₇₈₉")


def _sup(n: int) -> str:
    return str(n).translate(_SUP)


def _sub(n: int) -> str:
    return str(n).translate(_SUB)


def seed_notation(text: str) -> str:
    """ASCII transform names as the seeds print them: ``^0_1T`` → ``⁰₁T``, ``T_0^1`` → ``T₀¹``."""
    text = re.sub(r"\^(\d)_(\d)T", lambda m: _sup(int(m[1])) + _sub(int(m[2])) + "T", text)
    return re.sub(r"T_(\d)\^(\d)", lambda m: "T" + _sub(int(m[1])) + _sup(int(m[2])), text)


def pretty_entry(text: str) -> str:
    """A matrix entry in sympy syntax made readable: ``a**2*b`` → ``a²·b`` (text, unescaped)."""
    text = re.sub(r"\*\*(\d)\b", lambda m: _POW.get(m.group(1), "^" + m.group(1)), text)
    return text.replace("*", "·")


def _table(rows: Sequence[Sequence[str]], differ: set[tuple[int, int]], header: Any) -> str:
    h = ["<table class='mat'>"]
    if header:
        h.append("<tr>" + "".join(f"<th>{e(str(x))}</th>" for x in header) + "</tr>")
    for i, row in enumerate(rows):
        marked = [(" class='diff'" if (i, j) in differ else "", v) for j, v in enumerate(row)]
        tds = "".join(f"<td{c}>{e(pretty_entry(str(v)))}</td>" for c, v in marked)
        h.append(f"<tr>{tds}</tr>")
    h.append("</table>")
    return "".join(h)


def matrix_pair(cells: str | dict[str, Any]) -> str:
    """The seed's and our matrix of ``cells`` (:attr:`~.data.Verdict.cells`) side by side."""
    data = json.loads(cells) if isinstance(cells, str) else cells
    differ = {(int(i), int(j)) for i, j in data.get("differ", [])}
    header = data.get("header")
    n = len(differ)
    total = sum(len(r) for r in data["ours"])
    note = data.get("note") or ""
    seed_cap = "seed (as written" + (f"; {note}" if note else "") + ")"
    ours_cap = "hexapod_kin" + (
        f" — {n} of {total} entries differ (highlighted)" if n else " — every entry agrees"
    )
    return (
        "<div class='mats'>"
        f"<figure><figcaption>{e(seed_cap)}</figcaption>"
        f"{_table(data['seed'], differ, header)}</figure>"
        f"<figure><figcaption>{e(ours_cap)}</figcaption>"
        f"{_table(data['ours'], differ, header)}</figure></div>"
    )


_ENTRY = re.compile(r"^\((\d+),(\d+)\): seed (.*) vs (.*?)( \(sign slip\))?$")


def verdict_html(text: str, status: str) -> str:
    """A verdict's text; a list of differing entries (``(i,j): seed a vs b``) as a list."""
    head, sep, items = text.partition(" entries differ: ")
    if not sep:
        return f"<p class='{status}'><b>verdict: {e(text)}</b></p>"
    first, *notes = items.split(" — ")
    li = []
    for item in re.split(r"; (?=\(\d+,\d+\):)", first):
        m = _ENTRY.match(item)
        if m is None:
            li.append(f"<li>{e(item)}</li>")
            continue
        i, j, a, b, slip = m.groups()
        li.append(
            f"<li>({i},{j}): seed <code>{e(pretty_entry(a))}</code> vs "
            f"<code>{e(pretty_entry(b))}</code>{' — sign slip' if slip else ''}</li>"
        )
    tail = "".join(f"<p class='{status}'>{e(n)}</p>" for n in notes)
    return (
        f"<div class='{status}'><b>verdict: {e(head)} entries differ:</b>"
        f"<ul>{''.join(li)}</ul></div>{tail}"
    )


def derivation_layout(d: Any) -> dict[str, Any]:
    """A derivation as ``{"header", "items": [{"label", "rows" or "value"}], "footer"}``."""
    import sympy as sp

    from .compare import fmt  # the comparison's text of an expression (not needed by derive)

    joints = ", ".join(f"{fmt(s)} ({n})" for s, n in zip(d.q, d.joint_names))
    lens = ", ".join(
        f"{fmt(s)} = {v:g} m (table {d.length_sources[s]})" for s, v in d.lengths.items()
    )
    header = [
        f"{d.chain.name}: Khalil-Kleinfinger table, T = Rx(α) Tx(d) Rz(θ) Tz(r)",
        f"joints: {joints}",
        f"lengths: {lens or '(none)'}",
        f"p and J in the axes of '{d.reference}', tip '{d.tip}'",
    ]
    mats: list[tuple[str, Any]] = []
    if d.base_transform != sp.eye(4):
        mats.append((f"T({d.reference} → 0)", d.base_transform))
    n = len(d.transforms)
    mats += [(f"{_sup(j)}T{_sub(j + 1)}", d.transforms[j]) for j in range(n)]
    if d.tool_transform != sp.eye(4):
        mats.append((f"{_sup(n)}T(tool)", d.tool_transform))
    mats += [(f"⁰T{_sub(j + 1)}", d.cumulative[j]) for j in range(1, n)]
    mats += [("p(q)", d.p), ("J (indirect, ∂p/∂q)", d.J_indirect)]
    mats.append(("J (direct, [v; ω])", d.J_direct))
    items: list[dict[str, Any]] = [
        {"label": label, "rows": [[fmt(x) for x in m.row(i)] for i in range(m.rows)]}
        for label, m in mats
    ]
    if d.det is not None:
        items.append({"label": f"det J[{','.join(d.rows)}]", "value": fmt(d.det)})
    elif d.gram is not None:
        items.append({"label": f"det(J Jᵀ) [{','.join(d.rows)}]", "value": fmt(d.gram)})
    footer = [f"direct and indirect Jacobians agree: {d.methods_agree}"]
    if d.method:
        footer.append(f"determinant: {d.method}")
    for fam in d.families:
        mark = {True: "checked", False: "CHECK FAILED", None: "not checked"}[fam.verified]
        note = f" [{mark}: {fam.check}]" if fam.check else ""
        footer.append(f"singular family: {fam.name}{note}")
    footer += [f"NOT DONE: {what}" for what in d.incomplete]
    return {"header": header, "items": items, "footer": footer}


def derivation_html(title: str, printed: dict[str, Any]) -> str:
    """A derivation (:meth:`~.checks.Context.printed`) in a ``<details>``: matrices as tables."""
    h = [f"<details><summary>Derivation of {e(title)}</summary>"]
    h.append("<p>" + "<br>".join(e(line) for line in printed["header"]) + "</p>")
    for item in printed["items"]:
        if "rows" in item:
            h.append(
                f"<div class='mats'><figure><figcaption>{e(item['label'])} =</figcaption>"
                f"{_table(item['rows'], set(), None)}</figure></div>"
            )
        else:
            h.append(f"<p>{e(item['label'])} = <code>{e(pretty_entry(item['value']))}</code></p>")
    h.append("<ul>" + "".join(f"<li>{e(line)}</li>" for line in printed["footer"]) + "</ul>")
    h.append("</details>")
    return "".join(h)


def image(path: Path, alt: str | None = None, cls: str = "") -> str:
    """A PNG inlined as a data URI."""
    data = base64.b64encode(path.read_bytes()).decode("ascii")
    c = f" class='{cls}'" if cls else ""
    return f'<img{c} alt="{e(alt or path.stem)}" src="data:image/png;base64,{data}">'


def animation(page: Path, still: Path | None, when: str) -> str:
    """The animation ``page`` (inert until its button) over its ``still`` (showing ``when``)."""
    link = f"<a href='{e(page.name)}'>{e(page.name)}</a>"
    msg = (
        f"This browser has no WebGL: showing a still frame ({e(when)}) instead of the "
        f"animation (open {link} in a browser with WebGL to play it)."
    )
    still_html = image(still, f"still frame of {page.stem} ({when})", "still") if still else ""
    return (
        f"<div class='anim'><p>Animation (also {link}, self-contained):</p>"
        f"<p class='nogl'>{msg}</p>"
        f"<p class='gl'><button type='button' class='play'>▶ play the {e(page.stem)} "
        f"animation here</button> <small>(WebGL; the picture below is its still frame, "
        f"{e(when)})</small></p>{still_html}"
        f"<template>{frame(page.read_text(encoding='utf-8'), title=f'{page.stem} animation')}"
        "</template>"
        "<noscript><p>Scripts are off: the animation needs them; above is its still frame."
        "</p></noscript></div>"
    )


def line_anchor(seed: str, line: int) -> str:
    """The id of a line of a shipped seed text in the page."""
    return f"seed-{seed}-L{line}"


def seed_texts(
    seeds: dict[str, str], texts: dict[str, str], cited: dict[str, dict[int, list[str]]]
) -> str:
    """Every seed text (by key, titled by ``seeds``), one anchor per line, ``cited`` lines marked.

    ``cited``: seed key → line → the claims whose passage starts (an id) or runs (``""``) there.
    """
    h = []
    for key, title in seeds.items():
        marks = cited.get(key, {})
        h.append(
            f"<details id='seed-{e(key)}'><summary><b>{e(key)}</b>: {e(title)}</summary>"
            "<pre class='seed'>"
        )
        for n, line in enumerate(texts.get(key, "").split("\n"), start=1):
            ids = marks.get(n, [])
            cls = " class='cited'" if ids else ""
            back = "".join(f" <a href='#{e(c)}'>[{e(c)}]</a>" for c in ids if c)
            h.append(
                f"<span id='{line_anchor(key, n)}'{cls}>"
                f"<a class='ln' href='#{line_anchor(key, n)}'>{n:4d}</a>{e(line)}{back}</span>"
            )
        h.append("</pre></details>")
    return "".join(h)
