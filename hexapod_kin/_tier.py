"""Tiered kernels: run a numba kernel interpreted until compiling it pays, then compiled.

Every ``@njit`` function of hexapod_kin is a :class:`Kernel`: to numba it *is* its dispatcher
(other kernels call it compiled, inline it, cache it), to Python it is a callable that picks one
of two tiers per call, like a JIT virtual machine:

* **compiled** — numba's machine code, when it is already compiled in this process, when numba's
  on-disk cache holds it (``cache=True``: loading takes milliseconds), or when the call is big
  enough that running it interpreted would cost more than compiling it;
* **interpreted** — the very same source run by Python, every kernel it calls interpreted too
  (a twin function whose globals name the twins of the callees). Same code, same numbers up to
  rounding: a new user's first ``ik``, ``step`` or ``scan`` answers in a fraction of a second
  instead of waiting 4–5 s for LLVM.

The choice is the ski-rental rule: a kernel runs interpreted while the interpreted seconds it
has cost in this process plus the predicted cost of this call stay within its compile budget
(:data:`BUDGET_S`, about what compiling one of the bigger kernels costs), then it compiles once.
The prediction is ``work(*args)``, a kernel's own estimate of its interpreted seconds (given
where the cost scales with the input: samples, steps, iterations), else the measured cost of
its previous interpreted calls, else the element count of its array arguments at 1 µs each.

``HEXAPOD_KIN_JIT`` overrides the rule: ``auto`` (default), ``always`` (compile on the first
call, numba's own behaviour) or ``never`` (interpret every call: debugging, and the tests that
check both tiers give the same numbers).
"""

from __future__ import annotations

import os
import threading
import time
import types as pytypes
from collections.abc import Callable
from typing import Any

import numba
import numpy as np
from numba.core import types as nbtypes
from numba.core.dispatcher import Dispatcher
from numba.extending import typeof_impl

__all__ = ["BUDGET_S", "Kernel", "compiled", "interpreted", "mode", "njit", "pending", "set_mode"]

#: Interpreted seconds a kernel may spend in one process before it is compiled.
BUDGET_S = 1.0
#: Interpreted seconds per array element for kernels without a ``work`` estimate.
_PER_ELEMENT_S = 1e-6
_MODES = ("auto", "always", "never")
_lock = threading.Lock()
_all: list[Kernel] = []


def _env_mode() -> str:
    value = os.environ.get("HEXAPOD_KIN_JIT", "auto").strip().lower() or "auto"
    return value if value in _MODES else "auto"


_mode = _env_mode()


def mode() -> str:
    """The tier rule in force: ``auto``, ``always`` or ``never`` (``HEXAPOD_KIN_JIT``)."""
    return _mode


def set_mode(value: str) -> str:
    """Set the tier rule for this process; returns the previous one.

    Raises:
        ParameterError: ``value`` is not ``auto``, ``always`` or ``never``.

    """
    global _mode
    if value not in _MODES:
        from .exceptions import ParameterError

        raise ParameterError(
            f"jit mode {value!r} is not allowed; choose one of {', '.join(_MODES)}",
            parameter="mode",
            value=value,
            allowed=", ".join(_MODES),
        )
    before, _mode = _mode, value
    for kernel in _all:
        kernel._fast = False
    return before


class Kernel:
    """A numba kernel that Python calls through the tier rule (see the module docstring).

    Attributes:
        dispatcher: The numba dispatcher (what other kernels call).
        py_func: The Python source function.

    """

    def __init__(self, dispatcher: Dispatcher, work: Callable[..., float] | None) -> None:
        self.dispatcher = dispatcher
        self.py_func = dispatcher.py_func
        self.__name__ = self.py_func.__name__
        self.__qualname__ = self.py_func.__qualname__
        self.__module__ = self.py_func.__module__
        self.__doc__ = self.py_func.__doc__
        self.__wrapped__ = self.py_func
        self._work = work
        self._ready = False
        self._fast = False
        self._disk_checked = False
        self._spent = 0.0
        self._per_call = -1.0
        self._twin: Callable[..., Any] | None = None

    def __repr__(self) -> str:
        return f"<kernel {self.__module__}.{self.__qualname__}>"

    # -- tiers ---------------------------------------------------------------------------
    def ready(self) -> bool:
        """True when calling compiled costs no compilation (in memory, or in numba's cache)."""
        if self._ready:
            return True
        if self.dispatcher.signatures:
            self._ready = True
        elif not self._disk_checked:
            self._disk_checked = True
            self._ready = _on_disk(self.dispatcher)
        return self._ready

    def interpreted(self) -> Callable[..., Any]:
        """The same source as a plain Python function whose callees are interpreted too."""
        if self._twin is None:
            with _lock:
                if self._twin is None:
                    self._twin = _twin(self.dispatcher, {})
        return self._twin

    def _predict(self, args: tuple[Any, ...]) -> float:
        if self._work is not None:
            return float(self._work(*args))
        if self._per_call >= 0.0:
            return self._per_call
        return _PER_ELEMENT_S * sum(a.size for a in args if isinstance(a, np.ndarray))

    def __call__(self, *args: Any) -> Any:
        if self._fast:
            return self.dispatcher(*args)
        return self._tiered(args)

    def _tiered(self, args: tuple[Any, ...]) -> Any:
        if _mode == "always" or (_mode == "auto" and self.ready()):
            self._fast = True
            return self.dispatcher(*args)
        if _mode == "auto" and self._spent + self._predict(args) > BUDGET_S:
            self._ready = self._fast = True
            return self.dispatcher(*args)
        t0 = time.perf_counter()
        out = self.interpreted()(*args)
        dt = time.perf_counter() - t0
        self._spent += dt
        self._per_call = dt if self._per_call < 0.0 else 0.5 * (self._per_call + dt)
        return out


@typeof_impl.register(Kernel)
def _typeof_kernel(val: Kernel, c: Any) -> Any:
    """To numba a kernel is its dispatcher: compiled callers call it compiled."""
    return nbtypes.Dispatcher(val.dispatcher)


def _on_disk(disp: Dispatcher) -> bool:
    """Whether numba's on-disk cache holds fresh machine code of ``disp`` for this CPU."""
    try:
        cache = disp._cache
        index = cache._cache_file._load_index()
        magic = disp.targetctx.codegen().magic_tuple()
        return any(isinstance(k, tuple) and len(k) > 1 and k[1] == magic for k in index)
    except Exception:  # noqa: BLE001 - no cache (cache=False) or another numba layout
        return False


def _twin(disp: Dispatcher, seen: dict[Any, Any]) -> Callable[..., Any]:
    """A plain function running ``disp``'s source; every kernel it names is a twin too."""
    if disp in seen:
        return seen[disp]  # type: ignore[no-any-return]
    f = disp.py_func
    glb: dict[str, Any] = dict(f.__globals__)
    cells = None
    if f.__closure__ is not None:
        cells = tuple(pytypes.CellType(c.cell_contents) for c in f.__closure__)
    twin = pytypes.FunctionType(f.__code__, glb, f.__name__, f.__defaults__, cells)
    twin.__kwdefaults__ = f.__kwdefaults__
    seen[disp] = twin
    for name, value in list(glb.items()):
        inner = _dispatcher_of(value)
        if inner is not None:
            glb[name] = _twin(inner, seen)
    if cells is not None:
        for cell in cells:
            inner = _dispatcher_of(cell.cell_contents)
            if inner is not None:
                cell.cell_contents = _twin(inner, seen)
    return twin


def _dispatcher_of(value: Any) -> Dispatcher | None:
    if isinstance(value, Kernel):
        return value.dispatcher
    if isinstance(value, Dispatcher):
        return value
    return None


def njit(*args: Any, work: Callable[..., float] | None = None, **options: Any) -> Any:
    """``numba.njit`` returning a :class:`Kernel` (same options, plus ``work``).

    Args:
        *args: The function (bare decorator use) or nothing.
        work: Optional estimate of one call's interpreted seconds from its arguments.
        **options: numba options (``cache``, ``nogil``, ``parallel``, ``inline``...).

    """

    def wrap(func: Callable[..., Any]) -> Kernel:
        kernel = Kernel(numba.njit(**options)(func), work)
        _all.append(kernel)
        return kernel

    if args and callable(args[0]):
        return wrap(args[0])
    return wrap


def compiled(kernel: Any) -> Any:
    """The compiled callable of a kernel (compiling on its first call)."""
    return kernel.dispatcher if isinstance(kernel, Kernel) else kernel


def interpreted(kernel: Any) -> Any:
    """The interpreted twin of a kernel (its source run by Python)."""
    return kernel.interpreted() if isinstance(kernel, Kernel) else kernel


def pending() -> list[str]:
    """Kernels of the imported modules that are neither compiled nor cached on disk (names)."""
    return [f"{k.__module__}.{k.__qualname__}" for k in _all if not k.ready()]
