"""Names a package exports that load with their module on first use (PEP 562): a drawing's
process imports only the modules it draws with."""

from __future__ import annotations

import importlib
from collections.abc import Callable


def lazy_names(package: str, exports: dict[str, str], space: dict) -> tuple[Callable, Callable]:
    """A package's ``__getattr__`` and ``__dir__`` for ``exports`` (name -> module), each name
    kept in the package's namespace ``space`` once loaded."""

    def __getattr__(name: str):
        module = exports.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(module), name)
        space[name] = value
        return value

    def __dir__() -> list[str]:
        return sorted([*space, *exports])

    return __getattr__, __dir__
