"""A restricted reader of sympy's ``srepr`` text: rebuilds expressions without ``eval``.

:func:`read_srepr` parses with :func:`ast.parse` and builds the expression from a fixed table
of sympy constructors (listed names with literal arguments, the listed constants, keywords
only for symbol assumptions and ``Float`` precision); anything else raises
:class:`CacheFormatError`. Size is bounded. Numbers are not distributed over sums while
building (``distribute(False)``), so what is read is the expression stored, bit for bit.
"""

from __future__ import annotations

import ast
from typing import Any

import sympy as sp
from sympy.functions.elementary.piecewise import ExprCondPair

__all__ = ["CacheFormatError", "read_srepr"]

#: Largest text and number of syntax nodes read (a real entry is far inside).
MAX_CHARS = 5_000_000
MAX_NODES = 2_000_000

_FUNCTIONS = (
    "sin", "cos", "tan", "cot", "sec", "csc", "asin", "acos", "atan", "acot", "atan2",
    "sinh", "cosh", "tanh", "exp", "log", "sqrt", "Abs", "sign", "Min", "Max", "re", "im",
    "conjugate", "floor", "ceiling", "Piecewise",
)  # fmt: skip
_CLASSES = (
    "Add", "Mul", "Pow", "Symbol", "Dummy", "Integer", "Rational", "Float", "Tuple",
    "ImmutableDenseMatrix", "MutableDenseMatrix", "Matrix", "ImmutableMatrix", "Poly",
    "Equality", "Unequality", "StrictLessThan", "LessThan", "StrictGreaterThan",
    "GreaterThan", "And", "Or", "Not",
)  # fmt: skip
_CONSTANTS = {
    "pi": sp.pi, "E": sp.E, "I": sp.I, "oo": sp.oo, "nan": sp.nan, "zoo": sp.zoo,
    "true": sp.true, "false": sp.false, "EulerGamma": sp.EulerGamma,
}  # fmt: skip
_CALLABLES: dict[str, Any] = {name: getattr(sp, name) for name in (*_FUNCTIONS, *_CLASSES)}
_CALLABLES["ExprCondPair"] = ExprCondPair
#: Keyword arguments allowed, per constructor (symbol assumptions; Float's precision).
_ASSUMPTIONS = frozenset(
    ("real", "positive", "negative", "nonnegative", "nonpositive", "integer", "finite",
     "nonzero", "zero", "complex", "extended_real", "commutative")
)  # fmt: skip
_KEYWORDS = {"Symbol": _ASSUMPTIONS, "Dummy": _ASSUMPTIONS, "Float": frozenset(("precision",))}


class CacheFormatError(ValueError):
    """A stored expression that the restricted reader refuses (never evaluated)."""


def read_srepr(text: str) -> Any:
    """The sympy object of ``srepr`` ``text``, built without ``eval``.

    Raises CacheFormatError: text that is not a plain ``srepr`` of the allowed constructors.
    """
    if not isinstance(text, str) or len(text) > MAX_CHARS:
        raise CacheFormatError("not a stored expression (not text, or too long)")
    try:
        tree = ast.parse(text, mode="eval")
    except (SyntaxError, ValueError, RecursionError, MemoryError) as exc:
        raise CacheFormatError(f"not an expression ({type(exc).__name__})") from None
    count = sum(1 for _ in ast.walk(tree))
    if count > MAX_NODES:
        raise CacheFormatError(f"{count} syntax nodes; at most {MAX_NODES}")
    from sympy.core.parameters import distribute

    try:
        with distribute(False):  # thread-local in sympy
            return _build(tree.body)
    except RecursionError:
        raise CacheFormatError("nested too deeply") from None


def _literal(node: ast.expr) -> Any:
    if isinstance(node, ast.Constant) and isinstance(node.value, (int, float, str, bool)):
        return node.value
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
        value = node.operand.value if isinstance(node.operand, ast.Constant) else None
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            return -value
    return _build(node)


def _build(node: ast.expr) -> Any:
    if isinstance(node, ast.Name):
        if node.id in _CONSTANTS:
            return _CONSTANTS[node.id]
        raise CacheFormatError(f"name {node.id!r} is not an allowed constant")
    if isinstance(node, (ast.List, ast.Tuple)):
        items = [_literal(e) for e in node.elts]
        return items if isinstance(node, ast.List) else tuple(items)
    if isinstance(node, (ast.Constant, ast.UnaryOp)):
        return _literal(node)
    if isinstance(node, ast.Call):
        if not isinstance(node.func, ast.Name) or node.func.id not in _CALLABLES:
            what = node.func.id if isinstance(node.func, ast.Name) else type(node.func).__name__
            raise CacheFormatError(f"call of {what!r} is not an allowed constructor")
        name = node.func.id
        allowed = _KEYWORDS.get(name, frozenset())
        kwargs: dict[str, Any] = {}
        for kw in node.keywords:
            if kw.arg is None or kw.arg not in allowed:
                raise CacheFormatError(f"keyword {kw.arg!r} is not allowed for {name}")
            value = _literal(kw.value)
            if not isinstance(value, (bool, int, str)):
                raise CacheFormatError(f"keyword {kw.arg!r} of {name} must be a literal")
            kwargs[kw.arg] = value
        args = [_literal(a) for a in node.args]
        if name in ("Symbol", "Dummy") and not (len(args) == 1 and isinstance(args[0], str)):
            raise CacheFormatError(f"{name} takes one name")
        if name == "Pow" and len(args) == 2 and all(isinstance(a, sp.Number) for a in args):
            if abs(args[1]) > 64:  # a number to a huge power: an evaluation bomb, never stored
                raise CacheFormatError("a number raised to a power beyond 64")
        try:
            return _CALLABLES[name](*args, **kwargs)
        except CacheFormatError:
            raise
        except Exception as exc:  # noqa: BLE001 - sympy's own refusal of bad arguments
            raise CacheFormatError(f"{name}(...) refused: {type(exc).__name__}") from None
    raise CacheFormatError(f"{type(node).__name__} is not allowed in a stored expression")
