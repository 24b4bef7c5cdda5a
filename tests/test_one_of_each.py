"""One of each: the package's numeric FK implementations, IK loops and rotation builders, by name.

The package source is parsed (AST; nothing is imported) and four kinds of function are
listed (issue 30, "one of each"):

* **FK** — a numeric forward-kinematics implementation: a loop over joints that makes each
  joint's rotation itself (numeric ``cos`` and ``sin``, ``sincos``, or a per-row transform
  builder ``*transform(s)``) and accumulates the frame across iterations (a variable both read
  and written in the loop). Calls into Pinocchio are not implementations.
* **IK loop** — a damped-least-squares / Newton iteration: a loop that solves a (damped)
  normal system or applies a pseudo-inverse (``solve``, ``inv``, ``pinv``, ``lstsq``,
  ``cholesky``, the package's ``dls_*`` / ``step_into`` / ``*solve_spd`` / ``_inv_sym*``)
  and re-evaluates the kinematics in the same loop (a call whose name holds ``fk``,
  ``frames``, ``poses`` or ``jac``).
* **rotation** — a rotation matrix built from angles: numeric ``cos`` and ``sin`` of the same
  angle in a function that writes a matrix (a nested list literal, or an element store with
  two or more indices such as ``R[0, 1] = …``), or ``sincos``.
* **DLS step** — a damped-least-squares step: a function named ``*dls*``, or one that solves
  (``solve``, ``inv``, ``pinv``, ``lstsq``, ``cholesky``, ``cho_solve``, ``*solve_spd``) a
  sum with a product in it, a damped normal matrix such as ``JᵀJ + λ²I`` (the resolved-rate
  law kept a numpy copy, ``motion._law._dls``, until issue 34's session 8).

Each list must equal the allowed one: a new implementation makes the test fail, and the
second test proves it on a planted copy of the package.
"""

from __future__ import annotations

import ast
import shutil
from collections.abc import Iterator
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1] / "hexapod_kin"

#: One FK per engine (Pinocchio per call is Pinocchio's own): the numpy batch tree path, the
#: compiled layer (one FK + Jacobian core, per configuration and per block), the plain table
#: reference used by the tests and the seed report.
ALLOWED_FK = {
    "_tree.tree_frames",  # the numpy batch path (N configurations, structure of arrays)
    "_kernels.fk_jac_into",  # the compiled core, one configuration
    "_kernels.fk_jac_block",  # the compiled core, a block of configurations (z axes)
    "_table_kin.table_fk",  # the plain table reference (tests, seed report)
}

#: One IK loop: the compiled Levenberg–Marquardt loop of ik.solve / solve_many / solve_chain
#: (gait's numerical leg IK runs it through solve_chain; gait.paths.rolling_ik iterates
#: body_ik's solves on the rolling targets, a fixed point on targets, not a loop of its own).
ALLOWED_IK_LOOPS = {
    "ik.step.lm_loop",
}

#: Rotation matrices from angles: the pose module, the compiled core's sin/cos pair and block
#: FK, and one table row's transform (Khalil, standard DH).
ALLOWED_ROTATIONS = {
    "_pose.rpy_to_matrix",  # roll/pitch/yaw → R (the one Euler convention)
    "_kernels.fk_jac_block",  # joint rotations of the compiled block core
    "_kmath.sincos",  # the compiled core's sin/cos pair (fk_jac_into's rotations)
    "params.khalil_transform",  # one Khalil row's transform (the table)
    "params.dh_transform",  # one standard-DH row's transform
}

#: One DLS step per engine: numpy (a task; a stack of tasks), its 3×3 form on Python floats
#: (the same Cholesky as the compiled one) and the compiled one (the IK loop's).
ALLOWED_DLS = {
    "_numerics.dls_step",
    "_numerics.dls_step3",
    "_kmath.dls_into",
}

#: Still there, to be removed (issue 30): each named with what stands in the way. The test
#: fails when one disappears (then delete its entry) as when a new one appears.
PENDING = {
    "fk": set(),
    "ik": set(),
    "rotation": set(),
    "dls": set(),
}

#: Matches of the patterns that are something else (reviewed by hand).
REVIEWED = {
    "fk": set(),
    "ik": {
        "seeds.euler_baseline",  # the seed report's open-loop Euler + solve, kept on purpose
    },
    "rotation": {
        # SE(2)'s left Jacobian V(θ) of an unwrapped turn θ (a plan may turn past π, where
        # Pinocchio's log6 wraps): the mean twist of a plan's motion, not a rotation of a frame
        "robust.controlled.mean_twist",
    },
    "dls": set(),
}

_TRIG = {"cos", "sin"}
_SOLVES = {
    "solve",
    "inv",
    "pinv",
    "lstsq",
    "cholesky",
    "cho_solve",
    "solve_spd",
    "dls_step",
    "dls_step3",
    "dls_into",
    "step_into",
}
#: Solvers of a damped normal system (the DLS kind).
_DAMPED_SOLVES = {"solve", "inv", "pinv", "lstsq", "cholesky", "cho_solve"}
_BUILDERS = {"transform", "khalil_transform", "dh_transform", "table_transforms"}
_SYMBOLIC = {"sp", "sympy", "se", "symengine"}


def _name(call: ast.Call) -> str:
    f = call.func
    if isinstance(f, ast.Attribute):
        return f.attr
    return f.id if isinstance(f, ast.Name) else ""


def _numeric_trig(call: ast.Call) -> str:
    """``cos`` / ``sin`` / ``sincos`` of a numeric library (not sympy's), else ``""``."""
    f = call.func
    if isinstance(f, ast.Attribute) and isinstance(f.value, ast.Name):
        if f.value.id in _SYMBOLIC:
            return ""
    name = _name(call)
    return name if name in _TRIG or name == "sincos" else ""


def _own(nodes: list[ast.stmt] | ast.AST) -> Iterator[ast.AST]:
    """The nodes of a body, nested function and class bodies excluded."""
    stack: list[ast.AST] = list(nodes) if isinstance(nodes, list) else [nodes]
    while stack:
        node = stack.pop()
        yield node
        for child in ast.iter_child_nodes(node):
            if not isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                stack.append(child)


def _functions(tree: ast.Module) -> Iterator[tuple[str, ast.FunctionDef | ast.AsyncFunctionDef]]:
    def visit(node: ast.AST, prefix: str) -> Iterator[tuple[str, ast.FunctionDef]]:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                yield prefix + child.name, child  # type: ignore[misc]
                yield from visit(child, prefix + child.name + ".")
            elif isinstance(child, ast.ClassDef):
                yield from visit(child, prefix + child.name + ".")
            else:
                yield from visit(child, prefix)

    yield from visit(tree, "")


def _base(target: ast.AST) -> list[str]:
    """The variables a store target writes (``R``, ``R[…]``, ``a, b``, ``x.attr``)."""
    if isinstance(target, ast.Name):
        return [target.id]
    if isinstance(target, (ast.Subscript, ast.Attribute, ast.Starred)):
        return _base(target.value)
    if isinstance(target, (ast.Tuple, ast.List)):
        return [n for t in target.elts for n in _base(t)]
    return []


def _events(node: ast.AST, out: list[tuple[str, bool]]) -> None:
    """Reads (False) and writes (True) of variables in execution order (values before targets)."""
    if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef, ast.Lambda)):
        return
    if isinstance(node, ast.Assign):
        _events(node.value, out)
        for t in node.targets:
            _target(t, out)
    elif isinstance(node, ast.AugAssign):
        _events(node.value, out)
        out.extend((n, False) for n in _base(node.target))
        _target(node.target, out)
    elif isinstance(node, ast.Name):
        out.append((node.id, not isinstance(node.ctx, ast.Load)))
    else:
        for child in ast.iter_child_nodes(node):
            _events(child, out)


def _target(t: ast.AST, out: list[tuple[str, bool]]) -> None:
    if isinstance(t, ast.Subscript):
        _events(t.slice, out)
    out.extend((n, True) for n in _base(t))


def _accumulates(loop: ast.For | ast.While) -> bool:
    """True if a frame is carried across iterations into a product.

    A variable read before it is written in an iteration (loop-carried), or one assigned from
    such a variable, is an operand of a product (``*`` or ``@``) in the loop.
    """
    events: list[tuple[str, bool]] = []
    for stmt in loop.body:
        _events(stmt, events)
    first: dict[str, bool] = {}
    for name, write in events:
        first.setdefault(name, write)
    written = {n for n, w in events if w}
    carried = {n for n, w in first.items() if not w and n in written}
    for node in _own(loop.body):
        if isinstance(node, ast.Assign):
            loads = {n.id for n in ast.walk(node.value) if isinstance(n, ast.Name)}
            if loads & carried:
                for t in node.targets:
                    carried.update(_base(t))
    for node in _own(loop.body):
        if isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Mult, ast.MatMult)):
            names = {n.id for n in ast.walk(node) if isinstance(n, ast.Name)}
            if names & carried:
                return True
    return False


def _loops(fn: ast.AST) -> Iterator[ast.For | ast.While]:
    for node in _own(fn.body):  # type: ignore[attr-defined]
        if isinstance(node, (ast.For, ast.While)):
            yield node


def _calls(node: ast.AST) -> list[ast.Call]:
    return [n for n in _own([node]) if isinstance(n, ast.Call)]  # type: ignore[list-item]


def _calls_kinematics(calls: list[ast.Call]) -> bool:
    """A call whose name holds ``fk``, ``frames``, ``poses`` or ``jac`` (a kinematics user)."""
    return any(k in _name(c).lower() for c in calls for k in ("fk", "frames", "poses", "jac"))


def _steps(loop: ast.For | ast.While) -> bool:
    """True if the loop steps a carried iterate: ``x += …``, ``x -= …`` or ``x = x ± …``."""
    for node in _own(loop.body):
        if isinstance(node, ast.AugAssign) and isinstance(node.op, (ast.Add, ast.Sub)):
            return True
        if isinstance(node, ast.Assign) and isinstance(node.value, ast.BinOp):
            if isinstance(node.value.op, (ast.Add, ast.Sub)):
                left = {n.id for n in ast.walk(node.value.left) if isinstance(n, ast.Name)}
                if left & {n for t in node.targets for n in _base(t)}:
                    return True
    return False


def _is_fk(fn: ast.AST) -> bool:
    for loop in _loops(fn):
        calls = _calls(loop)
        trig = {_numeric_trig(c) for c in calls}
        rotates = _TRIG <= trig or "sincos" in trig
        builds = any(
            _name(c) in _BUILDERS and c.args and not isinstance(c.args[0], ast.Constant)
            for c in calls
        )
        if (rotates or builds) and _accumulates(loop) and not _calls_kinematics(calls):
            return True
    return False


def _is_ik_loop(fn: ast.AST) -> bool:
    for loop in _loops(fn):
        names = [_name(c) for c in _calls(loop)]
        solves = any(
            n in _SOLVES or n.endswith("solve_spd") or n.startswith("_inv_sym") for n in names
        )
        if solves and _calls_kinematics(_calls(loop)) and _steps(loop):
            return True
    return False


def _is_rotation(fn: ast.AST) -> bool:
    calls = _calls(fn)  # type: ignore[arg-type]
    if any(_numeric_trig(c) == "sincos" for c in calls) or getattr(fn, "name", "") == "sincos":
        return True
    args: dict[str, set[str]] = {"cos": set(), "sin": set()}
    for c in calls:
        kind = _numeric_trig(c)
        if kind in args and c.args:
            args[kind].add(ast.dump(c.args[0]))
    if not args["cos"] & args["sin"]:
        return False
    for node in _own(fn.body):  # type: ignore[attr-defined]
        if isinstance(node, ast.List) and any(isinstance(e, ast.List) for e in node.elts):
            return True
        targets = node.targets if isinstance(node, ast.Assign) else []
        for t in targets:
            if isinstance(t, ast.Subscript) and isinstance(t.slice, ast.Tuple):
                ints = [
                    e for e in t.slice.elts if isinstance(e, ast.Constant) and type(e.value) is int
                ]
                if len(ints) >= 2:
                    return True
    return False


def _has_product(node: ast.AST) -> bool:
    for n in ast.walk(node):
        if isinstance(n, ast.BinOp) and isinstance(n.op, (ast.Mult, ast.MatMult)):
            return True
        if isinstance(n, ast.Call) and _name(n) in {"dot", "matmul"}:
            return True
    return False


def _is_dls(fn: ast.FunctionDef | ast.AsyncFunctionDef) -> bool:
    """Named ``*dls*``, or a solve of ``A + B`` where ``A`` or ``B`` holds a product."""
    if "dls" in fn.name.lower():
        return True
    for c in _calls(fn):
        name = _name(c)
        if (name in _DAMPED_SOLVES or name.endswith("solve_spd")) and c.args:
            a = c.args[0]
            if isinstance(a, ast.BinOp) and isinstance(a.op, ast.Add):
                if _has_product(a.left) or _has_product(a.right):
                    return True
    return False


def scan(root: Path) -> dict[str, set[str]]:
    """The FK implementations, IK loops, rotation builders and DLS steps under ``root``, by name.

    Names are ``module.function`` relative to the package (``_tree.tree_frames``), methods
    and nested functions with their dotted path.
    """
    found: dict[str, set[str]] = {"fk": set(), "ik": set(), "rotation": set(), "dls": set()}
    for path in sorted(root.rglob("*.py")):
        module = ".".join(path.relative_to(root).with_suffix("").parts)
        module = module.removesuffix(".__init__").removesuffix("__init__")
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        for name, fn in _functions(tree):
            full = f"{module}.{name}" if module else name
            if _is_fk(fn):
                found["fk"].add(full)
            if _is_ik_loop(fn):
                found["ik"].add(full)
            if _is_rotation(fn):
                found["rotation"].add(full)
            if _is_dls(fn):
                found["dls"].add(full)
    return found


def _check(found: dict[str, set[str]]) -> None:
    for kind, allowed in (
        ("fk", ALLOWED_FK),
        ("ik", ALLOWED_IK_LOOPS),
        ("rotation", ALLOWED_ROTATIONS),
        ("dls", ALLOWED_DLS),
    ):
        known = allowed | PENDING[kind] | REVIEWED[kind]
        extra, missing = sorted(found[kind] - known), sorted(known - found[kind])
        assert not extra and not missing, (
            f"{kind}: new implementation(s) {extra} (use the existing one instead), "
            f"listed but no longer found {missing} (update the lists)"
        )


def test_one_fk_per_engine_one_ik_loop_one_dls_step_and_the_listed_rotations() -> None:
    _check(scan(ROOT))


PLANTED = """
import math
import numpy as np


def my_fk(rows, q):
    t = np.eye(4)
    for row, v in zip(rows, q):
        c, s = math.cos(v), math.sin(v)
        t = t @ np.array([[c, -s, 0, row[0]], [s, c, 0, 0], [0, 0, 1, row[1]], [0, 0, 0, 1]])
    return t


def my_ik(rows, target, q):
    for _ in range(50):
        p, jac = my_fk_jac(rows, q)
        q = q + np.linalg.solve(jac.T @ jac + 1e-6 * np.eye(len(q)), jac.T @ (target - p))
    return q


def my_rot(a):
    return np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])


def my_table_fk(rows, q):
    t = np.eye(4)
    for k, row in enumerate(rows):
        t = t @ row.transform(q[k])
    return t


def my_compiled_fk(q, out):
    r00, r01, r10, r11 = 1.0, 0.0, 0.0, 1.0
    for k in range(q.shape[0]):
        s, c = sincos(q[k])
        r00, r01, r10, r11 = c * r00 + s * r01, c * r01 - s * r00, c * r10 + s * r11, r11
    out[0] = r00


def my_rate_step(jac, xd, lam_eye):
    jt = jac.T
    return np.linalg.solve(np.dot(jt, jac) + lam_eye, np.dot(jt, xd))


def my_pinv_ik(model, data, target, q):
    while True:
        jac = pin.computeFrameJacobian(model, data, q, 3)
        q += np.linalg.pinv(jac) @ (target - data.oMf[3].translation)
    return q
"""


def test_a_planted_copy_lists_the_new_ones(tmp_path: Path) -> None:
    copy = tmp_path / "hexapod_kin"
    shutil.copytree(ROOT, copy, ignore=shutil.ignore_patterns("__pycache__", "*.nbi", "*.nbc"))
    (copy / "gait" / "planted.py").write_text(PLANTED, encoding="utf-8")
    found = scan(copy)
    new = {k: v - PENDING[k] - REVIEWED[k] for k, v in found.items()}
    planted = {f"gait.planted.my_{n}" for n in ("fk", "table_fk", "compiled_fk")}
    assert new["fk"] - ALLOWED_FK == planted
    assert new["ik"] - ALLOWED_IK_LOOPS == {"gait.planted.my_ik", "gait.planted.my_pinv_ik"}
    # my_ik solves JᵀJ + λ²I inline: a DLS step of its own as well as an IK loop
    assert new["dls"] - ALLOWED_DLS == {"gait.planted.my_ik", "gait.planted.my_rate_step"}
    assert new["rotation"] - ALLOWED_ROTATIONS == {
        "gait.planted.my_fk",
        "gait.planted.my_rot",
        "gait.planted.my_compiled_fk",
    }
    try:
        _check(found)
    except AssertionError as exc:
        assert "gait.planted.my_fk" in str(exc)
    else:  # pragma: no cover - the check must fail
        raise AssertionError("the planted FK was not caught")
