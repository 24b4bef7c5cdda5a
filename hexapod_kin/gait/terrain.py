"""The ground as a height function ``z = h(x, y)`` in the world frame (SI units).

:class:`Terrain` wraps a vectorised callable (arrays of x and y in [m] → heights in [m]) with
an optional rectangular domain; outside it (or where ``h`` returns NaN) a foot is *off the
terrain*. :func:`flat`, :func:`slope` and :func:`step` are the examples; :func:`terrain`
resolves a name or a user callable.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..exceptions import ParameterError, one_of

__all__ = [
    "EDGE_TOL",
    "RELIEF_RADIUS",
    "TERRAINS",
    "Terrain",
    "disc_offsets",
    "edge_distance",
    "disc_residual",
    "flat",
    "off_edges",
    "raise_profile",
    "slope",
    "sphere_gap",
    "step_terrain",
    "swing_profile",
    "swing_raise",
    "terrain",
]

#: The horizontal radius [m] over which :attr:`Terrain.relief` bounds the height change.
RELIEF_RADIUS = 0.1


@dataclass(frozen=True, eq=False)
class Terrain:
    """A height field of the ground.

    Attributes:
        name: A label.
        height: ``h(x, y) -> z``: arrays in [m] (same shape) to heights in [m]; NaN where
            there is no ground.
        bounds: Optional domain ``(x_min, x_max, y_min, y_max)`` in [m] (NaN outside).
        relief: A bound on ``|h(p + d) − h(p)|`` for ``|d| ≤`` :data:`RELIEF_RADIUS` [m]
            (∞: unknown). The sampled checks skip points higher above the ground than their
            radius plus this (they cannot touch it).

    """

    name: str
    height: Callable[[np.ndarray, np.ndarray], Any]
    bounds: tuple[float, float, float, float] | None = None
    relief: float = math.inf

    def __post_init__(self) -> None:
        if not callable(self.height):
            raise ParameterError(
                f"terrain height={self.height!r} is not callable; give h(x, y) -> z",
                parameter="terrain",
                value=repr(self.height),
                allowed="a callable h(x, y)",
            )

    def __call__(self, x: Any, y: Any) -> np.ndarray:
        """Heights [m] at ``x``, ``y`` [m] (NaN off the terrain)."""
        xa, ya = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
        try:
            z = np.asarray(self.height(xa, ya), dtype=float)
        except (TypeError, ValueError):  # a scalar-only user function
            z = np.asarray(np.vectorize(self.height, otypes=[float])(xa, ya))
        if z.shape != xa.shape:
            z = np.broadcast_to(z, xa.shape).copy()
        if self.bounds is not None:
            x0, x1, y0, y1 = self.bounds
            out = (xa < x0) | (xa > x1) | (ya < y0) | (ya > y1)
            z = np.where(out, np.nan, z)
        return np.asarray(z)


def flat(z: float = 0.0) -> Terrain:
    """Level ground at height ``z`` [m]."""
    z0 = float(z)
    return Terrain("flat", lambda x, y: np.full(np.shape(x), z0), relief=0.0)


def slope(angle: float = math.radians(8.0), heading: float = 0.0, z0: float = 0.0) -> Terrain:
    """A plane rising at ``angle`` [rad] in the direction ``heading`` [rad] (from +x).

    Raises:
        ParameterError: ``|angle|`` is not below π/2.

    """
    a = float(angle)
    if not (math.isfinite(a) and abs(a) < math.pi / 2):
        raise ParameterError(
            f"angle={angle!r} is not allowed; |angle| < pi/2 rad",
            parameter="angle",
            value=angle,
            allowed="(-pi/2, pi/2) rad",
        )
    g, c, s = math.tan(a), math.cos(heading), math.sin(heading)
    return Terrain(
        "slope",
        lambda x, y: z0 + g * (c * np.asarray(x) + s * np.asarray(y)),
        relief=abs(g) * RELIEF_RADIUS,
    )


def step_terrain(rise: float = 0.02, at: float = 0.25, heading: float = 0.0) -> Terrain:
    """A step of height ``rise`` [m] at distance ``at`` [m] along ``heading`` [rad].

    The ground is at 0 before the edge and at ``rise`` beyond it (the edge itself is up).
    """
    r, d, c, s = float(rise), float(at), math.cos(heading), math.sin(heading)
    return Terrain(
        "step",
        lambda x, y: np.where(c * np.asarray(x) + s * np.asarray(y) >= d, r, 0.0),
        relief=abs(r),
    )


#: The example terrains by name.
TERRAINS: dict[str, Callable[[], Terrain]] = {"flat": flat, "slope": slope, "step": step_terrain}


def terrain(spec: str | Terrain | Callable[..., Any] | None = None) -> Terrain:
    """A terrain by name (``flat``, ``slope``, ``step``), a :class:`Terrain` or ``h(x, y)``.

    Raises:
        ParameterError: Unknown name (the message lists them) or not callable.

    """
    if spec is None:
        return flat()
    if isinstance(spec, Terrain):
        return spec
    if isinstance(spec, str):
        one_of("terrain", spec, sorted(TERRAINS), also=" or h(x, y)")
        return TERRAINS[spec]()
    return Terrain(getattr(spec, "__name__", "custom"), spec)


# ---------------------------------------------------------------- sampled terrain geometry
#: Disc sampling: the centre plus rings at these fractions of the radius, :data:`ANGLES`
#: directions each (every other ring turned by half a step).
RINGS = (0.25, 0.5, 0.75, 1.0)
ANGLES = 16

#: A disc is flat when the plane fitted (least squares) to its sampled heights leaves no
#: residual above this [m]: a height discontinuity (an edge) inside it does.
EDGE_TOL = 1e-3


#: :func:`disc_offsets` with ``fine=True`` (:func:`edge_distance`): rings every 1/32 of the
#: radius (the outermost every 1/256) and 96 directions.
FINE_RINGS = tuple(np.r_[np.arange(1, 29) / 32.0, 1.0 - np.arange(32, -1, -1) / 256.0])
FINE_ANGLES = 96
#: Spheres sampled together by :func:`edge_distance` (its arrays stay within a CPU cache).
EDGE_CHUNK = 16


def disc_offsets(radius: float, fine: bool = False) -> np.ndarray:
    """(S, 2) horizontal sample offsets [m] of a disc: centre, :data:`RINGS` × :data:`ANGLES`.

    ``fine``: :data:`FINE_RINGS` × :data:`FINE_ANGLES` (an edge's clearance to a fraction of
    a millimetre).
    """
    rings, angles = (FINE_RINGS, FINE_ANGLES) if fine else (RINGS, ANGLES)
    rows = [np.zeros((1, 2))]
    for k, f in enumerate(rings):
        a = (np.arange(angles) + 0.5 * (k % 2)) * (2.0 * np.pi / angles)
        rows.append(f * radius * np.stack([np.cos(a), np.sin(a)], axis=1))
    return np.concatenate(rows)


def _plane_height(pl: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Heights z of the planes ``pl`` (n, 4) ``n·x = k`` (n_z > 0) at ``x``, ``y`` (n, S)."""
    return np.asarray((pl[:, 3:4] - pl[:, 0:1] * x - pl[:, 1:2] * y) / pl[:, 2:3])


def sphere_gap(ground: Terrain, centres: Any, radius: float, below: Any = None) -> np.ndarray:
    """How far spheres clear the terrain [m], sampled: negative = depth into it.

    The smallest ``c_z − h(c_xy + d) − √(r² − |d|²)`` over the offsets d of
    :func:`disc_offsets` (exact on level ground, ``c_z − h − r``); −∞ where the ground is
    undefined. Centres at least ``r +`` :attr:`Terrain.relief` above the ground are not
    sampled: their gap is ``c_z − h(c_xy) − r``.

    Args:
        ground: The terrain.
        centres: (..., 3) sphere centres [m].
        radius: r [m] (≥ 0).
        below: Optional (..., 4) planes ``n·x = k`` (n_z > 0): the ground at most
            :data:`EDGE_TOL` above its point's plane is ignored (a leg's own foot ground).

    """
    c = np.asarray(centres, dtype=float)
    h0 = ground(c[..., 0], c[..., 1])
    gap = c[..., 2] - h0 - radius  # exact on level ground, a bound below for the rest
    near = ~(gap >= ground.relief) if radius <= RELIEF_RADIUS else np.ones(gap.shape, bool)
    if near.any():
        cn = c[near]
        d = disc_offsets(radius)
        cap = np.sqrt(np.maximum(radius * radius - np.einsum("si,si->s", d, d), 0.0))
        x, y = cn[:, None, 0] + d[:, 0], cn[:, None, 1] + d[:, 1]
        h = ground(x, y)
        if below is not None:  # the ground at or under each point's plane is ignored
            plane = _plane_height(np.asarray(below, dtype=float)[near], x, y)
            h = np.where(h > plane + EDGE_TOL, h, -np.inf)
        gap = np.array(gap, dtype=float)
        gap[near] = (cn[:, None, 2] - h - cap).min(axis=-1)
    return np.asarray(np.where(np.isnan(gap), -np.inf, gap))


def edge_distance(
    ground: Terrain, centres: Any, radius: float, reach: float, below: Any
) -> np.ndarray:
    """3-D distance [m] from spheres to the terrain above given planes (``inf``: none near).

    Samples ``h = h(c_xy + d)`` in a disc of radius ``radius + reach`` around each centre
    (..., 3) (:func:`disc_offsets`, fine), kept where more than :data:`EDGE_TOL` above the
    point's plane ``below`` (..., 4); each is at ``√(|d|² + (c_z − h)²) − r`` from the sphere, or
    ``|d| − r`` when ``h ≥ c_z`` (a step's face); the smallest. Spheres more than ``reach``
    above the terrain's :attr:`Terrain.relief` are not sampled (``inf``).
    """
    c = np.asarray(centres, dtype=float)
    out = np.full(c.shape[:-1], np.inf)
    # only where the terrain may come within ``reach`` (Terrain.relief bounds it)
    near = ~(c[..., 2] - ground(c[..., 0], c[..., 1]) - radius - ground.relief > reach)
    if not near.any():
        return out
    c, pl = c[near], np.asarray(below, dtype=float)[near]
    d = disc_offsets(radius + reach, fine=True)
    flat = np.hypot(d[:, 0], d[:, 1])
    best = np.full(len(c), np.inf)
    for a in range(0, len(c), EDGE_CHUNK):  # ~6,000 samples a sphere: a few rows at a time
        cc = c[a : a + EDGE_CHUNK]
        x, y = cc[:, 0, None] + d[:, 0], cc[:, 1, None] + d[:, 1]
        h = ground(x, y)
        keep = (h > _plane_height(pl[a : a + EDGE_CHUNK], x, y) + EDGE_TOL) & np.isfinite(h)
        rows = np.flatnonzero(keep.any(axis=1))
        if len(rows):  # the distances of the spheres with a sample above its plane only
            dz = cc[rows, 2, None] - h[rows]
            dist = np.where(dz > 0, np.hypot(flat, dz), flat) - radius
            best[a + rows] = np.where(keep[rows], dist, np.inf).min(axis=1)
    out[near] = best
    return out


def disc_residual(ground: Terrain, points: Any, radius: float) -> np.ndarray:
    """Largest residual [m] of the plane fitted to the heights sampled in discs.

    Least squares ``h ≈ a + b·dx + c·dy`` over :func:`disc_offsets` around each point
    (..., 2|3) [m]: of the order of the jump across an edge, ~0 on a plane (∞: undefined).
    """
    p = np.asarray(points, dtype=float)
    d = disc_offsets(radius)
    A = np.column_stack([np.ones(len(d)), d])
    proj = np.eye(len(d)) - A @ np.linalg.pinv(A)  # residual operator
    h = ground(p[..., None, 0] + d[:, 0], p[..., None, 1] + d[:, 1])
    res = np.abs(np.einsum("st,...t->...s", proj, h)).max(axis=-1)
    return np.asarray(np.where(np.isnan(res), np.inf, res))


def off_edges(
    ground: Terrain, points: Any, direction: Any, radius: float, reach: float
) -> tuple[np.ndarray, np.ndarray]:
    """Footholds moved off terrain edges along a direction (the edge-aware foothold rule).

    A point whose disc is not flat (:func:`disc_residual` above :data:`EDGE_TOL`; rings of
    ``radius / cos(π/16)`` so that an edge inside the disc crosses a sample) moves along
    ``direction`` to the nearest flat place, forward or backward, at a multiple of
    ``radius/64`` and at most ``reach`` away (a tie goes forward); with none it stays.

    Args:
        ground: The terrain.
        points: (M, 2|3) footholds [m].
        direction: (M, 2) horizontal unit directions of travel.
        radius: Disc radius [m] (the foot radius plus a margin).
        reach: Largest move [m].

    Returns:
        ``(xy, shift)``: (M, 2) the footholds and (M,) the signed move along ``direction`` [m].

    """
    p = np.asarray(points, dtype=float)[:, :2]
    u = np.asarray(direction, dtype=float)
    shift = np.zeros(len(p))
    if ground.relief == 0.0:  # level ground: no edge
        return p.copy(), shift
    step = radius / 64.0
    radius = radius / math.cos(math.pi / ANGLES)  # the sampled rings circumscribe the disc
    bad = np.flatnonzero(disc_residual(ground, p, radius) > EDGE_TOL)
    if len(bad) and radius > 0.0:
        k = np.arange(1, int(np.ceil(reach / step)) + 1)
        ks = np.stack([k, -k], axis=1).reshape(-1) * step  # +1, −1, +2, −2, ... (forward first)
        cand = p[bad, None, :] + ks[None, :, None] * u[bad, None, :]
        ok = disc_residual(ground, cand, radius) <= EDGE_TOL
        found = ok.any(axis=1)
        first = np.argmax(ok, axis=1)
        shift[bad] = np.where(found, ks[first], 0.0)
    return p + shift[:, None] * u, shift


#: The swing raise's ramps: fraction of the swing over which it rises (and falls).
RAMP = 0.25

#: The swing raise is sized on the samples where its profile is at least this.
RAISE_FROM = 0.05


def swing_profile(s: Any) -> tuple[np.ndarray, np.ndarray]:
    """Swing progress ``(10s³ − 15s⁴ + 6s⁵, 64 s³(1 − s)³)`` at ``s ∈ [0, 1]``.

    The horizontal blend (and ground height) from lift-off to touch-down, and the lift's
    scale (1 at s = ½): both with zero first and second derivatives at s = 0 and 1.
    """
    s = np.asarray(s, dtype=float)
    u = s * (1.0 - s)
    return s**3 * (10.0 - 15.0 * s + 6.0 * s * s), 64.0 * u * u * u


def raise_profile(s: Any) -> np.ndarray:
    """The swing raise's shape at ``s ∈ [0, 1]``: a plateau with quintic ramps, C².

    ``q(s/a)`` for ``s < a``, 1 on ``[a, 1 − a]``, ``q((1 − s)/a)`` beyond (``a`` =
    :data:`RAMP`, ``q`` the first of :func:`swing_profile`): 0.32 already at s = 0.1, where the
    lift is 0.05, so it clears a rise close to the lift-off.
    """
    u = np.clip(
        np.minimum(np.asarray(s, dtype=float), 1.0 - np.asarray(s, dtype=float)) / RAMP, 0, 1
    )
    return swing_profile(u)[0]


def swing_raise(
    ground: Terrain,
    start: np.ndarray,
    end: np.ndarray,
    height: float,
    radius: float,
    margin: float,
    samples: int = 48,
) -> np.ndarray:
    """The extra height [m] each swing needs to clear the terrain (0 where it passes no edge).

    The sphere centre (radius r) goes from ``start`` to ``end`` (M, 3) as ``c(s) = start +
    (end − start)·b(s) + height·ℓ(s)·ẑ`` (:func:`swing_profile`) on ``samples + 1`` values of
    s. A path by an edge (a disc of radius ``r + margin`` not flat, :func:`disc_residual`) is
    raised by ``ΔH·p(s)`` (p = :func:`raise_profile`), ``ΔH = max(0, maxₛ (m(s) −
    gap(s)/p(s)))`` with ``gap`` of :func:`sphere_gap` and ``m = margin`` by the edge, else 0,
    over the samples with ``p ≥`` :data:`RAISE_FROM`; at most ``height``.
    """
    c0, c1 = np.asarray(start, dtype=float), np.asarray(end, dtype=float)
    s = np.linspace(0.0, 1.0, samples + 1)
    b, lift = swing_profile(s)
    path = c0[:, None] + (c1 - c0)[:, None] * b[:, None] + (height * lift)[:, None] * [0, 0, 1]
    out = np.zeros(len(c0))
    if ground.relief == 0.0:  # level ground: no edge
        return out
    near = disc_residual(ground, path, radius + margin) > EDGE_TOL  # (M, S+1) by an edge
    edge = near.any(axis=1)
    edge &= np.isfinite(c0[:, 2]) & np.isfinite(c1[:, 2])
    if edge.any():
        p = raise_profile(s)
        inside = p >= RAISE_FROM
        gap = sphere_gap(ground, path[edge][:, inside], radius)
        need = (np.where(near[edge][:, inside], margin, 0.0) - gap / p[inside]).max(axis=1)
        out[edge] = np.clip(need, 0.0, height)
    return out
