"""Scores of leg designs: workspace volume, stride, σ_min / manipulability, singular distances.

Every design is the ``hexabot_leg(l1, l2, l3)`` of :mod:`hexapod_kin.robots` (α2 = −π/2),
foot ``Rz(q1)·[l1 + l2 c2 + l3 c23, 0, −(l2 s2 + l3 s23)]`` in the hip frame, with joint limits,
on a body mount (radius, yaw). Conventions (all in the hip frame unless said):

* **ground**: the plane ``z = −height``. Its points reachable by the unlimited leg have
  distances ``ρ = l1 + u`` from the hip axis with ``u ∈ [b, a]``, ``a = √((l2+l3)² − h²)``,
  ``b = √(max((l2−l3)² − h², 0))``.
* **neutral foot** ``p0 = ρ0·(cos q1m, sin q1m, 0) − h·z``: ``ρ0 = l1 + b + neutral·(a − b)``,
  ``q1m`` the middle of the hip limits.
* **stride**: the walking direction is body x, i.e. ``d = (cos ψ, −sin ψ, 0)`` for a mount
  yaw ψ. The stride is the longest segment ``p0 + t·d``, ``t ∈ [−back, forward]``, reachable
  within the joint limits at every point (exact closed-form membership; found on a grid of
  ``line_points`` steps per side, then bisected to rounding).
* **along the stride**: the central ``stride_use`` fraction of it (the ends of a
  reach-limited stride are the stretched-leg singularity), ``stride_points`` points; at each
  point the within-limits IK branch with the largest σ_min is used. Reported minima over the
  points: σ_min [m/rad] and manipulability ``√det(J Jᵀ)`` [m³/rad³] of the 3×3 position
  Jacobian (closed form: σ values ``|ρ|`` and those of the 2×2 planar block,
  ``det J = ρ·l2·l3·sin q3`` up to sign), the distance of the foot to the hip axis ``|ρ|``
  [m] (family ``l1 + l2 c2 + l3 c23 = 0``), the angular distance of q3 to {0, π} [rad]
  (family ``sin q3 = 0``) and the joint-limit margin [rad].
* **volume**: Monte-Carlo over ``mc_samples`` points uniform in the bounding cylinder
  (radius ``l1+l2+l3``, ``|z| <= l2+l3``) with the exact membership test; binomial standard
  error. The same unit samples serve every design (common random numbers, seeded by the
  sweep's seed), so close designs rank by their difference, not by sampling noise. The closed
  form of :func:`volume_closed_form` is used where it exists (knee unlimited).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import prange

from .._numerics import njit
from ..exceptions import ParameterError
from .designs import PARAMETERS

__all__ = [
    "SCORES",
    "jacobian_position",
    "reachable",
    "score_designs",
    "unit_samples",
    "volume_closed_form",
]

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
_NS = len(SCORES)
_TWO_PI = 2.0 * math.pi


@njit(cache=True, nogil=True, inline="always")
def _fit(q: float, lo: float, hi: float) -> float:  # pragma: no cover - compiled
    """Angle q wrapped to (−π, π], shifted by ±2π into [lo, hi] if that helps; NaN if outside."""
    q = q - _TWO_PI * math.floor((q + math.pi) / _TWO_PI)
    if q <= -math.pi:
        q += _TWO_PI
    if q < lo - 1e-12 and q + _TWO_PI <= hi + 1e-12:
        q += _TWO_PI
    elif q > hi + 1e-12 and q - _TWO_PI >= lo - 1e-12:
        q -= _TWO_PI
    if q < lo - 1e-12 or q > hi + 1e-12:
        return math.nan
    return q


@njit(cache=True, nogil=True)
def _ik(
    x: float,
    y: float,
    z: float,
    l1: float,
    l2: float,
    l3: float,
    lim: np.ndarray,
    q: np.ndarray,
    first_only: bool,
) -> int:  # pragma: no cover - compiled
    """Within-limits closed-form solutions of one target into q (4, 3); returns their number."""
    hr = math.sqrt(x * x + y * y)
    phi = math.atan2(y, x)
    w = -z
    n = 0
    for k in range(2):
        u = (hr if k == 0 else -hr) - l1
        c3 = (u * u + w * w - l2 * l2 - l3 * l3) / (2.0 * l2 * l3)
        if c3 > 1.0 or c3 < -1.0:
            continue
        q1 = _fit(phi if k == 0 else phi + math.pi, lim[0], lim[1])
        if q1 != q1:
            continue
        s3a = math.sqrt(max(1.0 - c3 * c3, 0.0))
        base = math.atan2(w, u)
        for b in range(2):
            s3 = s3a if b == 0 else -s3a
            q3 = _fit(math.atan2(s3, c3), lim[4], lim[5])
            if q3 != q3:
                continue
            q2 = _fit(base - math.atan2(l3 * s3, l2 + l3 * c3), lim[2], lim[3])
            if q2 != q2:
                continue
            q[n, 0] = q1
            q[n, 1] = q2
            q[n, 2] = q3
            n += 1
            if first_only:
                return n
    return n


@njit(cache=True, nogil=True, inline="always")
def _sigmas(q2: float, q3: float, l1: float, l2: float, l3: float) -> tuple[float, float, float]:
    """(σ_min, manipulability, ρ) of the leg's 3×3 position Jacobian (closed form)."""
    c2, s2 = math.cos(q2), math.sin(q2)
    c23, s23 = math.cos(q2 + q3), math.sin(q2 + q3)
    rho = l1 + l2 * c2 + l3 * c23
    u = l2 * c2 + l3 * c23
    w = l2 * s2 + l3 * s23
    fro = u * u + w * w + l3 * l3
    det = l2 * l3 * abs(math.sin(q3))
    smax2 = 0.5 * (fro + math.sqrt(max(fro * fro - 4.0 * det * det, 0.0)))
    s2min = det / math.sqrt(smax2) if smax2 > 0 else 0.0
    return min(abs(rho), s2min), abs(rho) * det, rho


@njit(cache=True, nogil=True)
def _member(
    x: float,
    y: float,
    z: float,
    l1: float,
    l2: float,
    l3: float,
    lim: np.ndarray,
    q: np.ndarray,
) -> bool:  # pragma: no cover - compiled
    return _ik(x, y, z, l1, l2, l3, lim, q, True) > 0


@njit(cache=True, parallel=True)
def _score_kernel(
    d: np.ndarray,
    unit: np.ndarray,
    line_points: int,
    stride_points: int,
    stride_use: float,
    out: np.ndarray,
) -> None:  # pragma: no cover - compiled
    nd = d.shape[0]
    m = unit.shape[0]
    for i in prange(nd):
        l1, l2, l3, h = d[i, 0], d[i, 1], d[i, 2], d[i, 3]
        mrad, yaw, neutral = d[i, 4], d[i, 5], d[i, 12]
        lim = np.empty(6)
        for j in range(6):
            lim[j] = d[i, 6 + j]
        q = np.empty((4, 3))
        # ---- volume: Monte-Carlo in the bounding cylinder
        big = l1 + l2 + l3
        reach = l2 + l3
        vcyl = math.pi * big * big * 2.0 * reach
        hits = 0
        for s in range(m):
            r = big * math.sqrt(unit[s, 0])
            ph = _TWO_PI * unit[s, 1] - math.pi
            zz = reach * (2.0 * unit[s, 2] - 1.0)
            if _member(r * math.cos(ph), r * math.sin(ph), zz, l1, l2, l3, lim, q):
                hits += 1
        p = hits / m
        out[i, 4] = vcyl * p
        out[i, 5] = vcyl * math.sqrt(p * (1.0 - p) / m)
        for j in (0, 6, 7, 8, 9, 10, 11, 12, 13, 14):
            out[i, j] = 0.0
        # ---- neutral foot and stride
        if h >= reach:
            continue
        a = math.sqrt(reach * reach - h * h)
        dl = l2 - l3
        b = math.sqrt(max(dl * dl - h * h, 0.0))
        rho0 = l1 + b + neutral * (a - b)
        q1m = 0.5 * (lim[0] + lim[1])
        px, py, pz = rho0 * math.cos(q1m), rho0 * math.sin(q1m), -h
        fx = mrad * math.cos(yaw) + math.cos(yaw) * px - math.sin(yaw) * py
        fy = mrad * math.sin(yaw) + math.sin(yaw) * px + math.cos(yaw) * py
        out[i, 14] = math.sqrt(fx * fx + fy * fy)
        if not _member(px, py, pz, l1, l2, l3, lim, q):
            continue
        out[i, 0] = 1.0
        dx, dy = math.cos(yaw), -math.sin(yaw)
        tmax = 2.0 * big
        step = tmax / line_points
        ends = np.zeros(2)
        for side in range(2):
            sg = 1.0 if side == 0 else -1.0
            good, bad = 0.0, tmax
            for k in range(1, line_points + 1):
                t = k * step
                if _member(px + sg * t * dx, py + sg * t * dy, pz, l1, l2, l3, lim, q):
                    good = t
                else:
                    bad = t
                    break
            if bad < tmax or not _member(
                px + sg * tmax * dx, py + sg * tmax * dy, pz, l1, l2, l3, lim, q
            ):
                for _ in range(64):
                    mid = 0.5 * (good + bad)
                    if mid <= good or mid >= bad:
                        break
                    if _member(px + sg * mid * dx, py + sg * mid * dy, pz, l1, l2, l3, lim, q):
                        good = mid
                    else:
                        bad = mid
            ends[side] = good
        out[i, 8] = ends[0]
        out[i, 7] = ends[1]
        out[i, 6] = ends[0] + ends[1]
        # ---- along the central part of the stride
        centre = 0.5 * (ends[0] - ends[1])
        half = 0.5 * stride_use * (ends[0] + ends[1])
        smin, mmin, amin, q3min, lmin = np.inf, np.inf, np.inf, np.inf, np.inf
        for k in range(stride_points):
            t = (
                centre
                - half
                + (2.0 * half * k / (stride_points - 1) if stride_points > 1 else half)
            )
            n = _ik(px + t * dx, py + t * dy, pz, l1, l2, l3, lim, q, False)
            best = -1.0
            bm, br, bq3, bl = 0.0, 0.0, 0.0, 0.0
            for s in range(n):
                sv, mv, rho = _sigmas(q[s, 1], q[s, 2], l1, l2, l3)
                if sv > best:
                    best, bm, br = sv, mv, abs(rho)
                    aq3 = abs(q[s, 2]) % _TWO_PI
                    aq3 = min(aq3, _TWO_PI - aq3)
                    bq3 = min(aq3, math.pi - aq3)
                    bl = np.inf
                    for j in range(3):
                        bl = min(bl, q[s, j] - lim[2 * j], lim[2 * j + 1] - q[s, j])
            if n == 0:  # rounding at a boundary: treat as singular
                best, bm, br, bq3, bl = 0.0, 0.0, 0.0, 0.0, 0.0
            smin = min(smin, best)
            mmin = min(mmin, bm)
            amin = min(amin, br)
            q3min = min(q3min, bq3)
            lmin = min(lmin, bl)
        out[i, 9] = smin
        out[i, 10] = mmin
        out[i, 11] = amin
        out[i, 12] = q3min
        out[i, 13] = max(lmin, 0.0)


def unit_samples(seed: int, n: int) -> np.ndarray:
    """The (n, 3) uniform unit samples of the Monte-Carlo volume (the same for every design).

    Args:
        seed: The sweep's seed.
        n: Number of samples.

    Returns:
        A C-contiguous float array in [0, 1).

    """
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
    """Score designs (rows of :data:`~hexapod_kin.sweep.designs.PARAMETERS`), all cores.

    Args:
        designs: (N, 13) array, columns ``PARAMETERS`` (SI units).
        mc_samples: Monte-Carlo points per design for the volume.
        seed: Seed of the (common) Monte-Carlo samples.
        line_points: Grid steps per side of the stride search (then bisection).
        stride_points: Points along the stride for the σ/singularity/limit minima.
        stride_use: Central fraction of the stride over which those minima are taken.

    Returns:
        Column name → (N,) float array, the names of :data:`SCORES`. Each design's scores
        depend only on its parameters and the seed (not on batching or workers).

    Raises:
        ParameterError: Bad shapes or option values.

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
    if not 0.0 < stride_use <= 1.0:
        raise ParameterError(
            f"stride_use={stride_use}: expected a fraction in (0, 1]", parameter="stride_use"
        )
    out = np.zeros((d.shape[0], _NS))
    if d.shape[0]:
        _score_kernel(
            d,
            unit_samples(seed, mc_samples),
            int(line_points),
            int(stride_points),
            float(stride_use),
            out,
        )
    cols = {name: out[:, j].copy() for j, name in enumerate(SCORES)}
    exact = np.array([volume_closed_form(*row[:3], *row[6:12]) for row in d])
    has = np.isfinite(exact)
    cols["volume_exact"] = has.astype(float)
    cols["volume"] = np.where(has, exact, cols["volume_mc"])
    cols["volume_se"] = np.where(has, 0.0, cols["volume_mc_se"])
    return cols


def reachable(designs_row: Any, points: Any) -> np.ndarray:
    """Exact membership test of the sweep's kernel for one design: (N,) bool.

    Args:
        designs_row: One design (13 values, columns ``PARAMETERS``).
        points: (N, 3) foot positions in the hip frame [m].

    Returns:
        True where some IK solution lies within the joint limits.

    """
    row = np.asarray(designs_row, dtype=float)
    pts = np.asarray(points, dtype=float).reshape(-1, 3)
    return _reach_batch(pts, row[0], row[1], row[2], np.ascontiguousarray(row[6:12]))


@njit(cache=True)
def _reach_batch(
    pts: np.ndarray, l1: float, l2: float, l3: float, lim: np.ndarray
) -> np.ndarray:  # pragma: no cover - compiled
    out = np.zeros(pts.shape[0], dtype=np.bool_)
    q = np.empty((4, 3))
    for i in range(pts.shape[0]):
        out[i] = _member(pts[i, 0], pts[i, 1], pts[i, 2], l1, l2, l3, lim, q)
    return out


def jacobian_position(l1: float, l2: float, l3: float, q: Any) -> np.ndarray:
    """Closed-form 3×3 position Jacobian of the leg (hip frame), used by the kernel's σ.

    Args:
        l1: Coxa length [m].
        l2: Femur length [m].
        l3: Tibia length [m].
        q: (3,) joint values [rad].

    Returns:
        ``∂p/∂q`` (3, 3) in [m/rad].

    """
    q1, q2, q3 = (float(v) for v in q)
    c1, s1 = math.cos(q1), math.sin(q1)
    rho = l1 + l2 * math.cos(q2) + l3 * math.cos(q2 + q3)
    dr2 = -(l2 * math.sin(q2) + l3 * math.sin(q2 + q3))
    dz2 = -(l2 * math.cos(q2) + l3 * math.cos(q2 + q3))
    dr3, dz3 = -l3 * math.sin(q2 + q3), -l3 * math.cos(q2 + q3)
    return np.array(
        [[-rho * s1, c1 * dr2, c1 * dr3], [rho * c1, s1 * dr2, s1 * dr3], [0.0, dz2, dz3]]
    )


def sigmas(l1: float, l2: float, l3: float, q: Any) -> tuple[float, float]:
    """(σ_min [m/rad], manipulability [m³/rad³]) of the kernel's closed form at q."""
    s, m, _ = _sigmas(float(q[1]), float(q[2]), l1, l2, l3)
    return float(s), float(m)


# ---------------------------------------------------------------- closed-form volume
def _cos_bounds(lo: float, hi: float) -> tuple[float, float]:
    """(min, max) of cos q over [lo, hi]."""
    if hi - lo >= 2 * math.pi:
        return -1.0, 1.0
    cmax = (
        1.0
        if 2 * math.pi * math.ceil(lo / (2 * math.pi)) <= hi
        else max(math.cos(lo), math.cos(hi))
    )
    k = math.ceil((lo - math.pi) / (2 * math.pi))
    cmin = -1.0 if math.pi + 2 * math.pi * k <= hi else min(math.cos(lo), math.cos(hi))
    return cmin, cmax


def volume_closed_form(
    l1: float,
    l2: float,
    l3: float,
    q1_lower: float = -math.pi,
    q1_upper: float = math.pi,
    q2_lower: float = -math.pi,
    q2_upper: float = math.pi,
    q3_lower: float = -math.pi,
    q3_upper: float = math.pi,
) -> float:
    """Exact reachable volume of the leg where the knee (q2) is unlimited, else NaN.

    With q2 free, the (u, w) reach region of the femur/tibia pair is the annulus
    ``R_in <= |(u, w)| <= R_out`` (radii from the range of cos q3). At height z the hip-frame
    section of points at signed distance ``x' = l1 + u`` is a set of intervals S_z; a point at
    distance ρ and azimuth φ is reached with q1 = φ (needs ρ ∈ S_z) or q1 = φ + π (needs
    −ρ ∈ S_z). Integrating the azimuth measure of a hip range Δ:
    ``V = ∫ dz [Δ/2 (M(P) + M(N)) − max(Δ − π, 0) M(P ∩ N)]``, ``P = S_z ∩ (0, ∞)``,
    ``N = (−S_z) ∩ (0, ∞)``, ``M(X) = Σ (hi² − lo²)`` over X's intervals (Pappus: ρ dρ dφ).
    Between breakpoints each endpoint is ``±(l1 ± √(r² − z²))``, whose square integrates in
    closed form (``∫√(r² − z²) dz = (z√(r² − z²) + r² asin(z/r))/2``). Full rotation, Δ = 2π,
    of the seed leg's disk (l1 = 0.05, l2 = l3 = 0.1) gives 0.05637 m³.

    Args:
        l1: Coxa length [m].
        l2: Femur length [m].
        l3: Tibia length [m].
        q1_lower: Hip lower limit [rad].
        q1_upper: Hip upper limit [rad].
        q2_lower: Knee lower limit [rad].
        q2_upper: Knee upper limit [rad].
        q3_lower: Ankle lower limit [rad].
        q3_upper: Ankle upper limit [rad].

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
            raw = [
                (l1 - so, (-1, 1), l1 - si, (-1, 0)),
                (l1 + si, (1, 0), l1 + so, (1, 1)),
            ]
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
