"""Lazy package exports (PEP 562): a package names what it exports without importing it.

``import flashsync`` then costs nothing beyond the standard library, and each command loads
only the modules it uses (``flashsync --help`` starts in well under a second), while
``from flashsync import synchronize`` keeps working.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from importlib import import_module


def lazy_exports(package: str, namespace: dict, exports: Mapping[str, str]) -> tuple[Callable, Callable]:
    """A package's ``__getattr__`` and ``__dir__`` that import each export on first use.

    Parameters
    ----------
    package : the package's ``__name__``.
    namespace : the package's ``globals()``; an export is cached there once imported.
    exports : each exported name and the module that defines it.

    Returns
    -------
    (__getattr__, __dir__) to assign at the package's module level.
    """

    def __getattr__(name: str):
        if name not in exports:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(import_module(exports[name]), name)
        namespace[name] = value
        return value

    def __dir__() -> list[str]:
        return sorted({*namespace, *exports})

    return __getattr__, __dir__
