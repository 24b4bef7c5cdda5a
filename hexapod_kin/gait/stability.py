"""Static stability and leg clearance, vectorised over time (in chunks of :data:`CHUNK`).

* :func:`support_margin`: signed distance from the projected centre of mass to the edge of
  the stance feet's convex hull (xy): positive inside, negative outside; two feet give a
  segment, one a point (margin ≤ 0), none −∞.
* :func:`segment_clearance`: the smallest distance between the segments of neighbouring legs
  (Ericson, *Real-Time Collision Detection*, 5.1.9).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..exceptions import ParameterError
from .legs import GaitError
from .terrain import RELIEF_RADIUS, Terrain, sphere_gap

__all__ = [
    "CHUNK",
    "accel_limit_of",
    "leg_terrain_clearance",
    "periodic_spline",
    "raise_checks",
    "segment_clearance",
    "support_margin",
    "terrain_clearance",
]

#: Samples per vectorised pass.
CHUNK = 20_000


def _chunks(n: int) -> list[slice]:
    """Slices of :data:`CHUNK` samples covering ``n`` (one, empty, when ``n`` is 0)."""
    return [slice(i, i + CHUNK) for i in range(0, max(n, 1), CHUNK)]


def _seg_point(a: np.ndarray, b: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Distance from points ``p`` to segments ``ab`` (2-D, broadcast over leading axes)."""
    d = b - a
    ll = np.einsum("...i,...i->...", d, d)
    num = np.einsum("...i,...i->...", p - a, d)
    t = np.clip(np.divide(num, ll, out=np.zeros_like(num), where=ll > 0.0), 0.0, 1.0)
    e = a + t[..., None] * d - p
    return np.sqrt(np.einsum("...i,...i->...", e, e))


def _margin_numpy(pts: np.ndarray, mask: np.ndarray, com: np.ndarray) -> np.ndarray:
    """Support margin: hull edges as the stance pairs with no stance foot on their right.

    Collinear stance feet (or one or two) give minus the distance to their segment (the union
    of all stance pairs' segments).
    """
    a = pts[:, :, None, :]  # (N, L, 1, 2)
    b = pts[:, None, :, :]  # (N, 1, L, 2)
    d = b - a  # (N, L, L, 2): a -> b
    cross = d[:, :, :, None, 0] * d[:, :, None, :, 1] - d[:, :, :, None, 1] * d[:, :, None, :, 0]
    stance_c = mask[:, None, None, :]
    pair = mask[:, :, None] & mask[:, None, :]
    distinct = np.any(d != 0.0, axis=-1)
    edge = pair & distinct & np.all((cross >= 0.0) | ~stance_c, axis=-1)
    flat = ~np.any((cross != 0.0) & stance_c & pair[..., None], axis=(1, 2, 3))
    dist = _seg_point(a, b, com[:, None, None, :])  # (N, L, L)
    pc = d[..., 0] * (com[:, None, None, 1] - a[..., 1]) - d[..., 1] * (
        com[:, None, None, 0] - a[..., 0]
    )
    inside = np.all(~edge | (pc >= 0.0), axis=(1, 2))
    dmin = np.min(np.where(edge, dist, np.inf), axis=(1, 2))
    dflat = np.min(np.where(pair, dist, np.inf), axis=(1, 2))
    out = np.where(inside, dmin, -dmin)
    out = np.where(flat, -dflat, out)
    return np.where(mask.any(axis=1), out, -np.inf)


def _clearance_numpy(pts: np.ndarray, pairs: np.ndarray) -> np.ndarray:
    """:func:`segment_clearance` in numpy (Ericson's closest points, every segment pair)."""
    n, _, k, _ = pts.shape
    if not len(pairs):
        return np.empty((n, 0))
    # components first, (3, N, P, K): every operation below is one long vector operation
    ca = np.ascontiguousarray(np.moveaxis(pts[:, pairs[:, 0]], -1, 0))
    cb = np.ascontiguousarray(np.moveaxis(pts[:, pairs[:, 1]], -1, 0))
    p0 = ca[..., :-1, None]  # (3, N, P, K-1, 1)
    u = (ca[..., 1:] - ca[..., :-1])[..., :, None]
    q0 = cb[..., None, :-1]  # (3, N, P, 1, K-1)
    v = (cb[..., 1:] - cb[..., :-1])[..., None, :]
    r = p0 - q0

    def dot(x: np.ndarray, y: np.ndarray) -> np.ndarray:
        return np.asarray(x[0] * y[0] + x[1] * y[1] + x[2] * y[2])

    a = np.broadcast_to(dot(u, u), r.shape[1:])
    e = np.broadcast_to(dot(v, v), r.shape[1:])
    f, c, b = dot(v, r), dot(u, r), dot(u, v)
    eps = 1e-18
    with np.errstate(divide="ignore", invalid="ignore"):
        den = a * e - b * b
        s = np.where(den > 1e-12 * a * e, np.clip((b * f - c * e) / den, 0.0, 1.0), 0.0)
        t = (b * s + f) / e
        low, high = t < 0.0, t > 1.0
        s = np.where(
            low, np.clip(-c / a, 0.0, 1.0), np.where(high, np.clip((b - c) / a, 0.0, 1.0), s)
        )
        t = np.clip(t, 0.0, 1.0)
        if (e <= eps).any() or (a <= eps).any():  # degenerate segments (a point)
            s = np.where(e <= eps, np.clip(-c / a, 0.0, 1.0), s)
            t = np.where(e <= eps, 0.0, t)
            t = np.where(a <= eps, np.clip(f / e, 0.0, 1.0), t)
            s = np.where(a <= eps, 0.0, s)
            both = (a <= eps) & (e <= eps)
            s, t = np.where(both, 0.0, s), np.where(both, 0.0, t)
    d = r + u * s - v * t
    dist = np.sqrt(dot(d, d))
    return np.asarray(dist.reshape(n, len(pairs), -1).min(axis=2))


def support_margin(feet: Any, stance: Any, com: Any) -> np.ndarray:
    """Static stability margin at each sample, in [m].

    Args:
        feet: (N, L, 2 or 3) foot positions (only x, y are used) in [m], or (L, 2|3).
        stance: (N, L) booleans (or (L,)): the feet in the support set.
        com: (N, 2 or 3) centre of mass (projected: x, y) in [m], or (2|3,).

    Returns:
        (N,) signed distances (or a float for a single sample): positive inside the support
        polygon (distance to its nearest edge), negative outside (minus the distance to it).

    Raises:
        ParameterError: Shapes that do not match.

    """
    p = np.asarray(feet, dtype=float)
    s = np.asarray(stance, dtype=bool)
    c = np.asarray(com, dtype=float)
    single = p.ndim == 2
    if single:
        p, s, c = p[None], s[None], c[None]
    if (
        p.ndim != 3
        or p.shape[2] not in (2, 3)
        or s.shape != p.shape[:2]
        or c.shape != (len(p), c.shape[-1])
        or c.shape[-1] not in (2, 3)
    ):
        raise ParameterError(
            f"feet {np.shape(feet)}, stance {np.shape(stance)}, com {np.shape(com)}: expected "
            "(N, L, 2|3), (N, L), (N, 2|3)",
            parameter="feet",
            value=list(np.shape(feet)),
            allowed="(N, L, 2|3)",
        )
    out = np.concatenate([_margin_numpy(p[k, :, :2], s[k], c[k, :2]) for k in _chunks(len(p))])
    return np.asarray(out[0]) if single else out


def segment_clearance(points: Any, pairs: Any) -> np.ndarray:
    """Smallest distance between the segments of leg pairs at each sample, in [m].

    Args:
        points: (N, L, K, 3) each leg's polyline (e.g. hip, knee, ankle, foot) in [m].
        pairs: (P, 2) leg index pairs (e.g. neighbours).

    Returns:
        (N, P) minimum distances between the K − 1 segments of each leg of a pair.

    Raises:
        ParameterError: Bad shapes.

    """
    p = np.ascontiguousarray(points, dtype=float)
    pr = np.ascontiguousarray(pairs, dtype=np.int64)
    if p.ndim != 4 or p.shape[3] != 3 or p.shape[2] < 2 or pr.ndim != 2 or pr.shape[1] != 2:
        raise ParameterError(
            f"points {p.shape}, pairs {pr.shape}: expected (N, L, K>=2, 3) and (P, 2)",
            parameter="points",
            value=list(p.shape),
            allowed="(N, L, K, 3)",
        )
    if pr.size and (pr.min() < 0 or pr.max() >= p.shape[1]):
        raise ParameterError(f"pairs index legs 0..{p.shape[1] - 1}", parameter="pairs")
    return np.concatenate([_clearance_numpy(p[k], pr) for k in _chunks(len(p))])


def periodic_spline(knots: Any, values: Any, period: float, t: Any) -> np.ndarray:
    """The periodic cubic spline through ``(knots, values)`` evaluated at ``t``, C² everywhere.

    Args:
        knots: (M,) distinct times in [0, period) [s] (any order).
        values: (M, D) values at the knots.
        period: The period T [s]; the spline repeats with it.
        t: (N,) times [s] (any real).

    Returns:
        (N, D) values; the knots' second derivatives ``M_j`` solve the cyclic system
        ``h_{j−1} M_{j−1} + 2 (h_{j−1} + h_j) M_j + h_j M_{j+1} = 6 (δ_j − δ_{j−1})`` (δ_j the
        slope of chord j). One knot gives a constant.

    """
    x = np.asarray(knots, dtype=float)
    y = np.asarray(values, dtype=float)
    order = np.argsort(x, kind="stable")
    x, y = x[order], y[order]
    tt = np.asarray(t, dtype=float)
    m = len(x)
    if m == 1:
        return np.broadcast_to(y[0], (len(tt), y.shape[1])).copy()
    h = np.diff(np.append(x, x[0] + period))  # (M,)
    y_next = np.roll(y, -1, axis=0)
    delta = (y_next - y) / h[:, None]
    A = np.zeros((m, m))
    rhs = 6.0 * (delta - np.roll(delta, 1, axis=0))
    for j in range(m):
        hp = h[j - 1]
        A[j, (j - 1) % m] += hp
        A[j, j] += 2.0 * (hp + h[j])
        A[j, (j + 1) % m] += h[j]
    M = np.linalg.solve(A, rhs)
    u = np.remainder(tt - x[0], period) + x[0]
    j = np.clip(np.searchsorted(x, u, side="right") - 1, 0, m - 1)
    hj = h[j][:, None]
    a = (x[j] + h[j])[:, None] - u[:, None]
    b = u[:, None] - x[j][:, None]
    M0, M1 = M[j], np.roll(M, -1, axis=0)[j]
    y0, y1 = y[j], y_next[j]
    return np.asarray(
        (M0 * a**3 + M1 * b**3) / (6.0 * hj)
        + (y0 / hj - M0 * hj / 6.0) * a
        + (y1 / hj - M1 * hj / 6.0) * b
    )


def accel_limit_of(value: Any, nq: int) -> np.ndarray:
    """(nq,) joint acceleration limits [rad/s²] from one number or one per joint (None: inf).

    Raises:
        ParameterError: Not positive numbers of the right shape.

    """
    if value is None:
        return np.full(nq, np.inf)
    try:
        a = np.broadcast_to(np.asarray(value, dtype=float), (nq,)).copy()
    except (TypeError, ValueError):
        a = np.full(nq, np.nan)
    if not np.all(a > 0):
        raise ParameterError(
            f"accel_limit={value!r}: one number > 0 [rad/s²] or one per joint ({nq})",
            parameter="accel_limit",
            value=repr(value),
            allowed=f"> 0, scalar or ({nq},)",
        )
    return a


def terrain_clearance(
    ground: Terrain,
    feet: np.ndarray,
    swing: np.ndarray,
    rad: float,
    t: np.ndarray,
    names: tuple[str, ...],
    H: float,
    strict: bool = True,
    edge_gap: np.ndarray | None = None,
    promised: float = 0.0,
) -> np.ndarray:
    """The foot spheres against the terrain: (N, L) gaps [m] (:func:`~.terrain.sphere_gap`).

    Every foot, swing and stance (gap 0 in stance). With ``edge_gap`` (N, L), each swing
    sphere's clearance to the terrain above its own ground plane
    (:func:`~.terrain.edge_distance`), every swing must also clear edges by ``promised`` [m].

    Raises:
        GaitError: (``strict``) check ``"terrain clearance"``: a sphere more than 1e-9 m
            into the ground; check ``"swing clearance"``: a swing passes an edge closer than
            ``promised`` (both name the leg, the time, by how much).

    """

    def fail(msg: str, check: str, i: Any, leg: Any, d: float, allowed: str) -> GaitError:
        return GaitError(f"leg {names[leg]}: {msg}", check=check, leg=names[leg],
                         time=float(t[i]), amount=d, parameter="step_height", value=H,
                         allowed=allowed)  # fmt: skip

    gap = sphere_gap(ground, feet, rad)
    if strict and gap.min() < -1e-9:
        i, leg = np.unravel_index(int(np.argmin(gap)), gap.shape)
        d = float(-gap[i, leg])
        kind = "swing" if swing[i, leg] else "stance"
        where = "off the terrain" if math.isinf(d) else f"{d:.4g} m into the ground"
        raise fail(
            f"{kind} foot sphere (r={rad:g} m) {where} at t={t[i]:.4g} s (check 'terrain "
            f"clearance'; step_height={H:g} m, or the footholds near an edge)",
            "terrain clearance", i, leg, d, "foot spheres clear of the terrain",
        )  # fmt: skip
    gap_e = np.full(gap.shape, np.inf) if edge_gap is None else np.asarray(edge_gap)
    short = swing & (gap_e < promised)
    if strict and short.any():
        i, leg = np.unravel_index(int(np.argmin(np.where(short, gap_e, np.inf))), gap.shape)
        d = float(promised - gap_e[i, leg])
        raise fail(
            f"the swing passes a terrain edge {1e3 * gap_e[i, leg]:.3g} mm away at t={t[i]:.4g} "
            f"s, {1e3 * d:.3g} mm short of the {1e3 * promised:.3g} mm promised (check 'swing "
            f"clearance'; raise step_height={H:g} m or move the footholds)",
            "swing clearance", i, leg, d, f"swings clear of edges by {promised:g} m",
        )  # fmt: skip
    return gap


#: Ball spacing along a leg segment in :func:`leg_terrain_clearance`, in link radii.
SEGMENT_SPACING = 0.5


def leg_terrain_clearance(
    ground: Terrain,
    points: np.ndarray,
    link_radius: float,
    foot_radius: float,
    planes: np.ndarray,
    t: np.ndarray,
    names: tuple[str, ...],
    strict: bool = True,
) -> np.ndarray:
    """The legs' links against the terrain: (N, L) smallest gap [m] of each leg.

    Each segment of ``points`` (N, L, K, 3) is a capsule of radius ρ = ``link_radius``, sampled
    as balls of radius ρ at most :data:`SEGMENT_SPACING`·ρ apart and held against the terrain
    as :func:`~.terrain.sphere_gap` does, ignoring the ground within :data:`~.terrain.EDGE_TOL`
    of the leg's own ground plane ``planes`` (N, L, 4) and the balls within ``link_radius +
    foot_radius`` of the foot centre (the foot's own check covers it). A segment within
    :data:`~.terrain.RELIEF_RADIUS` of its ends whose lower end is ``link_radius + relief``
    above the higher ground under them is clear unsampled (that bound its gap).

    Raises:
        GaitError: (``strict``) check ``"leg terrain clearance"``: a link into the terrain.

    """
    p = np.asarray(points, dtype=float)
    a, b = p[:, :, :-1], p[:, :, 1:]  # (N, L, K-1, 3) segment ends
    top = np.maximum(ground(a[..., 0], a[..., 1]), ground(b[..., 0], b[..., 1]))
    side = 0.5 * np.hypot(b[..., 0] - a[..., 0], b[..., 1] - a[..., 1]) + link_radius
    gap = np.minimum(a[..., 2], b[..., 2]) - link_radius - top - ground.relief
    check = ~((side <= RELIEF_RADIUS) & (gap >= 0.0))
    if check.any():
        si, sl, sk = np.nonzero(check)
        a0, d = a[si, sl, sk], b[si, sl, sk] - a[si, sl, sk]  # (S, 3)
        longest = float(np.linalg.norm(d, axis=1).max())
        count = int(np.ceil(longest / max(SEGMENT_SPACING * link_radius, 1e-6))) + 1
        u = np.linspace(0.0, 1.0, min(max(count, 2), 200))
        balls = a0[:, None, :] + d[:, None, :] * u[:, None]  # (S, U, 3)
        foot = p[si, sl, -1]
        far = np.linalg.norm(balls - foot[:, None, :], axis=-1) >= link_radius + foot_radius
        pl = np.broadcast_to(np.asarray(planes, dtype=float)[si, sl][:, None, :], far.shape + (4,))
        g = np.full(far.shape, np.inf)
        g[far] = sphere_gap(ground, balls[far], link_radius, below=pl[far])
        gap[si, sl, sk] = g.min(axis=1)
    gap = gap.min(axis=2)
    if strict and gap.min() < -1e-9:
        i, leg = np.unravel_index(int(np.argmin(gap)), gap.shape)
        d = float(-gap[i, leg])
        raise GaitError(
            f"leg {names[leg]}: a link (capsule r={link_radius:g} m) {d:.4g} m into the "
            f"terrain at t={t[i]:.4g} s (check 'leg terrain clearance'; another stride or "
            "body height moves the legs off the edge)",
            check="leg terrain clearance",
            leg=names[leg],
            time=float(t[i]),
            amount=d,
            parameter="stride",
            allowed="legs clear of the terrain",
        )
    return gap


def raise_checks(
    wb: Any,
    st: Any,
    pairs: tuple[tuple[int, int], ...],
    clear: np.ndarray,
    margin: np.ndarray,
    qdot: np.ndarray,
    qddot: np.ndarray,
    vlim: np.ndarray,
    support: np.ndarray,
) -> None:
    """Raise the first failed walk check: leg clearance, stability margin, joint speed/accel.

    ``wb`` the robot, ``st`` the walk's settings (``table``, ``t``, ``tol``, ``strokes``,
    ``acc_lim``). The margin fails below ``−st.tol`` [m] and only for a statically stable
    table; a rate fails above its limit × (1 + 1e-9).

    Raises:
        GaitError: Names the check, the legs or the joint, the time and by how much.

    """
    names, table, t, tol, acc_lim = wb.leg_names, st.table, st.t, st.tol, st.acc_lim
    if clear.size and clear.min() <= 0:
        i, k = np.unravel_index(int(np.argmin(clear)), clear.shape)
        a, b = pairs[k]
        raise GaitError(
            f"legs {names[a]} and {names[b]} collide (links {-clear[i, k]:.4g} m into "
            f"each other) at t={t[i]:.4g} s (check 'leg clearance')",
            check="leg clearance",
            leg=names[a],
            time=float(t[i]),
            amount=float(-clear[i, k]),
            parameter="stride",
            value=st.strokes.max(),
        )
    if table.statically_stable and margin.min() <= -tol:
        im = int(np.argmin(margin))
        raise GaitError(
            f"the centre of mass leaves the support polygon by {-margin[im]:.4g} m at "
            f"t={t[im]:.4g} s (check 'stability margin'; stance legs "
            f"{[names[k] for k in np.flatnonzero(support[im])]})",
            check="stability margin",
            time=float(t[im]),
            amount=float(-margin[im]),
            parameter="pattern",
            value=table.name,
            allowed="margin > 0",
        )
    for rates, lim, check, unit in (
        (qdot, vlim, "joint speed", "rad/s"),
        (qddot, acc_lim, "joint acceleration", "rad/s²"),
    ):
        over = np.abs(rates) - lim * (1.0 + 1e-9)
        if over.size and over.max() > 0:
            i, j = np.unravel_index(int(np.argmax(over)), over.shape)
            joint = wb.joint_names[j]
            d = float(np.abs(rates[i, j]) - lim[j])
            raise GaitError(
                f"joint {joint}: |rate| {abs(rates[i, j]):.4g} {unit} exceeds its limit "
                f"{lim[j]:.4g} {unit} by {d:.4g} at t={t[i]:.4g} s (check '{check}'; slow "
                "down or lengthen the period)",
                check=check,
                leg=None,
                time=float(t[i]),
                amount=d,
                parameter=joint,
                value=float(abs(rates[i, j])),
                allowed=float(lim[j]),
            )
