"""dam: speech animation and coarticulation modelling.

Phone timings (and, for some models, audio) go in; frame-wise control
trajectories come out. The core is the Dominated Animeme Model (Chen et al.
2012); beside it stand the models it is compared with, all behind one
interface (:class:`dam.Synthesizer`).

The package's floors, bottom up: :mod:`dam.corpus` (data model and file formats),
:mod:`dam.base` / :mod:`dam.modelfile` / :mod:`dam.registry` (the one interface),
:mod:`dam.model` (the DAM), :mod:`dam.datasets` and :mod:`dam.crossmap`,
:mod:`dam.evaluation`, :mod:`dam.testing` (the conformance suite), and the command
line :mod:`dam.cli` on top. ``import dam`` is light: it imports numpy only;
scipy, scikit-learn, matplotlib and jax are imported by the piece that needs them.

Examples
--------
>>> import dam
>>> train = dam.datasets.load("tiny")
>>> model = dam.make("phone-mean").fit(train)
>>> model.predict(train[0].alignment).shape == train[0].trajectory.shape
True
"""

from __future__ import annotations

from dam import _compat
from dam._lazy import lazy_exports
from dam._version import __version__
from dam.base import (
    ConvergenceWarning,
    Interval,
    InvalidParameterError,
    NotFittedError,
    Options,
    Synthesizer,
    TupleOf,
    UnknownPhoneError,
    clone,
)
from dam.corpus.data import SILENCE, Alignment, Corpus, DataError, Utterance
from dam.modelfile import ModelFileError, StateArray, StateCounts, StateNames, load
from dam.registry import make, register

_compat.install()

_EXPORTS = {
    **dict.fromkeys(["load_corpus", "save_corpus", "read_alignment"], "dam.corpus.io"),
    "evaluate": "dam.evaluation.metrics",
    "compare": "dam.evaluation.compare",
    **dict.fromkeys(["align", "text_to_phones", "animate"], "dam.speech"),
}
_SUBMODULES = (
    "corpus",
    "model",
    "evaluation",
    "crossmap",
    "datasets",
    "testing",
    "registry",
    "base",
    "modelfile",
    "speech",
    "progress",
    "plotting",
    "export",
)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, _SUBMODULES)

__all__ = [
    "Alignment",
    "Utterance",
    "Corpus",
    "Synthesizer",
    "DataError",
    "NotFittedError",
    "ModelFileError",
    "UnknownPhoneError",
    "ConvergenceWarning",
    "InvalidParameterError",
    "Interval",
    "Options",
    "TupleOf",
    "StateArray",
    "StateNames",
    "StateCounts",
    "SILENCE",
    "clone",
    "load",
    "make",
    "register",
    "__version__",
    *_EXPORTS,
]
