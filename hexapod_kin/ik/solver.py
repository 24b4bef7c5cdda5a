"""Numerical IK for any loaded chain: position, position + yaw, or a full 6-D pose.

Levenberg–Marquardt on the weighted task rows of :mod:`hexapod_kin.ik.task`: ``λ² = μ(‖We‖² +
w̄)``, μ ÷4 after a kept step, ×8 after a refused one; a step is kept only if it lowers ``‖We‖``;
steps are capped per joint; continuous joints wrap, the others are clamped (a joint at a limit
pushed outward is frozen); 8 flat steps or 40 refusals end an attempt; seeded restarts follow.
On a redundant chain each step first tries the posture motion ``z`` on the task's null space,
``Δq = z + J⁺_λ(e − Jz)``, kept only if it quarters the squared error.

One compiled loop (:func:`~hexapod_kin.ik.step.lm_loop`) for :func:`solve` (one target, its row
of a batch bit for bit), :func:`solve_many` and :func:`solve_chain` (a chain view, a seed per
target); the first :data:`INTERPRETED_CALLS` small calls of :func:`solve` run it in Python
(:func:`~hexapod_kin._kmath.python_twin`, the same bits).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .._chain import ChainArrays
from .._numerics import chain_scale
from ..exceptions import ConfigurationError, IKError
from ..kinematics import KinematicModel
from .prepare import ModelLike, Prepared, as_model, prepared
from .result import (
    _DEFAULT,
    _O_Q,
    MAX_ITER,
    STATUSES,
    IKOptions,
    IKResult,
    _converged_fields,
    _result,
)
from .task import (
    MODES,
    TARGET_FACTOR,
    Task,
    _fast,
    _limit,
    _task,
    build_task,
    build_tasks,
    check_within,
)

__all__ = ["INTERPRETED_CALLS", "MAX_ITER", "STATUSES", "IKOptions", "IKResult", "solve",
           "solve_chain", "solve_many"]  # fmt: skip

_MU0 = 0.1  # initial LM factor: λ² = μ (‖e‖² + w̄)
_CODES = {mode: i for i, mode in enumerate(MODES)}  # task mode → the loop's mode number


#: Fewest targets per thread of :func:`solve_many` (the compiled loop releases the GIL).
_PER_THREAD = 64


# ============================================================================ the loop's setup


@dataclass(frozen=True)
class _Setup:
    """Checked options as the loop's C-contiguous arguments (``step.P_*`` / ``step.I_*``).

    The same types for one target and many: one compiled :func:`~hexapod_kin.ik.step.lm_loop`.
    """

    prep: Prepared
    par: np.ndarray  # tol, rot_tol, w̄, μ0, posture gain, yaw (per target), posture floor
    ipar: np.ndarray  # mode, max_iter, limits on, posture on, candidate first starts
    starts: np.ndarray  # (1 + restarts, n): home (or q0), then the seeded restarts
    fplan: np.ndarray  # the chain, limits, step caps, posture, first starts (:func:`_plans`)
    iplan: np.ndarray  # ipar, then the chain's joint kinds, columns, continuous flags
    iplan_q0: np.ndarray  # the same without the candidate first starts (a given q0)
    tols: tuple[float, float]  # tol, rot_tol as Python floats
    why: str  # the converged reason, "%"-formatted with the two errors
    one: tuple[np.ndarray, np.ndarray]  # par (1, 7) and starts (1, S, n): one target's rows
    width: int  # values per target in the loop's output
    n: int  # joints


def _arg(a: Any) -> np.ndarray:
    """A private C-contiguous writeable copy: an input of the compiled loop (never written)."""
    return np.array(a, order="C")


def _frozen(a: Any) -> np.ndarray:
    """A read-only C-contiguous array: the targets' input of the compiled loop."""
    a = np.array(a, order="C")
    a.setflags(write=False)
    return a


def _setup(mdl: KinematicModel, opts: IKOptions, mode: int) -> _Setup:
    """The loop's arguments for ``opts`` and task ``mode`` (cached per model when hashable)."""
    table: dict[Any, _Setup] = mdl.cached("ik.setups", dict)
    key: Any = mode if opts is _DEFAULT else (opts, mode)
    try:
        found = table.get(key)
    except TypeError:  # arrays in the options: built each time
        return _build_setup(mdl, opts, mode)
    if found is None:
        if len(table) >= 64:
            table.clear()
        found = table[key] = _build_setup(mdl, opts, mode)
    return found


def _build_setup(mdl: KinematicModel, opts: IKOptions, mode: int) -> _Setup:
    prep = prepared(mdl)
    posture, use = prep.middle, opts.posture is not None and opts.posture is not False
    if use and not isinstance(opts.posture, str):
        posture = mdl.check_q(opts.posture, "posture")
    par, limits = _par(opts, prep.scale), int(bool(opts.within_limits))
    ipar = np.array([mode, opts.max_iter, limits, int(use), len(prep.near)], np.int64)
    starts = np.vstack([prep.home, prep.starts[: opts.restarts]])
    lim = np.vstack([prep.lim, posture])
    fplan, iplan = _plans(mdl.arrays, lim, prep.cont, ipar, prep.near, prep.near_poses)
    iplan_q0 = np.array(iplan)
    iplan_q0[4] = 0
    tols = (float(opts.tol), float(opts.rot_tol))
    one = (par[None], starts[None])
    why = f"‖e‖ = %.3g m, %.3g rad <= tol {tols[0]:g}, {tols[1]:g}"
    n = mdl.nq
    width = _O_Q + n + 12 + opts.max_iter + 1
    return _Setup(prep, par, ipar, starts, fplan, iplan, iplan_q0, tols, why, one, width, n)


def _plans(
    chain: Any, lim: np.ndarray, cont: np.ndarray, ipar: Any, near: Any = (), near_poses: Any = (),
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """The compiled loop's two packed inputs ``(fplan, iplan)`` (see ``step.lm_loop``).

    Of a chain, ``lim`` (4, n), the continuous flags, ``ipar`` and the candidate first starts
    (K, n) with their tip poses (K, 12).
    """
    rot, trans, axis, kind, col = chain.packed
    parts = (rot, trans, axis, chain.tip_rot, lim, near, near_poses)
    fplan = np.concatenate([np.ravel(np.asarray(a, dtype=float)) for a in parts])
    head = np.array([*(int(v) for v in ipar), len(kind), len(cont)])
    iplan = np.concatenate([head, kind, col, cont]).astype(np.int64)
    return np.ascontiguousarray(fplan, dtype=np.float64), iplan


def _par(opts: IKOptions, scale: float) -> np.ndarray:
    """The loop's float parameters (``step.P_*``): tolerances, w̄, μ0, posture gain, yaw, floor."""
    tol, rot_tol, gain = float(opts.tol), float(opts.rot_tol), float(opts.posture_gain)
    return np.array([tol, rot_tol, 1e-8 * scale**2, _MU0, gain, 0.0, 1e-6 * scale])


#: The compiled loop once loaded in this process (the first call goes through ``run_blocks``:
#: the cache check, the compile notice, the stamp).
_LOADED: list[Any] = []
#: How many of a process's first :func:`solve` calls run the loop in Python (with their
#: diagnosis) when their step budget is small (:data:`_PYTHON_STEPS`): the same bits, nothing
#: to load or compile. The next call loads (or compiles) the machine code, as batches do.
INTERPRETED_CALLS = 16
_LEFT = [INTERPRETED_CALLS]
#: The most accepted steps a call run in Python may take (``max_iter`` × attempts): the
#: defaults with every restart (100 × 33); a larger budget runs compiled from the first call.
_PYTHON_STEPS = 3_300
#: :func:`~hexapod_kin._kmath.python_twin` of the loop, once built.
_PYTHON: list[Any] = []


def _run(
    fplan: np.ndarray, iplan: np.ndarray, tgts: np.ndarray, w6: np.ndarray, pars: np.ndarray,
    starts: np.ndarray, python: bool = False,
) -> np.ndarray:  # fmt: skip
    """The loop (:func:`~hexapod_kin.ik.step.lm_loop`) for N targets: output rows (N, width).

    ``fplan``, ``iplan``: the chain and the settings (:func:`_plans`); ``tgts`` (N, 4, 4),
    ``pars`` (N, 7), ``starts`` (N, S, n). Each target's numbers are its own: the same bits
    alone, in a batch, on any thread, compiled or (``python``) interpreted.
    """
    n_t, n = len(tgts), starts.shape[2]
    out = np.empty((n_t, _O_Q + n + 12 + int(iplan[1]) + 1))
    if n_t == 1 and _LOADED:  # one target: straight in (a few µs of call overhead)
        _LOADED[0](fplan, iplan, tgts, w6, pars, starts, out)
        return out
    from .step import lm_loop

    if python and not _LOADED:
        if not _PYTHON:
            from .._kmath import python_twin

            _PYTHON[:] = [python_twin(lm_loop)]
        _PYTHON[0](fplan, iplan, tgts, w6, pars, starts, out)
        return out
    from .._kernels import run_blocks

    def run(a: int, b: int) -> None:  # targets a..b-1
        lm_loop(fplan, iplan, tgts[a:b], w6, pars[a:b], starts[a:b], out[a:b])

    run_blocks("ik", run, n_t, 1, _PER_THREAD)
    _LOADED[:] = [lm_loop]
    return out


def _residuals(s: _Setup, task: Task, qs: np.ndarray, python: bool) -> np.ndarray:
    """‖W e‖ of the task at K configurations ``qs`` (K, n): the loop for 0 steps, no limits."""
    k = len(qs)
    par = s.par if task.code != 1 else _with_yaw(s.par[None], [task.yaw])[0]
    tgts = _frozen(np.broadcast_to(task.pose, (k, 4, 4)))
    iplan = np.array(s.iplan)
    iplan[1:5] = 0  # no steps, no limits, no posture, the given start
    starts = _arg(np.asarray(qs, dtype=float)[:, None, :])
    pars = _arg(np.tile(par, (k, 1)))
    out = _run(s.fplan, iplan, tgts, task.weights, pars, starts, python)
    return out[:, _O_Q + s.n + 12]


def _with_yaw(pars: np.ndarray, yaws: Any) -> np.ndarray:
    out = np.array(pars)
    out[:, 5] = yaws
    return out


# ============================================================================ solve
def solve(model: ModelLike, target: Any, q0: Any = None, **options: Any) -> IKResult:
    """Numerical IK of the tip: position, position + yaw, or a 6-D pose, for any chain.

    ``model``: a loaded model or anything :func:`hexapod_kin.load` takes. ``target``: tip
    position (3,) [m]; position + yaw (4,) (ψ [rad]: the tool's x axis in the base xy-plane);
    or a pose ``baseMtarget`` (4, 4). ``q0`` (nq,): default the candidate of
    :attr:`~hexapod_kin.ik.Prepared.near` whose tip pose is nearest the target, then
    :func:`~hexapod_kin.ik.home`, then the seeded restarts. ``options``: :class:`IKOptions`.

    Returns:
        An :class:`IKResult`: ``"unreachable"`` (every attempt ended at a local minimum of the
        error; ``nearest`` / ``distance`` give the best point), ``"joint_limits"`` (reachable
        only outside the limits), ``"singular"`` or ``"not_converged"`` (iteration cap).

    Raises:
        IKError: Bad target (:func:`~hexapod_kin.ik.check_within`) or mask/weights.
        ConfigurationError: Bad ``q0`` or ``posture``. ParameterError: Bad options.

    """
    mdl = model if isinstance(model, KinematicModel) else as_model(model)
    if _LOADED and not options and target.__class__ is np.ndarray:
        quick = _quick(mdl, target, q0)
        if quick is not None:
            return quick
    if options:
        opts = IKOptions.of(options)
        task = build_task(target, mask=opts.mask, weights=opts.weights)
    else:
        opts, task = _DEFAULT, build_task(target)
    check_within(mdl, task.pose[:3, 3])
    code = _CODES[task.mode]
    s = _setup(mdl, opts, code)
    pars, starts = s.one
    iplan = s.iplan
    if q0 is not None:
        starts = np.array(starts)
        starts[0, 0] = mdl.check_q(q0, "q0")
        iplan = s.iplan_q0
    if code == 1:
        pars = _with_yaw(pars, [task.yaw])
    python = not _LOADED and _LEFT[0] > 0 and int(s.ipar[1]) * len(s.starts) <= _PYTHON_STEPS
    _LEFT[0] -= python
    out = _run(s.fplan, iplan, task.pose[None], task.weights, pars, starts, python)
    return _report(mdl, s, task, out[0], python)


def _quick(mdl: KinematicModel, t: np.ndarray, q0: Any = None) -> IKResult | None:
    """:func:`solve` of a float64 position or pose, no options, once the loop is loaded.

    The same bits as the general path; a converged result's fields are built when first read.
    None: any other case (the general path checks it).
    """
    fast = _fast(t)
    if fast is None:
        return None
    mode, tg, w6, total = fast

    def setup() -> tuple[_Setup, float]:  # the setup, the farthest target |x| + |y| + |z|
        return _setup(mdl, _DEFAULT, _CODES[mode]), max(1e-3 * TARGET_FACTOR, _limit(mdl))

    s, limit = mdl.cached(_QUICK[mode], setup)
    if not total <= limit:  # farther, or not finite: the general path's check
        return None
    iplan, starts = s.iplan, s.one[1]
    if q0 is not None:
        iplan, starts = s.iplan_q0, starts.copy()
        starts[0, 0] = mdl.check_q(q0, "q0")
    out = np.empty((1, s.width))
    _LOADED[0](s.fplan, iplan, tg, w6, s.one[0], starts, out)
    out.setflags(write=False)
    if out[0, 2] != 0.0:
        return _report(mdl, s, _task(mode, tg[0], 0.0, w6), out[0], False)
    res = _NEW(IKResult)
    _SET(res, "__dict__", {"_lazy": (out, s, (mode, tg, w6))})
    return res


_QUICK = {"position": "ik.quick.position", "pose": "ik.quick.pose"}
_NEW, _SET = object.__new__, object.__setattr__


def _report(mdl: KinematicModel, s: _Setup, task: Task, row: np.ndarray, python: bool) -> IKResult:
    """The result of one output row of the loop (made read-only; ``python``: see :func:`_run`)."""
    row.setflags(write=False)
    err, rot = row[3:5].tolist()
    fields = _converged_fields(row, s, task)
    if row[2] == 0.0 or (err <= s.tols[0] and rot <= s.tols[1]):
        return _result(fields, "converged", fields["reason"], False)
    fields["reason"] = ""
    if row[2] == 2.0:
        why = f"{int(s.ipar[1])} steps taken, ‖e‖ = {err:.3g} m, {rot:.3g} rad, still decreasing"
        return _result(fields, "not_converged", why, False)
    return _diagnose(mdl, s, task, fields["q"], fields["history"], fields, python)


def _diagnose(
    mdl: KinematicModel, s: _Setup, task: Task, q: np.ndarray, hist: np.ndarray,
    fields: dict[str, Any], python: bool,
) -> IKResult:  # fmt: skip
    """The status of a stalled attempt: joint limits, unreachable, singular or not converged."""
    prep = s.prep
    err, rot, smin = fields["error"], fields["rotation_error"], fields["sigma_min"]
    blocked = _blocked(s, task, q, python) if s.ipar[2] else np.empty(0, dtype=int)
    if blocked.size:
        # the same loop without limits, 200 steps, from q and 8 seeded starts
        iplan = np.array(s.iplan)
        iplan[1:3] = 200, 0  # 200 steps, no limits
        iplan[4] = 0  # from q
        starts = np.vstack([q, prep.starts[:8]])[None]
        pars = s.par[None] if task.code != 1 else _with_yaw(s.par[None], [task.yaw])
        free = _run(s.fplan, iplan, task.pose[None], task.weights, pars, starts, python)
        if free[0, 2] == 0:
            names = [mdl.joint_names[i] for i in blocked]
            why = (
                f"reachable only beyond the limits of {names}; the nearest point within the "
                f"limits is {err:.3g} m, {rot:.3g} rad away"
            )
            return _result(fields, "joint_limits", why, True)
    if _is_local_min(mdl, s, task, q, float(hist[-1]), python):
        why = (
            f"outside the workspace: every start ends at a local minimum of the error, "
            f"{err:.6g} m, {rot:.6g} rad from the target"
        )
        return _result(fields, "unreachable", why, True)
    if smin <= 1e-6 * prep.scale:
        why = (
            f"stalled at a singular configuration (σ_min = {smin:.3g}) that is not a minimum "
            "of the error; try another q0 or more restarts"
        )
        return _result(fields, "singular", why, False)
    why = f"stalled at ‖e‖ = {err:.3g} m (no step lowers the error)"
    return _result(fields, "not_converged", why, False)


def _blocked(s: _Setup, task: Task, q: np.ndarray, python: bool) -> np.ndarray:
    """Joints at a limit where the task error decreases outward (1e-7 rad/m beyond it)."""
    lower, upper, cont = s.prep.lim[0], s.prep.lim[1], s.prep.cont
    at_lo = (~cont) & (q <= lower + 1e-12)
    idx = np.flatnonzero(at_lo | ((~cont) & (q >= upper - 1e-12)))
    if not idx.size:
        return idx
    trial = np.repeat(q[None], len(idx) + 1, axis=0)
    trial[np.arange(1, len(idx) + 1), idx] += np.where(at_lo[idx], -1e-7, 1e-7)
    res = _residuals(s, task, trial, python)
    return idx[res[1:] < res[0]]


def _is_local_min(
    mdl: KinematicModel, s: _Setup, task: Task, q: np.ndarray, cost_root: float, python: bool
) -> bool:
    """True if no small perturbation of q (±1e-3, ±3e-2 rad) lowers the task error."""
    prep, rng = s.prep, np.random.default_rng(7)
    jac, rows = mdl.jacobian(q), task.weights != 0
    _, sv, vt = np.linalg.svd(jac[rows] * task.weights[rows, None])
    sv_full = np.zeros(mdl.nq)
    sv_full[: sv.size] = sv
    null = vt[sv_full <= 1e-6 * max(prep.scale, float(sv_full.max()))]
    base = np.vstack([np.eye(mdl.nq), rng.normal(size=(16, mdl.nq)), null])
    dirs = np.vstack([base, -base])
    trial = np.vstack([q[None, :] + h * dirs for h in (1e-3, 3e-2)])
    if s.ipar[2]:
        trial = np.where(prep.cont, trial, np.clip(trial, prep.lim[0], prep.lim[1]))
    floor = cost_root - 1e-9 * prep.scale
    return not bool(np.any(_residuals(s, task, trial, python) < floor))


def solve_many(model: ModelLike, targets: Any, q0: Any = None, **options: Any) -> list[IKResult]:
    """:func:`solve` for N targets of one kind, the loops in one compiled call (a batch API).

    ``targets``: (N, 3) positions, (N, 4) positions + yaw, or (N, 4, 4) poses; ``q0``: None
    (:func:`solve`'s default start), one (nq,) start for all, or (N, nq); ``options`` as
    :func:`solve`'s, for all. Returns one :class:`IKResult` per target, :func:`solve`'s bits.

    Raises: as :func:`solve` (and ConfigurationError: ``q0`` rows do not match).
    """
    mdl, opts = as_model(model), IKOptions.of(options)
    t = np.asarray(targets, dtype=float)
    if not ((t.ndim == 2 and t.shape[1] in (3, 4)) or (t.ndim == 3 and t.shape[1:] == (4, 4))):
        msg = f"targets has shape {t.shape}; (N, 3), (N, 4) or (N, 4, 4) is needed"
        raise IKError(msg, parameter="targets", value=t.shape, allowed="(N, 3), (N, 4), (N, 4, 4)")
    tasks = build_tasks(t, mask=opts.mask, weights=opts.weights)
    if not tasks:
        return []
    check_within(mdl, t[..., :3, 3] if t.ndim == 3 else t[:, :3], "targets")
    n_t = len(tasks)
    s = _setup(mdl, opts, tasks[0].code)
    starts = np.empty((n_t, *s.starts.shape))
    starts[:] = s.starts
    iplan = s.iplan if q0 is None else s.iplan_q0
    if q0 is not None and np.ndim(q0) == 1:
        starts[:, 0] = mdl.check_q(q0, "q0")
    elif q0 is not None:
        rows = mdl.check_q_batch(q0, "q0")
        if len(rows) != n_t:
            msg = f"q0 has {len(rows)} rows; targets has {n_t}"
            raise ConfigurationError(msg, parameter="q0", value=len(rows), allowed=f"{n_t} rows")
        starts[:, 0] = rows
    pars = np.broadcast_to(s.par, (n_t, len(s.par)))
    if tasks[0].code == 1:
        pars = _with_yaw(pars, [task.yaw for task in tasks])
    pars = _arg(pars)
    tgts = _frozen(np.array([task.pose for task in tasks]).reshape(n_t, 4, 4))
    out = _run(s.fplan, iplan, tgts, tasks[0].weights, pars, starts)
    return [_report(mdl, s, task, row, False) for task, row in zip(tasks, out)]


#: :func:`solve_chain`'s prepared inputs per chain and settings (a chain is an immutable
#: view: an entry is reused only for the very same object; never written by the loop).
_CHAIN_SETUPS: dict[tuple[Any, ...], tuple[Any, ...]] = {}


def _chain_setup(
    chain: ChainArrays, lower: Any, upper: Any, tol: float, max_iter: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(fplan, iplan, par, w6)`` of the compiled loop for a chain view (cached)."""
    n = int(chain.nq)
    lo = np.broadcast_to(np.asarray(lower, dtype=float), (n,))
    hi = np.broadcast_to(np.asarray(upper, dtype=float), (n,))
    key = (id(chain), lo.tobytes(), hi.tobytes(), repr(tol), repr(max_iter))
    hit = _CHAIN_SETUPS.get(key)
    if hit is not None and hit[0] is chain:
        return hit[1:]
    opts = IKOptions(tol=tol, rot_tol=tol, max_iter=max_iter)
    prism = np.asarray(chain.kind, dtype=bool)
    cont = (~prism) & (hi - lo >= 2 * np.pi - 1e-9)
    scale = chain_scale(chain.trans)
    lim = np.vstack([lo, hi, np.where(prism, 0.25 * scale, 0.5)])
    fplan, iplan = _plans(chain, np.vstack([lim, np.zeros(n)]), cont, [0, opts.max_iter, 1, 0, 0])
    setup = (fplan, iplan, _par(opts, scale), _frozen([1.0, 1.0, 1.0, 0.0, 0.0, 0.0]))
    if len(_CHAIN_SETUPS) >= 256:
        _CHAIN_SETUPS.clear()
    _CHAIN_SETUPS[key] = (chain, *setup)
    return setup


def solve_chain(
    chain: ChainArrays,
    targets: Any,
    seeds: Any,
    lower: Any,
    upper: Any,
    *,
    tol: float = 1e-10,
    max_iter: int = 100,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Position IK of a chain view for N targets, each from its own seed (the one loop).

    On a :class:`~hexapod_kin._chain.ChainArrays` (a leg: mount → foot), position rows only,
    no restarts, no posture; limited joints are clamped, continuous ones wrap.

    ``targets`` (N, 3) [m] in the chain's frame, ``seeds`` (N, nq) starts (e.g. the previous
    sample's solution), ``lower`` / ``upper`` (nq,) limits [rad]/[m], ``tol`` [m] on the
    position error, ``max_iter`` accepted steps per target.

    Returns ``(q (N, nq), residual (N,) [m], converged (N,))``: the best configuration found,
    its position error and whether it is within ``tol``. Raises IKError (``targets``/``seeds``
    shape or values), ParameterError (``tol``, ``max_iter``).
    """
    n = int(chain.nq)
    fplan, iplan, par, w6 = _chain_setup(chain, lower, upper, tol, max_iter)
    t = np.asarray(targets, dtype=float)
    q0 = np.asarray(seeds, dtype=float)
    if t.ndim != 2 or t.shape[1] != 3 or q0.shape != (len(t), n):
        raise IKError(
            f"targets {t.shape} and seeds {q0.shape} do not match; (N, 3) and (N, {n}) needed",
            parameter="targets",
            value=t.shape,
            allowed=f"(N, 3) targets and (N, {n}) seeds",
        )
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(q0))):
        raise IKError("targets and seeds must be finite", parameter="targets", value=t.tolist())
    tgts = np.zeros((len(t), 4, 4))
    tgts[:, [0, 1, 2, 3], [0, 1, 2, 3]] = 1.0
    tgts[:, :3, 3] = t
    pars, starts = np.tile(par, (len(t), 1)), _arg(q0[:, None, :])
    out = _run(fplan, iplan, _frozen(tgts), w6, pars, starts)
    steps = out[:, 1].astype(np.intp)
    residual = out[np.arange(len(t)), _O_Q + n + 12 + steps]
    return np.array(out[:, _O_Q : _O_Q + n]), residual, out[:, 2] == 0
