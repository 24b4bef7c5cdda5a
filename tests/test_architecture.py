"""The layout rules of docs/ARCHITECTURE.md, checked by parsing every module of the package.

* no module over :data:`MAX_LINES` lines, except the documented :data:`LONG_MODULES`;
* no import circle, counting every import (module level, inside functions, under
  ``TYPE_CHECKING``): ``from . import sibling`` is an import of the module ``sibling``, and of
  the package ``__init__`` only when ``sibling`` is not a module;
* no two parts of the package (subpackages and top-level modules) import each other, even
  through different modules of each and inside functions (e.g. ``viewer`` may import ``gait``,
  then no module of ``gait`` imports ``viewer``);
* no ``from X import _private`` across modules, except between modules of the same subpackage;
* no private module or name of another package (a dependency), in any import form;
* the core (everything left of viewer/plots/cli in the data flow) never imports the
  application layer (:data:`APP_LAYER`) at module level;
* every subpackage and lazy submodule named by ``hexapod_kin`` exists.

These read the source only (nothing is imported), so they are fast and cannot be fooled by
import side effects.
"""

from __future__ import annotations

import ast
import functools
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1] / "hexapod_kin"
MAX_LINES = 800
#: Modules allowed over MAX_LINES, each with its reason (keep this list short and true).
LONG_MODULES: dict[str, str] = {
    # none today; an entry reads "path relative to hexapod_kin/": "why one job needs the length"
}
#: The application layer: the core never imports these at module level.
APP_LAYER = ("viewer", "plots", "cli", "report", "sweep", "drive")


def _modules() -> list[Path]:
    return sorted(p for p in ROOT.rglob("*.py") if "__pycache__" not in p.parts)


@functools.cache
def _tree(path: Path) -> ast.Module:
    return ast.parse(path.read_text(encoding="utf-8"), filename=str(path))


def _dotted(path: Path) -> str:
    rel = path.relative_to(ROOT.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _package_of(path: Path) -> str:
    dotted = _dotted(path)
    return dotted if path.name == "__init__.py" else dotted.rpartition(".")[0]


def _resolve(path: Path, node: ast.ImportFrom) -> str:
    """Absolute module name of an ``ImportFrom`` (relative levels resolved)."""
    if node.level == 0:
        return node.module or ""
    base = _package_of(path).split(".")
    base = base[: len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


@functools.cache
def _is_module(dotted: str) -> bool:
    rel = Path(*dotted.split("."))
    return (ROOT.parent / rel).with_suffix(".py").exists() or (ROOT.parent / rel).is_dir()


def _top_level_imports(tree: ast.Module) -> list[ast.Import | ast.ImportFrom]:
    """Imports run when the module is imported (not inside functions or TYPE_CHECKING)."""
    found: list[ast.Import | ast.ImportFrom] = []

    def visit(body: list[ast.stmt]) -> None:
        for node in body:
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                found.append(node)
            elif isinstance(node, ast.If):
                if "TYPE_CHECKING" in ast.unparse(node.test):
                    visit(node.orelse)
                else:
                    visit(node.body)
                    visit(node.orelse)
            elif isinstance(node, ast.Try):
                for part in (node.body, node.orelse, node.finalbody):
                    visit(part)
                for handler in node.handlers:
                    visit(handler.body)
            elif isinstance(node, (ast.With,)):
                visit(node.body)

    visit(tree.body)
    return found


def _all_imports(tree: ast.Module) -> list[ast.ImportFrom]:
    return [n for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)]


def _rel(path: Path) -> str:
    return path.relative_to(ROOT).as_posix()


def test_the_walk_finds_the_package() -> None:
    mods = {_rel(p) for p in _modules()}
    assert {"__init__.py", "params.py", "model.py", "_numerics.py"} <= mods
    assert len(mods) > 50


def test_no_module_over_the_line_cap_except_documented() -> None:
    sizes = {_rel(p): len(p.read_text(encoding="utf-8").splitlines()) for p in _modules()}
    over = {name: n for name, n in sizes.items() if n > MAX_LINES and name not in LONG_MODULES}
    assert not over, f"modules over {MAX_LINES} lines (split them or document why): {over}"
    stale = [name for name in LONG_MODULES if sizes.get(name, 0) <= MAX_LINES]
    assert not stale, f"allow-list entries no longer needed: {stale}"


def _private_in(path: Path, tree: ast.Module) -> list[str]:
    """``from X import _name`` lines of one module that break the rule."""
    bad = []
    here_pkg = _package_of(path).split(".")
    for node in _all_imports(tree):
        target = _resolve(path, node)
        for alias in node.names:
            name = alias.name
            if not name.startswith("_") or name.startswith("__"):
                continue
            if _is_module(f"{target}.{name}"):
                continue  # a private module of a package, imported as a module
            # Same subpackage (not the root package): hexapod_kin.<sub>... -> hexapod_kin.<sub>...
            target_parts = target.split(".")
            if len(here_pkg) > 1 and len(target_parts) > 1 and here_pkg[1] == target_parts[1]:
                continue
            bad.append(f"{_rel(path)}:{node.lineno}: from {target} import {name}")
    return bad


def _private_imports() -> list[str]:
    bad = []
    for path in _modules():
        bad += _private_in(path, _tree(path))
    return bad


def test_no_private_name_imported_across_modules() -> None:
    bad = _private_imports()
    assert not bad, "private names imported across modules:\n" + "\n".join(bad)


def _dependency_privates(tree: ast.Module) -> list[tuple[int, str]]:
    """Private modules or names of other packages imported in ``tree``, in any import form.

    ``import a._b``, ``import a._b as c``, ``from a._b import c``, ``from a import _b``: a
    leading underscore in any part of another package's dotted path (``__future__`` aside).
    """
    bad = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            paths = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            paths = [f"{node.module}.{a.name}" for a in node.names if a.name != "*"]
        else:
            continue
        for dotted in paths:
            parts = dotted.split(".")
            if parts[0] not in ("hexapod_kin", "__future__") and any(
                c.startswith("_") for c in parts
            ):
                bad.append((node.lineno, dotted))
    return bad


def test_no_private_module_or_name_of_a_dependency_is_imported() -> None:
    """The standards: no private APIs of our dependencies (they change without notice)."""
    planted = ast.parse(
        "import numpy.linalg._umath_linalg as lap\n"
        "from numpy.linalg import _umath_linalg\n"
        "from numba.core._caching import x\n"
        "import numpy as np\nfrom numpy.linalg import solve\nfrom __future__ import annotations\n"
        "from . import _private\nimport hexapod_kin._budget\n"
    )
    assert [n for n, _ in _dependency_privates(planted)] == [1, 2, 3]
    bad = [f"{_rel(p)}:{n}: {d}" for p in _modules() for n, d in _dependency_privates(_tree(p))]
    assert not bad, "private APIs of dependencies imported:\n" + "\n".join(bad)


def _layer(dotted: str) -> str:
    parts = dotted.split(".")
    return parts[1] if len(parts) > 1 else ""


def test_core_never_imports_the_application_layer_at_module_level() -> None:
    bad = []
    for path in _modules():
        here = _dotted(path)
        if _layer(here) in APP_LAYER or here == "hexapod_kin.__main__":
            continue
        tree = _tree(path)
        for node in _top_level_imports(tree):
            if isinstance(node, ast.ImportFrom):
                target = _resolve(path, node)
                names = [f"{target}.{a.name}" for a in node.names]
                targets = [target] + [n for n in names if _is_module(n)]
            else:
                targets = [a.name for a in node.names]
            for t in targets:
                if t.startswith("hexapod_kin.") and _layer(t) in APP_LAYER:
                    bad.append(f"{_rel(path)}:{node.lineno}: imports {t}")
    assert not bad, "core modules importing the application layer:\n" + "\n".join(bad)


@pytest.mark.parametrize("name", ["symbolic", "_gate", "singularity", "ik", "motion", "viewer"])
def test_packages_named_in_the_architecture_exist(name: str) -> None:
    assert (ROOT / name / "__init__.py").exists()


def test_lazy_submodules_exist() -> None:
    tree = ast.parse((ROOT / "__init__.py").read_text(encoding="utf-8"))
    lazy: list[str] = []
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(
            isinstance(t, ast.Name) and t.id == "_LAZY_SUBMODULES" for t in node.targets
        ):
            lazy = [ast.literal_eval(e) for e in node.value.elts]  # type: ignore[attr-defined]
    assert lazy, "hexapod_kin.__init__ has no _LAZY_SUBMODULES tuple"
    missing = [n for n in lazy if not _is_module(f"hexapod_kin.{n}")]
    assert not missing, f"lazy submodules that do not exist: {missing}"


# ----------------------------------------------------------------------------- import circles
def _module_names() -> dict[str, Path]:
    return {_dotted(p): p for p in _modules()}


def _imported(path: Path, tree: ast.AST, known: set[str]) -> set[str]:
    """Modules of the package that ``tree`` imports anywhere (functions and TYPE_CHECKING too)."""
    out: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            target = _resolve(path, node)
            for alias in node.names:
                sub = f"{target}.{alias.name}"
                out.add(sub if sub in known else target)
        elif isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
    return out & known - {_dotted(path)}


@functools.cache
def _import_graph() -> dict[str, set[str]]:
    mods = _module_names()
    known = set(mods)
    return {name: _imported(path, _tree(path), known) for name, path in mods.items()}


def _circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            v, edges = work[-1]
            w = next(edges, None)
            if w is not None:
                if w not in index:
                    index[w] = low[w] = len(index)
                    stack.append(w)
                    on_stack.add(w)
                    work.append((w, iter(sorted(graph.get(w, ())))))
                elif w in on_stack:
                    low[v] = min(low[v], index[w])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[v])
            if low[v] == index[v]:
                comp = []
                while True:
                    w = stack.pop()
                    on_stack.discard(w)
                    comp.append(w)
                    if w == v:
                        break
                if len(comp) > 1:
                    found.append(sorted(comp))
    return found


def test_no_import_circle() -> None:
    graph = _import_graph()
    assert {"hexapod_kin.params", "hexapod_kin.kinematics"} <= graph.keys()
    bad = _circles(graph)
    text = "\n".join(
        " <-> ".join(c) + ": " + str({m: sorted(graph[m] & set(c)) for m in c}) for c in bad
    )
    assert not bad, "import circles:\n" + text


def test_the_circle_finder_sees_planted_circles() -> None:
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a", "d"}, "d": set(), "e": {"e"}}
    assert _circles(graph) == [["a", "b", "c"]]
    kin = ROOT / "kinematics.py"
    known = {"hexapod_kin", "hexapod_kin.model", "hexapod_kin.params", "hexapod_kin.robots"}
    src = "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from .params import Chain\n"
    src += "def f():\n    from . import robots, load\n    import hexapod_kin.model\n"
    assert _imported(kin, ast.parse(src), known) == known


def _part(dotted: str) -> str:
    """The part of the package a module belongs to: ``hexapod_kin.gait.walk`` -> ``gait``."""
    parts = dotted.split(".")
    return parts[1] if len(parts) > 1 else ""


def _mutual_parts(graph: dict[str, set[str]]) -> dict[tuple[str, str], list[str]]:
    """Pairs of parts that import each other, each with the imports that make the pair."""
    edges: dict[tuple[str, str], list[str]] = {}
    for here, targets in graph.items():
        for there in targets:
            a, b = _part(here), _part(there)
            if a and b and a != b:
                edges.setdefault((a, b), []).append(f"{here} -> {there}")
    return {
        (a, b): sorted(why + edges[(b, a)])
        for (a, b), why in edges.items()
        if a < b and (b, a) in edges
    }


def test_no_two_parts_import_each_other() -> None:
    bad = _mutual_parts(_import_graph())
    text = "\n".join(f"{a} <-> {b}: {why}" for (a, b), why in sorted(bad.items()))
    assert not bad, "parts of the package importing each other:\n" + text


def test_the_pair_finder_sees_planted_pairs() -> None:
    graph = {
        "hexapod_kin.gait.show": {"hexapod_kin.viewer.page"},  # gait -> viewer ...
        "hexapod_kin.viewer.live": {"hexapod_kin.gait.stand"},  # ... and viewer -> gait
        "hexapod_kin.viewer.page": {"hexapod_kin._page", "hexapod_kin.viewer.scene"},
        "hexapod_kin.report.build": {"hexapod_kin._page", "hexapod_kin"},
        "hexapod_kin": {"hexapod_kin.report.build"},  # the root package is no part
    }
    assert list(_mutual_parts(graph)) == [("gait", "viewer")]
    # an import inside a function counts (the graph reads every import)
    show = ROOT / "gait" / "show.py"
    src = "def f():\n    from ..viewer import export_html\n"
    assert _imported(show, ast.parse(src), {"hexapod_kin.viewer"}) == {"hexapod_kin.viewer"}


def test_data_classes_never_reach_the_loader() -> None:
    graph = _import_graph()
    reach: set[str] = set()
    todo = ["hexapod_kin.params"]
    while todo:
        for m in graph[todo.pop()] - reach:
            reach.add(m)
            todo.append(m)
    assert not reach & {"hexapod_kin.model", "hexapod_kin.kinematics", "hexapod_kin.sources"}


def test_the_checkers_see_planted_violations() -> None:
    # Root-package modules are not a subpackage: a private name between them is refused ...
    kin = ROOT / "kinematics.py"
    assert _private_in(kin, ast.parse("from .model import _hidden\n"))
    assert _private_in(kin, ast.parse("def f():\n    from .ik.solver import _x\n"))
    assert _private_in(kin, ast.parse("from ._numerics import _helper\n"))
    # ... a private module, or a private name inside one subpackage, is allowed.
    assert not _private_in(kin, ast.parse("from . import _gate\n"))
    assert not _private_in(ROOT / "ik" / "solver.py", ast.parse("from .step import _x\n"))
    assert _private_in(ROOT / "ik" / "solver.py", ast.parse("from ..motion.rate import _x\n"))
    # Module-level imports of the application layer are seen; those inside functions are not.
    src = "import os\ntry:\n    from . import plots\nexcept ImportError:\n    pass\n"
    top = _top_level_imports(ast.parse(src))
    assert [type(n).__name__ for n in top] == ["Import", "ImportFrom"]
    inner = _top_level_imports(ast.parse("def f():\n    from . import plots\n"))
    assert inner == []
