"""The one page builder: every HTML page of the package, and its one escaping rule.

Every page the package writes (the seed report, the viewer's offline page, the walk and the
simulation pages, the notebook frames) is :data:`SKELETON` filled by :func:`page`, and every
fragment with a hole is a :class:`string.Template` filled by :func:`fill`. The rule:

* a value is **text** unless it is :class:`Html`; text is escaped with
  :func:`html.escape` (``& < > " '``), so it shows literally in an element or an attribute;
* :class:`Html` is markup built here (:func:`escape`, :func:`fill`, :func:`script_json`,
  :func:`frame`) or written in the package's own source, and is inserted as it is;
* a template is filled in one pass (:meth:`string.Template.substitute`): an inserted value is
  never scanned again, so a title holding ``$data``, ``${x}`` or ``__DATA__`` stays that text
  and cannot pull another value in.

A leaf module (standard library only), imported by ``viewer``, ``report`` and ``simulate``.
"""

from __future__ import annotations

import html
import json
from string import Template
from typing import Any

from ._version import __version__
from .exceptions import ParameterError

__all__ = [
    "SKELETON",
    "Html",
    "check_height",
    "escape",
    "fill",
    "frame",
    "page",
    "script_json",
]


class Html(str):
    """Markup inserted as it is (its text parts already escaped)."""

    __slots__ = ()


def escape(value: Any) -> Html:
    """The one escaping rule: :class:`Html` unchanged, anything else as escaped text."""
    if isinstance(value, Html):
        return value
    return Html(html.escape(str(value), quote=True))


def fill(template: str, **values: Any) -> Html:
    """``template`` (``$name`` holes) filled in one pass, each value through :func:`escape`.

    Raises:
        KeyError: A hole has no value (a bug in the caller's template).

    """
    return Html(_substitute(template, values))


def _substitute(template: str, values: dict[str, Any]) -> str:
    return Template(template).substitute({k: escape(v) for k, v in values.items()})


def script_json(obj: Any) -> Html:
    r"""JSON for an inline ``<script>``, with ``<``, ``>`` and ``&`` written as ``\u`` escapes.

    No ``</script>`` or ``<!--`` inside a string can then close or comment out the script;
    the value the script reads is unchanged.
    """
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
    """A whole page: :data:`SKELETON` filled once.

    Args:
        title: The page title (text).
        body: The body's markup.
        style: The page's CSS (the package's own, inserted as it is).
        policy: The page's Content-Security-Policy (the package's own, inserted as it is;
            ``None``: none).

    Returns:
        The HTML document.

    """
    meta = (
        fill('<meta http-equiv="Content-Security-Policy" content="$csp">\n', csp=Html(policy))
        if policy is not None
        else ""
    )
    values = {"policy": Html(meta), "version": __version__, "title": title, "style": Html(style)}
    return _substitute(SKELETON, {**values, "body": body})  # a document (text), not markup


def check_height(height: Any) -> int:
    """A frame height in [px], checked.

    Raises:
        ParameterError: ``height`` is not an int in [100, 4000].

    """
    if not (isinstance(height, int) and not isinstance(height, bool) and 100 <= height <= 4000):
        raise ParameterError(
            f"height={height!r} is not allowed; give pixels in [100, 4000]",
            parameter="height",
            value=height,
            allowed="[100, 4000]",
        )
    return height


def frame(doc: str, *, height: int | None = None, title: str | None = None) -> Html:
    """A whole page embedded as ``<iframe srcdoc>``, sandboxed (its own scripts only).

    The frame keeps the page isolated (ids, scripts, its Content-Security-Policy), so several
    can be shown in one notebook or page; ``allow-scripts`` only: it cannot reach its host.

    Args:
        doc: The page (text: escaped into the attribute).
        height: Frame height in [px] (full width, no border), or ``None`` to leave the size
            to the host's style sheet.
        title: The frame's accessible title, if any.

    Raises:
        ParameterError: ``height`` is not an int in [100, 4000].

    """
    if height is not None:
        check_height(height)
    named = fill('title="$t" ', t=title) if title is not None else Html("")
    sized = (
        Html("")
        if height is None
        else fill(' style="width: 100%; height: ${h}px; border: 0;"', h=height)
    )
    return fill(
        '<iframe ${named}srcdoc="$doc"$sized sandbox="allow-scripts"></iframe>',
        named=named,
        doc=Html(html.escape(doc, quote=True)),  # a page, even one built here, is text here
        sized=sized,
    )
