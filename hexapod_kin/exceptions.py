"""The one exception family of hexapod_kin: every error derives from :class:`HexapodKinError`.

Messages name the parameter, the value given and what is allowed (the valid names, where
there is a list), so that a user can fix the call without reading the source.
"""

from __future__ import annotations

import math

TYPE_CHECKING = False  # typing.TYPE_CHECKING without importing typing (mypy reads it so)

if TYPE_CHECKING:  # annotations only: the command line's start-up imports this module
    from collections.abc import Iterable
    from typing import Any

__all__ = ["HexapodKinError", "ParameterError", "ConfigurationError", "LimitError",
           "FrameNotFoundError", "UrdfError", "SourceError", "IKError", "ViewerError",
           "OptionalDependencyError", "UrdfWarning", "choices", "one_of",
           "did_you_mean", "finite", "positive"]  # fmt: skip


class HexapodKinError(ValueError):
    """Base of every error raised by hexapod_kin (a ``ValueError``).

    Args:
        message: The whole message (``str(err)``).
        parameter: The offending parameter (``"q"``, ``"source"``), if known.
        value: The value given, if known.
        allowed: What is allowed (names, a range, a description), if known.

    The keywords are kept as attributes of the same names (``None`` when not said).

    """

    def __init__(
        self,
        message: str = "",
        *,
        parameter: str | None = None,
        value: Any = None,
        allowed: Any = None,
    ) -> None:
        super().__init__(message)
        self.message = message
        self.parameter = parameter
        self.value = value
        self.allowed = allowed

    def to_dict(self) -> dict[str, Any]:
        """The error as JSON-ready data: type, message, parameter, value, allowed."""

        def plain(x: Any) -> Any:
            if x is None or isinstance(x, (str, int, float, bool)):
                return x
            if isinstance(x, (list, tuple, set, frozenset)):
                return [plain(v) for v in x]
            return repr(x)

        return {
            "type": type(self).__name__,
            "message": self.message,
            "parameter": self.parameter,
            "value": plain(self.value),
            "allowed": plain(self.allowed),
        }


class ParameterError(HexapodKinError):
    """A parameter table, chain, robot or preset argument is invalid."""


class ConfigurationError(HexapodKinError):
    """A joint configuration, velocity or target has the wrong shape or non-finite values."""


class LimitError(ConfigurationError):
    """A plan that reaches a limit (a servo's range or speed, a leg's reach, a friction cone).

    Answered, not achieved: the command line exits with status 1 (not 2: the input was good).
    """


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


class HexapodKinWarning(UserWarning):
    """The package's own warnings (the command line prints each as one line)."""


class CacheWarning(HexapodKinWarning):
    """A cache entry that was damaged, edited or planted: discarded and recomputed."""


class UrdfWarning(HexapodKinWarning):
    """A URDF loaded despite a defect of geometry (a mesh not found) or dynamics (inertials)."""


def choices(names: Iterable[str], limit: int = 40) -> str:
    """Valid names for an error message: ``"'a', 'b', 'c'"`` (``... (N more)`` past ``limit``)."""
    items = [repr(n) for n in names]
    if len(items) > limit:
        return ", ".join(items[:limit]) + f", ... ({len(items) - limit} more)"
    return ", ".join(items)


def one_of(parameter: str, value: Any, allowed: Iterable[Any], also: str = "") -> Any:
    """``value`` when it is one of ``allowed``, else a :class:`ParameterError` naming them.

    ``parameter`` is named in the message and the error's fields; ``also`` is appended to the
    list of valid values (e.g. ``" or h(x, y)"``).
    """
    valid = list(allowed)
    if value in valid:
        return value
    raise ParameterError(
        f"{parameter}={value!r} is not allowed; use one of {choices(valid)}{also}",
        parameter=parameter,
        value=value,
        allowed=valid,
    )


def did_you_mean(name: str, names: Iterable[str], n: int = 3, cutoff: float = 0.6) -> str:
    """``" (did you mean 'a' or 'b'?)"`` for an unknown ``name`` among ``names``, or ``""``.

    At most ``n`` suggestions by ``difflib.get_close_matches`` (``cutoff`` in [0, 1]), names
    starting with ``name`` (``ur5`` → ``ur5_robot``) too.
    """
    pool = [str(x) for x in names]
    if not isinstance(name, str) or not pool:
        return ""
    import difflib  # on first use: the command line's start-up imports this module

    close = difflib.get_close_matches(name, pool, n=n, cutoff=cutoff)
    low = name.lower()
    prefixed = [x for x in pool if low and x.lower().startswith(low) and x not in close]
    found = (close + sorted(prefixed, key=len))[:n]
    if not found:
        return ""
    return " (did you mean " + " or ".join(repr(x) for x in found) + "?)"


def finite(name: str, value: Any, need: str = "") -> float:
    """``value`` as a finite float: the package's one such check (a bool is not a number).

    ``need`` is a range also required, said in the message (e.g. ``"> 0"``).

    Raises:
        ParameterError: Not a number or not finite (naming ``name``).

    """
    try:
        if isinstance(value, bool):
            raise TypeError
        v = float(value)
    except (TypeError, ValueError):
        raise _needed(name, value, need, "is not a number") from None
    if not math.isfinite(v):
        raise _needed(name, value, need)
    return v


def _needed(name: str, value: Any, need: str, problem: str = "is not allowed") -> ParameterError:
    """The error of :func:`finite` / :func:`positive`: a finite value (``need``) is needed."""
    return ParameterError(
        f"{name}={value!r} {problem}; {f'a finite value {need}'.rstrip()} is needed",
        parameter=name,
        value=value,
        allowed=f"finite {need}".rstrip(),
    )


def positive(
    name: str, value: Any, *, allow_zero: bool = False, at_most: float = math.inf
) -> float:
    """``value`` as a finite float > 0 (>= 0 with ``allow_zero``; <= ``at_most``): the one check.

    Raises:
        ParameterError: Not a number (a bool is not one), not finite or out of range; the
            error names ``name`` and carries the value and what is allowed.

    """
    need = ">= 0" if allow_zero else "> 0"
    if at_most < math.inf:
        need += f" and <= {at_most:g}"
    v = finite(name, value, need)
    if v < 0 or (v == 0 and not allow_zero) or v > at_most:
        raise _needed(name, value, need)
    return v
