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

from . import _lazy
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

#: ``typing.TYPE_CHECKING`` without importing ``typing``: this module loads before the console
#: entry's Ctrl-C handler, in as little time as it can.
TYPE_CHECKING = False
if TYPE_CHECKING:  # pragma: no cover - the names below are imported on first access
    from . import robots
    from ._fromurdf import TableRecovery, chain_from_urdf, recover_chain
    from ._table_kin import table_fk, table_transforms
    from .kinematics import load
    from .params import Chain, DHRow, Hexapod, Inertial, JointLimits, KhalilRow, LegMount, Pose
    from .urdf import to_urdf, write_urdf

#: Names imported from their module on first access (PEP 562): ``import hexapod_kin`` imports
#: no numpy, Pinocchio, sympy or numba (a Ctrl-C at start-up meets the command line's handler).
_PARAMS_NAMES = ("Chain", "DHRow", "Hexapod", "Inertial", "JointLimits", "KhalilRow", "LegMount",
                 "Pose")  # fmt: skip
_LAZY_NAMES = {
    "load": ".kinematics",
    "chain_from_urdf": "._fromurdf",
    "recover_chain": "._fromurdf",
    "TableRecovery": "._fromurdf",
    "table_fk": "._table_kin",
    "table_transforms": "._table_kin",
    "to_urdf": ".urdf",
    "write_urdf": ".urdf",
    **dict.fromkeys(_PARAMS_NAMES, ".params"),
}
#: Submodules reachable as attributes (``hk.singularity``), imported on first access too.
_LAZY_SUBMODULES = (
    "dynamics", "export", "frames", "gait", "ik", "kinematics", "model", "motion", "params",
    "plots", "report", "robots", "seeds", "simulate", "singularity", "sources", "sweep",
    "symbolic", "tables", "urdf", "viewer", "workspace",
)  # fmt: skip

__getattr__, __dir__ = _lazy.lazy_names(__name__, _LAZY_NAMES, globals(), _LAZY_SUBMODULES)

__all__ = ["__version__", "Chain", "ConfigurationError", "DHRow", "FrameNotFoundError",
           "Hexapod", "HexapodKinError", "Inertial", "JointLimits", "KhalilRow",
           "LegMount", "ParameterError", "Pose", "SourceError", "TableRecovery",
           "UrdfError", "UrdfWarning", "chain_from_urdf", "load", "recover_chain",
           "robots", "table_fk", "table_transforms", "to_urdf", "write_urdf"]  # fmt: skip
