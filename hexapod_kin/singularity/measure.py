"""Singularity measures of one configuration or of many.

Of ``J``, k selected rows of the ``local_world_aligned`` tip Jacobian over n joints (singular
values ``σ1 ≥ … ≥ σm``): ``det`` (NaN unless square), ``manipulability`` (Yoshikawa's
``sqrt(det(J Jᵀ))``), ``condition`` (``σ1 / σm``) and ``sigma_min`` (``σm``). :func:`measures`
uses Pinocchio and numpy's SVD, :func:`measures_batch` the compiled kernel.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._numerics import chain_length
from ..exceptions import ConfigurationError
from ..jacobian_rows import ROW_NAMES, choose_rows, row_names
from ..kinematics import as_model

__all__ = ["Measures", "MeasuresBatch", "default_rows", "measures", "measures_batch", "reach"]


#: The four measures, in the order of a :class:`MeasuresBatch`'s iteration.
_MEASURES = ("det", "manipulability", "condition", "sigma_min")


def _clean(a: np.ndarray) -> list[Any]:
    return [v if math.isfinite(v) else None for v in np.asarray(a, dtype=float).tolist()]


@dataclass(frozen=True)
class Measures:
    """Singularity measures of one configuration.

    Attributes:
        det: ``det J`` (NaN when J is not square), units of the product of the rows'.
        manipulability: ``sqrt(det(J Jᵀ))`` (product of the singular values).
        condition: ``σmax / σmin`` (``inf`` when singular), dimensionless for uniform rows.
        sigma_min: Smallest singular value, in [m] for position rows of revolute joints.
        singular_values: All ``min(k, n)`` singular values, descending (read-only).
        rows: Row names of ``J`` used.

    """

    det: float
    manipulability: float
    condition: float
    sigma_min: float
    singular_values: np.ndarray
    rows: tuple[str, ...]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict with the same names (NaN / inf become ``None``)."""
        values = _clean(np.array([getattr(self, k) for k in _MEASURES]))
        sv = _clean(self.singular_values)
        return {**dict(zip(_MEASURES, values)), "singular_values": sv, "rows": list(self.rows)}


@dataclass(frozen=True)
class MeasuresBatch:
    """Singularity measures of N configurations (see :func:`measures_batch`).

    Iterating gives ``det, manipulability, condition, sigma_min``: ``det, manip, cond, smin =
    measures_batch(model, qs)`` works.

    Attributes:
        det: (N,) ``det J`` (NaN where J is not square).
        manipulability: (N,) ``sqrt(det(J Jᵀ))``.
        condition: (N,) ``σmax/σmin`` (``inf`` where singular).
        sigma_min: (N,) smallest singular value ([m] for position rows of revolute joints).
        rows: Row names of ``J``.

    """

    det: np.ndarray
    manipulability: np.ndarray
    condition: np.ndarray
    sigma_min: np.ndarray
    rows: tuple[str, ...]

    def __iter__(self) -> Iterator[np.ndarray]:
        return (getattr(self, k) for k in _MEASURES)

    def __len__(self) -> int:
        return 4

    def __getitem__(self, i: int) -> np.ndarray:
        return tuple(self)[i]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict with the same names (NaN / inf become ``None``)."""
        return {"rows": list(self.rows), **{k: _clean(getattr(self, k)) for k in _MEASURES}}


def _measures_numpy(jac: np.ndarray) -> tuple[np.ndarray, ...]:
    """``det, manipulability, condition, sigma_min, singular values`` of (N, k, n) Jacobians."""
    sv = np.linalg.svd(jac, compute_uv=False)
    square = jac.shape[1] == jac.shape[2]
    det = np.linalg.det(jac) if square else np.full(jac.shape[0], np.nan)
    manip = np.abs(det) if square else np.prod(sv, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):  # 0/0 where sigma_max is 0 too
        cond = np.where(sv[:, -1] > 0, sv[:, 0] / sv[:, -1], np.inf)
    return det, manip, cond, sv[:, -1], sv


def default_rows(model: Any) -> tuple[str, ...]:
    """Default row selection for ``model``: ``x, y, z`` plus the non-zero angular rows if square.

    A row is zero when below 1e-12 at 8 random configurations (SCARA: ``x y z wz``). ``model``:
    a loaded model or a source; the names are from :data:`~hexapod_kin.jacobian_rows.ROW_NAMES`.
    """
    mdl = as_model(model)

    def build() -> tuple[str, ...]:
        qs = mdl.random_q(8, seed=12345)
        jac = np.array([mdl.jacobian(q, "local_world_aligned") for q in qs])
        flags = np.abs(jac).max(axis=(0, 2)) > 1e-12
        return choose_rows([bool(f) for f in flags], mdl.nq)

    return mdl.cached("singularity.default_rows", build)


def selected_rows(model: Any, rows: Any) -> tuple[str, ...]:
    """The row names of ``rows`` for ``model`` (``None``: :func:`default_rows`)."""
    return default_rows(model) if rows is None else row_names(rows)


def reach(model: Any) -> float:
    """Sum of the chain's link offsets in [m] (an upper bound of the base-to-tip distance)."""
    return float(chain_length(as_model(model).arrays.trans))


def measures(model: Any, q: Any, rows: str | Sequence[str] | None = None) -> Measures:
    """Singularity measures of one configuration ``q`` (nq,) [rad]/[m] (Pinocchio J, numpy SVD).

    ``model``: a loaded model or a source; ``rows``: the row selection (default
    :func:`default_rows`). Raises ConfigurationError (bad ``q``), ParameterError (bad ``rows``).
    """
    mdl = as_model(model)
    names = selected_rows(mdl, rows)
    idx = [ROW_NAMES.index(r) for r in names]
    jac = np.asarray(mdl.jacobian(q, "local_world_aligned"))[idx]
    det, manip, cond, smin, sv = _measures_numpy(jac[None])
    sv = sv[0]
    sv.setflags(write=False)
    return Measures(float(det[0]), float(manip[0]), float(cond[0]), float(smin[0]), sv, names)


def measures_batch(
    model: Any, qs: Any, rows: str | Sequence[str] | None = None, *,
    out: tuple[np.ndarray, ...] | None = None,
) -> MeasuresBatch:  # fmt: skip
    """Measures of many configurations by the fused compiled kernel, as a :class:`MeasuresBatch`.

    ``qs`` (N, nq) [rad]/[m]; ``model`` and ``rows`` as :func:`measures`. ``out``: optional four
    float64 (N,) arrays to fill (det, manipulability, condition, sigma_min), then the result's.
    Raises ConfigurationError (bad ``qs`` or ``out``), ParameterError (bad ``rows``).
    """
    from ._plan import block_plan, compute, output_arrays

    mdl = as_model(model)
    names = selected_rows(mdl, rows)
    q = np.require(mdl.check_q_batch(qs, "qs"), requirements=("C", "W"))  # read-only: a copy
    sel = np.array([ROW_NAMES.index(r) for r in names], dtype=np.int64)
    n = q.shape[0]

    def good(o: Any) -> bool:
        return isinstance(o, np.ndarray) and o.shape == (n,) and o.dtype == np.float64

    if out is not None and (len(out) != 4 or not all(map(good, out))):
        raise ConfigurationError(
            f"out: four float64 arrays of shape ({n},) are required",
            parameter="out",
            value=type(out).__name__,
            allowed=f"four float64 arrays of shape ({n},)",
        )
    if out is None:
        out = output_arrays(n)
    if block_plan(len(sel), mdl.nq)[0]:
        compute(mdl, q, sel, out)
    else:  # too many maximal minors for the kernel (9 joints and more)
        for o, values in zip(out, _measures_small(mdl, q, names)):
            o[:] = values
    return MeasuresBatch(out[0], out[1], out[2], out[3], rows=names)


def _measures_small(model: Any, qs: np.ndarray, rows: tuple[str, ...]) -> MeasuresBatch:
    """:func:`measures_batch` of a checked (N, nq) array on Pinocchio Jacobians and numpy SVD."""
    jac = np.empty((qs.shape[0], 6, qs.shape[1]))
    for i, q in enumerate(qs):
        jac[i] = model.jacobian(q, "local_world_aligned")
    det, manip, cond, smin, _ = _measures_numpy(jac[:, [ROW_NAMES.index(r) for r in rows], :])
    return MeasuresBatch(det, manip, cond, smin, rows=rows)
