"""Parameter-table files (TOML/YAML) → :class:`~hexapod_kin.params.Chain` (being built)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from .exceptions import SourceError
from .params import Chain

__all__ = ["read_table"]


def read_table(path: Path, **params: Any) -> Chain:
    """Read a table file (not available yet).

    Raises:
        SourceError: Always, for now.

    """
    raise SourceError(
        f"source={str(path)!r}: table files are not supported yet", parameter="source"
    )
