"""Run a sweep: chunks scored on all local cores or on a Dask cluster, resumable output.

A chunk's scores depend only on its designs and the options, so the table is the same on local
threads or Dask workers. ``out`` is the one file written (``.csv``, ``.parquet`` or ``.json``);
finished chunks are kept meanwhile in a hidden sidecar (:mod:`._chunks`), so a sweep run again
scores only the missing chunks. A sweep estimated beyond :data:`MAX_HOURS` or :data:`MAX_GB`
is refused unless ``allow_large``.
"""

from __future__ import annotations

import hashlib
import io
import json
import math
import os
import sys
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .._fields import read_only
from .._io import atomic_write, read_regular
from .._reader import csv_table, parse_data, read_text
from ..exceptions import (
    ConfigurationError,
    HexapodKinError,
    OptionalDependencyError,
    ParameterError,
    SourceError,
)
from ._chunks import ChunkStore, check_scores
from .designs import PARAMETERS, DesignSpace
from .pareto import OBJECTIVES, best_index, pareto_front
from .scores import SCORES, score_designs

__all__ = ["TABLE_FORMATS", "SweepResult", "read_results", "sweep", "table_paths"]

_FORMAT = 2  # chunks carry their number and a SHA-256 of their scores
_UNCERTAIN = {"volume": "volume_se", "volume_mc": "volume_mc_se"}


@dataclass(frozen=True)
class SweepResult:
    """A finished sweep.

    Attributes:
        table: Column name → read-only (N,) array: ``index``, the design parameters
            (:data:`~hexapod_kin.sweep.designs.PARAMETERS`), the scores
            (:data:`~hexapod_kin.sweep.scores.SCORES`) and ``pareto`` (1 on the front).
        summary: JSON-ready summary (counts, best design with uncertainties, front, options).
        files: The written table by its kind (empty without ``out``).
        scored: Number of designs scored by this call (the others were loaded from chunks).
        elapsed: Wall time of this call in [s].

    """

    table: dict[str, np.ndarray]
    summary: dict[str, Any]
    files: dict[str, str] = field(default_factory=dict)
    scored: int = 0
    elapsed: float = 0.0

    @property
    def n(self) -> int:
        """Number of designs."""
        return int(self.table["index"].shape[0])

    def row(self, i: int) -> dict[str, float]:
        """Design ``i`` as a dict of plain floats (all columns)."""
        return {k: float(v[i]) for k, v in self.table.items()}

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: the summary plus files, scored count and elapsed time [s]."""
        out = {**self.summary, "files": dict(self.files)}
        return out | {"scored": self.scored, "elapsed_s": self.elapsed}


#: Table formats of ``out``, by extension.
TABLE_FORMATS = {".csv": "csv", ".parquet": "parquet", ".json": "json"}
#: Byte cap (and value cap) of a sweep table read back by :func:`read_results`.
_MAX_TABLE_BYTES = 1 << 30


def table_paths(out: str | Path) -> dict[str, Path]:
    """The table and chunks' sidecar: ``x.csv`` → ``{"csv": x.csv, "parts": .x.csv.sweep-parts}``.

    Raises ParameterError: ``out`` has another extension.
    """
    p = Path(out)
    kind = TABLE_FORMATS.get(p.suffix.lower())
    if kind is None:
        msg = (
            f"out={str(out)!r}: the table's format comes from its extension; use "
            f"{', '.join(TABLE_FORMATS)}"
        )
        raise ParameterError(msg, parameter="out", value=str(out), allowed=list(TABLE_FORMATS))
    return {kind: p, "parts": p.with_name(f".{p.name}.sweep-parts")}


def _score_chunk(designs: np.ndarray, options: Mapping[str, Any]) -> np.ndarray:
    """Score one chunk (runs on a Dask worker or locally): (n, len(SCORES)) array."""
    cols = score_designs(designs, **options)
    return np.stack([cols[k] for k in SCORES], axis=1)


#: Seconds to reach a Dask scheduler before the sweep is refused.
CONNECT_TIMEOUT = 4.0

#: A sweep estimated beyond these is refused unless asked (``allow_large`` / ``--yes``).
MAX_HOURS = 1.0
MAX_GB = 4.0


def _refuse_large(
    space: Any, method: str, samples: int, options: Mapping[str, Any], workers: int | None,
    client: Any, scheduler: str | None,
) -> None:  # fmt: skip
    """Refuse a sweep estimated beyond the limits (time from two designs scored here)."""
    n = space.count(method, samples)
    threads = 1 if (client is not None or scheduler is not None) else _check_workers(workers)
    # the designs and scores, the written table; each thread's Monte-Carlo points and temporaries
    memory = (
        n * (len(PARAMETERS) + len(SCORES) + 1) * 8 * 2 + options["mc_samples"] * 8 * 8 * threads
    ) / 1e9
    hours = math.nan  # not probed: the memory alone is far beyond the limit
    if memory <= 10 * MAX_GB:
        # the first designs only (a grid's head is built without the rest of the grid)
        probe = np.asarray(space.designs(method, 2, 0, first=64))[:2]
        t = time.perf_counter()
        _score_chunk(probe, options)
        per = (time.perf_counter() - t) / max(1, len(probe))
        hours = n * per / threads / 3600.0
    if not hours <= MAX_HOURS or memory > MAX_GB:
        scoring = (
            "" if math.isnan(hours) else f"{hours:.3g} h of scoring on {threads} thread(s) and "
        )
        raise ParameterError(
            f"sweep of {n} designs: estimated {scoring}{memory:.3g} GB; the limits are "
            f"{MAX_HOURS:g} h and {MAX_GB:g} GB: fewer "
            "designs, fewer --mc-samples, or --yes (allow_large=True) to run it anyway",
            parameter="samples",
            value=n,
            allowed=f"<= {MAX_HOURS:g} h and <= {MAX_GB:g} GB (estimated), or allow_large",
        )


def _check_workers(workers: int | None) -> int:
    top = os.cpu_count() or 1
    if workers is None:
        return top
    if int(workers) != workers or not 1 <= workers <= 4 * top:
        msg = f"workers={workers!r}: expected an integer in [1, {4 * top}] (threads)"
        raise ParameterError(msg, parameter="workers", value=workers, allowed=f"1..{4 * top}")
    return int(workers)


def _dask_client(client: Any, scheduler: str | None) -> tuple[Any, bool]:
    if client is not None:
        return client, False
    try:
        from distributed import Client
    except ImportError:
        raise OptionalDependencyError(
            "a Dask scheduler needs dask[distributed]: pip install 'hexapod-kin[sweep]'"
        ) from None
    try:
        return Client(scheduler, timeout=CONNECT_TIMEOUT), True
    except (OSError, TimeoutError, ValueError) as exc:
        msg = (
            f"scheduler={scheduler!r}: cannot connect ({exc}); expected a running Dask "
            "scheduler address such as tcp://HOST:8786"
        )
        raise ConfigurationError(msg, parameter="scheduler", value=scheduler) from None


def _check_out(out: str | Path | None) -> dict[str, Path] | None:
    """The table and sidecar paths of ``out``, checked before any work (None: no ``out``)."""
    if out is None:
        return None
    paths = table_paths(out)
    if "parquet" in paths:
        try:
            import pyarrow.parquet  # noqa: F401
        except ImportError:
            raise OptionalDependencyError(
                f"out={str(out)!r}: writing Parquet needs pyarrow (pip install "
                "'hexapod-kin[sweep]'); or write .csv or .json"
            ) from None
    table_path = next(v for k, v in paths.items() if k != "parts")
    folder = table_path.parent
    problem = (
        f"{str(out)!r} is a folder"
        if table_path.is_dir()
        else f"directory {str(folder)!r} does not exist"
        if not folder.is_dir()
        else f"directory {str(folder)!r} is not writable"
        if not os.access(folder, os.W_OK | os.X_OK)
        else None
    )
    if problem is not None:  # before any work
        raise ParameterError(
            f"out={str(out)!r}: {problem}; expected a table file path such as results.csv",
            parameter="out",
            value=str(out),
            allowed="a .csv, .parquet or .json path in an existing folder",
        )
    return paths


def sweep(
    space: DesignSpace,
    *,
    method: str = "grid",
    samples: int = 100,
    seed: int = 0,
    mc_samples: int = 10_000,
    line_points: int = 256,
    stride_points: int = 64,
    stride_use: float = 0.9,
    out: str | Path | None = None,
    chunk_size: int | None = None,
    workers: int | None = None,
    client: Any = None,
    scheduler: str | None = None,
    progress: bool | None = None,
    on_chunk: Callable[[int], None] | None = None,
    allow_large: bool = False,
) -> SweepResult:
    """Score every design of a design space; resumable, local or on Dask.

    Args:
        space: The design space.
        method: ``"grid"``, ``"random"`` or ``"lhs"``.
        samples: Designs drawn by ``random``/``lhs``.
        seed: Of the design sampling and of the Monte-Carlo volume samples.
        mc_samples: Monte-Carlo points per design (volume).
        line_points: Grid steps per side of the stride search.
        stride_points: Points along the stride for the σ/singularity/limit minima.
        stride_use: Central fraction of the stride for those minima.
        out: The table to write (``x.csv``, ``x.parquet`` or ``x.json``); None: nothing written.
        chunk_size: Designs per chunk (default: about 20 chunks, 10..250 designs each).
        workers: Local threads scoring chunks (default: one per core). Ignored on Dask.
        client: A ``distributed.Client`` to run the chunks on.
        scheduler: Or the address of a Dask scheduler to connect to (``tcp://host:8786``).
        progress: Show a tqdm bar on stderr (None: when stderr is a terminal).
        on_chunk: Called with the chunk number after each chunk is scored (and written).
        allow_large: Run a sweep estimated beyond :data:`MAX_HOURS` or :data:`MAX_GB`.

    Raises:
        ParameterError: Bad options or design space.
        ConfigurationError: ``out`` holds chunks of a different sweep; no scheduler there.
        OptionalDependencyError: Dask requested but not installed.

    """
    t0 = time.perf_counter()
    options: dict[str, Any] = dict(
        mc_samples=int(mc_samples), seed=int(seed), line_points=int(line_points)
    )
    options |= dict(stride_points=int(stride_points), stride_use=float(stride_use))
    paths = _check_out(out)
    if not allow_large:
        _refuse_large(space, method, samples, options, workers, client, scheduler)
    designs = space.designs(method, samples, seed)
    n = designs.shape[0]
    if chunk_size is None:
        chunk_size = min(250, max(10, math.ceil(n / 20)))
    if int(chunk_size) != chunk_size or chunk_size < 1:
        msg = f"chunk_size={chunk_size!r}: expected an integer >= 1"
        raise ParameterError(msg, parameter="chunk_size", value=chunk_size)
    chunk_size = int(chunk_size)
    spec = dict(format=_FORMAT, space=space.to_dict(), method=method, samples=int(samples))
    spec |= dict(n_designs=n, chunk_size=chunk_size, **options)
    h = hashlib.sha256(json.dumps(spec, sort_keys=True).encode())
    h.update(designs.tobytes())
    key = h.hexdigest()
    bounds = [(s, min(s + chunk_size, n)) for s in range(0, n, chunk_size)]
    results: dict[int, np.ndarray] = {}
    store = None
    if paths is not None:
        store = ChunkStore(paths["parts"], key, spec, len(bounds))
        results = store.resume(bounds, designs, lambda d: _score_chunk(d, options), str(out))
    missing = [k for k in range(len(bounds)) if k not in results]
    scored = sum(bounds[k][1] - bounds[k][0] for k in missing)

    from tqdm import tqdm

    off = (not sys.stderr.isatty()) if progress is None else not progress
    bar = tqdm(total=n, initial=n - scored, unit="design", desc="sweep", file=sys.stderr,
               disable=off, dynamic_ncols=True)  # fmt: skip

    def done(k: int, scores: Any) -> None:
        a, b = bounds[k]
        scores = np.asarray(scores)
        why: str | None = f"a {type(scores).__name__} of {scores.dtype} {scores.shape}"
        if scores.dtype.kind in "fiub" and scores.shape == (b - a, len(SCORES)):
            why = check_scores(scores.astype(float))
        if why is not None:  # never stored: a later run must not trust it
            msg = (
                f"sweep chunk {k} (designs {a}..{b - 1}) came back without valid "
                f"scores ({why}); nothing of it is kept"
            )
            raise ConfigurationError(msg, parameter="designs", value=k)
        scores = scores.astype(float)
        results[k] = scores
        if store is not None:
            store.save(k, scores)
        bar.update(b - a)
        if on_chunk is not None:
            on_chunk(k)

    try:
        if missing and (client is not None or scheduler is not None):
            cl, own = _dask_client(client, scheduler)
            from distributed import as_completed

            futures = {cl.submit(_score_chunk, np.array(designs[slice(*bounds[k])]), options,
                                 key=f"hexapod-sweep-{key[:16]}-{k}", pure=False): k
                       for k in missing}  # fmt: skip
            try:
                for fut, res in as_completed(list(futures), with_results=True):
                    # a result in hand counts (``done`` checks it) even if its worker died
                    # since: the future then reads "lost" though nothing is missing
                    got = isinstance(res, np.ndarray)
                    if isinstance(res, BaseException) or not (got or fut.status == "finished"):
                        then = "nothing was written"
                        if store is not None:
                            then = "the finished chunks are kept: run the same sweep again to "
                            then += "finish it"
                        msg = f"the Dask cluster lost sweep chunk {futures[fut]} ({fut.status}: "
                        msg += f"{type(res).__name__}; was the scheduler stopped?); {then}"
                        raise ConfigurationError(msg, parameter="scheduler", value=scheduler)
                    done(futures[fut], res)
            finally:
                for fut in futures:
                    fut.cancel()
                if own:
                    cl.close()
        elif missing:
            from concurrent.futures import ThreadPoolExecutor

            pool = ThreadPoolExecutor(min(_check_workers(workers), len(missing)))
            try:
                chunks = {k: pool.submit(_score_chunk, designs[slice(*bounds[k])], options)
                          for k in missing}  # fmt: skip
                for k, fut in chunks.items():  # written in order
                    done(k, fut.result())
            finally:  # on Ctrl-C: the running chunks end, the queued ones never start
                pool.shutdown(wait=True, cancel_futures=True)
    finally:
        bar.close()

    scores = np.concatenate([results[k] for k in range(len(bounds))], axis=0)
    table = {"index": np.arange(n, dtype=float)}
    table |= {p: np.array(designs[:, j]) for j, p in enumerate(PARAMETERS)}
    table |= {s: scores[:, j] for j, s in enumerate(SCORES)}
    table["pareto"] = pareto_front(table).astype(float)
    read_only(*table.values())
    summary = _summary(table, spec, key)
    files = {} if paths is None else _write_tables(table, summary, paths)
    return SweepResult(table, summary, files, scored, time.perf_counter() - t0)


def _design_dict(table: Mapping[str, np.ndarray], i: int) -> dict[str, Any]:
    d: dict[str, Any] = {"index": i, **{p: float(table[p][i]) for p in PARAMETERS}}
    for s in (s for s in SCORES if not s.endswith("_se")):
        d[s] = float(table[s][i])
        if s in _UNCERTAIN:
            d[s + "_se"] = float(table[_UNCERTAIN[s]][i])
    return d


def _summary(table: Mapping[str, np.ndarray], spec: dict[str, Any], key: str) -> dict[str, Any]:
    n = int(table["index"].shape[0])
    feas = np.asarray(table["feasible"]) > 0
    best = best_index(table)
    best_by = {
        s: best_index(table, (s,) + tuple(o for o in OBJECTIVES if o != s)) for s in OBJECTIVES
    }
    front = np.flatnonzero(np.asarray(table["pareto"]) > 0)
    return {
        "n_designs": n,
        "n_feasible": int(feas.sum()),
        "best": _design_dict(table, best) if best >= 0 else None,
        "best_by": {s: (_design_dict(table, i) if i >= 0 else None) for s, i in best_by.items()},
        "pareto_objectives": list(OBJECTIVES),
        "pareto_indices": [int(i) for i in front],
        "units": {"parameters": "lengths [m], angles [rad]", **SCORES},
        "spec": spec,
        "key": key,
    }


def _write_tables(
    table: Mapping[str, np.ndarray], summary: dict[str, Any], paths: dict[str, Path]
) -> dict[str, str]:
    """Write the one table asked for, then remove the chunks' sidecar."""
    import shutil

    kind, path = next((k, v) for k, v in paths.items() if k != "parts")
    if kind == "csv":
        ints = {"index", "feasible", "volume_exact", "pareto"}
        cells = [[str(int(v)) if nm in ints else repr(float(v)) for v in np.asarray(c)]
                 for nm, c in table.items()]  # fmt: skip
        rows = (",".join(row) for row in zip(*cells))
        atomic_write(path, "\n".join([",".join(table), *rows]) + "\n")
    elif kind == "parquet":
        import pyarrow as pa
        import pyarrow.parquet as pq

        buf = io.BytesIO()
        pq.write_table(pa.table({k: np.asarray(v) for k, v in table.items()}), buf)
        atomic_write(path, buf.getvalue())
    else:
        columns = {k: np.asarray(v).tolist() for k, v in table.items()}
        text = json.dumps({**summary, "table": columns}, indent=1, allow_nan=False)
        atomic_write(path, text + "\n")
    shutil.rmtree(paths["parts"], ignore_errors=True)
    return {kind: str(path)}


def read_results(path: str | Path) -> dict[str, np.ndarray]:
    """A sweep table written by :func:`sweep` (``.csv``, ``.parquet``, ``.json``): column → (N,).

    Raises:
        ParameterError: An unknown suffix.
        SourceError: A missing file, one the strict reader refuses, or not a sweep table.

    """
    p = Path(path)
    if p.suffix == ".parquet":
        import pyarrow.parquet as pq

        t = pq.read_table(io.BytesIO(read_regular(p, _MAX_TABLE_BYTES, "path")))
        return {c: np.asarray(t.column(c).to_numpy(), dtype=float) for c in t.column_names}
    if p.suffix not in (".json", ".csv"):
        msg = f"path={str(p)!r}: expected a .csv, .parquet or .json file"
        raise ParameterError(msg, parameter="path", value=str(p), allowed=list(TABLE_FORMATS))
    text = read_text(p, "path", _MAX_TABLE_BYTES)  # the one strict reader of user files
    try:
        if p.suffix == ".json":
            cols = parse_data(text, str(p), "json", "path", _MAX_TABLE_BYTES)["table"]
            return {str(c): np.asarray(v, dtype=float) for c, v in cols.items()}
        _, names, rows = csv_table(text, str(p), "path")  # strict numbers, line and column named
        data = np.array(rows, dtype=float).reshape(len(rows), len(names))
        return {c: data[:, j] for j, c in enumerate(names)}
    except (KeyError, ValueError, TypeError, IndexError, AttributeError) as exc:
        if isinstance(exc, HexapodKinError):
            raise
        why = " ".join(str(exc).split())[:120]
        msg = f"path={str(p)!r}: not a sweep table ({type(exc).__name__}: {why})"
        raise SourceError(msg, parameter="path", value=str(p)) from None
