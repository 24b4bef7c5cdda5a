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
has cost plus the predicted cost of this call stay within its compile budget (``compile_s``,
about what compiling it costs; :data:`COMPILE_S` by default), then it compiles once: at worst
twice what the better choice would have cost. The prediction is ``work(*args)`` units (steps,
samples, iterations, declared where the cost scales with the input; else the element count of
the array arguments) times the interpreted seconds per unit, learned from the kernel's earlier
interpreted calls (first guess ``per_unit_s``). A kernel with a disk cache also counts the
interpreted seconds of earlier processes (a small ledger in the package's cache folder, keyed
by the source file's stamp), so a command run again and again compiles once too.

``HEXAPOD_KIN_JIT`` overrides the rule: ``auto`` (default), ``always`` (compile on the first
call, numba's own behaviour) or ``never`` (interpret every call: debugging, and the tests that
check both tiers give the same numbers).
"""

from __future__ import annotations

import atexit
import math
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

__all__ = [
    "BACKGROUND_MAX_S",
    "COMPILE_S",
    "CONTEXT_S",
    "PER_UNIT_S",
    "Kernel",
    "background",
    "background_done",
    "background_running",
    "compiled",
    "interpreted",
    "mode",
    "njit",
    "set_mode",
]

#: Default interpreted seconds a kernel may spend in one process before it is compiled.
COMPILE_S = 1.0
#: Default first guess of interpreted seconds per unit of work (per array element).
PER_UNIT_S = 1e-5
#: What numba's first use in a process costs, even for cached machine code (its typing and
#: lowering registries load): about 0.25-0.45 s here.
CONTEXT_S = 0.3
_CONTEXT = {"warm": False}
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
        compile_s: This kernel's interpreted budget in [s] (about its compile time).

    """

    def __init__(
        self,
        dispatcher: Dispatcher,
        work: Callable[..., float] | None,
        per_unit_s: float,
        compile_s: float,
    ) -> None:
        self.dispatcher = dispatcher
        self.py_func = dispatcher.py_func
        self.__name__ = self.py_func.__name__
        self.__qualname__ = self.py_func.__qualname__
        self.__module__ = self.py_func.__module__
        self.__doc__ = self.py_func.__doc__
        self.__wrapped__ = self.py_func
        self.compile_s = compile_s
        self._work = work
        self._rate = per_unit_s
        self._ready = False
        self._fast = False
        self._disk_checked = False
        self._spent = 0.0
        self._spent_here = 0.0
        self._ledger_read = False
        self._twin: Callable[..., Any] | None = None

    def __repr__(self) -> str:
        return f"<kernel {self.__module__}.{self.__qualname__}>"

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

    def prefer_interpreted(self, predicted_s: float) -> bool:
        """The rule for a caller with an interpreted path of its own (then :meth:`charge` it).

        Args:
            predicted_s: Predicted seconds of that path for this call.

        Returns:
            True to run the interpreted path: mode ``never``; or mode ``auto`` while the
            kernel is neither compiled nor cached and its interpreted seconds (spent and
            predicted) stay within :attr:`compile_s`; or while its machine code is cached
            but no compiled code has run in this process yet (numba's first load costs
            :data:`CONTEXT_S`) and this process's interpreted seconds stay within that.

        """
        if _mode == "never":
            return True
        if _mode == "always":
            return False
        if self.ready():  # cached machine code: loading it first costs numba's start-up
            return not _CONTEXT["warm"] and self._spent_here + predicted_s <= CONTEXT_S
        if _BACKGROUND["on"] and predicted_s > CONTEXT_S:
            # machine code would pay for this call: have it compiled after this process
            area = _area(self)
            if area is not None:
                _BACKGROUND["areas"].add(area)
                if background_running():  # on its way: never compile the same code twice
                    return True
        if not self._ledger_read:
            self._ledger_read = True
            self._spent += _ledger().get(_ledger_key(self), 0.0)
        if self._spent + predicted_s > self.compile_s:
            self._ready = True  # compile now: later calls go straight to machine code
            return False
        return True

    def charge(self, seconds: float) -> None:
        """Count ``seconds`` spent on an interpreted path toward this kernel's budget."""
        self._spent += seconds
        self._spent_here += seconds

    def interpreted(self) -> Callable[..., Any]:
        """The same source as a plain Python function whose callees are interpreted too."""
        if self._twin is None:
            with _lock:
                if self._twin is None:
                    self._twin = _twin(self.dispatcher, {})
        return self._twin

    def _units(self, args: tuple[Any, ...]) -> float:
        if self._work is not None:
            return max(float(self._work(*args)), 1.0)
        return float(max(sum(a.size for a in args if isinstance(a, np.ndarray)), 1))

    def __call__(self, *args: Any) -> Any:
        if self._fast:
            return self.dispatcher(*args)
        return self._tiered(args)

    def _tiered(self, args: tuple[Any, ...]) -> Any:
        units = self._units(args) if _mode == "auto" else 1.0
        if not self.prefer_interpreted(self._rate * units):
            self._fast = _mode != "never"
            _CONTEXT["warm"] = True
            return self.dispatcher(*args)
        t0 = time.perf_counter()
        with np.errstate(all="ignore"):  # compiled code never warns (inf, NaN as computed)
            out = self.interpreted()(*args)
        dt = time.perf_counter() - t0
        self.charge(dt)
        if _mode == "auto":  # learn the interpreted seconds per unit (the first call included)
            self._rate = 0.5 * (self._rate + dt / units)
        return out


@typeof_impl.register(Kernel)
def _typeof_kernel(val: Kernel, c: Any) -> Any:
    """To numba a kernel is its dispatcher: compiled callers call it compiled."""
    return nbtypes.Dispatcher(val.dispatcher)


# -- the ledger: interpreted seconds across processes -------------------------------------
# A command run again and again (``hexapod-kin step`` in a shell loop) would run its kernels
# interpreted every time; the ledger carries each disk-cached kernel's interpreted seconds from
# one process to the next (keyed by the source file's stamp, like numba's cache), so the rule
# compiles once their sum reaches the budget, as it does within one process.
_LEDGER: dict[str, float] | None = None


def _ledger_file() -> Any:
    from ._io import cache_root

    return cache_root("tier") / f"interpreted-seconds-numba{numba.__version__}.json"


def _ledger() -> dict[str, float]:
    global _LEDGER
    if _LEDGER is None:
        try:
            import json

            data = json.loads(_ledger_file().read_text())
            _LEDGER = {str(k): float(v) for k, v in data.items() if isinstance(v, (int, float))}
        except Exception:  # noqa: BLE001 - none yet, unreadable or foreign: start afresh
            _LEDGER = {}
    return _LEDGER


def _ledger_key(kernel: Kernel) -> str:
    try:
        st = os.stat(kernel.py_func.__code__.co_filename)
        stamp = f"{st.st_mtime_ns}:{st.st_size}"
    except OSError:
        stamp = "?"
    return f"{kernel.__module__}.{kernel.__qualname__}@{stamp}"


def _save_ledger() -> None:
    """At exit: add this process's interpreted seconds of disk-cached kernels to the ledger."""
    spent = {
        _ledger_key(k): k._spent_here
        for k in _all
        if k._spent_here > 0.0 and _disk_cached(k.dispatcher) and not k.dispatcher.signatures
    }
    spent = {k: v for k, v in spent.items() if v > 0.0}
    if not spent:
        return
    try:
        import json

        from ._io import atomic_write

        global _LEDGER
        _LEDGER = None  # another process may have written meanwhile
        merged = dict(_ledger())
        for key, value in spent.items():
            merged[key] = merged.get(key, 0.0) + value
        path = _ledger_file()
        path.parent.mkdir(parents=True, exist_ok=True)
        atomic_write(path, json.dumps(merged, indent=0, sort_keys=True))
    except Exception:  # noqa: BLE001 - a ledger is an optimisation: never fail at exit
        pass


atexit.register(_save_ledger)


# -- background compiles: the command line's first use leaves machine code for the next ----
# The ski-rental rule bounds the total cost, but the command that crosses the budget pays the
# whole compile (6 s for the twist loop) at once. A command-line process therefore hands the
# compile to a detached, low-priority ``hexapod-kin precompile --only AREA`` started at its
# exit, for the areas whose kernels it ran interpreted although machine code would have paid
# (predicted interpreted seconds above :data:`CONTEXT_S`); while one runs, no process compiles
# the same code in the foreground. On with ``HEXAPOD_KIN_BACKGROUND=1`` (``cli.run`` sets it
# when unset) or :func:`background`; ``HEXAPOD_KIN_BACKGROUND=0`` keeps it off (the tests and
# the benchmarks' cold runs do).
_BACKGROUND: dict[str, Any] = {
    "on": os.environ.get("HEXAPOD_KIN_BACKGROUND", "0") == "1",  # cli.run sets "1" if unset
    "areas": set(),
}
#: Module prefix → :data:`hexapod_kin.precompile.AREAS` name.
_AREAS = (
    ("hexapod_kin._batch", "batch"),
    ("hexapod_kin.ik.", "ik"),
    ("hexapod_kin.motion.", "motion"),
    ("hexapod_kin.singularity.", "singularity"),
    ("hexapod_kin.gait.", "gait"),
)
#: A background compile older than this is taken for dead (its lock is ignored).
BACKGROUND_MAX_S = 1800.0


def background(on: bool = True) -> bool:
    """Turn background compiles on or off for this process; returns whether they are on.

    ``HEXAPOD_KIN_BACKGROUND=0`` keeps them off whatever is asked.
    """
    _BACKGROUND["on"] = bool(on) and os.environ.get("HEXAPOD_KIN_BACKGROUND", "1") != "0"
    return bool(_BACKGROUND["on"])


def _area(kernel: Kernel) -> str | None:
    module = kernel.py_func.__module__
    for prefix, area in _AREAS:
        if module == prefix or module.startswith(prefix):
            return area
    return None


def _lock_file() -> Any:
    from ._io import cache_root

    return cache_root("tier") / "background-compile.json"


def background_running() -> bool:
    """True while a background compile started by an earlier command is still running."""
    try:
        import json

        info = json.loads(_lock_file().read_text())
        if time.time() - float(info["started"]) > BACKGROUND_MAX_S:
            return False
        os.kill(int(info["pid"]), 0)  # raises when no such process
        return True
    except Exception:  # noqa: BLE001 - no lock, unreadable, or its process is gone
        return False


def _spawn_background() -> None:
    """At exit: start the background compile of the areas this process asked for."""
    if not (_BACKGROUND["on"] and _BACKGROUND["areas"]) or _mode != "auto":
        return
    try:
        if background_running():
            return
        import json
        import subprocess
        import sys

        from ._io import atomic_write

        env = dict(os.environ, HEXAPOD_KIN_BACKGROUND="0", HEXAPOD_KIN_JIT="auto")
        areas = sorted(_BACKGROUND["areas"])
        argv = [sys.executable, "-m", "hexapod_kin", "precompile", "--background", "--only"]
        proc = subprocess.Popen(
            argv + areas,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            start_new_session=True,
            env=env,
        )
        lock = _lock_file()
        lock.parent.mkdir(parents=True, exist_ok=True)
        info = {"pid": proc.pid, "started": time.time(), "areas": areas}
        atomic_write(lock, json.dumps(info))
    except Exception:  # noqa: BLE001 - an optimisation: never fail at exit
        pass


def background_done(pid: int) -> None:
    """Called by the background compile when it ends: remove its lock (if still its own)."""
    try:
        import json

        lock = _lock_file()
        if int(json.loads(lock.read_text())["pid"]) == pid:
            lock.unlink()
    except Exception:  # noqa: BLE001 - already gone, or another one's
        pass


atexit.register(_spawn_background)


def _disk_cached(disp: Dispatcher) -> bool:
    from numba.core.caching import NullCache

    return not isinstance(getattr(disp, "_cache", None), (NullCache, type(None)))


def _on_disk(disp: Dispatcher) -> bool:
    """Whether numba's on-disk cache holds fresh machine code of ``disp`` for this CPU."""
    try:
        cache = disp._cache  # type: ignore[attr-defined]
        index = cache._cache_file._load_index()
        magic = disp.targetctx.codegen().magic_tuple()
        return any(isinstance(k, tuple) and len(k) > 1 and k[1] == magic for k in index)
    except Exception:  # noqa: BLE001 - no cache (cache=False) or another numba layout
        return False


def _c_semantics(fn: Callable[..., float]) -> Callable[..., float]:
    """``fn`` as compiled code computes it: NaN outside the domain, inf on overflow."""

    def wrapped(*args: float) -> float:
        try:
            return fn(*args)
        except ValueError:  # sqrt(-1e-18), acos(1 + 1e-16): numba gives NaN, not an error
            return math.nan
        except OverflowError:
            return math.inf

    wrapped.__name__ = fn.__name__
    return wrapped


#: ``math`` as numba compiles it, for the interpreted twins.
_MATH = pytypes.SimpleNamespace(**{k: getattr(math, k) for k in dir(math) if not k.startswith("_")})
for _name in ("sqrt", "acos", "asin", "acosh", "atanh", "log", "log10", "log2", "log1p", "exp",
              "expm1", "cosh", "sinh", "pow", "fmod"):  # fmt: skip
    setattr(_MATH, _name, _c_semantics(getattr(math, _name)))
_MATH_BY_ID = {id(getattr(math, k)): getattr(_MATH, k) for k in vars(_MATH)}


def _twin(disp: Dispatcher, seen: dict[Any, Any]) -> Callable[..., Any]:
    """A plain function running ``disp``'s source; every kernel it names is a twin too."""
    if disp in seen:
        return seen[disp]
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
        elif value is math:
            glb[name] = _MATH
        elif (
            callable(value)
            and id(value) in _MATH_BY_ID
            and value is getattr(math, value.__name__, None)
        ):
            glb[name] = _MATH_BY_ID[id(value)]
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


def njit(
    *args: Any,
    work: Callable[..., float] | None = None,
    per_unit_s: float = PER_UNIT_S,
    compile_s: float = COMPILE_S,
    **options: Any,
) -> Any:
    """``numba.njit`` returning a :class:`Kernel` (same options, plus the tier hints).

    Args:
        *args: The function (bare decorator use) or nothing.
        work: Units of work of one call from its arguments (steps, samples, iterations...);
            default: the element count of its array arguments.
        per_unit_s: First guess of the interpreted seconds per unit (then learned).
        compile_s: Interpreted seconds allowed in one process before compiling (about the
            kernel's compile time, measured with ``tools/bench_startup.py --profile``).
        **options: numba options (``cache``, ``nogil``, ``parallel``, ``inline``...).

    """

    def wrap(func: Callable[..., Any]) -> Kernel:
        kernel = Kernel(numba.njit(**options)(func), work, per_unit_s, compile_s)
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
