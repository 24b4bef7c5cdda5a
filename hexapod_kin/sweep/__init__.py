"""Leg design sweeps: many designs of the hexabot leg scored on all cores or a Dask cluster.

:mod:`.designs` (the design table), :mod:`.scores` (volume, stride, σ_min, singular distances,
limit margins), :mod:`.run` (resumable chunks on threads or Dask; CSV/Parquet/JSON),
:mod:`.pareto` (the front), :mod:`.plot` (maps and the front).
"""

from __future__ import annotations

from .designs import DEFAULTS, METHODS, PARAMETERS, DesignSpace, Range, design_chain, parse_range
from .pareto import OBJECTIVES, best_index, pareto_front
from .plot import plot_sweep
from .run import SweepResult, read_results, sweep, table_paths
from .scores import SCORES, reachable, score_designs, volume_closed_form

__all__ = ["DEFAULTS", "METHODS", "OBJECTIVES", "PARAMETERS", "SCORES", "DesignSpace", "Range",
           "SweepResult", "best_index", "design_chain", "pareto_front", "parse_range", "plot_sweep",
           "read_results", "reachable", "score_designs", "sweep", "table_paths",
           "volume_closed_form"]  # fmt: skip
