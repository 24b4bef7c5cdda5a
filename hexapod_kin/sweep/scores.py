"""Scores of leg designs: workspace volume, stride, σ_min / manipulability, singular distances.

A design is ``hexabot_leg(l1, l2, l3)`` (α2 = −π/2), foot ``Rz(q1)·[l1 + l2 c2 + l3 c23, 0,
−(l2 s2 + l3 s23)]`` in the hip frame, with joint limits, on a body mount (radius, yaw).

* ground ``z = −height``, reached at ``ρ = l1 + u``, ``u ∈ [b, a]``, ``a = √((l2+l3)² − h²)``,
  ``b = √(max((l2−l3)² − h², 0))``; neutral foot at ``ρ0 = l1 + b + neutral·(a − b)`` in the
  middle of the hip limits;
* stride: the longest segment through it along body x reachable within the limits (grid,
  then bisection); along its central ``stride_use`` fraction the minima of σ_min,
  manipulability, ``|ρ|``, q3's distance to {0, π} and the joint-limit margin;
* volume: Monte-Carlo in the bounding cylinder (common random numbers, binomial standard
  error); :func:`volume_closed_form` where it exists (knee unlimited).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..exceptions import ParameterError
from ..ik.closed import leg_reachable, leg_solutions
from .designs import PARAMETERS

__all__ = ["SCORES", "reachable", "score_designs", "sigmas", "unit_samples",
           "volume_closed_form"]  # fmt: skip

#: Score columns of :func:`score_designs`, in order, with units.
SCORES: dict[str, str] = {
    "feasible": "1 if the neutral foot is reachable within limits, else 0 (stride scores 0)",
    "volume": "reachable workspace volume [m^3]: closed form where it exists, else Monte-Carlo",
    "volume_se": "standard error of volume [m^3] (0 for the closed form)",
    "volume_exact": "1 if volume is the closed form, else 0",
    "volume_mc": "Monte-Carlo workspace volume [m^3] (exact membership test)",
    "volume_mc_se": "binomial standard error of volume_mc [m^3]",
    "stride": "longest straight stride along the walking direction at the body height [m]",
    "stride_back": "stride extent behind the neutral foot [m]",
    "stride_forward": "stride extent ahead of the neutral foot [m]",
    "sigma_min": "minimum sigma_min of the 3x3 position Jacobian along the stride [m/rad]",
    "manipulability": "minimum sqrt(det(J J^T)) along the stride [m^3/rad^3]",
    "axis_distance": "minimum distance of the foot to the hip axis along the stride [m]",
    "q3_singular_margin": "minimum angular distance of q3 to {0, pi} along the stride [rad]",
    "limit_margin": "minimum joint-limit margin along the stride [rad]",
    "foot_radius": "horizontal distance of the neutral foot from the body centre [m]",
}
_COL = {name: j for j, name in enumerate(SCORES)}
_TWO_PI = 2.0 * math.pi
_BLOCK = 1 << 18  # targets per closed-form call (bounds the temporary arrays)


def _member(d: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """(N,) True where point i is reachable within the limits by design row i."""
    out = np.empty(len(pts), dtype=bool)
    for a in range(0, len(pts), _BLOCK):
        r = np.ascontiguousarray(d[a : a + _BLOCK].T)  # contiguous columns: faster ufuncs
        out[a : a + _BLOCK] = leg_reachable(
            pts[a : a + _BLOCK], (r[0], r[1], r[2]), sign=-1.0, limits=(r[6:12:2].T, r[7:12:2].T)
        )
    return out


def _sigma_rows(
    q2: np.ndarray, q3: np.ndarray, l1: Any, l2: Any, l3: Any
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(σ_min, manipulability, ρ) of the leg's 3×3 position Jacobian (closed form)."""
    c2, s2, c23, s23 = np.cos(q2), np.sin(q2), np.cos(q2 + q3), np.sin(q2 + q3)
    rho, u = l1 + l2 * c2 + l3 * c23, l2 * c2 + l3 * c23
    w = l2 * s2 + l3 * s23
    fro, det = u * u + w * w + l3 * l3, l2 * l3 * np.abs(np.sin(q3))
    smax2 = 0.5 * (fro + np.sqrt(np.maximum(fro * fro - 4.0 * det * det, 0.0)))
    with np.errstate(invalid="ignore", divide="ignore"):
        s2min = np.where(smax2 > 0, det / np.sqrt(smax2), 0.0)
    return np.minimum(np.abs(rho), s2min), np.abs(rho) * det, rho


def _score(d: np.ndarray, unit: np.ndarray, line: int, points: int, use: float) -> np.ndarray:
    """Scores of designs d (D, 13), columns of :data:`SCORES` (the volume columns MC only)."""
    nd, m = len(d), len(unit)
    out = np.zeros((nd, len(SCORES)))
    l1, l2, l3, h = d[:, 0], d[:, 1], d[:, 2], d[:, 3]
    mrad, yaw, neutral = d[:, 4], d[:, 5], d[:, 12]
    big, reach = l1 + l2 + l3, l2 + l3
    # ---- volume: Monte-Carlo in the bounding cylinder, the same unit samples for all
    r_u, ph = np.sqrt(unit[:, 0]), _TWO_PI * unit[:, 1] - math.pi
    c_u, s_u, z_u = r_u * np.cos(ph), r_u * np.sin(ph), 2.0 * unit[:, 2] - 1.0
    hits, per = np.empty(nd), max(1, _BLOCK // m)
    for a in range(0, nd, per):
        blk = slice(a, a + per)
        bb = big[blk, None]
        pts = np.stack([bb * c_u, bb * s_u, reach[blk, None] * z_u], axis=-1).reshape(-1, 3)
        ok = _member(np.repeat(d[blk], m, axis=0), pts)
        hits[blk] = ok.reshape(-1, m).sum(axis=1)
    p = hits / m
    vcyl = math.pi * big * big * 2.0 * reach
    out[:, _COL["volume_mc"]] = vcyl * p
    out[:, _COL["volume_mc_se"]] = vcyl * np.sqrt(p * (1.0 - p) / m)
    # ---- neutral foot
    live = np.flatnonzero(h < reach)
    d, l1, l2, l3, h = d[live], l1[live], l2[live], l3[live], h[live]
    yaw, big, reach = yaw[live], big[live], reach[live]
    a_r = np.sqrt(reach * reach - h * h)
    b_r = np.sqrt(np.maximum((l2 - l3) ** 2 - h * h, 0.0))
    rho0 = l1 + b_r + neutral[live] * (a_r - b_r)
    q1m = 0.5 * (d[:, 6] + d[:, 7])
    p0 = np.stack([rho0 * np.cos(q1m), rho0 * np.sin(q1m), -h], axis=1)
    cy, sy = np.cos(yaw), np.sin(yaw)
    fx = mrad[live] * cy + cy * p0[:, 0] - sy * p0[:, 1]
    fy = mrad[live] * sy + sy * p0[:, 0] + cy * p0[:, 1]
    out[live, _COL["foot_radius"]] = np.hypot(fx, fy)
    feasible = _member(d, p0)
    live, d, p0 = live[feasible], d[feasible], p0[feasible]
    l1, l2, l3, big = l1[feasible], l2[feasible], l3[feasible], big[feasible]
    direction = np.stack([cy[feasible], -sy[feasible], np.zeros(len(live))], axis=1)
    out[live, _COL["feasible"]] = 1.0
    n = len(live)
    # ---- stride: grid of ``line`` steps per side, then bisection to rounding
    tmax, ends = 2.0 * big, np.zeros((2, n))
    ks = np.arange(1, line + 1)
    for side, sg in enumerate((1.0, -1.0)):
        ts = (tmax / line)[:, None] * ks[None, :]  # (n, line)
        pts = p0[:, None, :] + sg * ts[..., None] * direction[:, None, :]
        ok = _member(np.repeat(d, line, axis=0), pts.reshape(-1, 3)).reshape(n, line)
        first_bad = np.where(ok.all(axis=1), line, np.argmin(ok, axis=1))
        rows = np.arange(n)
        good = np.where(first_bad > 0, ts[rows, np.maximum(first_bad - 1, 0)], 0.0)
        bad = np.where(first_bad < line, ts[rows, np.minimum(first_bad, line - 1)], tmax)
        active = first_bad < line
        for _ in range(64):
            mid = 0.5 * (good + bad)
            active &= (mid > good) & (mid < bad)
            if not active.any():
                break
            idx = np.flatnonzero(active)
            hit = _member(d[idx], p0[idx] + sg * mid[idx, None] * direction[idx])
            good[idx] = np.where(hit, mid[idx], good[idx])
            bad[idx] = np.where(hit, bad[idx], mid[idx])
        ends[side] = good
    out[live, _COL["stride_forward"]] = ends[0]
    out[live, _COL["stride_back"]] = ends[1]
    out[live, _COL["stride"]] = ends[0] + ends[1]
    # ---- along the central part of the stride: the within-limits branch of largest σ_min
    centre, half = 0.5 * (ends[0] - ends[1]), 0.5 * use * (ends[0] + ends[1])
    k = np.arange(points)[None, :]
    step = 2.0 * half[:, None] * k / (points - 1) if points > 1 else half[:, None]
    ts = centre[:, None] - half[:, None] + step  # (n, points)
    pts = p0[:, None, :] + ts[..., None] * direction[:, None, :]
    dr = np.repeat(d, points, axis=0)  # within-limits solutions (N, 4, 3), validity (N, 4)
    lo, hi = dr[:, 6:12:2], dr[:, 7:12:2]
    q, valid = leg_solutions(pts.reshape(-1, 3), (dr[:, 0], dr[:, 1], dr[:, 2]), sign=-1.0,
                             limits=(lo, hi))  # fmt: skip
    rep = (np.repeat(v, points)[:, None] for v in (l1, l2, l3))
    sv, mv, rho = _sigma_rows(q[..., 1], q[..., 2], *rep)
    sv = np.where(valid, sv, -1.0)
    best = np.argmax(sv, axis=1)
    rows = np.arange(len(best))
    qb = q[rows, best]
    aq3 = np.abs(qb[:, 2]) % _TWO_PI
    aq3 = np.minimum(aq3, _TWO_PI - aq3)
    cols = {
        "sigma_min": sv[rows, best],
        "manipulability": mv[rows, best],
        "axis_distance": np.abs(rho[rows, best]),
        "q3_singular_margin": np.minimum(aq3, math.pi - aq3),
        "limit_margin": np.minimum(qb - lo, hi - qb).min(axis=1),
    }
    none = ~valid.any(axis=1)  # rounding at a boundary: treat as singular
    for name, v in cols.items():
        v = np.where(none, 0.0, v).reshape(n, points).min(axis=1)
        out[live, _COL[name]] = np.maximum(v, 0.0) if name == "limit_margin" else v
    return out


def unit_samples(seed: int, n: int) -> np.ndarray:
    """The (n, 3) uniform unit samples of the Monte-Carlo volume for the sweep's ``seed``."""
    return np.random.Generator(np.random.PCG64([int(seed), 0x5EED])).random((int(n), 3))


def score_designs(
    designs: Any,
    *,
    mc_samples: int = 10_000,
    seed: int = 0,
    line_points: int = 256,
    stride_points: int = 64,
    stride_use: float = 0.9,
) -> dict[str, np.ndarray]:
    """Score designs, (N, 13) rows of :data:`~hexapod_kin.sweep.designs.PARAMETERS` (SI units).

    The options are :func:`~hexapod_kin.sweep.sweep`'s (``seed``: of the common Monte-Carlo
    samples; ``line_points``: grid steps per side of the stride search, then bisection).

    Returns column name → (N,) float array, the names of :data:`SCORES` (each design's scores
    depend only on its parameters and the seed). Raises ParameterError: bad shapes or options.
    """
    d = np.ascontiguousarray(np.asarray(designs, dtype=np.float64))
    if d.ndim != 2 or d.shape[1] != len(PARAMETERS):
        raise ParameterError(
            f"designs has shape {d.shape}; expected (N, {len(PARAMETERS)}) with columns "
            f"{', '.join(PARAMETERS)}",
            parameter="designs",
        )
    if int(mc_samples) < 1 or int(line_points) < 2 or int(stride_points) < 1:
        raise ParameterError(
            f"mc_samples={mc_samples}, line_points={line_points}, stride_points="
            f"{stride_points}: need >= 1, >= 2, >= 1",
            parameter="mc_samples",
        )
    if isinstance(seed, bool) or int(seed) != seed or not 0 <= int(seed) < 2**63:
        msg = f"seed={seed!r}: expected an integer in [0, 2**63)"
        raise ParameterError(msg, parameter="seed", value=seed, allowed="0 <= seed < 2**63")
    if not 0.0 < stride_use <= 1.0:
        msg = f"stride_use={stride_use}: expected a fraction in (0, 1]"
        raise ParameterError(msg, parameter="stride_use")
    out = np.zeros((d.shape[0], len(SCORES)))
    if d.shape[0]:
        unit = unit_samples(seed, mc_samples)
        out = _score(d, unit, int(line_points), int(stride_points), float(stride_use))
    cols = {name: out[:, j].copy() for j, name in enumerate(SCORES)}
    exact = np.array([volume_closed_form(*row[:3], *row[6:12]) for row in d])
    has = np.isfinite(exact)
    cols["volume_exact"] = has.astype(float)
    cols["volume"] = np.where(has, exact, cols["volume_mc"])
    cols["volume_se"] = np.where(has, 0.0, cols["volume_mc_se"])
    return cols


def reachable(designs_row: Any, points: Any) -> np.ndarray:
    """(N,) True where one design (13 values, ``PARAMETERS``) reaches ``points`` (N, 3) [m].

    The sweep's exact test: some IK solution in the hip frame lies within the joint limits.
    """
    row = np.asarray(designs_row, dtype=float)
    pts = np.asarray(points, dtype=float).reshape(-1, 3)
    return _member(np.broadcast_to(row, (len(pts), row.size)), pts)


def sigmas(l1: float, l2: float, l3: float, q: Any) -> tuple[float, float]:
    """(σ_min [m/rad], manipulability [m³/rad³]) of the sweep's closed form at q."""
    s, m, _ = _sigma_rows(np.array(float(q[1])), np.array(float(q[2])), l1, l2, l3)
    return float(s), float(m)


# ---------------------------------------------------------------- closed-form volume
def _cos_bounds(lo: float, hi: float) -> tuple[float, float]:
    """(min, max) of cos q over [lo, hi]."""
    if hi - lo >= 2 * math.pi:
        return -1.0, 1.0
    top = 2 * math.pi * math.ceil(lo / (2 * math.pi)) <= hi
    cmax = 1.0 if top else max(math.cos(lo), math.cos(hi))
    k = math.ceil((lo - math.pi) / (2 * math.pi))
    cmin = -1.0 if math.pi + 2 * math.pi * k <= hi else min(math.cos(lo), math.cos(hi))
    return cmin, cmax


def volume_closed_form(
    l1: float, l2: float, l3: float, q1_lower: float = -math.pi, q1_upper: float = math.pi,
    q2_lower: float = -math.pi, q2_upper: float = math.pi, q3_lower: float = -math.pi,
    q3_upper: float = math.pi,
) -> float:  # fmt: skip
    """Exact reachable volume of the leg where the knee (q2) is unlimited, else NaN.

    With q2 free the (u, w) reach is the annulus ``R_in <= |(u, w)| <= R_out``; at height z the
    section at signed distance ``l1 + u`` is a set of intervals S_z, reached with q1 = φ or
    φ + π: ``V = ∫ dz [Δ/2 (M(P) + M(N)) − max(Δ − π, 0) M(P ∩ N)]``, ``P = S_z ∩ (0, ∞)``,
    ``N = (−S_z) ∩ (0, ∞)``, ``M(X) = Σ (hi² − lo²)``, integrated in closed form between
    breakpoints. The seed leg, full rotation: 0.05637 m³. Lengths ``l1`` (coxa), ``l2``
    (femur), ``l3`` (tibia) in [m]; the hip, knee and ankle limits in [rad].

    Returns:
        The volume in [m³], or NaN when the knee range is narrower than 2π (no closed form).

    """
    if q2_upper - q2_lower < 2 * math.pi - 1e-12:
        return math.nan
    cmin, cmax = _cos_bounds(q3_lower, q3_upper)
    r_out = math.sqrt(max(l2 * l2 + l3 * l3 + 2 * l2 * l3 * cmax, 0.0))
    r_in = math.sqrt(max(l2 * l2 + l3 * l3 + 2 * l2 * l3 * cmin, 0.0))
    delta = min(q1_upper - q1_lower, 2 * math.pi)
    radii = (r_in, r_out)

    def s_of(r: float, z: float) -> float:
        return math.sqrt(max(r * r - z * z, 0.0))

    def anti(tag: tuple[int, int], z: float) -> float:
        sign, ri = tag
        r = radii[ri]
        zc = min(z, r)
        s_int = 0.5 * (zc * s_of(r, zc) + r * r * math.asin(zc / r)) if r > 0 else 0.0
        return l1 * l1 * z + 2 * sign * l1 * s_int + r * r * z - z**3 / 3.0

    def sections(z: float) -> tuple[list[Any], list[Any], list[Any]]:
        so = s_of(r_out, z)
        if z < r_in:
            si = s_of(r_in, z)
            raw = [(l1 - so, (-1, 1), l1 - si, (-1, 0)), (l1 + si, (1, 0), l1 + so, (1, 1))]
        else:
            raw = [(l1 - so, (-1, 1), l1 + so, (1, 1))]
        pos: list[Any] = []
        neg: list[Any] = []
        for lo, lt, hi, ht in raw:
            if hi > 0:
                pos.append((max(lo, 0.0), lt if lo > 0 else None, hi, ht))
            if lo < 0:
                neg.append((max(-hi, 0.0), ht if hi < 0 else None, -lo, lt))
        neg.sort(key=lambda iv: iv[0])
        both = []
        for a in pos:
            for b in neg:
                lo, lt = (a[0], a[1]) if a[0] >= b[0] else (b[0], b[1])
                hi, ht = (a[2], a[3]) if a[2] <= b[2] else (b[2], b[3])
                if hi > lo:
                    both.append((lo, lt, hi, ht))
        return pos, neg, both

    def piece(ivs: list[Any], za: float, zb: float) -> float:
        tot = 0.0
        for _, lt, _, ht in ivs:
            tot += anti(ht, zb) - anti(ht, za)
            if lt is not None:
                tot -= anti(lt, zb) - anti(lt, za)
        return tot

    cuts = {0.0, r_out, r_in}
    if l1 < r_out:
        cuts.add(math.sqrt(r_out**2 - l1**2))
    if l1 < r_in:
        cuts.add(math.sqrt(r_in**2 - l1**2))
    si_star = abs(l1 - (r_out**2 - r_in**2) / (4 * l1))
    if si_star < r_in:
        cuts.add(math.sqrt(r_in**2 - si_star**2))
    zs = sorted(c for c in cuts if 0.0 <= c <= r_out)
    vol = 0.0
    for za, zb in zip(zs[:-1], zs[1:]):
        if zb - za <= 0:
            continue
        pos, neg, both = sections(0.5 * (za + zb))
        vol += 0.5 * delta * (piece(pos, za, zb) + piece(neg, za, zb))
        vol -= max(delta - math.pi, 0.0) * piece(both, za, zb)
    return 2.0 * vol
