"""The seeds' claims and the computed verdicts, as data (light: no sympy, numpy or Pinocchio).

:class:`Claim` (one table of ``claims.toml``), :class:`Verdict` (a computed verdict) and
:func:`load_claims`. Re-exported by :mod:`.compare` and :mod:`hexapod_kin.report`; kept apart
so that a replayed report (:mod:`.replay`) is rebuilt without importing the comparison rules.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..exceptions import ConfigurationError, OptionalDependencyError

__all__ = ["CLAIMS_FILE", "Claim", "Verdict", "load_claims", "pendulum_duration"]

#: The claims shipped with the package.
CLAIMS_FILE = Path(__file__).with_name("claims.toml")


@dataclass(frozen=True)
class Claim:
    """One claim of a seed (the raw TOML table plus its identity)."""

    id: str
    seed: str
    where: str
    kind: str
    data: Mapping[str, Any]


@dataclass(frozen=True)
class Verdict:
    """A computed verdict.

    Attributes:
        claim: The claim's id.
        seed: The seed (``"000"`` … ``"003"``).
        where: Location in the seed (section / equation / table / figure).
        kind: The claim's kind.
        claimed: The seed's value, as text.
        computed: hexapod_kin's value, as text.
        status: ``"agrees"``, ``"wrong"`` (the seed is wrong), ``"differs"`` (a different but
            consistent convention) or ``"error"`` (the comparison could not run: a bug).
        reason: The computed reason (empty when it agrees).
        method: How it was compared, with the tolerance.

    """

    claim: str
    seed: str
    where: str
    kind: str
    claimed: str
    computed: str
    status: str
    reason: str
    method: str

    @property
    def text(self) -> str:
        """``agrees`` / ``seed is wrong: …`` / ``differs: …``."""
        if self.status == "agrees":
            return "agrees"
        if self.status == "wrong":
            return f"seed is wrong: {self.reason}"
        if self.status == "differs":
            return f"differs: {self.reason}"
        return f"not computed: {self.reason}"

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready."""
        return {
            "claim": self.claim,
            "seed": self.seed,
            "where": self.where,
            "kind": self.kind,
            "claimed": self.claimed,
            "computed": self.computed,
            "status": self.status,
            "verdict": self.text,
            "method": self.method,
        }


def load_claims(path: str | Path | None = None) -> tuple[list[Claim], dict[str, str]]:
    """Read the claims file; return the claims and the seed titles.

    Raises:
        OptionalDependencyError: Python 3.10 without ``tomli``.
        ConfigurationError: A claim without ``id``, ``seed``, ``where`` or ``kind``, or a
            duplicated id.

    """
    try:
        import tomllib as toml_reader  # type: ignore[import-not-found,unused-ignore]
    except ModuleNotFoundError:  # pragma: no cover - Python 3.10
        try:
            import tomli as toml_reader  # type: ignore[no-redef,import-not-found,unused-ignore]
        except ModuleNotFoundError:
            raise OptionalDependencyError(
                "reading the claims file on Python 3.10 needs tomli; "
                "`pip install hexapod-kin[tables]`",
                parameter="claims",
            ) from None
    raw = toml_reader.loads(Path(path or CLAIMS_FILE).read_text(encoding="utf-8"))
    out: list[Claim] = []
    seen: set[str] = set()
    for item in raw.get("claim", []):
        missing = [k for k in ("id", "seed", "where", "kind") if k not in item]
        if missing or item.get("id") in seen:
            raise ConfigurationError(
                f"claims file {path or CLAIMS_FILE}: claim {item.get('id')!r} "
                f"{'lacks ' + ', '.join(missing) if missing else 'is duplicated'}"
            )
        seen.add(item["id"])
        out.append(Claim(item["id"], item["seed"], item["where"], item["kind"], item))
    return out, dict(raw.get("seeds", {}))


def pendulum_duration(quick: bool) -> float:
    """Length of the report's pendulum runs in [s] (reduced with ``quick``)."""
    return 12.0 if quick else 20.0
