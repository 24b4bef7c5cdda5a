"""Pareto front of a sweep table and the best design."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ..exceptions import ParameterError

__all__ = ["OBJECTIVES", "best_index", "pareto_front"]

#: Objectives maximised by default: stride [m], workspace volume [m³], min σ_min [m/rad].
OBJECTIVES: tuple[str, ...] = ("stride", "volume", "sigma_min")


def _columns(table: Mapping[str, Any], names: Sequence[str]) -> np.ndarray:
    missing = [n for n in names if n not in table]
    if missing:
        msg = f"objectives {missing} not in the table; columns: {', '.join(table)}"
        raise ParameterError(msg, parameter="objectives", value=missing, allowed=list(table))
    return np.stack([np.asarray(table[n], dtype=float) for n in names], axis=1)


def pareto_front(table: Mapping[str, Any], objectives: Sequence[str] = OBJECTIVES) -> np.ndarray:
    """(N,) mask of the non-dominated feasible designs of a sweep table, ``objectives`` maximised.

    Dominated: another one at least as good in every objective, better in one; infeasible
    designs are never on the front. Raises ParameterError: an objective is not a column.
    """
    f = _columns(table, objectives)
    n = f.shape[0]
    ok = np.asarray(table.get("feasible", np.ones(n)), dtype=float) > 0
    ok &= np.all(np.isfinite(f), axis=1)
    idx = np.flatnonzero(ok)
    # lexicographic descending order: a design can only be dominated by earlier ones
    order = idx[np.lexsort(tuple(-f[idx, k] for k in reversed(range(f.shape[1]))))]
    front: list[int] = []
    for i in order:
        g = f[front]  # duplicates of a front point stay on it
        if not front or not np.any(np.all(g >= f[i], axis=1) & np.any(g > f[i], axis=1)):
            front.append(int(i))
    mask = np.zeros(n, dtype=bool)
    mask[front] = True
    return mask


def best_index(table: Mapping[str, Any], key: Sequence[str] = OBJECTIVES) -> int:
    """Row of the best feasible design (-1: none): max of ``key[0]``, ties broken by the next keys.

    Ties are values within 1e-9 (relative) of the maximum; ``table``: column name → (N,) array.
    Raises ParameterError: a key is not a column.
    """
    f = _columns(table, key)
    n = f.shape[0]
    cand = np.flatnonzero(np.asarray(table.get("feasible", np.ones(n)), dtype=float) > 0)
    for k in range(f.shape[1]):
        if cand.size <= 1:
            break
        v = f[cand, k]
        top = np.max(v)
        cand = cand[v >= top - 1e-9 * max(abs(top), 1e-300)]
    return int(cand[0]) if cand.size else -1
