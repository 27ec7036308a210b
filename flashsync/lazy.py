"""Lazy package exports (PEP 562): a package names what it exports without importing it.

``import flashsync`` then costs nothing beyond the standard library, and each command loads
only the modules it uses (``flashsync --help`` starts in well under a second), while
``from flashsync import synchronize`` keeps working.
"""

from __future__ import annotations

import sys
import types
from collections.abc import Mapping
from importlib import import_module


def lazy_exports(package: str, exports: Mapping[str, str]) -> None:
    """Make the package ``package`` import each export on first use.

    Parameters
    ----------
    package : the package's ``__name__`` (call this at the end of its ``__init__``).
    exports : each exported name and the module that defines it.

    An export named like a submodule (``tracking_adapter.restamp``, the function, from
    ``tracking_adapter/restamp.py``) stays the export when the submodule is imported, as it
    did when ``__init__`` imported it eagerly.
    """

    class LazyPackage(types.ModuleType):
        def __getattr__(self, name: str):
            if name not in exports:
                raise AttributeError(f"module {package!r} has no attribute {name!r}")
            value = getattr(import_module(exports[name]), name)
            super().__setattr__(name, value)
            return value

        def __setattr__(self, name: str, value) -> None:
            if name in exports and getattr(value, "__name__", None) == f"{package}.{name}":
                return  # the import system binding the submodule: the export keeps the name
            super().__setattr__(name, value)

        def __dir__(self) -> list[str]:
            return sorted({*self.__dict__, *exports})

    sys.modules[package].__class__ = LazyPackage
