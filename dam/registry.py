"""The explicit registry: model name -> synthesizer class.

Entries are ``"module:Class"`` strings so that listing models imports
nothing heavy; a class is imported only when it is asked for. Third-party
models register with :func:`register` or through the ``dam.synthesizers``
entry-point group.
"""
from __future__ import annotations

import importlib

# name -> "module:Class". Keep sorted by family: references, DAM, classical, neural.
_REGISTRY: dict[str, str] = {
    "phone-mean": "baselines.reference:PhoneMean",
    "target-interpolation": "baselines.reference:TargetInterpolation",
    "dam": "dam.model:DAM",
    "dam-m0": "dam.model:DAMM0",
    "cohen-massaro": "baselines.cohen_massaro:CohenMassaro",
    "mmm": "baselines.mmm:MMM",
    "dtree": "baselines.dtree:DecisionTree",
    "sliding-dnn": "baselines.nn.sliding_dnn:SlidingDNN",
    "lstm": "baselines.nn.lstm:FanLSTM",
    "causal-mlp": "baselines.nn.causal_mlp:CausalMLP",
    "gru": "baselines.nn.rnn:RecurrentDecoder",
    "transformer": "baselines.nn.transformer:TransformerDecoder",
}
_LOADED: dict[str, type] = {}

__all__ = ["register", "get", "names", "available"]


def register(name: str, cls_or_path) -> None:
    """Register a synthesizer class (or a ``"module:Class"`` path) under ``name``."""
    if isinstance(cls_or_path, str):
        _REGISTRY[name] = cls_or_path
        _LOADED.pop(name, None)
    else:
        _REGISTRY[name] = f"{cls_or_path.__module__}:{cls_or_path.__qualname__}"
        _LOADED[name] = cls_or_path


def _entry_points() -> None:
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
    if name not in _REGISTRY:
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
