"""Leg design sweeps: many designs of the hexabot leg scored on all cores or a Dask cluster.

``designs`` builds the design table (grid, random, Latin hypercube), ``scores`` scores it
(exact closed-form membership, Monte-Carlo volume with standard errors and the closed form
where one exists, stride, σ_min, singular distances, limit margins), ``run`` executes the
sweep in resumable chunks (threads or Dask) and writes CSV/Parquet/JSON, ``pareto``
finds the front, ``plot`` draws maps and the front.

Example:
    >>> from hexapod_kin.sweep import DesignSpace, Range, sweep
    >>> space = DesignSpace({"l1": Range(0.02, 0.08, 4), "l2": Range(0.06, 0.14, 5)},
    ...                     total=0.25)
    >>> res = sweep(space, mc_samples=2000)  # doctest: +SKIP

"""

from __future__ import annotations

from .designs import DEFAULTS, METHODS, PARAMETERS, DesignSpace, Range, design_chain, parse_range
from .pareto import OBJECTIVES, best_index, pareto_front
from .plot import plot_sweep
from .run import SweepResult, read_results, sweep, table_paths
from .scores import SCORES, jacobian_position, reachable, score_designs, volume_closed_form

__all__ = [
    "DEFAULTS",
    "METHODS",
    "OBJECTIVES",
    "PARAMETERS",
    "SCORES",
    "DesignSpace",
    "Range",
    "SweepResult",
    "best_index",
    "design_chain",
    "jacobian_position",
    "pareto_front",
    "parse_range",
    "plot_sweep",
    "read_results",
    "reachable",
    "score_designs",
    "sweep",
    "table_paths",
    "volume_closed_form",
]
