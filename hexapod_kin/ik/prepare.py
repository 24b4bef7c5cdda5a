"""What the solver keeps per model: packed chain arrays, limits, restart starts, and the home pose.

Built once per model and kept in its cache (:meth:`~hexapod_kin.model.Model.cached`); read-only,
so one model can be solved from many threads. :func:`home` is the package's one home pose (the
IK's first candidate start and the default start of resolved-rate runs).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any, Union

import numpy as np

from .._numerics import chain_scale
from ..kinematics import KinematicModel
from ..params import Chain, Hexapod

__all__ = ["LEG_HOME", "N_NEAR", "N_STARTS", "ModelLike", "Prepared", "as_model", "home",
           "prepared"]  # fmt: skip

#: A model argument: a loaded model, or anything :func:`hexapod_kin.load` takes.
ModelLike = Union[KinematicModel, Chain, Hexapod, str, "os.PathLike[str]"]

#: Standing pose of the 3-DOF legs [rad] (the seeds' start), away from the singularities.
LEG_HOME = (0.0, 0.3, 1.2)

#: Seeded restart configurations kept per model (the most :func:`~hexapod_kin.ik.solve` tries).
N_STARTS = 32
#: Candidate first starts kept per model: :func:`home` and seeded samples (see :class:`Prepared`).
N_NEAR = 64


def as_model(model: ModelLike) -> KinematicModel:
    """``model`` itself if loaded, else :func:`hexapod_kin.load` of it."""
    if isinstance(model, KinematicModel):
        return model
    from ..kinematics import load

    return load(model)


@dataclass(frozen=True)
class Prepared:
    """What the solver needs of one model, built once (arrays read-only).

    Attributes:
        lim: (3, n) lower limits, upper limits and step caps ([rad]/[m]).
        cont: (n,) True for continuous revolute joints (range ≥ 2π: they wrap).
        scale: The chain's length scale in [m] (sum of the link offsets).
        home: The home pose (see :func:`home`).
        starts: (32, n) seeded random restart configurations within the limits.
        middle: (n,) middle of each joint's range (continuous joints: 0).
        near: (:data:`N_NEAR`, n) the candidate first starts of a solve without ``q0``:
            ``home``, then seeded random configurations in the middle half of each range
            (ranges clipped to ±π).
        near_poses: (:data:`N_NEAR`, 12) their tip positions [m] and rotations (row-major),
            Pinocchio's FK: the solver starts from the one nearest the target.
        model: The model (not compared).

    """

    lim: np.ndarray
    cont: np.ndarray
    scale: float
    home: np.ndarray
    starts: np.ndarray
    middle: np.ndarray
    near: np.ndarray
    near_poses: np.ndarray
    model: Any = field(repr=False, compare=False)


def _build_prepared(model: KinematicModel) -> Prepared:
    lower, upper = np.asarray(model.lower, dtype=float), np.asarray(model.upper, dtype=float)
    prism = np.asarray(model.is_prismatic, dtype=bool)
    cont = (~prism) & (upper - lower >= 2 * np.pi - 1e-9)
    scale = chain_scale(model.arrays.trans)
    cap = np.where(prism, 0.25 * scale, 0.5)
    lim = np.ascontiguousarray(np.vstack([lower, upper, cap]))
    lo, hi = np.where(cont, -np.pi, lower), np.where(cont, np.pi, upper)
    starts = np.random.default_rng(12345).uniform(lo, hi, size=(N_STARTS, model.nq))
    middle = np.where(cont, 0.0, 0.5 * (lower + upper))
    q_home = _dexterous_home(model, lower, upper, cont)
    mid, half = 0.5 * (lo + hi), 0.25 * (hi - lo)  # the middle half of each range
    samples = np.random.default_rng(54321).uniform(mid - half, mid + half, (N_NEAR - 1, model.nq))
    near = np.vstack([q_home, samples])
    poses = np.array([model.fk(q) for q in near])
    near_poses = np.hstack([poses[:, :3, 3], poses[:, :3, :3].reshape(-1, 9)])
    for a in (lim, cont, starts, middle, q_home, near, near_poses):
        a.setflags(write=False)
    return Prepared(lim, cont, scale, q_home, starts, middle, near, near_poses, model)


def _dexterous_home(
    model: KinematicModel, lower: np.ndarray, upper: np.ndarray, cont: np.ndarray
) -> np.ndarray:
    if model.nq == 3:
        q = np.array(LEG_HOME)
        if np.all(q >= lower) and np.all(q <= upper):
            return q
    lo, hi = np.maximum(lower, -np.pi), np.minimum(upper, np.pi)
    mid, half = 0.5 * (lo + hi), 0.25 * (hi - lo)
    rng = np.random.default_rng(0)
    cands = np.vstack([mid, rng.uniform(mid - half, mid + half, size=(256, model.nq))])
    jacs = np.array([model.jacobian(q)[:3] for q in cands])
    sv = np.linalg.svd(jacs, compute_uv=False)
    return np.array(cands[int(np.argmax(sv[:, min(model.nq, 3) - 1]))])


def prepared(model: ModelLike) -> Prepared:
    """The solver's per-model data (cached in the model; see :class:`Prepared`)."""
    mdl = as_model(model)
    return mdl.cached("ik.prepared", lambda: _build_prepared(mdl))


def home(model: ModelLike) -> np.ndarray:
    """The package's one home pose: the IK's first candidate start and resolved-rate start.

    ``LEG_HOME`` for 3-joint chains inside its limits; otherwise the most dexterous (largest
    3rd singular value of the position Jacobian) of the ranges' middle and 256 seeded samples
    in the middle half of each range (clipped to ±π). Computed once per model; returns a copy,
    (nq,) [rad]/[m]. ``model``: a loaded model or anything :func:`hexapod_kin.load` takes.
    """
    return np.array(prepared(model).home)
