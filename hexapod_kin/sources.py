"""What a model source means — one meaning everywhere (load, chain_from_urdf, the exporters).

:func:`resolve_source` turns a :class:`~hexapod_kin.params.Chain` or ``Hexapod``, a path, or a
string (in this order: URDF text, a preset name, ``erd:NAME``, a ``.urdf``/``.xml``/``.xacro``
or table file) into a :class:`ResolvedSource`. Also example-robot-data's index
(:func:`erd_names`, :func:`erd_path`) and yourdfpy (:func:`yourdfpy_load`). No Pinocchio.
"""

from __future__ import annotations

import functools
import io
import os
import re
import threading
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from . import robots
from ._fields import fields_dict
from .exceptions import SourceError, UrdfError, choices, did_you_mean
from .params import Chain, Hexapod
from .urdf import TABLE_SUFFIXES, to_urdf

__all__ = ["ResolvedSource", "erd_names", "erd_path", "erd_share", "resolve_source",
           "yourdfpy_load"]  # fmt: skip


# ------------------------------------------------------------------------ example-robot-data
def erd_share() -> Path:
    """Directory ``share`` of the example-robot-data 6 (cmeel) package (else SourceError)."""
    import importlib.metadata  # here: ~30 ms that the other sources do not need

    try:
        dist = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError:
        raise SourceError(
            "example-robot-data is not installed; `pip install example-robot-data==6.0.0`",
            parameter="source",
        ) from None
    share = Path(str(dist.locate_file("cmeel.prefix/share")))
    if not (share / "example-robot-data" / "robots").is_dir():
        raise SourceError(f"example-robot-data data not found under {share}")
    return share


@functools.lru_cache(maxsize=1)
def _erd_index() -> dict[str, Path]:
    robots_dir = erd_share() / "example-robot-data" / "robots"
    index: dict[str, Path] = {}
    files = sorted(robots_dir.rglob("*.urdf"))
    stems = Counter(path.stem for path in files)
    for path in files:
        index.setdefault(path.stem, path)
        if stems[path.stem] > 1:  # e.g. anymal: also "<description folder>/<stem>"
            index[f"{path.relative_to(robots_dir).parts[0]}/{path.stem}"] = path
    return index


def erd_names() -> list[str]:
    """Names of every example-robot-data URDF, sorted (``<folder>/<stem>`` too for ``anymal``)."""
    return sorted(_erd_index())


def erd_path(name: str) -> Path:
    """Path of the example-robot-data URDF ``name`` (``"solo12"``; a unique prefix, ``"ur5"``).

    Raises:
        SourceError: No such robot (close names suggested, those that exist listed).

    """
    index = _erd_index()
    if name in index:
        return index[name]
    names = sorted(index)
    aliases = [n for n in names if isinstance(name, str) and name and n.startswith(name)]
    exact = [n for n in aliases if n in (f"{name}_robot", f"{name}_description")]
    if len(exact) == 1:
        return index[exact[0]]
    if len(aliases) == 1:
        return index[aliases[0]]
    raise SourceError(
        f"erd robot {name!r} does not exist{did_you_mean(str(name), names)}; "
        f"example-robot-data has {choices(names, limit=200)}",
        parameter="source",
        value=f"erd:{name}",
        allowed=names,
    )


# ------------------------------------------------------------------------ package://
_PACKAGE_URI = re.compile(r"package:///?([^/\s\"'<>]+)/")


def _package_name(folder: Path) -> str | None:
    """The ``<name>`` of ``folder/package.xml`` (None without one, or unreadable)."""
    manifest = folder / "package.xml"
    try:
        if not manifest.is_file() or manifest.stat().st_size > 1_000_000:
            return None
        found = re.search(r"<name>\s*([^<\s]+)\s*</name>", manifest.read_text("utf-8", "replace"))
    except OSError:
        return None
    return found.group(1) if found else None


def _package_dirs_for(path: Path | None, text: str, extra: tuple[str, ...] = ()) -> tuple[str, ...]:
    """Directories where the ``package://PKG/...`` URIs of ``text`` resolve, as ROS tools do.

    In order, de-duplicated: ``extra`` (the user's), ``ROS_PACKAGE_PATH`` entries holding
    ``PKG``, being ``PKG`` or with ``PKG/package.xml`` at most three levels below, then the
    folders named ``PKG`` above the URDF file ``path`` (``None`` for text).
    """
    out: list[str] = []

    def add(p: str | os.PathLike[str]) -> None:
        full = os.path.abspath(os.fspath(p))
        if os.path.isdir(full) and full not in out:
            out.append(full)

    for d in extra:
        add(d)
    packages = sorted(set(_PACKAGE_URI.findall(text)))
    if not packages:
        return tuple(out)
    for entry in filter(None, os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep)):
        root = Path(entry)
        for pkg in packages:
            if (root / pkg).is_dir():
                add(root)
            elif root.name == pkg or _package_name(root) == pkg:
                add(root.parent)
            else:
                for depth in ("*", "*/*", "*/*/*"):
                    for hit in root.glob(f"{depth}/{pkg}/package.xml"):
                        add(hit.parent.parent)
    if path is not None:
        here = path.resolve().parent
        for folder in (here, *here.parents):
            if folder.name in packages:
                add(folder.parent)
    return tuple(out)


# ------------------------------------------------------------------------ sources
@dataclass(frozen=True)
class ResolvedSource:
    """A source resolved to URDF ``text``, with its ``name`` (preset, file, ``erd:NAME``).

    Its meshes resolve in ``package_dirs`` and ``mesh_root``; ``params``, ``path``: if any.
    """

    text: str
    name: str
    package_dirs: tuple[str, ...] = ()
    mesh_root: str | None = None
    params: Chain | Hexapod | None = None
    path: str | None = None

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready fields (the URDF text left out; ``params`` as its name)."""
        params = None if self.params is None else self.params.name
        return {**fields_dict(self, "name", "package_dirs", "mesh_root"), "params": params,
                "path": self.path}  # fmt: skip


def _read_text(path: Path) -> str:
    from ._gate import MAX_URDF_BYTES
    from ._reader import read_text

    return read_text(path, "source", MAX_URDF_BYTES, too_big=UrdfError)


def _no_params(params: dict[str, Any], what: str) -> None:
    if params:
        raise SourceError(
            f"preset parameters {sorted(params)} given for non-preset {what}; only a preset "
            "name or a table file takes parameters (-s/--set NAME=VALUE on the command line)",
            parameter="params",
            value=sorted(params),
            allowed="a preset name or a .toml/.yaml table file",
        )


# ------------------------------------------------------------------------ xacro
_FIND = re.compile(r"\$\(find\s+([^)\s]+)\s*\)")
_XACRO_LOCK = threading.Lock()


def _find_package(pkg: str, path: Path, dirs: tuple[str, ...], named: dict[str, str]) -> str:
    """The folder of ROS package ``pkg`` for ``$(find pkg)``, without ROS (see :func:`_expand`)."""
    if pkg in named:
        return named[pkg]
    for folder in _package_dirs_for(path, f"package://{pkg}/", dirs):
        if (Path(folder) / pkg).is_dir():
            return str(Path(folder) / pkg)
    raise SourceError(
        f"source={str(path)!r}: $(find {pkg}) names a ROS package that was not found; give "
        f"--package-dir {pkg}=PATH (package_dirs=['{pkg}=PATH']), a folder holding {pkg}/, "
        "or set ROS_PACKAGE_PATH",
        parameter="package_dirs",
        value=pkg,
        allowed="DIR or NAME=PATH",
    )


def _expand(path: Path, text: str, dirs: tuple[str, ...], named: dict[str, str]) -> str:
    """A ROS xacro file expanded by the ``xacro`` package without ROS (one at a time: a lock).

    ``$(find PKG)``: a ``NAME=PATH`` entry of ``package_dirs``, else a ``PKG`` folder found as
    :func:`_package_dirs_for` finds them (xacro's hook swapped for the call only).

    Raises:
        SourceError: A package that cannot be found.
        UrdfError: xacro refuses the document.

    """
    from .exceptions import OptionalDependencyError

    try:
        import xacro
        from xacro import substitution_args
    except ImportError:
        raise OptionalDependencyError(
            "expanding a .xacro file needs the xacro package (the `export` extra: "
            "`pip install -e '.[export]'` in a clone)",
            parameter="source",
        ) from None
    find = functools.cache(lambda pkg: _find_package(pkg, path, dirs, named))
    for pkg in _FIND.findall(text):  # a missing package: one clear error before xacro runs
        find(pkg)
    with _XACRO_LOCK:
        saved = substitution_args._eval_find, xacro.filestack, xacro.macrostack
        substitution_args._eval_find = find
        xacro.init_stacks(str(path))  # relative includes resolve next to the file
        try:
            doc = xacro.parse(text)
            xacro.process_doc(doc)
            return str(doc.toxml())
        except SourceError:
            raise
        except Exception as exc:  # xacro raises XacroException, expat errors, NameError, ...
            raise UrdfError(f"source={str(path)!r}: xacro could not expand it: {exc}") from None
        finally:
            substitution_args._eval_find, xacro.filestack, xacro.macrostack = saved


def _from_file(path: Path, package_dirs: tuple[str, ...], **params: Any) -> ResolvedSource:
    if not path.exists():
        raise SourceError(
            f"source={str(path)!r}: no such file", parameter="source", value=str(path)
        )
    if path.suffix.lower() in TABLE_SUFFIXES:
        from .tables import read_table

        chain = read_table(path, **params)
        return ResolvedSource(to_urdf(chain), path.name, params=chain, path=str(path))
    _no_params(params, f"file {str(path)!r}")
    text = _read_text(path)
    plain: list[str] = []  # package_dirs: folders, and NAME=PATH (package NAME is PATH)
    named: dict[str, str] = {}
    for entry in package_dirs:
        name, eq, folder = entry.partition("=")
        if eq and name and "/" not in name and os.sep not in name and not os.path.isdir(entry):
            if not os.path.isdir(folder):
                raise SourceError(
                    f"package_dirs entry {entry!r}: {folder!r} is not a directory; give "
                    "NAME=PATH with PATH the package's folder (the one holding package.xml)",
                    parameter="package_dirs",
                    value=entry,
                    allowed="DIR or NAME=PATH",
                )
            named[name] = os.path.abspath(folder)
        else:
            plain.append(entry)
    package_dirs = tuple(plain)
    if path.suffix.lower() == ".xacro":
        text = _expand(path, text, package_dirs, named)
    for name, folder in named.items():  # package://NAME/ resolves in NAME=PATH's parent
        if Path(folder).name == name:
            package_dirs = (*package_dirs, str(Path(folder).parent))
    dirs, root = _package_dirs_for(path, text, package_dirs), str(path.parent.resolve())
    return ResolvedSource(text, path.name, dirs, root, path=str(path))


_ACCEPTED = (
    "a Chain, a Hexapod, a preset name, a URDF path, URDF text, a table file "
    "(.toml/.yaml) or 'erd:NAME'"
)


def resolve_source(source: Any, *, package_dirs: Any = (), **params: Any) -> ResolvedSource:
    """Turn a chain, robot, preset name, file, URDF text or ``erd:NAME`` into URDF text.

    Args:
        source: What to load: a :class:`~hexapod_kin.params.Chain` or ``Hexapod``, a preset
            name (``"hexabot_leg"``), a URDF file path, URDF text, a table file (``.toml``,
            ``.yaml``; see :mod:`hexapod_kin.tables`) or ``"erd:NAME"``.
        package_dirs: Directories where ``package://PKG/...`` resolves first (``<dir>/PKG``);
            ``NAME=PATH``: package NAME is the folder PATH (a xacro's ``$(find NAME)``).
        **params: Preset parameters (only with a preset name).

    Raises:
        SourceError: The source cannot be resolved (close names suggested).

    """
    if isinstance(package_dirs, (str, os.PathLike)):
        package_dirs = (package_dirs,)
    try:
        extra = tuple(os.fspath(d) for d in package_dirs)
    except TypeError:
        raise SourceError(
            f"package_dirs={package_dirs!r} is not allowed; give a list of directories",
            parameter="package_dirs",
            value=package_dirs,
        ) from None
    if isinstance(source, (Chain, Hexapod)):
        _no_params(params, type(source).__name__)
        return ResolvedSource(to_urdf(source), source.name, params=source)
    if isinstance(source, os.PathLike):
        return _from_file(Path(source), extra, **params)
    if not isinstance(source, str):
        raise SourceError(
            f"source of type {type(source).__name__} is not allowed; give {_ACCEPTED}",
            parameter="source",
            value=source,
            allowed=_ACCEPTED,
        )
    text = source.strip()
    names = robots.names()
    if not text:
        raise SourceError(
            f"source={source!r} is empty; give a preset name ({choices(names)}), a URDF "
            "path, URDF text, a table file or 'erd:NAME'",
            parameter="source",
            value=source,
            allowed=names,
        )
    if text.startswith("<"):
        _no_params(params, "URDF text")
        return ResolvedSource(
            source, "urdf-text", package_dirs=_package_dirs_for(None, source, extra)
        )
    if text in robots.PRESETS:
        built = robots.get(text, **params)
        return ResolvedSource(to_urdf(built), text, params=built)
    if text.startswith("erd:"):
        _no_params(params, repr(text))
        path = erd_path(text[4:])
        return ResolvedSource(_read_text(path), f"erd:{path.stem}", (*extra, str(erd_share())),
                              str(path.parent), path=str(path))  # fmt: skip
    path = Path(text).expanduser()
    if path.suffix.lower() in (".urdf", ".xml", ".xacro", *TABLE_SUFFIXES) or path.exists():
        return _from_file(path, extra, **params)
    hint = did_you_mean(text, names)
    if not hint:  # then example-robot-data names (given as erd:NAME)
        try:
            close = did_you_mean(text[3:].lstrip(":") if text.startswith("erd") else text,
                                 erd_names())  # fmt: skip
        except SourceError:
            close = ""
        found = close[len(" (did you mean ") : -len("?)")].split(" or ")
        erd = " or ".join(f"'erd:{n.strip(chr(39))}'" for n in found)
        hint = f" (did you mean {erd}?)" if close else ""
    raise SourceError(
        f"source={text!r} is not a preset, a file or 'erd:NAME'{hint}; presets are "
        f"{choices(names)}",
        parameter="source",
        value=text,
        allowed=names,
    )


# ------------------------------------------------------------------------ second engine
def yourdfpy_load(text: str) -> Any:
    """The URDF text, which passed the gate, loaded by yourdfpy (meshes not loaded).

    Raises:
        OptionalDependencyError: yourdfpy is not installed.

    """
    try:
        import yourdfpy
    except ImportError:  # pragma: no cover - yourdfpy is a test dependency
        from .exceptions import OptionalDependencyError

        raise OptionalDependencyError(
            "yourdfpy is not installed; `pip install yourdfpy`", parameter="engine"
        ) from None
    return yourdfpy.URDF.load(
        io.BytesIO(text.encode("utf-8")),
        build_scene_graph=True,
        build_collision_scene_graph=False,
        load_meshes=False,
        load_collision_meshes=False,
    )
