"""The one exception family of hexapod_kin.

Every error the package raises derives from :class:`HexapodKinError`. Messages name the
parameter, the value that was given and what is allowed (listing the valid names where there
is a list), so that a user can fix the call without reading the source.
"""

from __future__ import annotations

from collections.abc import Iterable

__all__ = [
    "HexapodKinError",
    "ParameterError",
    "ConfigurationError",
    "FrameNotFoundError",
    "UrdfError",
    "SourceError",
    "IKError",
    "ViewerError",
    "OptionalDependencyError",
    "choices",
]


class HexapodKinError(ValueError):
    """Base of every error raised by hexapod_kin (a ``ValueError``)."""


class ParameterError(HexapodKinError):
    """A parameter table, chain, robot or preset argument is invalid."""


class ConfigurationError(HexapodKinError):
    """A joint configuration, velocity or target has the wrong shape or non-finite values."""


class FrameNotFoundError(HexapodKinError):
    """A frame or joint name does not exist in the model (the message lists those that do)."""


class UrdfError(HexapodKinError):
    """A URDF failed the loader gate; the message names element, attribute, value and line."""


class SourceError(HexapodKinError):
    """A model source (preset name, URDF path or text, ``erd:NAME``) cannot be resolved."""


class IKError(HexapodKinError):
    """An inverse-kinematics request is invalid (e.g. a non-finite target)."""


class ViewerError(HexapodKinError):
    """The meshcat viewer could not start, answer in time or export."""


class OptionalDependencyError(HexapodKinError, ImportError):
    """An optional dependency (viewer, plots, browser) is missing; says what to install."""


def choices(names: Iterable[str], limit: int = 40) -> str:
    """Format a list of valid names for an error message.

    Args:
        names: The valid names.
        limit: How many to show before eliding.

    Returns:
        A string such as ``"'a', 'b', 'c'"`` (with ``... (N more)`` past ``limit``).

    """
    items = [repr(n) for n in names]
    if len(items) > limit:
        return ", ".join(items[:limit]) + f", ... ({len(items) - limit} more)"
    return ", ".join(items)
