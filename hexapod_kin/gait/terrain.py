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

__all__ = ["TERRAINS", "Terrain", "flat", "slope", "step_terrain", "terrain"]


@dataclass(frozen=True, eq=False)
class Terrain:
    """A height field of the ground.

    Attributes:
        name: A label.
        height: ``h(x, y) -> z``: arrays in [m] (same shape) to heights in [m]; NaN where
            there is no ground.
        bounds: Optional domain ``(x_min, x_max, y_min, y_max)`` in [m] (NaN outside).

    """

    name: str
    height: Callable[[np.ndarray, np.ndarray], Any]
    bounds: tuple[float, float, float, float] | None = None

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
    return Terrain("flat", lambda x, y: np.full(np.shape(x), z0))


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
    return Terrain("slope", lambda x, y: z0 + g * (c * np.asarray(x) + s * np.asarray(y)))


def step_terrain(rise: float = 0.02, at: float = 0.25, heading: float = 0.0) -> Terrain:
    """A step of height ``rise`` [m] at distance ``at`` [m] along ``heading`` [rad].

    The ground is at 0 before the edge and at ``rise`` beyond it (the edge itself is up).
    """
    r, d, c, s = float(rise), float(at), math.cos(heading), math.sin(heading)
    return Terrain(
        "step", lambda x, y: np.where(c * np.asarray(x) + s * np.asarray(y) >= d, r, 0.0)
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
