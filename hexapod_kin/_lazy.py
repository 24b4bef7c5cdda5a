"""A package's names imported from their submodules on first access (PEP 562)."""

from __future__ import annotations

import importlib
import importlib.util

TYPE_CHECKING = False  # typing.TYPE_CHECKING without importing typing (``import hexapod_kin``)
if TYPE_CHECKING:
    from collections.abc import Callable, Iterable
    from typing import Any

__all__ = ["lazy_names"]


def lazy_names(
    package: str, where: dict[str, str], namespace: dict[str, Any], submodules: Iterable[str] = ()
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """``(__getattr__, __dir__)`` of ``package`` (its ``__name__``) for lazily imported names.

    ``where``: name → its module relative to ``package`` (``".build"``, ``"..workspace"``);
    ``submodules``: submodules imported as attributes, when installed; ``namespace``: the
    package's ``globals()``, where a name is stored once imported.
    """
    subs = frozenset(submodules)

    def __getattr__(name: str) -> Any:
        if name in where:
            value = getattr(importlib.import_module(where[name], package), name)
        elif name in subs and importlib.util.find_spec(f"{package}.{name}") is not None:
            value = importlib.import_module(f"{package}.{name}")
        else:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        namespace[name] = value
        return value

    def __dir__() -> list[str]:
        return sorted(set(namespace) | set(where) | subs)

    return __getattr__, __dir__
