"""Materials, visual/collision geometry, and the mesh/texture files they name."""

from __future__ import annotations

import os
import stat
from collections.abc import Sequence
from pathlib import Path
from urllib.parse import unquote, urlsplit

from lxml import etree

from ..exceptions import UrdfError
from .limits import MAX_MESH_BYTES, SCHEME, SHAPES
from .parse import error_at, numbers_of, single, unique


class MeshMissing(UrdfError):
    """A mesh file that cannot be found (as opposed to one that is refused)."""


class MeshOutside(UrdfError):
    """A refused file name (a URI scheme, ``~``, a forbidden absolute path): dropped, unread."""


class MeshEmpty(UrdfError):
    """A mesh file of 0 bytes (mesh loaders fail on it): dropped like a missing one."""


#: Mesh formats read from an absolute or ``file://`` path of a URDF loaded from its file.
MESH_SUFFIXES = (".stl", ".dae", ".obj", ".ply")


def _absolute_mesh(uri: str, path: str, mesh_root: object) -> Path:
    """An absolute mesh path: read only for a file-loaded URDF and a mesh file."""
    if mesh_root is None:
        raise MeshOutside(
            f"{uri!r}: refused: absolute and file:// paths are read only when the URDF is "
            "loaded from its file (this source is URDF text)"
        )
    real = os.path.realpath(path)
    for name in (path, real):
        if not name.lower().endswith(MESH_SUFFIXES):
            raise MeshOutside(
                f"{uri!r}: refused: only mesh files ({', '.join(MESH_SUFFIXES)}) are read "
                "from an absolute or file:// path"
                + ("" if name == path else f" (it links to {real!r})")
            )
    return Path(real)


def resolve_mesh(
    uri: str,
    *,
    package_dirs: Sequence[str | os.PathLike[str]] = (),
    mesh_root: str | os.PathLike[str] | None = None,
) -> Path:
    """The real path of a mesh/texture ``filename`` (rule 7 of :mod:`hexapod_kin._gate`).

    Raises:
        UrdfError: Refused, outside the root, missing, not regular or too large (no line).

    """
    if not uri or not uri.strip():
        raise UrdfError("empty file name")
    scheme = SCHEME.match(uri)
    candidates: list[tuple[str, str]] = []  # (root, joined path)
    if scheme and scheme.group(1).lower() == "package" and uri[8:10] == "//":
        # Pinocchio also accepts package:///pkg/path (it joins "<dir>/" + "/pkg/path").
        rest = uri[10:].lstrip("/")
        pkg = rest.split("/", 1)[0]
        if not pkg or "/" not in rest or pkg in (".", ".."):
            raise UrdfError(f"package URI {uri!r} must be package://<package>/<path>")
        if not package_dirs:
            raise MeshMissing(
                f"{uri!r}: not found: no package directories are known for this source "
                "(give package_dirs= or set ROS_PACKAGE_PATH)"
            )
        candidates = [
            (os.path.realpath(os.fspath(d)), os.path.join(os.fspath(d), rest)) for d in package_dirs
        ]
    elif scheme and scheme.group(1).lower() == "file" and uri[5:7] == "//":
        parts = urlsplit(uri)
        path = unquote(parts.path)
        if parts.netloc not in ("", "localhost") or not os.path.isabs(path):
            raise MeshOutside(
                f"{uri!r}: refused: a file:// URI must name a local absolute path "
                "(file:///path/to/mesh.stl)"
            )
        candidates = [("", os.fspath(_absolute_mesh(uri, path, mesh_root)))]
    elif scheme:
        raise MeshOutside(
            f"{uri!r}: refused: URI scheme {scheme.group(1)!r} is never read; use "
            "package://<package>/<path> or a path relative to the URDF file"
        )
    elif uri.startswith("~"):
        raise MeshOutside(f"{uri!r}: refused: '~' is not expanded; give the path itself")
    elif os.path.isabs(uri):
        candidates = [("", os.fspath(_absolute_mesh(uri, uri, mesh_root)))]
    else:
        if mesh_root is None:
            raise MeshMissing(
                f"{uri!r}: not found: relative mesh path but no mesh root (URDF given as "
                "text); load the URDF from its file so relative paths resolve next to it"
            )
        root = os.fspath(mesh_root)
        candidates = [(os.path.realpath(root), os.path.join(root, uri))]
    last: UrdfError | None = None
    for root_real, joined in candidates:
        real = os.path.realpath(joined)
        inside = real == root_real or real.startswith(root_real.rstrip(os.sep) + os.sep)
        if root_real and not inside:
            # an escape out of the root through ".." or a link is hostile: always refused
            raise UrdfError(f"{uri!r} resolves to {real!r}, outside the allowed root {root_real!r}")
        try:
            st = os.stat(real)
        except OSError:
            last = MeshMissing(f"{uri!r}: not found: file {real!r} does not exist")
            continue
        if not stat.S_ISREG(st.st_mode):
            raise UrdfError(f"{uri!r}: {real!r} is not a regular file")
        if st.st_size > MAX_MESH_BYTES:
            raise UrdfError(
                f"{uri!r}: {real!r} has {st.st_size} bytes; the cap is {MAX_MESH_BYTES}"
            )
        if st.st_size == 0:
            raise MeshEmpty(f"{uri!r}: empty: {real!r} has 0 bytes")
        return Path(real)
    assert last is not None
    raise last


def _check_color(material: etree._Element) -> None:
    """The ``<color rgba>`` of a material, when it has one: four numbers in [0, 1]."""
    color = single(material, "color", required=False)
    if color is None:
        return
    rgba = numbers_of(color, "rgba", 4, None)
    if not rgba:
        raise error_at(color, "<color> needs rgba (four numbers in [0, 1])", "rgba")
    if not all(0.0 <= c <= 1.0 for c in rgba):
        raise error_at(color, "colour components must be in [0, 1]", "rgba", color.get("rgba"))


def check_materials_and_geometry(root: etree._Element) -> None:
    """Materials (named, unique, colours in [0, 1]) and visual/collision geometry."""
    defined: dict[str, etree._Element] = {}
    for mat in root.findall("material"):
        name = mat.get("name")
        if name is None or not name.strip():
            raise error_at(mat, "every <material> needs a non-empty name", "name", name)
        unique(defined, mat, name, "material")
        _check_color(mat)
    for link in root.findall("link"):
        for part in ("visual", "collision"):
            for el in link.findall(part):
                single(el, "origin", required=False)
                geometry = single(el, "geometry", required=True)
                assert geometry is not None
                shapes = [c for c in geometry if isinstance(c.tag, str)]
                if len(shapes) != 1:
                    one = f"exactly one shape ({', '.join(SHAPES)})"
                    raise error_at(geometry, f"<geometry> must hold {one}, found {len(shapes)}")
                shape = shapes[0]
                if shape.tag not in SHAPES:
                    raise error_at(
                        shape, f"unknown shape <{shape.tag}>; URDF shapes are {', '.join(SHAPES)}"
                    )
                for attr in SHAPES[shape.tag]:
                    if shape.get(attr) is None:
                        raise error_at(shape, f"<{shape.tag} {attr}> is required", attr)
                mat = single(el, "material", required=False) if part == "visual" else None
                if mat is None:
                    continue
                if mat.get("name") is None:  # urdfdom drops the visual; "" is accepted
                    raise error_at(mat, "a visual <material> needs a name attribute", "name")
                _check_color(mat)
