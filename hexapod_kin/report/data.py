"""The seeds' claims and the computed verdicts, as data (light: no sympy, numpy or Pinocchio)."""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

from .._reader import check_keys, named, read_data, text
from ..exceptions import ConfigurationError

__all__ = ["CLAIMS_FILE", "SEEDS_DIR", "STATUSES", "Claim", "Verdict", "load_claims", "seed_file"]

#: The claims shipped with the package.
CLAIMS_FILE = Path(__file__).with_name("claims.toml")
#: What each verdict category means (the legend; also in the Markdown).
LEGEND: tuple[tuple[str, str, str], ...] = (
    ("agrees", "agrees", "hexapod_kin computes the same (rule and tolerance under 'compared')."),
    (
        "wrong",
        "seed is wrong",
        "false for every value the seed leaves open: the seed's own data contradict it.",
    ),
    (
        "underdetermined",
        "underdetermined",
        "false with hexapod_kin's stand-in values, but the seed does not give a value that "
        "decides it (named in the verdict) and an admissible value makes it true: neither "
        "confirmed nor refuted.",
    ),
    (
        "differs",
        "differs",
        "a different but consistent convention (e.g. the sign of α2); what it changes is computed.",
    ),
    ("error", "NOT COMPUTED", "the comparison failed to run (a bug in hexapod_kin)."),
)

#: The statuses of a computed verdict (their meaning: :data:`LEGEND`).
STATUSES = tuple(status for status, _, _ in LEGEND)
#: Each status's label in the report.
LABELS = {status: label for status, label, _ in LEGEND}
#: Where the seeds' texts are shipped (package data: a wheel has them).
SEEDS_DIR = Path(__file__).with_name("seeds")


@dataclass(frozen=True)
class Claim:
    """One claim of a seed (the raw TOML table plus its identity)."""

    id: str
    seed: str
    where: str
    kind: str
    data: Mapping[str, Any]

    @property
    def lines(self) -> tuple[int, int]:
        """First and last line (1-based) of the claim's passage in the shipped seed text."""
        raw = [int(x) for x in self.data.get("lines", [])]
        return (raw[0], raw[-1]) if raw else (0, 0)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: the claim's TOML table."""
        return dict(self.data)


@dataclass(frozen=True)
class Verdict:
    """A computed verdict: the claim's id, seed (``"000"`` … ``"003"``), place and kind.

    Attributes:
        claimed: The seed's value, as text; ``computed``: hexapod_kin's.
        status: One of :data:`STATUSES`; ``reason``: why (empty when it agrees).
        method: How it was compared, with the tolerance.
        cells: For a matrix or table: JSON text ``{"seed": rows, "ours": rows, "differ":
            [[i, j], ...] (0-based), "header": [...] or absent, "note": text}``; else ``""``.
        lines: The claim's passage in the shipped seed text, ``"first-last"`` (1-based), or
            ``""``.

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
    cells: str = ""
    lines: str = ""

    @property
    def text(self) -> str:
        """The verdict as a sentence: ``agrees`` or ``<label>: <reason>``."""
        if self.status == "agrees":
            return "agrees"
        return f"{LABELS.get(self.status, 'not computed').lower()}: {self.reason}"

    def fields(self) -> dict[str, str]:
        """Every field by name (what :meth:`from_fields` reads back)."""
        return {f.name: getattr(self, f.name) for f in fields(self)}

    @classmethod
    def from_fields(cls, data: Mapping[str, Any]) -> Verdict:
        """The verdict of :meth:`fields`.

        Raises:
            ValueError: A field is missing, extra or not text, or the status is unknown.

        """
        names = [f.name for f in fields(cls)]
        if set(data) != set(names) or not all(isinstance(data[n], str) for n in names):
            raise ValueError(f"not a verdict: {sorted(data)}")
        if data["status"] not in STATUSES:
            raise ValueError(f"unknown status {data['status']!r}")
        return cls(**{n: data[n] for n in names})

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: the fields, ``verdict`` = :attr:`text` (no ``reason``), ``cells`` parsed."""
        out: dict[str, Any] = self.fields()
        del out["reason"], out["method"], out["cells"]
        cells = json.loads(self.cells) if self.cells else None
        return {**out, "verdict": self.text, "method": self.method, "cells": cells}


def load_claims(path: str | Path | None = None) -> tuple[list[Claim], dict[str, str]]:
    """Read the claims file; return the claims and the seed titles.

    Raises:
        SourceError: The file is refused by the strict reader (:mod:`hexapod_kin._reader`).
        OptionalDependencyError: Python 3.10 without ``tomli``.
        ConfigurationError: A claim without ``id``, ``seed``, ``where`` or ``kind``, or a
            duplicated id.

    """
    path = path or CLAIMS_FILE
    raw = read_data(path, "claims", fmt="toml", mapping="claim, seeds")
    out: list[Claim] = []
    seen: set[str] = set()
    with named(path, "claims", ConfigurationError):
        check_keys(raw, ("claim", "seeds"), "claims file")
        for item in raw.get("claim", []):
            missing = [k for k in ("id", "seed", "where", "kind") if k not in item]
            if missing or item.get("id") in seen:
                raise ConfigurationError(
                    f"claims file {path}: claim {item.get('id')!r} "
                    f"{'lacks ' + ', '.join(missing) if missing else 'is duplicated'}"
                )
            ident, seed, where, kind = (
                text(item[k], f"claim {k}") for k in ("id", "seed", "where", "kind")
            )
            seen.add(ident)
            out.append(Claim(ident, seed, where, kind, item))
    return out, dict(raw.get("seeds", {}))


def seed_file(title: str) -> Path:
    """The shipped text of a seed from its title in the claims file (``"000_….txt — …"``)."""
    return SEEDS_DIR / title.split(" ", 1)[0]
