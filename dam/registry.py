"""The explicit registry: model name -> synthesizer class.

Entries are ``"module:Class"`` strings so that listing models imports
nothing heavy; a class is imported only when it is asked for. dam's own
models are listed here; every other synthesizer, the ones in ``baselines/``
included, comes in through the ``dam.synthesizers`` entry-point group
(``pyproject.toml`` lists the baselines there, so that dam never imports
them), or at run time with :func:`register`.
"""

from __future__ import annotations

import contextlib
import importlib

# name -> "module:Class": dam's own; the entry points follow in the order pyproject.toml lists them.
_REGISTRY: dict[str, str] = {
    "dam": "dam.model.estimator:DAM",
    "dam-m0": "dam.model.estimator:DAMM0",
    "dam-paper": "dam.model.estimator:DAMPaper",
}
_LOADED: dict[str, type] = {}
_ENTRY_POINTS_READ = False

__all__ = [
    "register",
    "registered",
    "unregister",
    "get",
    "names",
    "available",
    "make",
    "registered_name",
    "check_params",
    "MissingExtraError",
    "extra_for",
]


class MissingExtraError(ImportError):
    """A model (or feature) needs an optional dependency that is not installed; the message says
    which module is missing and which extra installs it (``pip install "dam[jax]"``)."""


def extra_for(module: str) -> str | None:
    """The extra of dam (pyproject ``optional-dependencies``) that installs ``module``, or None.

    Read from the installed package's metadata, so pyproject.toml stays the one list.
    """
    import re

    top = module.split(".")[0].replace("-", "_").lower()
    try:
        from importlib.metadata import requires

        reqs = requires("dam") or []
    except Exception:  # not installed as a distribution (a bare checkout on sys.path)
        reqs = []
    for req in reqs:
        m = re.match(r"\s*([A-Za-z0-9_.\-]+).*?extra\s*==\s*['\"]([^'\"]+)['\"]", req)
        if m and m.group(1).replace("-", "_").lower() == top and m.group(2) not in ("test", "all"):
            return m.group(2)
    return None


def missing_extra(what: str, exc: ImportError) -> MissingExtraError:
    """``exc`` (raised importing what ``what`` needs) as a MissingExtraError saying what to install."""
    missing = getattr(exc, "name", None) or str(exc)
    extra = extra_for(missing) if missing else None
    hint = f'pip install "dam[{extra}]"' if extra else f"pip install {missing}"
    return MissingExtraError(f"{what} needs the Python module {missing!r}, which is not installed here: {hint}")


def register(name: str, cls_or_path) -> None:
    """Register a synthesizer class (or a ``"module:Class"`` path) under ``name``.

    Examples
    --------
    >>> import dam
    >>> from baselines.reference import PhoneMean
    >>> dam.register("my-phone-mean", PhoneMean)
    >>> type(dam.make("my-phone-mean")).__name__
    'PhoneMean'
    >>> from dam.registry import unregister
    >>> unregister("my-phone-mean")
    """
    if isinstance(cls_or_path, str):
        _REGISTRY[name] = cls_or_path
        _LOADED.pop(name, None)
    else:
        _REGISTRY[name] = f"{cls_or_path.__module__}:{cls_or_path.__qualname__}"
        _LOADED[name] = cls_or_path


def unregister(name: str) -> None:
    """Remove ``name`` (registered with :func:`register`); unknown names are ignored."""
    _REGISTRY.pop(name, None)
    _LOADED.pop(name, None)


@contextlib.contextmanager
def registered(name: str, cls_or_path):
    """Register ``cls_or_path`` under ``name`` for the duration of a ``with`` block only.

    Afterwards the registry is exactly as before (a previous entry of ``name``
    comes back). The conformance suite saves and loads a student's model this way.

    Examples
    --------
    >>> from dam import registry
    >>> from baselines.reference import PhoneMean
    >>> with registry.registered("my-mean", PhoneMean):
    ...     registry.get("my-mean") is PhoneMean
    True
    >>> "my-mean" in registry.names()
    False
    """
    _entry_points()
    missing = object()
    old, old_loaded = _REGISTRY.get(name, missing), _LOADED.get(name, missing)
    register(name, cls_or_path)
    try:
        yield
    finally:
        for table, value in ((_REGISTRY, old), (_LOADED, old_loaded)):
            if value is missing:
                table.pop(name, None)
            else:
                table[name] = value


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
    try:
        obj = importlib.import_module(module)
    except ModuleNotFoundError as exc:
        if exc.name and (exc.name == module or module.startswith(exc.name + ".")):
            raise  # the model's own module is gone: a broken registration, not a missing extra
        raise missing_extra(f"model {name!r}", exc) from exc
    for part in qual.split("."):
        obj = getattr(obj, part)
    _LOADED[name] = obj
    return obj


def registered_name(cls: type) -> str | None:
    """The name ``cls`` is registered under (the first, in registry order), or None.

    Compares imported classes and ``"module:Class"`` paths, so it imports nothing.
    """
    _entry_points()
    path = f"{cls.__module__}:{cls.__qualname__}"
    for name, spec in _REGISTRY.items():
        if _LOADED.get(name) is cls or spec == path:
            return name
    return None


def available(name: str) -> tuple[bool, str]:
    """Whether ``name`` can be imported here, and why not."""
    try:
        get(name)
        return True, ""
    except ImportError as exc:
        return False, str(exc)


def check_params(model):
    """Check ``model``'s hyperparameters now, as ``fit`` would first thing; return ``model``.

    For tools that must refuse bad settings before any work starts (``dam fit``, ``dam compare``).

    Raises
    ------
    ValueError or TypeError
        Naming the model, the parameter, the value and what is allowed.
    """
    check = (
        getattr(model, "validate", None)
        or getattr(model, "_validate_params", None)
        or getattr(model, "_check_params", None)
    )
    if callable(check):
        check()
    return model


def make(name: str, **params):
    """A registered synthesizer by name: ``dam.make("dam", degree=4)``.

    Examples
    --------
    >>> import dam
    >>> dam.make("dam", degree=2, normalize=False)
    DAM(degree=2, normalize=False)
    """
    return get(name)(**params)
