"""Matplotlib figures (PNG). Imported lazily; never imported by the core.

Every function takes computed results (no model building here), returns the written
:class:`~pathlib.Path`, and writes the PNG atomically. Sections: singularity pictures
(heat maps, workspace) and motion pictures (foot/joint time series).
"""

from __future__ import annotations

import io
import os
from pathlib import Path
from typing import Any

from ._io import atomic_write
from .exceptions import OptionalDependencyError

__all__ = ["pyplot", "save_figure"]


def pyplot() -> Any:
    """Return ``matplotlib.pyplot`` with the non-interactive Agg backend.

    Raises:
        OptionalDependencyError: If matplotlib is missing (says what to install).
    """
    try:
        import matplotlib
    except ImportError:
        raise OptionalDependencyError(
            "plots need matplotlib: pip install 'hexapod-kin[plots]'"
        ) from None
    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    return plt


def save_figure(fig: Any, path: str | os.PathLike[str], dpi: int = 120) -> Path:
    """Render ``fig`` to PNG in memory, write it atomically, close it; return the path."""
    plt = pyplot()
    buf = io.BytesIO()
    try:
        fig.savefig(buf, format="png", dpi=dpi, bbox_inches="tight")
    finally:
        plt.close(fig)
    return atomic_write(path, buf.getvalue())


# ---------------------------------------------------------------- singularity pictures


# ---------------------------------------------------------------- motion pictures
