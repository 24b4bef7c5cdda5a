"""Reachable space of a chain's tip: sampled points, a volume estimate, cross-sections."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ._fields import fields_dict, read_only
from ._numerics import chain_length
from .exceptions import ParameterError, one_of, positive
from .kinematics import as_model

__all__ = ["WorkspaceResult", "workspace", "cross_section"]


@dataclass(frozen=True)
class WorkspaceResult:
    """Reachable tip points and a reachable-volume estimate (arrays read-only).

    The tips of ``samples`` random configurations binned into cubic voxels of edge ``voxel``:
    ``volume = (interior + boundary / 2) · voxel³`` (a boundary voxel, with an empty face
    neighbour, is cut through its middle on average); ``volume_occupied`` counts every occupied
    voxel (an over-estimate). For solid workspaces (≥ 3 joints acting on the position).

    ``q`` (N, n) sampled configurations; ``points`` (N, 3) tips [m], base frame; ``voxel``
    [m]; ``volume_occupied``, ``volume`` [m³]; ``interior``, ``boundary``: voxel counts;
    ``lower``, ``upper`` (3,): bounding-box corners [m]; ``source``: the model's name.

    """

    q: np.ndarray
    points: np.ndarray
    voxel: float
    volume_occupied: float
    volume: float
    interior: int
    boundary: int
    lower: np.ndarray
    upper: np.ndarray
    source: str

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict (points and configurations as nested lists)."""
        names = ("source", "voxel", "volume", "volume_occupied", "interior", "boundary", "lower",
                 "upper", "q", "points")  # fmt: skip
        return fields_dict(self, *names)


def workspace(
    model: Any, samples: int = 2_000_000, voxel: float | None = None, seed: int | None = 0
) -> WorkspaceResult:
    """Tip points of ``samples`` random configurations of ``model`` and the reachable volume.

    ``voxel`` [m]: default ``reach / 25`` (finer voxels need more samples: empty voxels inside
    the workspace bias the estimate low).

    Raises:
        ParameterError: ``samples`` out of range or ``voxel`` not > 0.

    """
    mdl = as_model(model)
    if isinstance(samples, bool) or int(samples) != samples or not 1 <= samples <= 50_000_000:
        raise ParameterError(f"samples={samples!r}: an integer in 1..50,000,000 is required")
    h = positive("voxel", float(chain_length(mdl.arrays.trans)) / 25.0 if voxel is None else voxel)
    q = mdl.random_q(int(samples), seed=seed)
    pts = np.empty((len(q), 3))
    for i in range(0, len(q), 1_000_000):  # the batch kernel, in chunks: (n, 4, 4) is 128 B a row
        pts[i : i + 1_000_000] = mdl.fk_batch(q[i : i + 1_000_000])[:, :3, 3]
    span = float(np.ptp(pts, axis=0).max())
    if span / h > 2000:
        raise ParameterError(f"voxel={h!r} m is too small for a workspace {span:.3g} m wide")
    idx = np.floor((pts - (pts.min(axis=0) - h)) / h).astype(np.int64)  # voxels, one margin
    occ = np.zeros(tuple(int(d) for d in idx.max(axis=0) + 2), dtype=bool)
    occ[idx[:, 0], idx[:, 1], idx[:, 2]] = True
    pad = np.pad(occ, 1)
    inner = occ.copy()  # occupied voxels whose six neighbours are occupied
    for ax in range(3):
        for shift in (1, -1):
            inner &= np.roll(pad, shift, axis=ax)[1:-1, 1:-1, 1:-1]
    n_in = int(inner.sum())
    n_b = int(occ.sum()) - n_in
    lower, upper = pts.min(axis=0), pts.max(axis=0)
    read_only(q, pts, lower, upper)
    volumes = (n_in + n_b) * h**3, (n_in + 0.5 * n_b) * h**3  # occupied, boundary-corrected
    return WorkspaceResult(q, pts, h, *volumes, n_in, n_b, lower, upper, mdl.name)


def cross_section(
    points: np.ndarray, plane: str = "xz", offset: float = 0.0, thickness: float | None = None
) -> np.ndarray:
    """The (M, 2) coordinates of the tip ``points`` (N, 3) [m] in a slab around a plane.

    ``plane``: ``"xz"``, ``"yz"`` or ``"xy"`` (the kept coordinates, in order); the slab is
    ``|coordinate − offset| ≤ thickness / 2`` along the dropped axis ([m]; ``thickness``
    default 1 % of the points' extent).

    Raises:
        ParameterError: Unknown plane or bad thickness.

    """
    planes = {"xz": (0, 2, 1), "yz": (1, 2, 0), "xy": (0, 1, 2)}
    a, b, c = planes[one_of("plane", plane, planes)]
    pts = np.asarray(points, float)
    if thickness is None:
        thickness = 0.01 * float(np.ptp(pts, axis=0).max() or 1.0)
    positive("thickness", thickness)
    keep = np.abs(pts[:, c] - offset) <= thickness / 2
    return pts[keep][:, [a, b]].copy()
