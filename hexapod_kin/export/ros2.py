"""A ROS 2 description package (ament_cmake) for a chain or robot, written atomically.

``package.xml`` (format 3), ``CMakeLists.txt``, ``urdf/<robot>.urdf`` and ``.urdf.xacro``,
``launch/display.launch.py``, ``rviz/display.rviz``, ``meshes/`` and a README; built in a
temporary folder beside ``out`` and renamed into place. No ROS installation is needed.
"""

from __future__ import annotations

import os
import re
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .. import __version__
from .._io import atomic_write
from ..exceptions import ParameterError
from ..params import Chain
from ..urdf import to_urdf
from ._common import comment, table_of
from .meshes import add_collisions, mesh_visuals
from .xacro import to_xacro

__all__ = ["export_package", "package_name_for", "PackageExport", "PACKAGE_NAME_RE"]

#: REP 144 package names: lower case letters, digits and underscores, starting with a letter.
PACKAGE_NAME_RE = re.compile(r"^[a-z][a-z0-9_]*$")
_EMAIL_RE = re.compile(r"^[^@\s<>\"]+@[^@\s<>\"]+\.[A-Za-z]{2,}$")
#: The package's file templates (``str.format`` fields; package data).
_TEMPLATES = Path(__file__).with_name("templates")

#: exec_depend of package.xml: everything the launch file imports or runs.
EXEC_DEPENDS = tuple(
    "launch launch_ros robot_state_publisher joint_state_publisher joint_state_publisher_gui "
    "rviz2 xacro".split()
)


@dataclass(frozen=True)
class PackageExport:
    """What :func:`export_package` wrote: the folder, the ROS package name, the files (sorted)."""

    path: Path
    name: str
    files: tuple[str, ...]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: path, name, files."""
        return {"path": str(self.path), "name": self.name, "files": list(self.files)}


def package_name_for(robot_name: str) -> str:
    """Default package name: ``<robot>_description`` made a valid REP 144 name."""
    base = re.sub(r"[^a-z0-9_]", "_", robot_name.lower())
    if not base or not base[0].isalpha():
        base = "robot_" + base
    return f"{base}_description"


def _template(file: str, **fields: str) -> str:
    """The file template ``templates/<file>.tmpl`` filled with ``fields`` (``str.format``)."""
    return (_TEMPLATES / f"{file}.tmpl").read_text(encoding="utf-8").format(**fields)


def _check_out(out: Path, force: bool) -> None:
    parent = out.parent if str(out.parent) else Path(".")
    why = None
    if not parent.is_dir():
        why = f": directory {str(parent)!r} does not exist"
    elif out.exists() and not out.is_dir():
        why = " is a file; expected a directory for the package"
    elif out.is_dir() and any(out.iterdir()) and not force:
        why = " exists and is not empty; choose a new folder or pass force=True (--force) to "
        why += "replace it"
    if why is not None:
        raise ParameterError(f"out={str(out)!r}{why}", parameter="out", value=str(out))


def package_files(
    source: Any,
    *,
    name: str | None = None,
    meshes: bool = False,
    header: str | None = None,
    maintainer: str = "hexapod_kin user",
    email: str = "user@example.com",
    license: str = "BSD-3-Clause",  # noqa: A002
) -> tuple[str, dict[str, bytes]]:
    """The package name and its files (path relative to the package → bytes, sorted).

    Args:
        source: Any source with a parameter table (a Chain, a Hexapod, a preset, a file).
        name: ROS package name (REP 144); default ``<robot>_description``.
        meshes: STL visuals (trimesh) in ``meshes/`` (``package://<name>/meshes/...``).
        header: Header line recorded in every file (the command that made it).
        maintainer: Maintainer name.
        email: Maintainer e-mail (package format 3 requires one).
        license: License identifier.

    Raises:
        ParameterError: For an invalid name, e-mail or source.

    """
    from xml.sax.saxutils import escape  # here: it imports urllib and ssl (~70 ms)

    src = table_of(source)
    pkg = package_name_for(src.name) if name is None else name
    if not isinstance(pkg, str) or not PACKAGE_NAME_RE.match(pkg):
        msg = (
            f"name={pkg!r} is not a valid ROS package name; use lower case letters, digits and "
            "underscores, starting with a letter (REP 144)"
        )
        raise ParameterError(msg, parameter="name", value=pkg)
    if not _EMAIL_RE.match(email):
        msg = f"email={email!r} is not an e-mail address (package.xml requires one)"
        raise ParameterError(msg, parameter="email", value=email)
    for label, value in (("maintainer", maintainer), ("license", license)):
        if not value.strip():
            raise ParameterError(f"{label}={value!r} is empty", parameter=label, value=value)
    made = header or f"made by hexapod_kin {__version__}"
    description = src.description or src.name
    urdf = to_urdf(src, header=made)
    files: dict[str, str | bytes] = {}
    if meshes:
        meshed = mesh_visuals(urdf, f"package://{pkg}/meshes/")
        files[f"urdf/{src.name}.urdf"] = meshed.urdf
        files.update({f"meshes/{fname}": data for fname, data in meshed.files.items()})
    else:
        files[f"urdf/{src.name}.urdf"] = add_collisions(urdf)
        files["meshes/README.md"] = (
            "No meshes: this package was exported without `--meshes`; visuals are primitives.\n"
        )
    files[f"urdf/{src.name}.urdf.xacro"] = to_xacro(src, header=made)
    deps = "\n".join(f"  <exec_depend>{d}</exec_depend>" for d in EXEC_DEPENDS)
    files["package.xml"] = _template(
        "package.xml",
        name=pkg,
        description=escape(f"Robot description of {src.name}: {description}"),
        maintainer=escape(maintainer),
        email=escape(email),
        license=escape(license),
        comment=comment(made),
        deps=deps,
    )
    files["CMakeLists.txt"] = _template("CMakeLists.txt", name=pkg, header=made)
    launch = _template("display.launch.py", name=pkg, robot=src.name, header=made)
    files["launch/display.launch.py"] = launch
    root = src.base if isinstance(src, Chain) else src.body
    files["rviz/display.rviz"] = _template("display.rviz", fixed_frame=root, header=made)
    visuals = "primitives (cylinders, spheres, boxes)"
    if meshes:
        visuals = "STL meshes in `meshes/` (generated with trimesh from the link primitives)"
    files["README.md"] = _template(
        "README.md",
        name=pkg,
        robot=src.name,
        description=description,
        header=made,
        visuals=visuals,
        version=__version__,
    )
    out = {k: (v.encode("utf-8") if isinstance(v, str) else v) for k, v in files.items()}
    return pkg, dict(sorted(out.items()))


def export_package(
    source: Any, out: str | os.PathLike[str], *, force: bool = False, **options: Any
) -> PackageExport:
    """Write the ROS 2 description package of ``source`` into the folder ``out``, atomically.

    Args:
        source: A source with a parameter table (as :func:`package_files`).
        out: The package folder to create (its parent must exist).
        force: Replace ``out`` if it exists and is not empty.
        **options: The keywords of :func:`package_files`.

    Raises:
        ParameterError: Invalid name/e-mail/source, missing parent folder, or ``out`` exists
            and is not empty without ``force``.
        OptionalDependencyError: ``meshes=True`` without trimesh.

    """
    dest = Path(out)
    _check_out(dest, force)
    pkg, files = package_files(source, **options)
    parent = dest.parent if str(dest.parent) else Path(".")
    tmp = Path(tempfile.mkdtemp(prefix=f".{dest.name}.", suffix=".tmp", dir=parent))
    old: Path | None = None
    try:
        for rel, data in files.items():
            path = tmp / rel
            path.parent.mkdir(parents=True, exist_ok=True)
            atomic_write(path, data)
        for d in [tmp, *(p for p in tmp.rglob("*") if p.is_dir())]:
            os.chmod(d, 0o755)
        if dest.exists():
            old = Path(tempfile.mkdtemp(prefix=f".{dest.name}.", suffix=".old", dir=parent))
            os.rename(dest, old / "pkg")
        os.rename(tmp, dest)
    except BaseException:
        if old is not None and not dest.exists():
            os.rename(old / "pkg", dest)
        shutil.rmtree(tmp, ignore_errors=True)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
        raise
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)
    return PackageExport(dest, pkg, tuple(files))
