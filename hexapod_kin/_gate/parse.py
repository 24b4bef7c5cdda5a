"""Strict, hostile-safe XML parsing; element paths in messages; plain decimal numbers."""

from __future__ import annotations

import math
import re

import numpy as np
from lxml import etree

from .._pose import rpy_to_matrix
from ..exceptions import UrdfError
from .limits import (
    BIG_NUMBER,
    CHECKED_TOP,
    LIMIT_TAGS,
    MAX_ABS,
    MAX_ABS_LIMIT,
    MAX_URDF_BYTES,
    NEGATIVE,
    NUMBER,
    NUMERIC,
    PATTERNS,
    RESERVED,
)


# ------------------------------------------------------------------------ messages
def error_at(
    el: etree._Element, problem: str, attr: str | None = None, value: object = None
) -> UrdfError:
    """The :class:`UrdfError` of ``problem`` at ``el`` (``line 7: <joint name="j1"> <axis>``)."""
    parts: list[str] = []
    node: etree._Element | None = el
    while node is not None and node.tag != "robot":
        name = node.get("name")
        tag = node.tag if isinstance(node.tag, str) else "?"
        named = name is not None and tag in ("link", "joint", "material", "visual", "collision")
        parts.append(f'<{tag} name="{name}">' if named else f"<{tag}>")
        node = node.getparent()
    parts.reverse()
    where = f"line {el.sourceline}: {' '.join(parts) or '<robot>'}"
    attr_part = f" {attr}={value!r}" if attr is not None else ""
    return UrdfError(f"URDF {where}{attr_part}: {problem}")


# ------------------------------------------------------------------------ numbers
def numbers_of(
    el: etree._Element, attr: str, count: int, minimum: float | None
) -> tuple[float, ...]:
    """The ``count`` plain decimal numbers of ``el.attr`` (``()`` when absent), checked."""
    raw = el.get(attr)
    if raw is None:
        return ()
    if count == 1 and raw != raw.strip():
        raise error_at(el, "a single number without surrounding spaces is required", attr, raw)
    parts = re.split(r"[ \t\r\n]+", raw.strip(" \t\r\n"))
    if len(parts) != count:
        raise error_at(el, f"{count} number(s) required, found {len(parts)}", attr, raw)
    out = []
    for p in parts:
        if not NUMBER.match(p):
            raise error_at(el, f"{p!r} is not a decimal number", attr, raw)
        x = float(p)
        if not math.isfinite(x):
            raise error_at(el, "numbers must be finite", attr, raw)
        cap = MAX_ABS_LIMIT if el.tag in LIMIT_TAGS else MAX_ABS
        if abs(x) > cap:
            why = f"|{p}| exceeds {cap:g} (the cap for <{el.tag}>)"
            raise error_at(el, f"{why}; numbers are SI values of a robot", attr, raw)
        if minimum is not None and x < minimum:
            raise error_at(el, f"must be >= {minimum:g}", attr, raw)
        out.append(x)
    return tuple(out)


def check_numbers(root: etree._Element) -> None:
    """Check every numeric attribute under the ``<link>``, ``<joint>`` and ``<material>``s.

    One regular expression per attribute; :func:`numbers_of` only to explain or bound.
    """
    patterns, numeric = PATTERNS, NUMERIC
    for top in root:
        if top.tag not in CHECKED_TOP:
            continue
        for node in top.iter(*numeric):
            spec = numeric[node.tag]
            for attr, raw in node.items():
                kind = spec.get(attr)
                if kind is None:
                    continue
                odd = BIG_NUMBER.search(raw) or (kind[1] is not None and NEGATIVE.search(raw))
                if odd or not patterns[kind[0]].match(raw):  # explained (or passed) there
                    numbers_of(node, attr, kind[0], kind[1])


def number_of(el: etree._Element, attr: str, default: float | None = None) -> float:
    """A single number already validated by :func:`check_numbers` (or ``default``)."""
    raw = el.get(attr)
    if raw is None:
        if default is None:
            raise error_at(el, "attribute is required", attr)
        return default
    return float(raw)


# ------------------------------------------------------------------------ parsing
def parse_urdf(text: str | bytes) -> etree._Element:
    """Parse URDF text strictly (no DOCTYPE, ENTITY or other encodings), no other check."""
    data = text.encode("utf-8") if isinstance(text, str) else bytes(text)
    if len(data) > MAX_URDF_BYTES:
        raise UrdfError(f"URDF size {len(data)} bytes exceeds the cap of {MAX_URDF_BYTES} bytes")
    if b"<!DOCTYPE" in data or b"<!ENTITY" in data:
        raise UrdfError(
            "URDF contains a DOCTYPE or ENTITY declaration; these are refused (entity "
            "expansion and external entities are not allowed)"
        )
    parser = etree.XMLParser(
        resolve_entities=False,
        no_network=True,
        recover=False,
        huge_tree=False,
        load_dtd=False,
        dtd_validation=False,
        remove_comments=True,
        remove_pis=True,
    )
    try:
        tree = etree.fromstring(data, parser).getroottree()
    except etree.XMLSyntaxError as exc:
        raise UrdfError(f"URDF is not well-formed XML: {exc}") from None
    info = tree.docinfo
    if info.doctype or info.internalDTD is not None or info.externalDTD is not None:
        raise UrdfError("URDF contains a DOCTYPE declaration; DOCTYPE is refused")
    enc = (info.encoding or "UTF-8").upper().replace("_", "-")
    if enc not in ("UTF-8", "UTF8", "US-ASCII", "ASCII"):
        raise UrdfError(f"URDF encoding={info.encoding!r} is not allowed; use UTF-8")
    root = tree.getroot()
    for node in root.iter(etree.Entity):  # entity references left unexpanded
        raise UrdfError(f"URDF line {node.sourceline}: entity reference {node!s}; refused")
    return root


def element_name(el: etree._Element, what: str) -> str:
    name = el.get("name")
    if name is None or not name.strip():
        raise error_at(el, f"every <{what}> needs a non-empty name", "name", name)
    if name in RESERVED:
        raise error_at(el, "the name 'universe' is reserved by Pinocchio", "name", name)
    return name


def unique(seen: dict[str, etree._Element], el: etree._Element, name: str, what: str) -> None:
    """Record ``el`` as ``seen[name]``; a second ``<what>`` of the same name is refused."""
    if name in seen:
        why = f"duplicate {what} name (first at line {seen[name].sourceline})"
        raise error_at(el, f"{why}; {what} names must be unique", "name", name)
    seen[name] = el


def single(el: etree._Element, tag: str, required: bool) -> etree._Element | None:
    found = el.findall(tag)
    if len(found) > 1:
        raise error_at(found[1], f"<{tag}> given {len(found)} times; at most once")
    if required and not found:
        raise error_at(el, f"<{tag}> is required")
    return found[0] if found else None


def origin_of(el: etree._Element | None) -> tuple[np.ndarray, np.ndarray]:
    """Rotation and translation of an element's ``<origin>`` (identity when absent)."""
    origin = None if el is None else el.find("origin")
    if origin is None:
        return np.eye(3), np.zeros(3)
    xyz = numbers_of(origin, "xyz", 3, None) or (0.0, 0.0, 0.0)
    rpy = numbers_of(origin, "rpy", 3, None) or (0.0, 0.0, 0.0)
    rot = np.eye(3) if not any(rpy) else rpy_to_matrix(*rpy)
    return rot, np.array(xyz, dtype=float)
