"""The one interface every synthesizer follows.

A synthesizer is a scikit-learn style estimator: ``__init__`` stores
keyword-only hyperparameters and does nothing else; ``fit(corpus)`` learns
attributes whose names end in ``_`` and returns ``self``;
``predict(alignment)`` returns an array of shape ``(n_frames, n_channels)``
at the training frame rate (a list in, a list out).

Subclasses implement ``_fit(corpus)`` and ``_predict(alignment, n_frames)``;
the base class does the validation and the bookkeeping, and
:mod:`dam.modelfile` the file format.
"""
from __future__ import annotations

import copy
import inspect
import os

import numpy as np

from dam.corpus.data import Alignment, Corpus, DataError
from dam.modelfile import ModelFileError, load, write_model_file

__all__ = ["Synthesizer", "NotFittedError", "ModelFileError", "UnknownPhoneError", "ConvergenceWarning",
           "clone", "load"]


class NotFittedError(RuntimeError, AttributeError):
    """Raised when ``predict`` (or similar) is called before ``fit``."""


class ConvergenceWarning(UserWarning):
    """An iterative fit stopped at its iteration limit before meeting its tolerance
    (as scikit-learn's, without importing scikit-learn)."""


class UnknownPhoneError(DataError):
    """A phone the model never saw in training and cannot fall back from."""


class Synthesizer:
    """Base class for all synthesizers.

    Class attributes
    ----------------
    name : str
        The registry name (``dam models`` lists them).
    _tags : dict
        ``requires`` (tuple of optional extras, e.g. ``("jax",)``), ``reads``
        (``("phones",)`` or ``("phones", "audio")``), ``deterministic``
        (bool: same data and params give the same model), ``slow`` (bool:
        fitting takes long enough that the conformance suite uses
        ``get_test_params``).
    """

    name: str = ""
    _tags: dict = {}
    _default_tags = {"requires": (), "reads": ("phones",), "deterministic": True, "slow": False,
                     "reference": False}

    # -- hyperparameters (scikit-learn conventions) ------------------------
    @classmethod
    def _param_names(cls) -> list[str]:
        sig = inspect.signature(cls.__init__)
        names = []
        for p in sig.parameters.values():
            if p.name == "self" or p.kind in (p.VAR_KEYWORD, p.VAR_POSITIONAL):
                continue
            names.append(p.name)
        return sorted(names)

    def get_params(self, deep: bool = True) -> dict:
        """Hyperparameters as a dict (``deep`` is accepted for compatibility)."""
        return {k: getattr(self, k) for k in self._param_names()}

    def set_params(self, **params) -> "Synthesizer":
        valid = set(self._param_names())
        for k, v in params.items():
            if k not in valid:
                raise ValueError(f"{type(self).__name__}: unknown parameter {k!r}; "
                                 f"valid parameters are {sorted(valid)}")
            setattr(self, k, v)
        return self

    def __repr__(self) -> str:
        defaults = {p.name: p.default for p in inspect.signature(type(self).__init__).parameters.values()}
        changed = {k: v for k, v in self.get_params().items() if not _same(defaults.get(k), v)}
        inner = ", ".join(f"{k}={v!r}" for k, v in changed.items())
        return f"{type(self).__name__}({inner})"

    @classmethod
    def get_tags(cls) -> dict:
        tags = dict(Synthesizer._default_tags)
        for klass in reversed(cls.__mro__):
            tags.update(getattr(klass, "_tags", {}) or {})
        return tags

    @classmethod
    def get_test_params(cls) -> list[dict]:
        """Two small settings for the tests (override in subclasses)."""
        return [{}, {}]

    # -- fitting -----------------------------------------------------------
    def fit(self, corpus: Corpus) -> "Synthesizer":
        """Learn from ``corpus`` and return ``self``."""
        if not isinstance(corpus, Corpus):
            raise TypeError(f"{type(self).__name__}.fit expects a dam.Corpus, got {type(corpus).__name__}"
                            "; build one with dam.Corpus([...]) or dam.load_corpus(path)")
        self._check_params()
        self._forget_learned()
        self.frame_rate_ = corpus.frame_rate
        self.channels_ = list(corpus.channels)
        counts: dict[str, int] = {}
        for a in corpus.alignments:
            for lab in a.labels:
                counts[lab] = counts.get(lab, 0) + 1
        self.phone_counts_ = dict(sorted(counts.items()))
        try:
            self._fit(corpus)
        except BaseException:
            self._forget_learned()  # a failed fit leaves an unfitted model, not a half-fitted one
            raise
        return self

    def _forget_learned(self) -> None:
        """Delete every learned attribute (public names ending in ``_``)."""
        for k in [k for k in vars(self) if k.endswith("_") and not k.startswith("_")]:
            delattr(self, k)

    def _check_params(self) -> None:
        """Validate hyperparameters before fitting (override)."""

    def _fit(self, corpus: Corpus) -> None:  # pragma: no cover - abstract
        raise NotImplementedError

    # -- prediction --------------------------------------------------------
    def is_fitted(self) -> bool:
        return hasattr(self, "frame_rate_")

    def _check_fitted(self) -> None:
        if not self.is_fitted():
            raise NotFittedError(f"this {type(self).__name__} is not fitted yet; call fit(corpus) first")

    def predict(self, alignment):
        """Synthesize trajectories.

        Parameters
        ----------
        alignment : Alignment or list of Alignment

        Returns
        -------
        ndarray of shape (n_frames, n_channels), or a list of them
            ``n_frames = alignment.n_frames(frame_rate_)``.
        """
        self._check_fitted()
        if isinstance(alignment, (list, tuple)):
            return [self._predict_one(a) for a in alignment]
        return self._predict_one(alignment)

    def _predict_one(self, alignment) -> np.ndarray:
        if not isinstance(alignment, Alignment):
            raise TypeError(f"{type(self).__name__}.predict expects a dam.Alignment (or a list of them), "
                            f"got {type(alignment).__name__}")
        n = alignment.n_frames(self.frame_rate_)
        out = np.asarray(self._predict(alignment, n), dtype=float)
        if out.shape != (n, len(self.channels_)):
            raise RuntimeError(f"{type(self).__name__} produced shape {out.shape}, expected {(n, len(self.channels_))}")
        if not np.all(np.isfinite(out)):
            raise RuntimeError(f"{type(self).__name__} produced non-finite values for {alignment!r}")
        return out

    def _predict(self, alignment: Alignment, n_frames: int) -> np.ndarray:  # pragma: no cover
        raise NotImplementedError

    @property
    def phones_(self) -> list[str]:
        """Phones seen in training, sorted."""
        self._check_fitted()
        return list(self.phone_counts_)

    def _known_labels(self, alignment: Alignment, unknown_phone: str = "error") -> list[str]:
        """Labels of ``alignment`` with unseen phones resolved.

        ``unknown_phone="error"`` raises UnknownPhoneError naming the segment;
        ``"fallback"`` follows :func:`dam.phonetics.fallback_phone` (same phone
        without stress, then the most frequent seen phone of its class, then
        silence) and raises only if every step fails.
        """
        counts = self.phone_counts_
        out = []
        for i, lab in enumerate(alignment.labels):
            if lab in counts:
                out.append(lab)
                continue
            sub = None
            if unknown_phone == "fallback":
                from dam.corpus.phonetics import fallback_phone
                sub = fallback_phone(lab, counts, alignment.silence)
            elif unknown_phone != "error":
                raise ValueError(f"{type(self).__name__}: parameter 'unknown_phone' is {unknown_phone!r}; "
                                 "use 'error' or 'fallback'")
            if sub is None:
                raise UnknownPhoneError(alignment.source, f"segment {i} label", lab,
                                        "phone not seen in training",
                                        f"known phones: {' '.join(counts)}; pass unknown_phone='fallback' "
                                        "to substitute a phone of the same class")
            out.append(sub)
        return out

    def score(self, corpus: Corpus) -> float:
        """Negative overall RMSE on ``corpus`` (higher is better, as scikit-learn scorers)."""
        from dam.evaluation.metrics import evaluate
        return -evaluate(self, corpus).rmse

    # -- persistence -------------------------------------------------------
    def _get_state(self) -> dict:
        """Learned state as JSON-able values and numpy arrays (override for exotic state)."""
        return {k: v for k, v in vars(self).items() if k.endswith("_") and not k.startswith("_")}

    def _set_state(self, state: dict) -> None:
        for k, v in state.items():
            setattr(self, k, v)

    def save(self, path: str | os.PathLike) -> None:
        """Write the fitted model to ``path`` (npz + JSON; see :mod:`dam.modelfile`)."""
        self._check_fitted()
        write_model_file(self, path)

    @classmethod
    def load(cls, path) -> "Synthesizer":
        model = load(path)
        if not isinstance(model, cls):
            raise ModelFileError(f"{path}: holds a {type(model).__name__}, not a {cls.__name__}")
        return model


def clone(estimator: Synthesizer) -> Synthesizer:
    """An unfitted copy of ``estimator`` with the same hyperparameters (deep-copied)."""
    return type(estimator)(**copy.deepcopy(estimator.get_params()))


def _same(a, b) -> bool:
    try:
        return bool(a == b) if not isinstance(a, np.ndarray) else False
    except Exception:
        return False


