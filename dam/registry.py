"""The explicit registry: model name -> synthesizer class.

Entries are ``"module:Class"`` strings so that listing models imports
nothing heavy; a class is imported only when it is asked for. dam's own
models are listed here; every other synthesizer, the ones in ``baselines/``
included, comes in through the ``dam.synthesizers`` entry-point group
(``pyproject.toml`` lists the baselines there, so that dam never imports
them), or at run time with :func:`register`.
"""
from __future__ import annotations

import importlib

# name -> "module:Class": dam's own; the entry points follow in the order pyproject.toml lists them.
_REGISTRY: dict[str, str] = {
    "dam": "dam.model.estimator:DAM",
    "dam-m0": "dam.model.estimator:DAMM0",
}
_LOADED: dict[str, type] = {}
_ENTRY_POINTS_READ = False

__all__ = ["register", "get", "names", "available", "make"]


def register(name: str, cls_or_path) -> None:
    """Register a synthesizer class (or a ``"module:Class"`` path) under ``name``."""
    if isinstance(cls_or_path, str):
        _REGISTRY[name] = cls_or_path
        _LOADED.pop(name, None)
    else:
        _REGISTRY[name] = f"{cls_or_path.__module__}:{cls_or_path.__qualname__}"
        _LOADED[name] = cls_or_path


def _entry_points() -> None:
    global _ENTRY_POINTS_READ
    if _ENTRY_POINTS_READ:
        return
    _ENTRY_POINTS_READ = True
    try:
        from importlib.metadata import entry_points
        for ep in entry_points(group="dam.synthesizers"):
            _REGISTRY.setdefault(ep.name, ep.value)
    except Exception:  # a broken third-party entry point must not break dam
        pass


def names() -> list[str]:
    """All registered names, in registry order."""
    _entry_points()
    return list(_REGISTRY)


def get(name: str) -> type:
    """The class registered under ``name``; KeyError with the known names otherwise."""
    if name in _LOADED:
        return _LOADED[name]
    _entry_points()
    if name not in _REGISTRY:
        raise KeyError(f"unknown model {name!r}; known models: {', '.join(_REGISTRY)} (see `dam models`)")
    module, _, qual = _REGISTRY[name].partition(":")
    obj = importlib.import_module(module)
    for part in qual.split("."):
        obj = getattr(obj, part)
    _LOADED[name] = obj
    return obj


def available(name: str) -> tuple[bool, str]:
    """Whether ``name`` can be imported here, and why not."""
    try:
        get(name)
        return True, ""
    except ImportError as exc:
        return False, str(exc)


def make(name: str, **params):
    """A registered synthesizer by name: ``dam.make("dam", degree=4)``."""
    return get(name)(**params)
