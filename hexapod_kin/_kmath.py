"""Small compiled maths (numba) of the kernels, re-exported by :mod:`hexapod_kin._kernels`.

Every function is ``@njit(cache=True, nogil=True)`` on ``float64`` C-contiguous arrays, no
``fastmath`` (the same bits in every process and thread): :func:`eig3_sym`,
:func:`solve_spd`, :func:`dls_into`, :func:`wrap_angle`, :func:`sincos` (libm-free, within
1 ulp for ``|x| ≤ POLY_TRIG_MAX``). Also numba's cache seal. Angles in [rad].
"""

from __future__ import annotations

import atexit
import contextlib
import math
import os
import threading
import types
import warnings
from typing import Any

import numba
import numpy as np
from numba.core import event as _event

from . import _cache
from .exceptions import CacheWarning

__all__ = ["NUMBA_FILES", "POLY_TRIG_MAX", "dls_into", "eig3_sym", "njit", "python_twin",
           "reseal_if_compiled", "seal_compiled", "sealed_folder", "sincos", "solve_spd",
           "wrap_angle"]  # fmt: skip

_TWO_PI = 2.0 * math.pi


def njit(*args: Any, **options: Any) -> Any:
    """``numba.njit`` with ``cache=True`` by default; ``fastmath`` (position-dependent) refused.

    Without a writable, sealed cache folder (:func:`sealed_folder`) the kernels are compiled in
    memory (one :class:`~hexapod_kin.exceptions.CacheWarning`).
    """
    if options.get("fastmath"):
        raise ValueError("hexapod_kin kernels never use fastmath (the same bits every time)")
    options.setdefault("cache", True)

    def decorate(func: Any) -> Any:
        try:
            compiled = numba.njit(**options)(func)
        except RuntimeError as exc:
            if not options["cache"] or "cannot cache" not in str(exc):
                raise
            if not _IN_MEMORY:
                _IN_MEMORY.append(True)
                warnings.warn(
                    f"no writable folder for numba's compiled-code cache ({exc}); the kernels "
                    "are compiled in memory in this process (set NUMBA_CACHE_DIR to a "
                    "writable folder to keep them)",
                    CacheWarning,
                    stacklevel=3,
                )
            return numba.njit(**{**options, "cache": False})(func)
        if options["cache"] and not sealed_folder(compiled.stats.cache_path):
            return numba.njit(**{**options, "cache": False})(func)
        return compiled

    return decorate(args[0]) if args and callable(args[0]) else decorate


_IN_MEMORY: list[bool] = []


def python_twin(kernel: Any, _memo: dict[int, Any] | None = None) -> Any:
    """``kernel``'s Python function calling the twins of the kernels it calls: the same bits.

    Each function gets a copy of its module's globals, compiled functions replaced by twins.
    """
    memo: dict[int, Any] = {} if _memo is None else _memo
    found = memo.get(id(kernel))
    if found is not None:
        return found
    py = kernel.py_func
    names = dict(py.__globals__)
    twin = types.FunctionType(py.__code__, names, py.__name__, py.__defaults__, py.__closure__)
    memo[id(kernel)] = twin
    for name in py.__code__.co_names:
        obj = names.get(name)
        if isinstance(obj, numba.core.dispatcher.Dispatcher):
            names[name] = python_twin(obj, memo)
    return twin


#: numba's cache files (its index and its machine code): what the seal covers, as bytes.
NUMBA_FILES = (".nbi", ".nbc")
#: numba cache folder → whether numba may load from it in this process (checked once).
_FOLDERS: dict[str, bool] = {}
_FOLDERS_LOCK = threading.Lock()


def sealed_folder(folder: str | None) -> bool:
    """Whether numba may use its cache ``folder`` (every numba file sealed; once per process).

    Failing files cost one :class:`~hexapod_kin.exceptions.CacheWarning` and are removed
    (compiled afresh); where they cannot be, the kernels are compiled in memory.
    """
    if folder is None:
        return True
    with _FOLDERS_LOCK:
        if folder not in _FOLDERS:
            _FOLDERS[folder] = _check(folder)
        return _FOLDERS[folder]


def _check(folder: str) -> bool:
    """The check of :func:`sealed_folder` (its one warning included)."""
    bad = _cache.check_folder(folder, NUMBA_FILES)
    if not bad:
        return True
    name, why = sorted(bad.items())[0]
    usable = False
    if "no secret" not in bad.values():
        for file in bad:
            with contextlib.suppress(OSError):
                os.unlink(os.path.join(folder, file))
        usable = not _cache.check_folder(folder, NUMBA_FILES)
    more = f" and {len(bad) - 1} more" if len(bad) > 1 else ""
    then = (
        "removed: those kernels are compiled afresh"
        if usable
        else "the kernels are compiled in memory, never loaded from it"
    )
    unsealed = f"numba's compiled-code cache in {folder} holds files not sealed by this user"
    warnings.warn(f"{unsealed} ({name}: {why}{more}); {then}", CacheWarning, stacklevel=5)
    return usable


def seal_compiled() -> None:
    """Seal every cache folder numba writes this process's kernels to (after they are written)."""
    _DIRTY.clear()
    with _FOLDERS_LOCK:
        folders = [f for f, ok in _FOLDERS.items() if ok]
    for folder in folders:
        _cache.seal_folder(folder, NUMBA_FILES)


def reseal_if_compiled() -> None:
    """:func:`seal_compiled` if a kernel was compiled since (numba's lock released; at exit)."""
    if _DIRTY:
        seal_compiled()


#: Set when numba compiled a kernel of the package since the last seal.
_DIRTY: list[bool] = []


class OnEnd(_event.Listener):
    """A numba event listener calling ``callback(event)`` at each event's end."""

    def __init__(self, callback: Any) -> None:
        self.callback = callback

    def on_start(self, ev: Any) -> None:
        pass

    def on_end(self, ev: Any) -> None:
        self.callback(ev)


def _compiled(ev: Any) -> None:
    """Mark a compile of the package's (``"numba:compile"``, ended before numba saves)."""
    func = getattr((ev.data or {}).get("dispatcher"), "py_func", None)
    if getattr(func, "__module__", "").startswith("hexapod_kin"):
        _DIRTY[:] = [True]


_event.register("numba:compile", OnEnd(_compiled))
_event.register("numba:compiler_lock", OnEnd(lambda ev: reseal_if_compiled()))
atexit.register(reseal_if_compiled)


# ------------------------------------------------------------------------ eigenvalues
@njit(cache=True, nogil=True)
def eig3_sym(
    a00: float, a11: float, a22: float, a01: float, a02: float, a12: float
) -> tuple[float, float, float]:  # pragma: no cover - compiled
    """Eigenvalues (descending) of the symmetric ``[[a00,a01,a02],[a01,a11,a12],[a02,a12,a22]]``.

    Smith's (1961) closed form; a diagonal matrix gives its sorted diagonal exactly.
    """
    p1 = a01 * a01 + a02 * a02 + a12 * a12
    if p1 == 0.0:
        x, y, z = a00, a11, a22
        if x < y:
            x, y = y, x
        if y < z:
            y, z = z, y
        if x < y:
            x, y = y, x
        return x, y, z
    qm = (a00 + a11 + a22) / 3.0
    b00, b11, b22 = a00 - qm, a11 - qm, a22 - qm
    p2 = b00 * b00 + b11 * b11 + b22 * b22 + 2.0 * p1
    p = math.sqrt(p2 / 6.0)
    if p == 0.0:
        return qm, qm, qm
    inv = 1.0 / p
    c00, c11, c22 = b00 * inv, b11 * inv, b22 * inv
    c01, c02, c12 = a01 * inv, a02 * inv, a12 * inv
    r = 0.5 * (
        c00 * (c11 * c22 - c12 * c12)
        - c01 * (c01 * c22 - c12 * c02)
        + c02 * (c01 * c12 - c11 * c02)
    )
    if r <= -1.0:
        phi = math.pi / 3.0
    elif r >= 1.0:
        phi = 0.0
    else:
        phi = math.acos(r) / 3.0
    l1 = qm + 2.0 * p * math.cos(phi)
    l3 = qm + 2.0 * p * math.cos(phi + _TWO_PI / 3.0)
    l2 = 3.0 * qm - l1 - l3
    return l1, l2, l3


# ------------------------------------------------------------------------ linear solve
@njit(cache=True, nogil=True)
def solve_spd(
    a: np.ndarray, b: np.ndarray, out: np.ndarray, n: int
) -> bool:  # pragma: no cover - compiled
    """Solve ``a x = b`` for the leading n×n block of an SPD ``a``; False if not SPD.

    Reads the lower triangle of ``a`` and overwrites it with the Cholesky factor.
    """
    for j in range(n):
        s = a[j, j]
        for k in range(j):
            s -= a[j, k] * a[j, k]
        if not s > 0.0:
            return False
        d = math.sqrt(s)
        a[j, j] = d
        for i in range(j + 1, n):
            t = a[i, j]
            for k in range(j):
                t -= a[i, k] * a[j, k]
            a[i, j] = t / d
    for i in range(n):
        t = b[i]
        for k in range(i):
            t -= a[i, k] * out[k]
        out[i] = t / a[i, i]
    for i in range(n - 1, -1, -1):
        t = out[i]
        for k in range(i + 1, n):
            t -= a[k, i] * out[k]
        out[i] = t / a[i, i]
    return True


# ------------------------------------------------------------------------ damped least squares
@njit(cache=True, nogil=True)
def dls_into(
    jac: np.ndarray,
    e: np.ndarray,
    m: int,
    lam2: float,
    free: np.ndarray,
    dq: np.ndarray,
    work: np.ndarray,
    rhs: np.ndarray,
    sol: np.ndarray,
) -> bool:  # pragma: no cover - compiled
    """Damped least squares of the first ``m`` rows of a task; frozen joints (``~free``) get 0.

    :func:`hexapod_kin._numerics.dls_step`'s system, by Cholesky on the lower triangle;
    ``work`` at least k×k, ``rhs``/``sol`` k, k = max(m, n). False if not SPD.
    """
    n = jac.shape[1]
    if n <= m:
        for i in range(n):
            g = 0.0
            if free[i]:
                for r in range(m):
                    g += jac[r, i] * e[r]
            rhs[i] = g
            for k in range(i + 1):
                s = 0.0
                if free[i] and free[k]:
                    for r in range(m):
                        s += jac[r, i] * jac[r, k]
                work[i, k] = s
            work[i, i] += lam2
        ok = solve_spd(work, rhs, sol, n)
        for i in range(n):
            dq[i] = sol[i] if free[i] else 0.0
        return ok
    for a in range(m):
        rhs[a] = e[a]
        for b in range(a + 1):
            s = 0.0
            for k in range(n):
                if free[k]:
                    s += jac[a, k] * jac[b, k]
            work[a, b] = s
        work[a, a] += lam2
    ok = solve_spd(work, rhs, sol, m)
    for k in range(n):
        if free[k]:
            s = 0.0
            for a in range(m):
                s += jac[a, k] * sol[a]
            dq[k] = s
        else:
            dq[k] = 0.0
    return ok


# ------------------------------------------------------------------------ angles
@njit(cache=True, nogil=True, inline="always")
def wrap_angle(a: float) -> float:  # pragma: no cover - compiled
    """Wrap one angle to (−π, π] in [rad] (exact for inputs within a few turns)."""
    if -math.pi < a <= math.pi:
        return a
    if abs(a) > 64.0 * math.pi:  # far out: one floor instead of many subtractions
        a -= _TWO_PI * math.floor(a / _TWO_PI)
    while a > math.pi:
        a -= _TWO_PI
    while a <= -math.pi:
        a += _TWO_PI
    return a


# Cody–Waite split of π/2 (two 33-bit pieces and a tail) and the fdlibm minimax kernels of
# sin / cos on [−π/4, π/4]: |error| ≤ 1 ulp for |x| ≤ POLY_TRIG_MAX, no calls, so the
# per-joint block loops vectorise (SIMD); larger angles take libm, element by element.
_PIO2_1 = 1.57079632673412561417e00
_PIO2_2 = 6.07710050630396597660e-11
_PIO2_2T = 2.02226624879595063154e-21
_INVPIO2 = 6.36619772367581382433e-01
POLY_TRIG_MAX = 1.0e5
_S1, _S2, _S3 = -1.66666666666666324348e-01, 8.33333333332248946124e-03, -1.98412698298579493134e-04
_S4, _S5, _S6 = 2.75573137070700676789e-06, -2.50507602534068634195e-08, 1.58969099521155010221e-10
_C1, _C2, _C3 = 4.16666666666666019037e-02, -1.38888888888741095749e-03, 2.48015872894767294178e-05
_C4, _C5, _C6 = -2.75573143513906633035e-07, 2.08757232129817482790e-09, -1.13596475577881948265e-11


@njit(cache=True, nogil=True, error_model="numpy")
def sincos(x: float) -> tuple[float, float]:  # pragma: no cover - compiled
    """``(sin x, cos x)`` without libm calls (branch-free quadrant selection)."""
    n = math.floor(x * _INVPIO2 + 0.5)
    r = ((x - n * _PIO2_1) - n * _PIO2_2) - n * _PIO2_2T
    z = r * r
    s = r + (z * r) * (_S1 + z * (_S2 + z * (_S3 + z * (_S4 + z * (_S5 + z * _S6)))))
    cr = z * (_C1 + z * (_C2 + z * (_C3 + z * (_C4 + z * (_C5 + z * _C6)))))
    hz = 0.5 * z
    w = 1.0 - hz
    c = w + (((1.0 - w) - hz) + z * cr)
    quad = int(n) & 3
    swap = quad & 1
    sgn_s = 1.0 - 2.0 * ((quad >> 1) & 1)
    sgn_c = 1.0 - 2.0 * (((quad + 1) >> 1) & 1)
    ss = c if swap else s
    cc = s if swap else c
    return ss * sgn_s, cc * sgn_c
