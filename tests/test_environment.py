"""No process-wide side effects: the package never writes the process's environment.

Importing every module, loading MuJoCo (which the toolkit never renders with), exporting a
MuJoCo model and running commands through :func:`hexapod_kin.cli.main` leave ``os.environ``
as it was; only the ``hexapod-kin`` program itself (:func:`hexapod_kin.cli.run`, which owns
its process) may set a default there.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "hexapod_kin"

CHILD = r"""
import importlib, json, os, pkgutil, warnings
before = dict(os.environ)
import hexapod_kin as hk
names = [m.name for m in pkgutil.walk_packages(hk.__path__, "hexapod_kin.")
         if not m.name.endswith("__main__")]
with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    for name in names:
        importlib.import_module(name)
from hexapod_kin.export._common import need
from hexapod_kin.export.mjcf import to_mjcf
from hexapod_kin.simulate.scene import _mujoco
need("mujoco")
_mujoco()
to_mjcf("hexabot_leg")
from hexapod_kin.cli import main
assert main(["fk", "hexabot_leg", "--json"]) == 0
assert main(["mjcf", "hexabot_leg", "-o", os.path.join(os.environ["HK_TMP"], "m.xml")]) == 0
after = dict(os.environ)
print(json.dumps({"modules": len(names),
                  "changed": sorted(k for k in set(before) | set(after)
                                    if before.get(k) != after.get(k))}))
"""


def test_importing_and_calling_leaves_the_environment_unchanged(tmp_path: Path) -> None:
    import json
    import os

    env = {k: v for k, v in os.environ.items() if k != "MUJOCO_GL"}
    env["HK_TMP"] = str(tmp_path)
    done = subprocess.run(
        [sys.executable, "-c", CHILD], capture_output=True, text=True, env=env, timeout=300
    )
    assert done.returncode == 0, done.stderr[-2000:]
    report = json.loads(done.stdout.strip().splitlines()[-1])
    assert report["modules"] > 50
    assert report["changed"] == [], report


def _writes_environ(tree: ast.AST) -> list[tuple[int, str]]:
    """Lines that write ``os.environ`` (item set/delete, a mutating method) or call putenv."""
    found: list[tuple[int, str]] = []
    mutating = {"setdefault", "update", "pop", "popitem", "clear", "__setitem__", "__delitem__"}

    def is_environ(node: ast.AST) -> bool:
        return (isinstance(node, ast.Attribute) and node.attr == "environ") or (
            isinstance(node, ast.Name) and node.id == "environ"
        )

    for node in ast.walk(tree):
        targets: list[ast.AST] = []
        if isinstance(node, (ast.Assign, ast.AugAssign, ast.AnnAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
        elif isinstance(node, ast.Delete):
            targets = node.targets
        for target in targets:
            if isinstance(target, ast.Subscript) and is_environ(target.value):
                found.append((node.lineno, "os.environ[...]"))
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute):
            if node.func.attr in mutating and is_environ(node.func.value):
                found.append((node.lineno, f"os.environ.{node.func.attr}"))
            if node.func.attr in ("putenv", "unsetenv"):
                found.append((node.lineno, f"os.{node.func.attr}"))
    return found


def _function_at(tree: ast.AST, line: int) -> str:
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef) and node.lineno <= line <= (node.end_lineno or 0):
            return node.name
    return "<module>"


def test_no_module_writes_the_environment() -> None:
    """Static: the one write of the package is the program's default in ``cli.run``."""
    writes = []
    for path in sorted(PACKAGE.rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for line, what in _writes_environ(tree):
            where = f"{path.relative_to(PACKAGE.parent)}:{_function_at(tree, line)}"
            writes.append((where, what))
    assert writes == [("hexapod_kin/cli/__init__.py:run", "os.environ.setdefault")], writes


def test_the_scan_finds_writes() -> None:
    """The scan itself: each form of writing is found, reading is not."""
    text = (
        "import os\nos.environ['A'] = '1'\nos.environ.setdefault('B', '2')\n"
        "del os.environ['A']\nos.putenv('C', '3')\nx = os.environ.get('D')\n"
        "from os import environ\nenviron.update(E='4')\n"
    )
    assert sorted(line for line, _ in _writes_environ(ast.parse(text))) == [2, 3, 4, 5, 8]
