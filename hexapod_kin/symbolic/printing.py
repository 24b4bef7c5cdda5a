"""Plain-text layout of a :class:`~hexapod_kin.symbolic.Derivation`: one line per formula.

Expressions print on one line (``-d4·sin(q1)·cos²(q3)``); a matrix whose rows fit in
:data:`WIDTH` columns prints as a matrix, any other entry by entry (``[2,3] = …``), long
entries wrapped between terms. Linear in the expression's size.
"""

from __future__ import annotations

from typing import Any

import sympy as sp
from sympy.printing.str import StrPrinter

__all__ = ["WIDTH", "expr_text", "matrix_lines", "wrap"]

#: Target width of a printed line in characters.
WIDTH = 100

_SUPERSCRIPT = str.maketrans("0123456789-", "⁰¹²³⁴⁵⁶⁷⁸⁹⁻")


class _Printer(StrPrinter):
    """``sstr`` with ``·`` for products and ``sin²(q1)``, ``d4²`` for small integer powers."""

    def _print_Pow(self, expr: Any, rational: bool = False) -> str:
        base, exp = expr.as_base_exp()
        if exp.is_Integer and 1 < int(exp) < 10:
            sup = str(int(exp)).translate(_SUPERSCRIPT)
            if isinstance(base, (sp.sin, sp.cos, sp.tan)):
                return f"{type(base).__name__}{sup}({self._print(base.args[0])})"
            if base.is_Symbol:
                return f"{self._print(base)}{sup}"
            if base.is_Add or base.is_Mul:
                return f"({self._print(base)}){sup}"
        return str(super()._print_Pow(expr, rational))

    def _print_Mul(self, expr: Any) -> str:
        return str(super()._print_Mul(expr)).replace("**", "^").replace("*", "·")


def expr_text(expr: Any) -> str:
    """``expr`` on one line (see the module docstring)."""
    return str(_Printer({"order": "none"}).doprint(expr)).replace("**", "^")


def wrap(text: str, width: int = WIDTH, indent: int = 8) -> list[str]:
    """``text`` cut into lines of at most ``width`` characters, before a ``" + "``/``" - "``.

    A piece with no such break inside the width stays whole (longer than ``width``).
    """
    if len(text) <= width:
        return [text]
    pieces = _split(text, top_only=True)
    if len(pieces) == 1:  # no break outside parentheses: break inside them
        pieces = _split(text, top_only=False)
    if len(pieces) == 1:  # prose: break between words
        import textwrap

        return textwrap.wrap(text, width, subsequent_indent=" " * indent, break_long_words=False)
    lines: list[str] = []
    current, pad = "", " " * indent
    for piece in pieces:
        cand = f"{current} {piece}" if current else piece
        limit = width if not lines else width - indent
        if current and len(cand) > limit:
            lines.append(current)
            current = piece
        else:
            current = cand
    lines.append(current)
    return [lines[0]] + [pad + line for line in lines[1:]]


def _split(text: str, top_only: bool) -> list[str]:
    """``text`` cut before each ``" + "``/``" - "`` at the shallowest parenthesis depth found.

    With ``top_only`` only outside parentheses (depth 0); else at the smallest depth that
    has such a break (a sum inside one pair of parentheses breaks there, never deeper).
    """
    found: list[tuple[int, int]] = []
    depth = 0
    for i in range(1, len(text) - 1):
        ch = text[i]
        if ch in "([":
            depth += 1
        elif ch in ")]":
            depth -= 1
        elif ch in "+-" and text[i - 1] == " " and text[i + 1] == " ":
            found.append((depth, i))
    if not found:
        return [text]
    level = 0 if top_only else min(d for d, _ in found)
    cuts = [i for d, i in found if d == level]
    pieces, start = [], 0
    for i in cuts:
        pieces.append(text[start : i - 1])
        start = i
    pieces.append(text[start:])
    return pieces


def matrix_lines(mat: Any, width: int = WIDTH, indent: str = "  ") -> list[str]:
    """A sympy matrix as text lines: a matrix when it fits in ``width``, else entry by entry.

    Entries are indexed from 1 (``[row,column]``), as in the printed formulas.
    """
    rows, cols = mat.shape
    cells = [[expr_text(mat[i, j]) for j in range(cols)] for i in range(rows)]
    widths = [max(len(cells[i][j]) for i in range(rows)) for j in range(cols)]
    if len(indent) + 4 + sum(widths) + 2 * (cols - 1) <= width:
        out = []
        for i in range(rows):
            left, right = ("⎡", "⎤") if i == 0 else ("⎣", "⎦") if i == rows - 1 else ("⎢", "⎥")
            if rows == 1:
                left, right = "[", "]"
            body = "  ".join(cells[i][j].rjust(widths[j]) for j in range(cols))
            out.append(f"{indent}{left} {body} {right}")
        return out
    out = []
    for i in range(rows):
        for j in range(cols):
            head = f"{indent}[{i + 1},{j + 1}] = "
            out.extend(wrap(head + cells[i][j], width, indent=len(head)))
    return out
