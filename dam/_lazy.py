"""Lazy re-exports for package ``__init__`` files: a name is imported when first used.

Keeps ``import dam`` (and ``import dam.corpus``) light: scipy, praatio, scikit-learn and
matplotlib are imported only by the piece that needs them.
"""

from __future__ import annotations

import importlib


def lazy_exports(package: str, exports: dict[str, str], submodules=()):
    """``__getattr__`` and ``__dir__`` for ``package``, importing on first use.

    ``exports`` maps a name to the module that defines it (relative to ``package``,
    ``".io"``, or absolute); ``submodules`` are names of ``package``'s own modules.
    """
    submodules = frozenset(submodules)

    def __getattr__(name: str):
        if name in submodules:
            return importlib.import_module(f"{package}.{name}")
        if name not in exports:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        return getattr(importlib.import_module(exports[name], package), name)

    def __dir__():
        mod = importlib.import_module(package)
        return sorted(set(vars(mod)) | set(exports) | submodules)

    return __getattr__, __dir__
