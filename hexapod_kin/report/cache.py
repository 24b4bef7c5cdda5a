"""The printed derivations: their text cached on disk, and their layout for the report.

The text (``sympy.pretty``) is one sealed entry of :mod:`hexapod_kin._cache` per derivation,
keyed by its fields (``srepr``) but timing, the versions, :data:`FORMAT` and the package's
source; a damaged entry is printed again with one ``CacheWarning``. Text is never evaluated.
"""

from __future__ import annotations

from dataclasses import fields
from typing import Any

import sympy as sp

from .. import _cache as _disk
from .replay import package_digest

__all__ = ["FORMAT", "derivation_layout", "derivation_text"]

#: Version of the file layout and of the key's parts.
FORMAT = 4


def _text(obj: Any) -> Any:
    """JSON-ready ``obj``: sympy objects by ``srepr``, sequences walked, the rest by ``repr``."""
    if isinstance(obj, sp.MatrixBase):
        return sp.srepr(sp.ImmutableMatrix(obj))
    if isinstance(obj, sp.Basic):
        return sp.srepr(obj)
    if isinstance(obj, (list, tuple)):
        return [_text(x) for x in obj]
    return repr(obj)


def _key(d: Any) -> str:
    from .. import __version__

    parts = {f.name: _text(getattr(d, f.name)) for f in fields(d)}
    del parts["seconds"], parts["cached"]
    parts.update(format=FORMAT, version=__version__, sympy=sp.__version__, code=package_digest())
    return "text-" + _disk.key(parts)


def derivation_text(d: Any, cache: bool = True) -> str:
    """``d.text()`` (a :class:`~hexapod_kin.symbolic.Derivation`), read from the cache when kept.

    ``cache=False``: printed, neither read nor kept.
    """
    if not cache:
        return str(d.text())
    try:
        digest = _key(d)
    except Exception:  # noqa: BLE001 - no key: print it
        return str(d.text())
    found = _disk.load("report", digest, FORMAT, "printing it again")
    if isinstance(found, str):
        return found
    text = str(d.text())
    _disk.store("report", digest, text, FORMAT)
    return text


def derivation_layout(d: Any) -> dict[str, Any]:
    """A derivation laid out for the report: matrices as rows of entry texts (no pretty-printing).

    Returns:
        ``{"header": [lines], "items": [{"label", "rows"} or {"label", "value"}],
        "footer": [lines]}``; entries are :func:`~.compare.fmt` text of the expressions.

    """
    from .compare import fmt  # the comparison's text of an expression (not needed by derive)

    joints = ", ".join(f"{fmt(s)} ({n})" for s, n in zip(d.q, d.joint_names))
    lens = ", ".join(
        f"{fmt(s)} = {v:g} m (table {d.length_sources[s]})" for s, v in d.lengths.items()
    )
    header = [
        f"{d.chain.name}: Khalil-Kleinfinger table, T = Rx(α) Tx(d) Rz(θ) Tz(r)",
        f"joints: {joints}",
        f"lengths: {lens or '(none)'}",
        f"p and J in the axes of '{d.reference}', tip '{d.tip}'",
    ]
    mats: list[tuple[str, Any]] = []
    if d.base_transform != sp.eye(4):
        mats.append((f"T({d.reference} → 0)", d.base_transform))
    n = len(d.transforms)
    mats += [(f"{_sup(j)}T{_sub(j + 1)}", d.transforms[j]) for j in range(n)]
    if d.tool_transform != sp.eye(4):
        mats.append((f"{_sup(n)}T(tool)", d.tool_transform))
    mats += [(f"⁰T{_sub(j + 1)}", d.cumulative[j]) for j in range(1, n)]
    mats += [
        ("p(q)", d.p),
        ("J (indirect, ∂p/∂q)", d.J_indirect),
        ("J (direct, [v; ω])", d.J_direct),
    ]
    items: list[dict[str, Any]] = [
        {"label": label, "rows": [[fmt(x) for x in m.row(i)] for i in range(m.rows)]}
        for label, m in mats
    ]
    if d.det is not None:
        items.append({"label": f"det J[{','.join(d.rows)}]", "value": fmt(d.det)})
    elif d.gram is not None:
        items.append({"label": f"det(J Jᵀ) [{','.join(d.rows)}]", "value": fmt(d.gram)})
    footer = [f"direct and indirect Jacobians agree: {d.methods_agree}"]
    if d.method:
        footer.append(f"determinant: {d.method}")
    for fam in d.families:
        mark = {True: "checked", False: "CHECK FAILED", None: "not checked"}[fam.verified]
        footer.append(
            f"singular family: {fam.name} [{mark}: {fam.check}]"
            if fam.check
            else f"singular family: {fam.name}"
        )
    footer += [f"NOT DONE: {what}" for what in d.incomplete]
    return {"header": header, "items": items, "footer": footer}


def _sup(n: int) -> str:
    return str(n).translate(str.maketrans("0123456789", "⁰¹²³⁴⁵⁶⁷⁸⁹"))


def _sub(n: int) -> str:
    return str(n).translate(str.maketrans("0123456789", "₀₁₂₃₄₅₆₇₈₉"))
