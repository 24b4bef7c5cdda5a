"""The one page builder: every HTML page of the package, and its one escaping rule.

Every page is :data:`SKELETON` filled by :func:`page`, every fragment a
:class:`string.Template` filled by :func:`fill`: a value is text, escaped (``& < > " '``),
unless it is :class:`Html` (markup of the package's own); one pass, so an inserted value is
never read again (a title holding ``$data`` stays that text).
"""

from __future__ import annotations

import html
import json
from string import Template
from typing import Any

from ._version import __version__
from .exceptions import ParameterError

__all__ = ["SKELETON", "Html", "check_height", "escape", "fill", "frame", "page", "script_json"]


class Html(str):
    """Markup, inserted as it is (its text parts already escaped)."""

    __slots__ = ()


def escape(value: Any) -> Html:
    """The one escaping rule: :class:`Html` unchanged, anything else as escaped text."""
    return value if isinstance(value, Html) else Html(html.escape(str(value), quote=True))


def fill(template: str, **values: Any) -> Html:
    """``template`` (``$name`` holes) filled in one pass, each value through :func:`escape`."""
    return Html(Template(template).substitute({k: escape(v) for k, v in values.items()}))


def script_json(obj: Any) -> Html:
    r"""JSON for an inline ``<script>``: ``<``, ``>``, ``&`` as ``\u`` escapes (same value)."""
    text = json.dumps(obj, allow_nan=False)
    return Html(text.replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026"))


#: Every page: the document, its head (policy, title, style) and its body.
SKELETON = """<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
$policy<meta name="generator" content="hexapod_kin $version">
<title>$title</title>
<style>
$style
</style>
</head>
<body>
$body
</body>
</html>
"""


def page(title: str, body: Html, *, style: str = "", policy: str | None = None) -> str:
    """A whole document: :data:`SKELETON` filled once (``style`` CSS, ``policy`` a CSP: ours)."""
    csp = (
        ""
        if policy is None
        else f'<meta http-equiv="Content-Security-Policy" content="{policy}">\n'
    )
    values = {"policy": Html(csp), "version": __version__, "title": title, "style": Html(style)}
    return str(fill(SKELETON, **values, body=body))  # a document (text), not markup


def check_height(height: Any) -> int:
    """A frame height in [px] (an int in [100, 4000]), else :class:`ParameterError`."""
    if not (isinstance(height, int) and not isinstance(height, bool) and 100 <= height <= 4000):
        raise ParameterError(
            f"height={height!r} is not allowed; give pixels in [100, 4000]",
            parameter="height",
            value=height,
            allowed="[100, 4000]",
        )
    return height


def frame(doc: str, *, height: int | None = None, title: str | None = None) -> Html:
    """A whole page in a sandboxed ``<iframe srcdoc>`` (``allow-scripts``: cannot reach its host).

    ``height`` in [px] (:func:`check_height`; None: the host's style sheet decides);
    ``title``: the frame's accessible title.
    """
    named = Html("") if title is None else fill('title="$t" ', t=title)
    sized = (
        ""
        if height is None
        else f' style="width: 100%; height: {check_height(height)}px; border: 0;"'
    )
    return fill(
        '<iframe ${named}srcdoc="$doc"$sized sandbox="allow-scripts"></iframe>',
        named=named,
        doc=Html(html.escape(doc, quote=True)),
        sized=Html(sized),
    )
