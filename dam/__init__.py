"""dam: speech animation and coarticulation modelling.

Phone timings (and, for some models, audio) go in; frame-wise control
trajectories come out. The core is the Dominated Animeme Model (Chen et al.
2012); beside it stand the models it is compared with, all behind one
interface (:class:`dam.Synthesizer`).

``import dam`` is light: it imports numpy only. Everything else (scipy,
scikit-learn, matplotlib, jax) is imported by the piece that needs it.
"""
from __future__ import annotations

__version__ = "0.1.0"

from .data import SILENCE, Alignment, Corpus, DataError, Utterance  # noqa: E402
from .base import ModelFileError, NotFittedError, Synthesizer, UnknownPhoneError, load  # noqa: E402
from .registry import register  # noqa: E402

_LAZY = {
    "load_corpus": ("dam.io", "load_corpus"),
    "save_corpus": ("dam.io", "save_corpus"),
    "read_alignment": ("dam.io", "read_alignment"),
    "evaluate": ("dam.metrics", "evaluate"),
    "datasets": ("dam.datasets", None),
    "testing": ("dam.testing", None),
    "registry": ("dam.registry", None),
}


def __getattr__(name):
    if name in _LAZY:
        import importlib
        module, attr = _LAZY[name]
        mod = importlib.import_module(module)
        return mod if attr is None else getattr(mod, attr)
    raise AttributeError(f"module 'dam' has no attribute {name!r}")


def __dir__():
    return sorted(list(globals()) + list(_LAZY))


def make(name: str, **params) -> Synthesizer:
    """A registered synthesizer by name: ``dam.make("dam", degree=4)``."""
    from .registry import get
    return get(name)(**params)


__all__ = ["Alignment", "Utterance", "Corpus", "Synthesizer", "DataError", "NotFittedError",
           "ModelFileError", "UnknownPhoneError", "SILENCE", "load", "make", "register", *_LAZY]
