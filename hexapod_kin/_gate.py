"""The loader gate: every URDF passes here before Pinocchio or yourdfpy see it.

This first version checks size, strict XML (no DOCTYPE/entities) and the root element; the
full set of checks (tree, numbers, limits, inertia, meshes) is documented in ``check_urdf``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from lxml import etree

from .exceptions import UrdfError

__all__ = ["MAX_URDF_BYTES", "MAX_LINKS", "GateResult", "check_urdf"]

#: Largest URDF text accepted, in bytes.
MAX_URDF_BYTES = 20 * 1024 * 1024
#: Most links accepted (Pinocchio segfaults on chains of ~4,000 links).
MAX_LINKS = 1000


@dataclass(frozen=True)
class GateResult:
    """What the gate learned: the parsed root and the mesh files it resolved."""

    root: etree._Element
    meshes: tuple[Path, ...] = ()


def check_urdf(
    text: str | bytes,
    *,
    mesh_roots: tuple[str | os.PathLike[str], ...] = (),
    check_meshes: bool = False,
) -> GateResult:
    """Check a URDF document; raise :class:`UrdfError` on the first problem.

    Args:
        text: The URDF document.
        mesh_roots: Directories mesh paths may resolve into.
        check_meshes: Whether mesh files must exist inside ``mesh_roots``.

    Returns:
        A :class:`GateResult`.

    Raises:
        UrdfError: Naming the element, attribute, value and line of the problem.
    """
    data = text.encode("utf-8") if isinstance(text, str) else bytes(text)
    if len(data) > MAX_URDF_BYTES:
        raise UrdfError(f"URDF size {len(data)} bytes exceeds the cap of {MAX_URDF_BYTES} bytes")
    if b"<!DOCTYPE" in data or b"<!ENTITY" in data:
        raise UrdfError("URDF contains a DOCTYPE or ENTITY declaration; these are refused")
    parser = etree.XMLParser(
        resolve_entities=False, no_network=True, recover=False, huge_tree=False, load_dtd=False
    )
    try:
        root = etree.fromstring(data, parser)
    except etree.XMLSyntaxError as exc:
        raise UrdfError(f"URDF is not well-formed XML: {exc}") from None
    if root.tag != "robot":
        raise UrdfError(f"root element <{root.tag}> (line {root.sourceline}); <robot> required")
    links = root.findall("link")
    if not links:
        raise UrdfError("<robot> has no <link>; at least one link is required")
    if len(links) > MAX_LINKS:
        raise UrdfError(f"<robot> has {len(links)} links; the cap is {MAX_LINKS}")
    return GateResult(root=root)
