"""Names of the rows of the tip Jacobian ``[v; ω]`` (local_world_aligned) and their selections.

A leaf (no sympy, no numpy) shared by :mod:`hexapod_kin.singularity` and
:mod:`hexapod_kin.symbolic`.
"""

from __future__ import annotations

from collections.abc import Sequence

from .exceptions import ParameterError, choices

__all__ = ["ROW_NAMES", "row_indices", "row_names", "choose_rows"]

#: The six rows of the tip Jacobian: linear then angular velocity.
ROW_NAMES: tuple[str, ...] = ("x", "y", "z", "wx", "wy", "wz")


def row_indices(rows: str | Sequence[str] | None) -> tuple[int, ...]:
    """The indices (0..5, in the given order) of a row selection ``rows``.

    ``None`` or ``"position"`` (x, y, z), ``"all"``, or names of :data:`ROW_NAMES` (``"x,y,wz"``).

    Raises:
        ParameterError: Unknown or repeated row names, or an empty selection.

    """
    if rows is None or rows == "position":
        return (0, 1, 2)
    if rows == "all":
        return tuple(range(6))
    if isinstance(rows, str):
        rows = [r.strip() for r in rows.split(",")]
    names = [str(r).lower() for r in rows]
    bad = [r for r in names if r not in ROW_NAMES]
    if bad or not names or len(set(names)) != len(names):
        raise ParameterError(
            f"rows={tuple(rows)!r} is not allowed; give distinct names from "
            f"{choices(ROW_NAMES)}, or 'position' / 'all'",
            parameter="rows",
            value=tuple(rows),
            allowed=[*ROW_NAMES, "position", "all"],
        )
    return tuple(ROW_NAMES.index(r) for r in names)


def row_names(rows: str | Sequence[str] | None) -> tuple[str, ...]:
    """The row names of a selection (see :func:`row_indices`)."""
    return tuple(ROW_NAMES[i] for i in row_indices(rows))


def choose_rows(nonzero: Sequence[bool], nq: int) -> tuple[str, ...]:
    """``x, y, z`` plus the angular rows not identically zero when they make ``nq > 3`` rows.

    ``nonzero``: six flags (SCARA: ``x, y, z, wz``); else ``x, y, z``.
    """
    chosen = [0, 1, 2] + [i for i in (3, 4, 5) if nonzero[i]]
    if len(chosen) == nq and nq > 3:
        return tuple(ROW_NAMES[i] for i in chosen)
    return ("x", "y", "z")
