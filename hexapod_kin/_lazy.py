"""A package's names imported from their submodules on first access (PEP 562)."""

from __future__ import annotations

import importlib
from collections.abc import Callable
from typing import Any

__all__ = ["lazy_names"]


def lazy_names(
    package: str, where: dict[str, str], namespace: dict[str, Any]
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """The ``__getattr__`` and ``__dir__`` of ``package`` for its lazily imported names.

    Args:
        package: The package's ``__name__``.
        where: Name → the module defining it, relative to ``package`` (``".build"``,
            ``"..workspace"``).
        namespace: The package's ``globals()``: a name is stored there once imported.

    Returns:
        ``(__getattr__, __dir__)``; ``__getattr__`` raises :class:`AttributeError` for a
        name not in ``where``.

    """

    def __getattr__(name: str) -> Any:
        if name not in where:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(where[name], package), name)
        namespace[name] = value
        return value

    def __dir__() -> list[str]:
        return sorted(set(namespace) | set(where))

    return __getattr__, __dir__
