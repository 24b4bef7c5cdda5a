"""Design spaces of the 3-DOF hexabot leg on a body mount: grids, random and LHS samples.

A design is one row of :data:`PARAMETERS` (SI units), each fixed or a :class:`Range`
``lo:hi:n``: a grid of the ranges, or seeded ``random`` / ``lhs`` samples. With ``total`` set,
``l3 = total − l1 − l2``; designs with ``l3 <= 0`` are dropped before they are numbered.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..exceptions import ParameterError, finite, one_of, positive

__all__ = ["ANGLES", "DEFAULTS", "METHODS", "PARAMETERS", "DesignSpace", "Range", "design_chain",
           "parse_range"]  # fmt: skip

#: Defaults: the seed leg (seed 001, Table 1) as the middle leg of ``robots.hexapod``.
DEFAULTS: dict[str, float] = {
    "l1": 0.05,  # coxa (hip → knee) [m]
    "l2": 0.10,  # femur [m]
    "l3": 0.10,  # tibia [m]
    "height": 0.10,  # body height: the ground is the plane z = −height in the hip frame [m]
    "mount_radius": 0.12,  # distance of the hip axis from the body centre [m]
    "mount_yaw": math.pi / 2,  # yaw of the hip frame on the body [rad]; walking is body x
    # joint limits [rad]: q1_lower, q1_upper, ..., q3_upper
    **{f"q{j}_{end}": s * math.pi for j in (1, 2, 3) for end, s in (("lower", -1), ("upper", 1))},
    "neutral": 0.5,  # neutral foot: fraction of the ground's radial reach (0 inner, 1 outer)
}

#: Design parameters, in table column order. Lengths in [m], angles in [rad].
PARAMETERS: tuple[str, ...] = tuple(DEFAULTS)

#: Parameters that are angles (the CLI's ``--deg`` converts them).
ANGLES: frozenset[str] = frozenset(p for p in PARAMETERS if p.startswith("q") or "yaw" in p)

#: Largest design length or height [m] and angle magnitude [rad] (the closed forms stay finite).
MAX_LENGTH = 1e3
MAX_ANGLE = 1e3

#: Sampling methods of :meth:`DesignSpace.designs`.
METHODS: tuple[str, ...] = ("grid", "random", "lhs")


@dataclass(frozen=True)
class Range:
    """A swept parameter: ``n >= 1`` grid points from ``lo`` to ``hi >= lo`` (inclusive, finite).

    ``random``/``lhs`` sampling ignores ``n``.
    """

    lo: float
    hi: float
    n: int = 2

    def __post_init__(self) -> None:
        lo, hi = float(self.lo), float(self.hi)
        if not (math.isfinite(lo) and math.isfinite(hi)) or lo > hi:
            raise ParameterError(
                f"range {self.lo}:{self.hi}: bounds must be finite with lo <= hi",
                parameter="range",
                value=(self.lo, self.hi),
                allowed="lo <= hi, finite",
            )
        if int(self.n) != self.n or self.n < 1:
            msg = f"range n={self.n!r}: expected an integer >= 1"
            raise ParameterError(msg, parameter="n", value=self.n)
        for name, v in (("lo", lo), ("hi", hi), ("n", int(self.n))):
            object.__setattr__(self, name, v)

    def grid(self) -> np.ndarray:
        """The ``n`` grid values (``lo`` alone when ``n == 1``)."""
        return np.linspace(self.lo, self.hi, self.n) if self.n > 1 else np.array([self.lo])


def parse_range(name: str, text: str, scale: float = 1.0) -> float | Range:
    """Parse ``VALUE``, ``A:B`` or ``A:B:N`` (CLI syntax) into a float or a :class:`Range`.

    ``name`` is the parameter named in errors; ``scale`` multiplies the values (π/180: degrees).
    Raises ParameterError: malformed text, with the expected syntax.
    """
    parts = str(text).split(":")
    try:
        if len(parts) == 1:
            return float(parts[0]) * scale
        if len(parts) in (2, 3):
            n = int(parts[2]) if len(parts) == 3 else 2
            return Range(float(parts[0]) * scale, float(parts[1]) * scale, n)
    except ValueError:
        pass
    msg = f"{name}={text!r}: expected VALUE, A:B or A:B:N (e.g. 0.04:0.08:5)"
    raise ParameterError(msg, parameter=name, value=text, allowed="VALUE | A:B | A:B:N")


@dataclass(frozen=True)
class DesignSpace:
    """Fixed and swept design parameters.

    ``values``: parameter name → fixed value or :class:`Range` (missing names take
    :data:`DEFAULTS`); ``total``: if set, ``l3 = total − l1 − l2`` in [m] (then no ``l3``).
    """

    values: Mapping[str, float | Range] = field(default_factory=dict)
    total: float | None = None

    def __post_init__(self) -> None:
        vals: dict[str, float | Range] = {}
        for k, v in dict(self.values).items():
            if k not in PARAMETERS:
                msg = f"design parameter {k!r} unknown; valid: {', '.join(PARAMETERS)}"
                raise ParameterError(msg, parameter=k, allowed=list(PARAMETERS))
            vals[k] = v if isinstance(v, Range) else finite(k, v)
        if self.total is not None:
            if "l3" in vals:
                msg = "total and l3 both given; with total set, l3 = total − l1 − l2"
                raise ParameterError(msg, parameter="l3", value=vals["l3"])
            object.__setattr__(self, "total", positive("total", self.total))
        object.__setattr__(self, "values", vals)

    @property
    def swept(self) -> tuple[str, ...]:
        """Names of the swept parameters (those given as a :class:`Range`)."""
        return tuple(p for p in PARAMETERS if isinstance(self.values.get(p), Range))

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready description (ranges as ``[lo, hi, n]``)."""
        out: dict[str, Any] = {}
        for p in PARAMETERS:
            v = self.values.get(p)
            if isinstance(v, Range):
                out[p] = [v.lo, v.hi, v.n]
            elif v is not None:
                out[p] = v
        return {"values": out, "total": self.total}

    def count(self, method: str = "grid", samples: int = 100) -> int:
        """How many designs :meth:`designs` draws at most, without drawing them."""
        one_of("method", method, METHODS)
        if method == "grid" or not self.swept:
            return math.prod(
                v.n if isinstance(v, Range) else 1 for v in map(self._value, PARAMETERS)
            )
        return int(samples)

    def designs(
        self, method: str = "grid", samples: int = 100, seed: int = 0, first: int | None = None
    ) -> np.ndarray:
        """The designs, a read-only (N, len(PARAMETERS)) array: one row per design.

        ``method``: ``"grid"`` (cartesian product of the ranges, ``first``: only its first
        points, a probe of a huge grid), ``"random"`` (uniform) or ``"lhs"`` (Latin hypercube),
        ``samples`` designs from ``seed``. With ``total``, rows with ``l3 <= 0`` are dropped.
        Raises ParameterError: unknown method, ``samples < 1``, or invalid designs.
        """
        one_of("method", method, METHODS)
        swept = self.swept
        if method == "grid" or not swept:
            axes = [
                v.grid() if isinstance(v, Range) else np.array([v])
                for v in (self._value(p) for p in PARAMETERS)
            ]
            shape = tuple(a.size for a in axes)
            count = math.prod(shape) if first is None else min(int(first), math.prod(shape))
            index = np.unravel_index(np.arange(count), shape)  # C order: the meshgrid's "ij"
            table = np.stack([a[i] for a, i in zip(axes, index)], axis=1)
        else:
            if int(samples) != samples or samples < 1:
                msg = f"samples={samples!r}: expected an integer >= 1"
                raise ParameterError(msg, parameter="samples")
            if method == "lhs":
                from scipy.stats import qmc

                lhs = qmc.LatinHypercube(d=len(swept), seed=np.random.default_rng(seed))
                unit = lhs.random(int(samples))
            else:
                unit = np.random.default_rng(seed).random((int(samples), len(swept)))
            table = np.empty((int(samples), len(PARAMETERS)))
            for j, p in enumerate(PARAMETERS):
                v = self._value(p)
                if isinstance(v, Range):
                    k = swept.index(p)
                    table[:, j] = v.lo + (v.hi - v.lo) * unit[:, k]
                else:
                    table[:, j] = v
        if self.total is not None:
            l3 = self.total - table[:, 0] - table[:, 1]
            table[:, 2] = l3
            table = table[l3 > 1e-12 * self.total]
        self._validate(table, empty_ok=first is not None)
        table = np.ascontiguousarray(table)
        table.setflags(write=False)
        return table

    def _value(self, p: str) -> float | Range:
        if p == "l3" and self.total is not None:
            return 0.0  # filled from total
        return self.values.get(p, DEFAULTS[p])

    @staticmethod
    def _validate(table: np.ndarray, empty_ok: bool = False) -> None:
        col = {p: table[:, j] for j, p in enumerate(PARAMETERS)}
        top, ang = MAX_LENGTH, MAX_ANGLE
        checks = [
            ((col[p] > 0) & (col[p] <= top), p, f"> 0 and <= {top:g} [m]")
            for p in ("l1", "l2", "l3")
        ]
        checks += [
            ((col[p] >= 0) & (col[p] <= top), p, f"in [0, {top:g}] [m]")
            for p in ("height", "mount_radius")
        ]
        checks.append(((col["neutral"] >= 0) & (col["neutral"] <= 1), "neutral", "in [0, 1]"))
        checks += [
            (np.abs(col[p]) <= ang, p, f"|{p}| <= {ang:g} [rad]") for p in PARAMETERS if p in ANGLES
        ]
        checks += [(col[f"q{j}_lower"] <= col[f"q{j}_upper"], f"q{j}_lower", f"<= q{j}_upper")
                   for j in (1, 2, 3)]  # fmt: skip
        for ok, name, allowed in checks:
            bad = np.flatnonzero(~ok)
            if bad.size:
                value = float(table[bad[0], PARAMETERS.index(name)])
                msg = f"design parameter {name}={value!r} (design {int(bad[0])}): must be {allowed}"
                raise ParameterError(msg, parameter=name, value=value, allowed=allowed)
        if table.shape[0] == 0 and not empty_ok:
            msg = "the design space is empty (with total, every design had l3 <= 0)"
            raise ParameterError(msg, parameter="total")


def design_chain(design: Any) -> Any:
    """The :func:`~hexapod_kin.robots.hexabot_leg` chain (hip frame, limits, no mount) of a design.

    ``design``: 13 values in the order of :data:`PARAMETERS`, or name → value (missing names
    take :data:`DEFAULTS`). Raises ParameterError: bad lengths or limits.
    """
    from ..params import JointLimits
    from ..robots import hexabot_leg

    if isinstance(design, Mapping):
        vals = [float(design.get(p, DEFAULTS[p])) for p in PARAMETERS]
    else:
        vals = [float(v) for v in np.asarray(design, dtype=float).ravel()]
    if len(vals) != len(PARAMETERS):
        msg = f"design has {len(vals)} values; expected {len(PARAMETERS)}: {', '.join(PARAMETERS)}"
        raise ParameterError(msg, parameter="design")
    limits = tuple(JointLimits(vals[6 + 2 * j], vals[7 + 2 * j]) for j in range(3))
    return hexabot_leg(vals[0], vals[1], vals[2], limits=limits)
