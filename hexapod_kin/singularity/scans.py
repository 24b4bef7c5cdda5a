"""Scans of joint space: measures on a grid or random samples, flags, family labels.

A configuration is flagged ``singular`` when ``sigma_min < threshold`` or ``sigma_min = 0``;
each flagged sample is labelled with its nearest singular family (:mod:`.families`). Scans of
at most :data:`SMALL_SCAN` configurations run on Pinocchio + numpy, larger ones on the
compiled :func:`~.measure.measures_batch` kernel.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._fields import fields_dict
from ..exceptions import ConfigurationError, ParameterError, choices, one_of, positive
from ..tables import MIN_LENGTH as MIN_REACH  # a table's smallest length: the smallest reach
from .families import Families, Family, families_for
from .measure import _clean, _measures_small, as_model, measures_batch, reach, selected_rows

__all__ = ["DEFAULT_GRID", "SMALL_SCAN", "ScanResult", "scan", "default_joints",
           "default_q_fixed"]  # fmt: skip

#: Largest number of configurations of one scan (memory: ~80 bytes each plus q).
MAX_CONFIGURATIONS = 50_000_000
#: Points per scanned joint when neither ``grid`` nor ``samples`` is given.
DEFAULT_GRID = 61
#: Largest scan run on Pinocchio + numpy; above it, the compiled kernel.
SMALL_SCAN = 10_000


def _kernel_scan(
    mdl: Any, q: np.ndarray, names: tuple[str, ...], progress: bool | None, chunk: int
) -> tuple[np.ndarray, ...]:
    """The four measures of a large scan by the compiled kernel, ``chunk`` at a time."""
    n = q.shape[0]
    out = tuple(np.empty(n) for _ in range(4))
    show = (n > 2_000_000 and sys.stderr.isatty()) if progress is None else bool(progress)
    bar = None
    if show:
        from tqdm import tqdm

        bar = tqdm(total=n, file=sys.stderr, unit="cfg", desc="scan", leave=False)
    try:
        for start in range(0, n, chunk):
            stop = min(n, start + chunk)
            measures_batch(mdl, q[start:stop], names, out=tuple(o[start:stop] for o in out))
            if bar is not None:
                bar.update(stop - start)
    finally:
        if bar is not None:
            bar.close()
    return out


#: The (N,) arrays of a :class:`ScanResult`, in the order of its JSON.
_PER_SAMPLE = (
    "det manipulability condition sigma_min singular family family_distance second_family "
    "second_distance"
).split()


def _listed(arr: np.ndarray) -> list[Any]:
    """A float array as a list with NaN / inf as ``None``; any other as its list."""
    return _clean(arr) if arr.dtype.kind == "f" else arr.tolist()


def _count(v: Any, lo: int, hi: float = math.inf) -> bool:
    """``v`` is an integer (not a bool) in ``lo..hi``."""
    return not isinstance(v, bool) and isinstance(v, (int, np.integer)) and lo <= int(v) <= hi


def _ro(arr: np.ndarray) -> np.ndarray:
    arr = np.ascontiguousarray(arr)
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True)
class ScanResult:
    """Result of :func:`scan` (arrays are read-only).

    Also: ``joint_names`` and ``prismatic`` flags of the n joints, ``joints`` (the scanned
    ones' indices), ``rows`` of ``J``, the ``threshold`` used, ``q_fixed`` (n,) of the joints not
    scanned and ``source`` (the model's name).

    Attributes:
        q: Configurations (N, n) in [rad] / [m].
        det: (N,), and ``manipulability``, ``condition``, ``sigma_min``: as in
            :class:`~.measure.MeasuresBatch`.
        singular: (N,) boolean mask ``sigma_min < threshold`` or ``sigma_min = 0``.
        family: (N,) index into :attr:`families` of the nearest family of each flagged
            configuration (−1: none).
        family_distance: (N,) joint-space distance to it in [rad]/[m] (NaN: none).
        second_family: (N,) the second-nearest family (−1: none).
        second_distance: (N,) the distance to it in [rad]/[m] (NaN: none).
        families: The singular families (:class:`~.families.Family`).
        family_reason: Why :attr:`families` is empty ("" when it is not).
        family_tol: Distance in [rad]/[m] within which a flagged sample counts as explained.
        family_tols: Per family, the tolerance used: ``family_tol`` widened to ``1.5 ×
            threshold / s`` (``s`` the family's measured lever arm), at most ``4 × family_tol``.
        grid_shape: Points per scanned joint for a grid scan (``q`` in C order), else ``None``.

    """

    q: np.ndarray
    det: np.ndarray
    manipulability: np.ndarray
    condition: np.ndarray
    sigma_min: np.ndarray
    singular: np.ndarray
    family: np.ndarray
    family_distance: np.ndarray
    second_family: np.ndarray
    second_distance: np.ndarray
    families: tuple[Family, ...]
    family_reason: str
    family_tol: float
    family_tols: tuple[float, ...]
    joint_names: tuple[str, ...]
    prismatic: tuple[bool, ...]
    joints: tuple[int, ...]
    rows: tuple[str, ...]
    threshold: float
    grid_shape: tuple[int, ...] | None
    q_fixed: np.ndarray
    source: str

    @property
    def explained(self) -> np.ndarray:
        """(N,) flagged configurations on a known family.

        Within :attr:`family_tols` of the nearest family, or within twice that of two families.
        """
        tols = np.asarray((*self.family_tols, np.nan))[self.family]  # -1: NaN (no family)
        tols2 = np.asarray((*self.family_tols, np.nan))[self.second_family]
        with np.errstate(invalid="ignore"):
            near = self.family_distance <= tols
            meet = (self.family_distance <= 2.0 * tols) & (self.second_distance <= 2.0 * tols2)
        return np.asarray(self.singular & (near | meet))

    @property
    def unexplained(self) -> np.ndarray:
        """(N,) flagged configurations on no known family (see :attr:`explained`)."""
        return np.asarray(self.singular & ~self.explained)

    @property
    def family_counts(self) -> dict[str, int]:
        """Explained flagged configurations per nearest family, by family name."""
        near = self.explained
        return {
            fam.name: int(np.count_nonzero(near & (self.family == f)))
            for f, fam in enumerate(self.families)
        }

    def family_residual(self, q: Any, f: int) -> np.ndarray:
        """Signed residual of family ``f`` at ``q`` (…, n) (zero on the family).

        Raises ParameterError: ``f`` is not the index of a family.
        """
        if not 0 <= int(f) < len(self.families):
            raise ParameterError(
                f"family_residual: f={f!r}; this scan has {len(self.families)} families"
                + (f" ({self.family_reason})" if self.family_reason else ""),
                parameter="f",
                value=f,
                allowed=f"0..{len(self.families) - 1}" if self.families else "none",
            )
        return self.families[int(f)].residual(q)

    def grid(self, name: str) -> np.ndarray:
        """A measure reshaped to :attr:`grid_shape` (grid scans only).

        Raises ParameterError: not a grid scan, or an unknown measure name.
        """
        if self.grid_shape is None:
            raise ParameterError("grid(): this scan used random samples, not a grid")
        one_of("name", name, _PER_SAMPLE[:7])
        return np.asarray(getattr(self, name)).reshape(self.grid_shape)

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dict with the same names (NaN / inf become ``None``)."""
        counts, names = self.family_counts, self.joint_names
        out = fields_dict(self, "source", "joint_names", "prismatic")
        out["joints"] = [names[j] for j in self.joints]
        out |= fields_dict(self, "rows", "threshold")
        out["grid_shape"] = list(self.grid_shape) if self.grid_shape else None
        out |= fields_dict(self, "q_fixed", "q")
        out |= {k: _listed(getattr(self, k)) for k in _PER_SAMPLE}
        out |= fields_dict(self, "family_tol", "family_tols", "family_reason")
        fams = [fam.to_dict(names) | {"count": counts[fam.name]} for fam in self.families]
        out["families"] = fams
        out["n_singular"] = int(np.count_nonzero(self.singular))
        return out | {"n_unexplained": int(np.count_nonzero(self.unexplained))}


# ------------------------------------------------------------------------ defaults
def _joint_indices(model: Any, joints: Any) -> tuple[int, ...]:
    if isinstance(joints, str) and joints == "all" and "all" not in model.joint_names:
        return tuple(range(model.nq))
    if isinstance(joints, (str, int)):
        joints = [joints]
    out = []
    for j in joints:
        if isinstance(j, (int, np.integer)) and not isinstance(j, bool):
            if not 0 <= int(j) < model.nq:
                raise ParameterError(
                    f"joints: index {j} is out of range 0..{model.nq - 1} "
                    f"(joints {choices(model.joint_names)})",
                    parameter="joints",
                    value=j,
                    allowed=f"0..{model.nq - 1} or {list(model.joint_names)}",
                )
            out.append(int(j))
        else:
            out.append(model.joint_index(str(j)))
    if len(set(out)) != len(out) or not out:
        msg = f"joints={joints!r}: give distinct joint names or indices"
        raise ParameterError(msg, parameter="joints", value=joints, allowed=list(model.joint_names))
    return tuple(out)


def default_q_fixed(
    model: Any, rows: Any = None, joints: Sequence[int] | None = None, seed: int = 7
) -> np.ndarray:
    """A dexterous configuration for the joints that a scan does not move, in [rad]/[m].

    Among 256 seeded random configurations, the one whose worst ``σmin/σmax`` over a coarse
    grid (5 points per joint) of the scanned ``joints`` (indices) is largest. ``rows``: the row
    selection (default :func:`~.measure.default_rows`); ``seed``: of the candidates.
    """
    mdl = as_model(model)
    names = selected_rows(mdl, rows)
    scanned = tuple(sorted(joints)) if joints is not None else ()

    def build() -> np.ndarray:
        cand = mdl.random_q(256, seed=seed)
        cand[0] = mdl.neutral()
        sub = list(scanned)[:3]
        if sub:
            axes = [np.linspace(mdl.lower[j], mdl.upper[j], 5) for j in sub]
            mesh = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, len(sub))
        else:
            mesh = np.zeros((1, 0))
        qs = np.repeat(cand, mesh.shape[0], axis=0)
        qs[:, sub] = np.tile(mesh, (cand.shape[0], 1))
        res = _measures_small(mdl, qs, names)
        with np.errstate(divide="ignore"):
            inv = np.where(np.isfinite(res.condition), 1.0 / res.condition, 0.0)
        score = inv.reshape(cand.shape[0], mesh.shape[0])
        # the worst grid point, then the mean (ties: all-singular fixed joints lose)
        key = score.min(axis=1) + 1e-3 * score.mean(axis=1)
        best = cand[int(np.argmax(key))].copy()
        best.setflags(write=False)
        return best

    return np.array(mdl.cached(f"singularity.q_fixed.{names}.{scanned}.{seed}", build))


def default_joints(model: Any, rows: Any = None, count: int = 2) -> tuple[int, ...]:
    """The ``count`` joints that change ``sigma_min`` most: the ones a heat map should show.

    Each joint that moves the tip is swept over its range at 32 seeded configurations of the
    others; its score is the mean spread of ``log σmin`` (ties: revolute, then later joints).
    ``rows`` as :func:`default_q_fixed`'s. Returns joint indices, ascending.
    Raises ParameterError: the model has fewer than ``count`` joints.
    """
    mdl = as_model(model)
    if mdl.nq < count:
        msg = f"default_joints: {mdl.name!r} has {mdl.nq} joint(s); {count} are needed"
        raise ParameterError(msg, parameter="count", value=count, allowed=f"<= {mdl.nq}")
    names = selected_rows(mdl, rows)

    def build() -> tuple[int, ...]:
        moving = sorted({int(c) for c in mdl.arrays.col})  # a hexapod: 15 do not move one foot
        cands = moving if len(moving) >= count else list(range(mdl.nq))
        base, score = mdl.random_q(32, seed=11), np.zeros(mdl.nq)
        floor = 1e-12 * max(reach(mdl), 1e-12)
        for j in cands:
            sweep = np.linspace(mdl.lower[j], mdl.upper[j], 17)
            qs = np.repeat(base, sweep.size, axis=0)
            qs[:, j] = np.tile(sweep, base.shape[0])
            smin = _measures_small(mdl, qs, names).sigma_min.reshape(base.shape[0], sweep.size)
            logs = np.log(np.maximum(smin, floor))
            score[j] = float(np.mean(logs.max(axis=1) - logs.min(axis=1)))
        prism = np.asarray(mdl.is_prismatic, dtype=bool)
        order = sorted(cands, key=lambda j: (-round(float(score[j]), 9), bool(prism[j]), -j))
        return tuple(sorted(order[:count]))

    return mdl.cached(f"singularity.default_joints.{names}.{count}", build)


def _grid_points(
    model: Any, joints: tuple[int, ...], grid: Any, q_fixed: np.ndarray
) -> tuple[np.ndarray, tuple[int, ...]]:
    counts: list[Any] = [grid] * len(joints) if np.isscalar(grid) else list(grid)
    shape = [int(c) for c in counts if _count(c, 2)]
    total, most = math.prod(shape), f"{MAX_CONFIGURATIONS:,}"
    for bad, why, a in (  # the first that fails
        (len(counts) != len(joints), f": one count or one per scanned joint ({len(joints)}) is "
         "required", f"an integer >= 2 or {len(joints)} of them"),
        (len(shape) != len(counts), ": counts must be integers >= 2", "integers >= 2"),
        (total > MAX_CONFIGURATIONS, f" makes {total} configurations; at most {most}",
         f"at most {most} configurations in all"),
    ):  # fmt: skip
        if bad:
            raise ParameterError(f"grid={grid!r}{why}", parameter="grid", value=grid, allowed=a)
    axes = [np.linspace(model.lower[j], model.upper[j], c) for j, c in zip(joints, shape)]
    q = np.empty((*shape, model.nq))
    q[...] = q_fixed
    for k, (j, ax) in enumerate(zip(joints, axes)):
        index: list[slice | None] = [None] * len(shape)
        index[k] = slice(None)
        q[..., j] = ax[tuple(index)]  # broadcast along the other grid axes, no meshgrid copies
    return q.reshape(total, model.nq), tuple(shape)


def _sample_points(
    model: Any, joints: tuple[int, ...], samples: Any, q_fixed: np.ndarray, seed: int | None
) -> np.ndarray:
    if not _count(samples, 1, MAX_CONFIGURATIONS):
        raise ParameterError(
            f"samples={samples!r}: an integer in 1..{MAX_CONFIGURATIONS:,} is required",
            parameter="samples",
            value=samples,
            allowed=f"1..{MAX_CONFIGURATIONS:,}",
        )
    rng = np.random.default_rng(seed)
    q = np.empty((int(samples), model.nq))
    q[:] = q_fixed
    for j in joints:
        q[:, j] = rng.uniform(model.lower[j], model.upper[j], int(samples))
    return q


def scan(
    model: Any,
    grid: int | Sequence[int] | None = None,
    samples: int | None = None,
    joints: Sequence[str | int] | str | None = None,
    *,
    rows: str | Sequence[str] | None = None,
    q_fixed: Any = None,
    threshold: float | None = None,
    rtol: float = 1e-2,
    family_tol: float | None = None,
    families: bool | str = True,
    family_budget: float = 10.0,
    seed: int | None = 0,
    progress: bool | None = None,
    chunk: int = 1_000_000,
) -> ScanResult:
    """Scan joint space (grid or random samples) for singularity measures and singular families.

    Args:
        model: A loaded model or any source for :func:`hexapod_kin.load`.
        grid: Points per scanned joint (one count, or one per joint) over the joint limits;
            default :data:`DEFAULT_GRID`.
        samples: Uniform random configurations instead of a grid (``seed``: theirs).
        joints: Joints to scan (names or indices, or ``"all"``); default
            :func:`default_joints`. The others stay at ``q_fixed``.
        rows: Row selection of ``J`` (``("x", "y", "z", "wz")``, ``"position"``, ``"all"``);
            default :func:`~.measure.default_rows`.
        q_fixed: Values of the joints not scanned; default :func:`default_q_fixed`.
        threshold: ``sigma_min`` below which a configuration is flagged singular; default
            ``rtol × reach(model)``.
        rtol: Relative threshold (see ``threshold``).
        family_tol: Joint-space distance in [rad]/[m] within which a flagged configuration
            counts as on its nearest family; default ``15 × rtol``.
        families: ``True``: derive them when needed (sympy, within ``family_budget``);
            ``"cached"``: only families already derived; ``False``: none.
        family_budget: CPU budget in [s] of the families (:func:`~.families.families_for`).
        progress: Show a tqdm bar on stderr (default: when N > 2,000,000 and stderr is a tty).
        chunk: Configurations per kernel call (scans above :data:`SMALL_SCAN`).
        seed: Of ``samples``.

    Raises:
        ParameterError: Bad arguments. ConfigurationError: Bad ``q_fixed`` or ``family_tol``.

    """
    mdl = as_model(model)
    names = selected_rows(mdl, rows)
    if joints is None:
        jidx = default_joints(mdl, names, 2) if mdl.nq > 2 else tuple(range(mdl.nq))
    else:
        jidx = _joint_indices(mdl, joints)
    one_of("families", families, (True, False, "cached"))
    if not _count(chunk, 1):
        msg = f"chunk={chunk!r}: an integer >= 1 is required"
        raise ParameterError(msg, parameter="chunk", value=chunk, allowed=">= 1")
    if grid is not None and samples is not None:
        msg = "scan: give grid= or samples=, not both"
        raise ParameterError(msg, parameter="samples", value=samples, allowed="grid= or samples=")
    if q_fixed is None:
        qf = default_q_fixed(mdl, names, jidx) if len(jidx) < mdl.nq else mdl.neutral()
    else:
        qf = mdl.check_q(q_fixed, "q_fixed").copy()
    length = reach(mdl)
    if 0.0 < length < MIN_REACH:
        raise ParameterError(
            f"model: the chain's reach (sum of its link offsets) is {length:g} m, below "
            f"{MIN_REACH:g} m: its Jacobian's singular values underflow and no verdict holds; "
            f"allowed a reach of 0 or >= {MIN_REACH:g} m",
            parameter="model",
            value=length,
            allowed=f"reach 0 or >= {MIN_REACH:g} m",
        )
    thr = positive("threshold", rtol * length if threshold is None else threshold, allow_zero=True)
    if samples is not None:
        q, shape = _sample_points(mdl, jidx, samples, qf, seed), None
    else:
        q, shape = _grid_points(mdl, jidx, DEFAULT_GRID if grid is None else grid, qf)
    n = q.shape[0]
    if n <= SMALL_SCAN:
        det, manip, cond, smin = _measures_small(mdl, q, names)
    else:
        det, manip, cond, smin = _kernel_scan(mdl, q, names, progress, int(chunk))
    singular = (smin < thr) | (smin <= 0.0)  # a zero sigma_min is singular at any threshold
    family, second = np.full(n, -1, dtype=np.int64), np.full(n, -1, dtype=np.int64)
    distance, distance2 = np.full(n, np.nan), np.full(n, np.nan)
    if families is False:
        fams = Families((), "none", "families=False")
    else:
        fams = families_for(mdl, names, derive=families is True, budget=family_budget)
    idx = np.flatnonzero(singular)
    if fams.families and idx.size:
        family[idx], distance[idx], second[idx], dist2 = fams.nearest(q[idx])
        distance2[idx] = np.where(second[idx] >= 0, dist2, np.nan)
    tol = 15.0 * rtol if family_tol is None else float(family_tol)
    if not tol >= 0:
        msg = f"family_tol={family_tol!r}: a value >= 0 is required"
        raise ConfigurationError(msg, parameter="family_tol", value=family_tol, allowed=">= 0")
    tols = []
    for f in range(len(fams.families)):
        mine = (family == f) & (distance > 0) & (distance <= tol)
        lever = float(np.quantile(smin[mine] / distance[mine], 0.25)) if mine.sum() >= 8 else np.inf
        tols.append(min(max(tol, 1.5 * thr / lever), 4.0 * tol) if lever > 0 else 4.0 * tol)
    arrays = (q, det, manip, cond, smin, singular, family, distance, second, distance2)
    q, det, manip, cond, smin, singular, family, distance, second, distance2 = map(_ro, arrays)
    prismatic = tuple(bool(p) for p in mdl.is_prismatic)
    return ScanResult(
        q, det, manip, cond, smin, singular, family, distance, second, distance2, fams.families,
        fams.reason, tol, tuple(tols), tuple(mdl.joint_names), prismatic, jidx, names, thr,
        shape, _ro(qf), mdl.name,
    )  # fmt: skip
