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
#: The statuses of a computed verdict (their meaning: :data:`~.html.LEGEND`).
STATUSES = ("agrees", "wrong", "underdetermined", "differs", "error")
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
        if not raw:
            return (0, 0)
        return (raw[0], raw[-1])

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: the claim's TOML table."""
        return dict(self.data)


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
        status: One of :data:`STATUSES`.
        reason: The computed reason (empty when it agrees).
        method: How it was compared, with the tolerance.
        cells: For a matrix or table: JSON text ``{"seed": rows, "ours": rows, "differ":
            [[i, j], ...] (0-based), "header": [...] or absent, "note": text}`` (entries as
            text), so the report lays it out as a matrix; ``""`` otherwise.
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
        label = {
            "wrong": "seed is wrong",
            "differs": "differs",
            "underdetermined": "underdetermined",
        }
        return f"{label.get(self.status, 'not computed')}: {self.reason}"

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
        """JSON-ready: the fields, ``verdict`` = :attr:`text` (no ``reason``), ``cells`` parsed.

        ``cells`` is None for a verdict that is not a matrix or table.
        """
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
