"""hexapod_kin: robot legs and the robots they carry.

Khalil–Kleinfinger / DH tables → URDF → Pinocchio forward kinematics, frame Jacobians,
singularities, inverse kinematics and resolved-rate motion, with a meshcat viewer.

Quick start::

    import hexapod_kin as hk
    leg = hk.robots.hexabot_leg()          # seed 001 Table 1, metres
    model = hk.load(leg)                   # Pinocchio model built from the generated URDF
    model.fk([0.1, 0.4, -0.8])             # 4x4 foot pose in the base frame
    model.jacobian([0.1, 0.4, -0.8])       # 6x3, LOCAL_WORLD_ALIGNED
"""

from __future__ import annotations

from typing import Any

from . import robots
from ._fromurdf import TableRecovery, chain_from_urdf, recover_chain
from ._table_kin import table_fk, table_transforms
from ._version import __version__
from .exceptions import (
    ConfigurationError,
    FrameNotFoundError,
    HexapodKinError,
    ParameterError,
    SourceError,
    UrdfError,
    UrdfWarning,
)
from .params import Chain, DHRow, Hexapod, Inertial, JointLimits, KhalilRow, LegMount, Pose
from .urdf import to_urdf, write_urdf

#: Submodules reachable as attributes (``hk.singularity``) without importing them up front
#: (PEP 562): ``import hexapod_kin`` stays light (no Pinocchio, sympy or numba).
_LAZY_SUBMODULES = (
    "dynamics",
    "export",
    "frames",
    "gait",
    "ik",
    "kinematics",
    "model",
    "motion",
    "params",
    "plots",
    "report",
    "seeds",
    "singularity",
    "sources",
    "sweep",
    "symbolic",
    "tables",
    "urdf",
    "viewer",
    "workspace",
)


def __getattr__(name: str) -> Any:
    """Import the submodule ``name`` on first access (PEP 562); ``load`` is ``kinematics.load``.

    Raises:
        AttributeError: If ``name`` is neither a submodule of the list above that exists in
            this installation nor another attribute of the package.

    """
    import importlib
    import importlib.util

    if name == "load":  # the one loader, without importing Pinocchio up front
        return importlib.import_module(f"{__name__}.kinematics").load
    if name in _LAZY_SUBMODULES:
        full = f"{__name__}.{name}"
        if importlib.util.find_spec(full) is not None:
            module = importlib.import_module(full)
            globals()[name] = module
            return module
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY_SUBMODULES))


__all__ = [
    "__version__",
    "Chain",
    "ConfigurationError",
    "DHRow",
    "FrameNotFoundError",
    "Hexapod",
    "HexapodKinError",
    "Inertial",
    "JointLimits",
    "KhalilRow",
    "LegMount",
    "ParameterError",
    "Pose",
    "SourceError",
    "TableRecovery",
    "UrdfError",
    "UrdfWarning",
    "chain_from_urdf",
    "load",
    "recover_chain",
    "robots",
    "table_fk",
    "table_transforms",
    "to_urdf",
    "write_urdf",
]
