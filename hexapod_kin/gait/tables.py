"""Gait phase tables: which legs swing when (per-leg phase offset) and the duty factor.

A leg's phase is ``φ(t) = t / T + offset`` (cycles, modulo 1): stance for ``φ < β`` (the
duty factor), swing for ``β ≤ φ < 1``; it lifts off at ``t = (k + β − offset)·T``. Leg order
is the robot's (``hexapod``: leg1 front-left, leg2 middle-left, leg3 rear-left, leg4
rear-right, leg5 middle-right, leg6 front-right). The built-in patterns are made from the
legs' xy in the body frame (``positions``, x forward, y left), for any order of legs:

* ``wave`` (N ≥ 5): one leg at a time in the *lateral sequence* (left legs rear to front,
  then right rear to front), lift-offs 1/N cycle apart, ``β = max(1 − 1/N, 0.8)``.
* ``crawl`` (N = 4): the four-legged wave (LH, LF, RH, RF), β = 0.8 rather than 0.75 so that
  two swings never meet (a diagonal hand-over puts the CoM on the diagonal, margin 0); the
  walk sways the body over each support triangle (:mod:`.sway`).
* ``tripod`` (N = 6): alternate legs around the body (the front-left leg's set first), β = ½.
* ``ripple`` (even N ≥ 6, as many a side): each side rear to front, lift-offs 2/N apart, the
  right side half a cycle after the left, ``β = 1 − 2/N``.
* ``trot`` (N = 4, diagonal pairs) and ``pace`` (lateral pairs), β = ½: two feet down, **not
  statically stable** (the walk reports their margin but does not fail on it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._fields import fields_dict
from ..exceptions import ParameterError, choices

__all__ = [
    "LAYOUT_TOL",
    "PATTERNS",
    "PhaseTable",
    "default_positions",
    "pattern_names",
    "phase_table",
]


@dataclass(frozen=True)
class PhaseTable:
    """A periodic gait: per-leg phase offsets and the duty factor.

    Attributes:
        name: Pattern name.
        offsets: Phase offset of each leg in cycles, in [0, 1).
        duty_factor: Fraction β of the cycle each leg spends in stance, in (0, 1).
        statically_stable: False for a pattern meant to be dynamically balanced (trot, pace):
            the walk then reports the static stability margin but never fails on it.

    """

    name: str
    offsets: tuple[float, ...]
    duty_factor: float
    statically_stable: bool = True

    def __post_init__(self) -> None:
        offs = tuple(float(o) for o in self.offsets)
        if not offs or not all(math.isfinite(o) and 0.0 <= o < 1.0 for o in offs):
            raise ParameterError(
                f"offsets={self.offsets!r}: one phase offset per leg in [0, 1) cycles",
                parameter="offsets",
                value=list(self.offsets),
                allowed="values in [0, 1)",
            )
        object.__setattr__(self, "offsets", offs)
        beta = float(self.duty_factor)
        if not (math.isfinite(beta) and 0.0 < beta < 1.0):
            raise ParameterError(
                f"duty_factor={self.duty_factor!r} is not allowed; 0 < duty_factor < 1",
                parameter="duty_factor",
                value=self.duty_factor,
                allowed="(0, 1)",
            )
        object.__setattr__(self, "duty_factor", beta)
        object.__setattr__(self, "statically_stable", bool(self.statically_stable))

    @property
    def n_legs(self) -> int:
        """Number of legs."""
        return len(self.offsets)

    def with_duty_factor(self, duty_factor: float | None) -> PhaseTable:
        """The same offsets with another duty factor (``None``: unchanged)."""
        if duty_factor is None:
            return self
        return PhaseTable(self.name, self.offsets, duty_factor, self.statically_stable)

    def phase(self, t: Any, period: float) -> np.ndarray:
        """Phases (N, L) in cycles in [0, 1) at times ``t`` [s] for cycle ``period`` [s]."""
        tt = np.asarray(t, dtype=float).reshape(-1, 1)
        return np.asarray(np.remainder(tt / period + np.asarray(self.offsets)[None, :], 1.0))

    def stance(self, t: Any, period: float) -> np.ndarray:
        """(N, L) True where the leg is in stance."""
        return np.asarray(self.phase(t, period) < self.duty_factor)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: name, offsets [cycles], duty_factor, statically_stable."""
        return fields_dict(self, "name", "offsets", "duty_factor", "statically_stable")


def _snap(x: float) -> float:
    """``x`` modulo 1, with round-off next to a whole cycle snapped to 0."""
    v = float(np.remainder(x, 1.0))
    return 0.0 if v < 1e-12 or v > 1.0 - 1e-12 else v


def _offsets(lift: dict[int, float], beta: float, n: int) -> tuple[float, ...]:
    """Offsets so that leg ``k`` lifts off at ``lift[k]`` cycles."""
    return tuple(_snap(beta - lift[k]) for k in range(n))


def default_positions(n_legs: int) -> np.ndarray:
    """The legs' layout assumed when none is given: (N, 2) xy in the body frame.

    The built-in hexapod's: the first ⌈N/2⌉ legs left (y = 1) front to rear, the others right
    (y = −1) rear to front; x in steps of 1 centred on 0.
    """
    n = int(n_legs)
    left = (n + 1) // 2
    right = n - left
    out = np.empty((n, 2))
    out[:left, 0] = (left - 1) / 2.0 - np.arange(left)
    out[:left, 1] = 1.0
    out[left:, 0] = np.arange(right) - (right - 1) / 2.0
    out[left:, 1] = -1.0
    return out


#: Layout tolerance, relative to the layout's size (the largest |xy|): a leg whose |y| is
#: within it is *on the axis*, and coordinates within it of each other are equal. Offered
#: patterns do not change when a mount moves by less than it (round-off of a URDF's angles).
LAYOUT_TOL = 1e-6


def _tol(xy: np.ndarray) -> float:
    return LAYOUT_TOL * max(float(np.abs(xy).max(initial=0.0)), 1e-3)


def _rank(values: np.ndarray, tol: float) -> np.ndarray:
    """Ranks of ``values`` with values within ``tol`` of their neighbour sharing a rank."""
    order = np.argsort(values, kind="stable")
    rank = np.empty(len(values), dtype=int)
    r = 0
    for i, k in enumerate(order):
        if i and values[k] - values[order[i - 1]] > tol:
            r += 1
        rank[k] = r
    return rank


def _sides(xy: np.ndarray) -> tuple[list[int], list[int]]:
    """Left and right legs, each sorted rear to front (by x within the tolerance; ties by index).

    Left for ``y > tol``, right for ``y < −tol`` (``tol``: :data:`LAYOUT_TOL` × the layout's
    size); a leg on the x axis goes to the side with fewer legs (front first, left on a tie:
    the RARL hexapod's legs at 0° and 180° make three a side). With an even number of legs,
    while one side has two more, its leg nearest the axis changes side (Kraby's legs at ±3 mm).
    """
    tol = _tol(xy)
    xr = _rank(xy[:, 0], tol)
    left = [k for k in range(len(xy)) if xy[k, 1] > tol]
    right = [k for k in range(len(xy)) if xy[k, 1] < -tol]
    axis = sorted((k for k in range(len(xy)) if abs(xy[k, 1]) <= tol), key=lambda k: (-xr[k], k))
    for k in axis:
        (left if len(left) <= len(right) else right).append(k)
    if len(xy) % 2 == 0:  # as many a side: the legs nearest the axis change side
        yr = _rank(np.abs(xy[:, 1]), tol)
        for big, small, s in ((left, right, 1), (right, left, -1)):  # rear leaves left first
            while len(big) > len(small) + 1:
                k = min(big, key=lambda k: (yr[k], s * xr[k], k))
                big.remove(k)
                small.append(k)
    return (
        sorted(left, key=lambda k: (xr[k], k)),
        sorted(right, key=lambda k: (xr[k], k)),
    )


def _ring(xy: np.ndarray) -> list[int]:
    """Legs counter-clockwise from the front (angle in (−π, π], within the tolerance)."""
    tol = _tol(xy)
    y = np.where(np.abs(xy[:, 1]) <= tol, 0.0, xy[:, 1])
    x = np.where(np.abs(xy[:, 0]) <= tol, 0.0, xy[:, 0])
    ang = np.arctan2(y, x)
    ang[ang <= -np.pi + 1e-12] = np.pi
    rank = _rank(ang, tol / max(float(np.abs(xy).max(initial=0.0)), 1e-3))
    return sorted(range(len(xy)), key=lambda k: (rank[k], k))


def _wave(xy: np.ndarray) -> PhaseTable:
    n = len(xy)
    left, right = _sides(xy)
    beta = max((n - 1.0) / n, 0.8)
    lift = {leg: k / n for k, leg in enumerate(left + right)}
    return PhaseTable("wave", _offsets(lift, beta, n), beta)


def _crawl(xy: np.ndarray) -> PhaseTable:
    return PhaseTable("crawl", _wave(xy).offsets, 0.8)


def _tripod(xy: np.ndarray) -> PhaseTable:
    # alternate legs around the body (by the angle of their position); the front-left leg's
    # set lifts at t = 0, the other half a cycle later
    ring = _ring(xy)
    left, right = _sides(xy)
    first = left[-1] if left else ring[0]
    parity = ring.index(first) % 2
    lift = {leg: 0.0 if i % 2 == parity else 0.5 for i, leg in enumerate(ring)}
    return PhaseTable("tripod", _offsets(lift, 0.5, len(xy)), 0.5)


def _ripple(xy: np.ndarray) -> PhaseTable:
    n = len(xy)
    left, right = _sides(xy)
    m = len(left)
    beta = (m - 1.0) / m
    lift = {leg: k / m for k, leg in enumerate(left)}
    lift.update({leg: 0.5 + k / m for k, leg in enumerate(right)})
    return PhaseTable("ripple", _offsets(lift, beta, n), beta)


def _pairs(xy: np.ndarray, name: str) -> PhaseTable:
    (lh, lf), (rh, rf) = _sides(xy)  # rear, front each
    first = (lf, rh) if name == "trot" else (lf, lh)
    lift = {leg: (0.0 if leg in first else 0.5) for leg in (lh, lf, rh, rf)}
    return PhaseTable(name, _offsets(lift, 0.5, 4), 0.5, statically_stable=False)


def _offer(n: int, xy: np.ndarray, names: Any = None) -> tuple[dict[str, Any], dict[str, str]]:
    """The makers of the patterns offered for this layout, and why each other one is not."""
    left, right = _sides(xy)
    label = list(names) if names is not None and len(names) == n else [str(k) for k in range(n)]

    def legs(ks: list[int]) -> str:
        return ", ".join(label[k] for k in ks) or "none"

    out: dict[str, Any] = {}
    why: dict[str, str] = {}
    sides = f"{len(left)} on the left ({legs(left)}) and {len(right)} on the right ({legs(right)})"
    if n == 4 and len(left) == 2 and len(right) == 2:
        out["crawl"] = _crawl
        out["pace"] = lambda p: _pairs(p, "pace")
        out["trot"] = lambda p: _pairs(p, "trot")
    else:
        reason = f"needs 4 legs, 2 a side; this robot has {n}: {sides}"
        why.update(dict.fromkeys(("crawl", "pace", "trot"), reason))
    if n == 6:
        out["tripod"] = _tripod
    else:
        why["tripod"] = f"needs 6 legs; this robot has {n}"
    if n >= 6 and n % 2 == 0 and len(left) == len(right):
        out["ripple"] = _ripple
    else:
        why["ripple"] = f"needs an even number >= 6 of legs, as many a side; this robot has {sides}"
    if n >= 5:
        out["wave"] = _wave
    elif n == 4:
        why["wave"] = "on four legs is the crawl (the same lateral sequence, with body sway)"
    else:
        why["wave"] = f"needs 5 legs or more; this robot has {n}"
    return out, why


def default_pattern(n_legs: int) -> str:
    """The pattern a walk takes when none is named: tripod (6 legs), crawl (4), else wave."""
    return {6: "tripod", 4: "crawl"}.get(int(n_legs), "wave")


def pattern_names(n_legs: int = 6, positions: Any = None) -> tuple[str, ...]:
    """The built-in patterns for ``n_legs`` legs laid out at ``positions`` (sorted)."""
    xy = _layout(int(n_legs), positions)
    return tuple(sorted(_offer(int(n_legs), xy)[0]))


def _layout(n: int, positions: Any) -> np.ndarray:
    if positions is None:
        return default_positions(n)
    xy = np.asarray(positions, dtype=float)
    if xy.ndim != 2 or xy.shape[0] != n or xy.shape[1] not in (2, 3) or not np.isfinite(xy).all():
        raise ParameterError(
            f"positions has shape {np.shape(positions)}; one finite (x, y) per leg: ({n}, 2)",
            parameter="positions",
            value=list(np.shape(positions)),
            allowed=f"({n}, 2)",
        )
    return np.ascontiguousarray(xy[:, :2])


#: The built-in patterns of the six-legged robot (its default layout).
PATTERNS: dict[str, PhaseTable] = {
    p.name: p for p in (f(default_positions(6)) for f in (_tripod, _wave, _ripple))
}


def phase_table(
    pattern: str | PhaseTable, n_legs: int = 6, positions: Any = None, names: Any = None
) -> PhaseTable:
    """A built-in pattern by name, made for the robot's legs, or a user's table.

    Args:
        pattern: A name (:func:`pattern_names`, the module doc) or a :class:`PhaseTable`
            with one offset per leg.
        n_legs: Number of legs.
        positions: (N, 2) the legs' xy in the body frame (x forward, y left), e.g. the mounts;
            default :func:`default_positions` (the built-in hexapod's order). Sides are
            decided within :data:`LAYOUT_TOL` (see :func:`_sides`).
        names: The legs' names, for the message of a refused pattern.

    Raises:
        ParameterError: Unknown name for this number of legs (the message lists the allowed
            ones), or a table whose number of offsets is not ``n_legs``.

    """
    n = int(n_legs)
    if isinstance(pattern, PhaseTable):
        table = pattern
    else:
        xy = _layout(n, positions)
        makers, why = _offer(n, xy, names)
        if not (isinstance(pattern, str) and pattern in makers):
            because = f" ({pattern} {why[pattern]})" if pattern in why else ""
            raise ParameterError(
                f"pattern={pattern!r} is not allowed for {n} legs{because}; use one of "
                f"{choices(makers) if makers else '(none built in)'} or a PhaseTable",
                parameter="pattern",
                value=repr(pattern),
                allowed=sorted(makers),
            )
        table = makers[pattern](xy)
    if table.n_legs != n:
        raise ParameterError(
            f"pattern {table.name!r} has {table.n_legs} offsets; the robot has {n} legs",
            parameter="pattern",
            value=table.n_legs,
            allowed=n,
        )
    return table
