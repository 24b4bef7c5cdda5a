"""Figures of a sweep: score maps over two parameters and the Pareto front (matplotlib)."""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..exceptions import ParameterError
from .designs import PARAMETERS

__all__ = ["plot_sweep"]

_MAPS = (("stride", "stride [m]"), ("volume", "volume [m³]"), ("sigma_min", "min σ_min [m/rad]"))


def _axis(values: np.ndarray) -> np.ndarray:
    return np.unique(np.round(values, 12))


def plot_sweep(
    result: Any, path: str | os.PathLike[str], params: Sequence[str] | None = None
) -> Path:
    """Score maps (stride, volume, σ_min) over two parameters and the Pareto front, one PNG.

    Each map cell shows the best score over the other parameters (random/LHS: a scatter); the
    front panel plots stride against volume, coloured by min σ_min. ``result``: a
    :class:`~hexapod_kin.sweep.run.SweepResult` (or its ``table``); ``params``: the maps' two
    parameters (default: the two most varied). Returns ``path``, the PNG written atomically.
    Raises ParameterError: unknown parameter names; OptionalDependencyError: matplotlib missing.
    """
    from ..plots import pyplot, save_figure

    table = getattr(result, "table", result)
    if params is None:
        spec = getattr(result, "summary", {}).get("spec", {}).get("space", {}).get("values", {})
        swept = [p for p in PARAMETERS if isinstance(spec.get(p), list)]
        varied = sorted(PARAMETERS, key=lambda p: -len(_axis(np.asarray(table[p]))))
        params = (swept + [p for p in varied if p not in swept])[:2]
    if len(params) != 2 or any(p not in PARAMETERS for p in params):
        msg = f"params={list(params)!r}: expected two of {', '.join(PARAMETERS)}"
        raise ParameterError(msg, parameter="params", value=list(params), allowed=list(PARAMETERS))
    px, py = params
    x, y = np.asarray(table[px]), np.asarray(table[py])
    feas = np.asarray(table["feasible"]) > 0
    plt = pyplot()
    fig, axes = plt.subplots(1, 4, figsize=(18, 4.2))
    xs, ys = _axis(x), _axis(y)
    gridded = len(xs) * len(ys) <= 4 * len(x) and len(xs) > 1 and len(ys) > 1
    for ax, (name, label) in zip(axes[:3], _MAPS):
        v = np.where(feas, np.asarray(table[name], dtype=float), np.nan)
        if gridded:
            img = np.full((len(ys), len(xs)), np.nan)
            ix = np.searchsorted(xs, np.round(x, 12))
            iy = np.searchsorted(ys, np.round(y, 12))
            for i, j, val in zip(iy, ix, v):
                if np.isfinite(val) and not (img[i, j] >= val):
                    img[i, j] = val
            m = ax.pcolormesh(xs, ys, img, shading="nearest", cmap="viridis")
        else:
            m = ax.scatter(x, y, c=v, s=12, cmap="viridis")
        fig.colorbar(m, ax=ax, label=label)
        ax.set(xlabel=px, ylabel=py)
        title = f"best {name} over the other parameters" if gridded else f"{name} per design"
        ax.set_title(title, fontsize=9)
    ax = axes[3]
    front = np.asarray(table["pareto"]) > 0
    stride, volume = np.asarray(table["stride"]), np.asarray(table["volume"])
    s = ax.scatter(stride[feas], volume[feas], c=np.asarray(table["sigma_min"])[feas], s=10,
                   cmap="viridis")  # fmt: skip
    ax.scatter(stride[front], volume[front], facecolors="none", edgecolors="red", s=40,
               label="Pareto front")  # fmt: skip
    fig.colorbar(s, ax=ax, label="min σ_min [m/rad]")
    ax.set(xlabel="stride [m]", ylabel="volume [m³]")
    ax.legend(loc="best", fontsize=8)
    ax.set_title("front: max stride, volume, σ_min", fontsize=9)
    fig.tight_layout()
    return save_figure(fig, path, crop=False)
