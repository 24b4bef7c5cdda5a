"""Tree kinematics for N configurations at once, structure of arrays (numpy).

Joint ``j``'s frame is ``parent · P_j · M_j(q_j)``: ``P_j`` its placement at q = 0, ``M_j`` the
rotation ``R(a, q) = cos q I + sin q [a]× + (1 − cos q) a aᵀ`` about its unit axis ``a``, or
the translation ``a q`` (the kinds of :func:`hexapod_kin.frames.joint_kind`). :func:`tree_frames`
takes one vector operation per depth of the tree and axis kind.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np

__all__ = ["Tree", "mat_vec", "robot_size", "tree_frames", "tree_poses"]


@dataclass(frozen=True)
class Tree:
    """The actuated joints of a floating-base tree as arrays (joint order = Pinocchio's q).

    ``parents`` (n,): parent joints (−1: the floating body); ``placements`` (n, 4, 4): in the
    parent's frame at q = 0; ``axes`` (n, 3): unit, in the joint's frame; ``prismatic`` (n,).
    """

    parents: np.ndarray
    placements: np.ndarray
    axes: np.ndarray
    prismatic: np.ndarray

    @classmethod
    def of_model(cls, model: Any, first: int = 1, label: str = "") -> Tree:
        """The joints ``first``, ``first + 1``, … of a Pinocchio model (q: one per joint).

        ``first = 2``: the joints below a free-flyer root (parent −1: the floating body).

        Raises:
            ConfigurationError: A joint that is not revolute, continuous or prismatic (named,
                with ``label``, the robot's name).

        """
        from .exceptions import ConfigurationError
        from .frames import joint_kind

        n = model.njoints - first
        axes = np.empty((n, 3))
        prismatic = np.zeros(n, dtype=bool)
        for j in range(first, model.njoints):
            kind = joint_kind(model.joints[j])
            if kind is None:
                raise ConfigurationError(
                    f"joint {model.names[j]!r} of {label!r} is a {model.joints[j].shortname()}; "
                    "a leg joint must be revolute, continuous or prismatic (one variable)",
                    parameter="source",
                    value=str(model.names[j]),
                    allowed="revolute, continuous or prismatic joints",
                )
            axes[j - first] = kind[1] / np.linalg.norm(kind[1])
            prismatic[j - first] = kind[0] == "prismatic"
        joints = range(first, model.njoints)
        parents = np.array([int(model.parents[j]) - first for j in joints]).reshape(n)
        parents[parents < 0] = -1
        placements = np.array([model.jointPlacements[j].homogeneous for j in joints])
        return cls(parents, placements.reshape(n, 4, 4), axes, prismatic)

    @cached_property
    def levels(self) -> tuple[tuple[np.ndarray, np.ndarray | None], ...]:
        """The joints by depth: ``(joints, their parents or None: the body)`` (one pass)."""
        par = np.asarray(self.parents)
        depth = np.zeros(len(par), dtype=int)
        for j, p in enumerate(par):
            depth[j] = 0 if p < 0 else depth[p] + 1
        out = []
        for d in range(int(depth.max()) + 1 if len(par) else 0):
            idx = np.flatnonzero(depth == d)
            out.append((idx, None if d == 0 else par[idx]))
        return tuple(out)

    @cached_property
    def groups(self) -> tuple[tuple[np.ndarray, np.ndarray | None, int, np.ndarray], ...]:
        """:attr:`levels` split by axis ``k``: 0, 1, 2 about ``sign`` × x, y, z; 3: any other."""
        a = np.asarray(self.axes, dtype=float)
        pr = np.asarray(self.prismatic, dtype=bool)
        kind = np.full(len(a), 3)
        for k in range(3):
            kind[(np.abs(a[:, k]) == 1.0) & ~pr] = k
        out = []
        for idx, par in self.levels:
            for k in range(4):
                sel = kind[idx] == k
                if sel.any():
                    sub = idx[sel]
                    sign = np.where(a[sub, min(k, 2)] < 0, -1.0, 1.0)[:, None]
                    out.append((sub, None if par is None else par[sel], k, sign))
        return tuple(out)

    @cached_property
    def soa_terms(self) -> tuple[np.ndarray, ...]:
        """:attr:`local_terms` components first for :func:`tree_frames`, the 4th less ``P_R``."""
        Pr, Pt, K1, K2, Pa = self.local_terms
        mat = [np.ascontiguousarray(x.transpose(1, 2, 0)[..., None]) for x in (Pr, K1, K2 - Pr)]
        vec = [np.ascontiguousarray(x.T[..., None]) for x in (Pt, Pa)]
        return mat[0], vec[0], mat[1], mat[2], vec[1]

    @cached_property
    def local_terms(self) -> tuple[np.ndarray, ...]:
        """``(P_R, P_t, P_R[a]×, (P_R a) aᵀ, P_R a)`` per joint: placement ``P``, axis ``a``.

        ``P_R R(a, q) = cos q P_R + sin q P_R[a]× + (1 − cos q)(P_R a) aᵀ``; a prismatic
        joint's frame is at ``P_t + (P_R a) q``.
        """
        Pr = np.ascontiguousarray(self.placements[:, :3, :3])
        a = np.asarray(self.axes, dtype=float)
        skew = np.zeros(a.shape + (3,))
        skew[:, 0, 1], skew[:, 0, 2] = -a[:, 2], a[:, 1]
        skew[:, 1, 0], skew[:, 1, 2] = a[:, 2], -a[:, 0]
        skew[:, 2, 0], skew[:, 2, 1] = -a[:, 1], a[:, 0]
        Pa = np.einsum("nij,nj->ni", Pr, a)
        return (
            Pr,
            np.ascontiguousarray(self.placements[:, :3, 3]),
            Pr @ skew,
            Pa[:, :, None] * a[:, None, :],
            Pa,
        )


def tree_frames(tree: Tree, q: np.ndarray, base: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The joints' world frames: rotations (3, 3, n, N), origins (3, n, N), samples last.

    ``q`` (N, n) joint values, ``base`` (N, 4, 4) body poses; a joint about ``±x, ±y, ±z``
    mixes two columns by ``cos q, ±sin q``, any other by Rodrigues (:attr:`Tree.soa_terms`).
    """
    qt = np.ascontiguousarray(np.asarray(q, dtype=float).T)  # (n, N)
    nj, n = qt.shape
    Pr, Pt, K1, K2, Pa = tree.soa_terms
    R = np.empty((3, 3, nj, n))
    p = np.empty((3, nj, n))
    Rb = np.ascontiguousarray(base[:, :3, :3].transpose(1, 2, 0))[:, :, None, :]
    pb = np.ascontiguousarray(base[:, :3, 3].T)[:, None, :]
    for idx, par, k, sign in tree.groups:
        Rp, pp = (Rb, pb) if par is None else (R[:, :, par], p[:, par])
        qi = qt[idx]
        if k < 3:  # X = R_parent P_R, then X R_k(±q) mixes two columns
            P = Pr[:, :, idx]
            X = Rp[:, 0, None] * P[None, 0] + Rp[:, 1, None] * P[None, 1]
            X += Rp[:, 2, None] * P[None, 2]
            c, s_ = np.cos(qi), np.sin(qi) * sign
            u, v = (k + 1) % 3, (k + 2) % 3
            R[:, k, idx] = X[:, k]
            R[:, u, idx] = c * X[:, u] + s_ * X[:, v]
            R[:, v, idx] = c * X[:, v] - s_ * X[:, u]
            ti = Pt[:, idx]
        else:  # P_R R(a, q) = P_R + sin q P_R[a]× + (1 − cos q)((P_R a) aᵀ − P_R)
            pris = np.asarray(tree.prismatic, dtype=bool)[idx][:, None]
            qr = np.where(pris, 0.0, qi)
            Mi = np.sin(qr) * K1[:, :, idx]
            Mi += (1.0 - np.cos(qr)) * K2[:, :, idx]
            Mi += Pr[:, :, idx]
            R[:, :, idx] = Rp[:, 0, None] * Mi[None, 0] + Rp[:, 1, None] * Mi[None, 1]
            R[:, :, idx] += Rp[:, 2, None] * Mi[None, 2]
            ti = Pt[:, idx] + np.where(pris, Pa[:, idx] * qi, 0.0)
        p[:, idx] = Rp[:, 0] * ti[0] + Rp[:, 1] * ti[1] + Rp[:, 2] * ti[2] + pp
    return R, p


def tree_poses(tree: Tree, q: np.ndarray, base: np.ndarray) -> np.ndarray:
    """World poses (N, n, 4, 4) of the joints' frames at joints ``q`` (N, n), bodies ``base``."""
    R, p = tree_frames(tree, q, base)
    out = np.empty((R.shape[-1], R.shape[2], 4, 4))
    out[..., :3, :3] = R.transpose(3, 2, 0, 1)
    out[..., :3, 3] = p.transpose(2, 1, 0)
    out[..., 3, :3] = 0.0
    out[..., 3, 3] = 1.0
    return out


def mat_vec(A: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Stacked 3×3 matrix times 3-vector (..., 3) (broadcast sums: faster than matmul here)."""
    return np.asarray(
        A[..., :, 0] * v[..., 0, None]
        + A[..., :, 1] * v[..., 1, None]
        + A[..., :, 2] * v[..., 2, None]
    )


def robot_size(model: Any) -> float:
    """A Pinocchio model's size [m] (>= 1e-3): its frames' bounding-box diagonal at neutral."""
    import pinocchio as pin

    data = model.createData()
    pin.framesForwardKinematics(model, data, pin.neutral(model))
    pts = np.array([f.translation for f in data.oMf])
    return max(float(np.linalg.norm(pts.max(axis=0) - pts.min(axis=0))), 1e-3)
