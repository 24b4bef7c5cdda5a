"""Per-frame overlays: caller-given polylines and points that move with the animation.

Each overlay ``name -> (N, M, 3)`` is drawn under ``/meshcat/overlays/<name>`` as M − 1 unit
cylinders (scaled along y to each segment's length and turned onto it at every frame) or, for
M = 1, one sphere (e.g. a walk's support polygon and projected centre of mass).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..exceptions import ConfigurationError
from .objects import (
    ObjectJSON,
    cylinder,
    set_object,
    set_property,
    set_transform,
    sphere,
    trace_rgba,
)
from .trajectory import clip, track


def check_overlays(overlays: Any, n: int) -> dict[str, np.ndarray]:
    """Validate ``overlays``: name -> (N, M, 3) polylines, one per sample (M = 1: a point)."""
    if overlays is None:
        return {}
    if not hasattr(overlays, "items"):
        msg = f"overlays={type(overlays).__name__}: expected a mapping name -> (N, M, 3) array"
        raise ConfigurationError(msg)
    out: dict[str, np.ndarray] = {}
    for name, value in overlays.items():
        try:
            arr = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            raise ConfigurationError(f"overlays[{name!r}] is not an array of numbers") from None
        if arr.ndim != 3 or arr.shape[0] != n or arr.shape[2] != 3 or arr.shape[1] < 1:
            msg = f"overlays[{name!r}] has shape {arr.shape}; expected ({n}, M, 3): one polyline"
            raise ConfigurationError(f"{msg} of M points per sample (M = 1: a moving point)")
        if not np.all(np.isfinite(arr)):
            raise ConfigurationError(f"overlays[{name!r}] contains non-finite values")
        out[str(name)] = arr
    return out


def _y_to(d: np.ndarray) -> np.ndarray:
    """(K, 4) quaternions x, y, z, w turning +y onto the unit directions ``d`` (K, 3)."""
    q = np.empty((len(d), 4))
    q[:, 0], q[:, 1], q[:, 2] = d[:, 2], np.zeros(len(d)), -d[:, 0]  # y × d
    q[:, 3] = 1.0 + d[:, 1]
    flip = q[:, 3] < 1e-9  # d = -y: half turn about x
    q[flip] = [1.0, 0.0, 0.0, 0.0]
    return np.asarray(q / np.linalg.norm(q, axis=1, keepdims=True))


def overlay_parts(
    overlays: dict[str, np.ndarray], times: np.ndarray, size: float
) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    """Objects and animation clips of the overlays (segments: unit cylinders scaled along y)."""
    cmds: list[dict[str, Any]] = []
    clips: list[dict[str, Any]] = []
    r = max(size * 0.005, 1e-4)
    for k, (name, arr) in enumerate(overlays.items()):
        rgb = trace_rgba(k + 3)
        pieces = [(0, 0)] if arr.shape[1] == 1 else [(j, j + 1) for j in range(arr.shape[1] - 1)]
        for j, (a, b) in enumerate(pieces):
            path = f"/meshcat/overlays/{name}/{j}"
            o = ObjectJSON(path)
            geom = sphere(3 * r) if a == b else cylinder(r, 1.0, 8)
            mesh = o.node("Mesh", geometry=o.geometry(geom), material=o.material(rgb))
            cmds.append(set_object(path, o.lower(mesh)))
            pa, pb = arr[:, a], arr[:, b]
            d = pb - pa
            length = np.linalg.norm(d, axis=1)
            unit = np.where(
                length[:, None] > 1e-12, d / np.maximum(length, 1e-12)[:, None], [0.0, 1.0, 0.0]
            )
            scale = np.ones((len(arr), 3))
            if a != b:
                scale[:, 1] = np.maximum(length, 1e-9)
                scale[length <= 1e-12] = 1e-9  # a repeated point: hidden
            T = np.tile(np.eye(4), (len(arr), 1, 1))
            T[:, :3, 3] = (pa + pb) / 2
            cmds.append(set_transform(path, T[0]))
            cmds.append(set_property(path, "scale", [float(v) for v in scale[0]]))
            if len(times) > 1:
                turned = clip(path, times, T)
                turned["clip"]["tracks"][1] = track("quaternion", "quaternion", times, _y_to(unit))
                turned["clip"]["tracks"].append(track("scale", "vector3", times, scale))
                clips.append(turned)
    return cmds, clips
