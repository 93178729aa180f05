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
import weakref
from dataclasses import dataclass

import numpy as np

from dam._params import Interval, InvalidParameterError, Options, TupleOf, validate_params
from dam.corpus.data import MAX_FRAME_RATE, Alignment, Corpus, DataError, Utterance
from dam.modelfile import ModelFileError, StateCounts, StateNames, load, write_model_file

#: One prediction holds at most this many values (2 GiB of float64; a day at 100 Hz with
#: 300 channels): larger is refused before anything is allocated (issue 12).
MAX_PREDICTION_VALUES = 2**28

# get_tags() of every class asked so far (tags are class constants; weak keys let test classes go)
_TAGS_OF: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()

__all__ = [
    "Estimator",
    "Synthesizer",
    "Transformer",
    "NotFittedError",
    "ModelFileError",
    "UnknownPhoneError",
    "ConvergenceWarning",
    "InvalidParameterError",
    "Interval",
    "Options",
    "TupleOf",
    "Tag",
    "TAGS",
    "clone",
    "load",
    "predict_inputs",
]


class NotFittedError(RuntimeError, AttributeError):
    """Raised when ``predict`` (or similar) is called before ``fit``."""


class ConvergenceWarning(UserWarning):
    """An iterative fit stopped at its iteration limit before meeting its tolerance
    (as scikit-learn's, without importing scikit-learn)."""


class UnknownPhoneError(DataError):
    """A phone the model never saw in training and cannot fall back from."""


@dataclass(frozen=True)
class Tag:
    """One entry of the tag register :data:`TAGS`.

    Attributes
    ----------
    name : str
    type : type
        ``bool`` or ``tuple`` (a tuple of str).
    default
        The value of a class that does not set it.
    meaning : str
        What it says, and which check of :mod:`dam.testing` relies on it.
    values : tuple of str or None
        For tuple tags: the strings allowed in it (None: any).
    """

    name: str
    type: type
    default: object
    meaning: str
    values: tuple | None = None

    def check(self, owner: str, value) -> None:
        """Raise TypeError naming ``owner``, the tag and the value if ``value`` is not a valid value."""
        ok = isinstance(value, self.type) and not (self.type is bool and not isinstance(value, bool))
        if ok and self.type is tuple:
            ok = all(isinstance(v, str) and (self.values is None or v in self.values) for v in value)
        if not ok:
            allowed = (
                f"a tuple of {', '.join(map(repr, self.values))}"
                if self.values
                else ("a tuple of str" if self.type is tuple else "True or False")
            )
            raise TypeError(f"{owner}: tag {self.name!r} is {value!r}; it must be {allowed}")


#: Every tag a synthesizer may set in its ``_tags`` (unknown names are an error).
TAGS: dict[str, Tag] = {
    t.name: t
    for t in (
        Tag(
            "requires",
            tuple,
            (),
            "optional extras of dam the model needs to fit and predict, e.g. ('jax',) "
            '(`pip install "dam[jax]"`); a model whose extra is missing is skipped by `dam compare`',
        ),
        Tag("reads", tuple, ("phones",), "what predict reads: phone timings, and audio", values=("phones", "audio")),
        Tag(
            "deterministic",
            bool,
            True,
            "the same data and parameters (random_state included) give the same model: "
            "check_refit_idempotent asks it; otherwise check_same_seed_same_model",
        ),
        Tag("slow", bool, False, "fitting takes seconds even with get_test_params (the neural models)"),
        Tag(
            "reference",
            bool,
            False,
            "a reference the others are measured against: check_beats_phone_mean does not apply",
        ),
        Tag(
            "numpy_runtime",
            bool,
            False,
            "a saved model loads and predicts with numpy alone (no scipy, "
            "scikit-learn or jax): check_numpy_runtime asks it",
        ),
    )
}


class Estimator:
    """Hyperparameters the scikit-learn way, for every estimator of dam.

    ``__init__`` only stores keyword-only hyperparameters; ``get_params``/``set_params``
    read and write them; ``_parameter_constraints`` declares what each may be (checked by
    :meth:`_validate_params` at the start of ``fit``); ``_preset`` makes a subclass a
    preset of its parent. :class:`Synthesizer` (phones or audio to trajectories) and
    :class:`Transformer` (frames to frames: the cross-mapping estimators) build on it.

    Examples
    --------
    >>> import dam
    >>> from dam.base import Estimator, Interval
    >>> class Smoother(Estimator):
    ...     _parameter_constraints = {"width": [Interval(int, 1, None, closed="left")]}
    ...     def __init__(self, *, width=3):
    ...         self.width = width
    >>> Smoother(width=5)
    Smoother(width=5)
    >>> Smoother(width=0)._validate_params()
    Traceback (most recent call last):
    ...
    dam._params.InvalidParameterError: Smoother: parameter 'width' is 0; it must be an int in [1, inf)
    """

    _parameter_constraints: dict = {}
    _preset: dict = {}

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        if cls.__dict__.get("_preset"):
            _apply_preset(cls, dict(cls.__dict__["_preset"]))

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

    def set_params(self, **params) -> Estimator:
        valid = set(self._param_names())
        for k, v in params.items():
            if k not in valid:
                raise ValueError(
                    f"{type(self).__name__}: unknown parameter {k!r}; valid parameters are {sorted(valid)}"
                )
            setattr(self, k, v)
        return self

    def __repr__(self) -> str:
        defaults = {p.name: p.default for p in inspect.signature(type(self).__init__).parameters.values()}
        changed = {k: v for k, v in self.get_params().items() if not _same(defaults.get(k), v)}
        inner = ", ".join(f"{k}={v!r}" for k, v in changed.items())
        return f"{type(self).__name__}({inner})"

    @classmethod
    def get_parameter_constraints(cls) -> dict:
        """``{parameter: [constraint, ...]}`` of every parameter that declares one (merged down the
        class hierarchy, subclasses overriding)."""
        merged: dict = {}
        for klass in reversed(cls.__mro__):
            merged.update(klass.__dict__.get("_parameter_constraints") or {})
        names = set(cls._param_names())
        return {k: v for k, v in merged.items() if k in names}

    def _validate_params(self) -> None:
        """Check the hyperparameters against their declared constraints, then the relations
        between them (:meth:`_check_param_relations`).

        Raises
        ------
        InvalidParameterError
            Naming the class, the parameter, the value and what is allowed.
        """
        validate_params(type(self).__name__, self.get_parameter_constraints(), self.get_params())
        self._check_param_relations()
        if hasattr(self, "_check_params"):  # dam 0.1's hand-written hook, still honoured; declare constraints instead
            self._check_params()

    def _check_param_relations(self) -> None:
        """Check rules that tie parameters together (override; each parameter alone is
        declared in ``_parameter_constraints``). Raise :class:`InvalidParameterError`."""


class Synthesizer(Estimator):
    """Base class for all synthesizers.

    Class attributes
    ----------------
    name : str
        The registry name (``dam models`` lists them).
    _tags : dict
        Tags of the register :data:`TAGS` (``requires``, ``reads``,
        ``deterministic``, ``slow``, ``reference``, ``numpy_runtime``);
        :meth:`get_tags` merges them over the class hierarchy and checks them.
    _parameter_constraints : dict
        ``{parameter: [constraint, ...]}`` in the vocabulary of
        :mod:`dam._params` (:class:`Interval`, :class:`Options`,
        :class:`TupleOf`, ``"boolean"``, ``"random_state"``, ``"callable"``,
        None, a class); a value must satisfy one of its list. Merged over the
        class hierarchy (this base declares ``unknown_phone``, ``random_state``
        and ``verbose`` for every subclass that has them) and checked at the
        start of :meth:`fit`.
    _preset : dict
        A preset of the parent class: ``class DAMM0(DAM): _preset = {"degree": 0}``
        changes those defaults and nothing else (no ``__init__`` to repeat);
        ``get_params``, ``clone``, ``repr`` and model files see the new defaults.

    Examples
    --------
    A synthesizer of your own: store keyword-only hyperparameters, learn ``*_`` attributes.

    >>> import numpy as np, dam
    >>> class Constant(dam.Synthesizer):
    ...     name = "constant-example"
    ...     def __init__(self, *, offset=0.0):
    ...         self.offset = offset
    ...     def _fit(self, corpus):
    ...         self.mean_ = np.mean(np.vstack([u.trajectory for u in corpus]), axis=0) + self.offset
    ...     def _predict(self, alignment, n_frames):
    ...         return np.tile(self.mean_, (n_frames, 1))
    >>> train = dam.datasets.load("tiny")
    >>> model = Constant(offset=1.0).fit(train)
    >>> model.predict(train[0].alignment).shape == train[0].trajectory.shape
    True
    >>> model.get_params()
    {'offset': 1.0}
    """

    name: str = ""
    _tags: dict = {}
    _parameter_constraints: dict = {
        "unknown_phone": [Options({"error", "fallback"})],
        "random_state": ["random_state"],
        "verbose": [Interval(int, 0, None, closed="left"), "boolean"],
    }
    # What a model file must hold (dam.modelfile.check_state, at save and at load): the
    # state every synthesizer has. A subclass declares its own learned attributes the same
    # way; then its schema is complete and a file holding anything else is refused.
    _state_schema: dict = {
        "frame_rate_": Interval(float, 0, MAX_FRAME_RATE, closed="right"),
        "channels_": StateNames("n_channels"),
        "phone_counts_": StateCounts("n_phones"),
    }
    _state_schema_common = True

    @classmethod
    def get_tags(cls) -> dict:
        """Every tag of :data:`TAGS`: the register's default, overridden down the class hierarchy.

        Raises
        ------
        TypeError
            A class sets a tag the register does not know, or a value of the wrong type.
        """
        cached = _TAGS_OF.get(cls)
        if cached is not None:  # predict reads a tag on every call
            return dict(cached)
        tags = {name: tag.default for name, tag in TAGS.items()}
        for klass in reversed(cls.__mro__):
            for k, v in (klass.__dict__.get("_tags") or {}).items():
                if k not in TAGS:
                    raise TypeError(
                        f"{klass.__name__}: unknown tag {k!r}; the tags are {', '.join(TAGS)} (dam.base.TAGS)"
                    )
                TAGS[k].check(klass.__name__, v)
                tags[k] = v
        _TAGS_OF[cls] = tags
        return dict(tags)

    @classmethod
    def get_test_params(cls) -> list[dict]:
        """Two small settings for the tests (override in subclasses)."""
        return [{}, {}]

    # -- fitting -----------------------------------------------------------
    def fit(self, corpus: Corpus) -> Synthesizer:
        """Learn from ``corpus`` and return ``self``.

        Missing data: where ``Utterance.mask`` marks a value as not observed,
        the trajectory a model sees holds the linear interpolation over time
        of the channel's observed values (never the value the source had
        there, never NaN), so every model fits without special cases and a
        masked value cannot influence any fit. For a model with a per-frame
        loss, fitting the interpolated values is not the same as skipping
        them; models that can skip them exactly do (``phone-mean`` averages
        observed values only; the DAM weights its E- and M-step least squares
        by the mask, while its mode clustering sees the interpolated values).
        """
        if not isinstance(corpus, Corpus):
            raise TypeError(
                f"{type(self).__name__}.fit expects a dam.Corpus, got {type(corpus).__name__}"
                "; build one with dam.Corpus([...]) or dam.load_corpus(path)"
            )
        self._validate_params()
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
        alignment : Alignment, Utterance, or a list of them
            A model that reads audio (:meth:`reads`) takes an Utterance with
            audio or a :class:`dam.corpus.AudioClip` instead.

        Returns
        -------
        ndarray of shape (n_frames, n_channels), or a list of them
            ``n_frames = alignment.n_frames(frame_rate_)`` (of the
            utterance's alignment; of the clip's duration).
        """
        self._check_fitted()
        if isinstance(alignment, (list, tuple)):
            return [self._predict_one(a) for a in alignment]
        return self._predict_one(alignment)

    def reads(self) -> tuple:
        """What :meth:`predict` reads: ``("phones",)`` (alignments) or ``("audio",)``.

        The class tag ``reads``; a model whose input depends on a parameter
        (the neural models' ``encoder``) overrides this. A model that reads
        audio predicts from an :class:`~dam.Utterance` with audio or a
        :class:`dam.corpus.AudioClip`; every model accepts an Utterance.
        """
        return tuple(type(self).get_tags()["reads"])

    def predict_inputs(self, corpus: Corpus) -> list:
        """What :meth:`predict` reads for every utterance of ``corpus``: the utterances
        themselves for a model that reads audio, else their alignments."""
        return list(corpus) if "audio" in self.reads() else corpus.alignments

    def _check_output_size(self, alignment, n_frames: int) -> None:
        """Refuse, before allocating, a prediction of more than :data:`MAX_PREDICTION_VALUES` values."""
        size = n_frames * len(self.channels_)
        if size > MAX_PREDICTION_VALUES:
            raise DataError(
                getattr(alignment, "source", None),
                "duration",
                f"{alignment.duration:g} s",
                f"{n_frames} frames x {len(self.channels_)} channels at {self.frame_rate_:g} Hz "
                f"exceed the {MAX_PREDICTION_VALUES} values one prediction may hold",
                "split the alignment into utterances",
            )

    def _predict_one(self, alignment) -> np.ndarray:
        audio = "audio" in self.reads()
        if isinstance(alignment, Utterance) and not audio:
            alignment = alignment.alignment  # a phone-driven model reads the utterance's alignment
        if isinstance(alignment, Alignment):
            n = alignment.n_frames(self.frame_rate_)
            self._check_output_size(alignment, n)
            out = np.asarray(self._predict(alignment, n), dtype=float)
        else:
            from dam.corpus.formats.audio import AudioClip

            if not (audio and isinstance(alignment, (Utterance, AudioClip))):
                raise TypeError(
                    f"{type(self).__name__}.predict expects a dam.Alignment, a dam.Utterance"
                    f"{' or a dam.corpus.AudioClip' if audio else ''} (or a list of them), "
                    f"got {type(alignment).__name__}"
                )
            timing = alignment.alignment if isinstance(alignment, Utterance) else alignment
            n = timing.n_frames(self.frame_rate_)
            self._check_output_size(timing, n)
            out = np.asarray(self._predict_audio(alignment, n), dtype=float)
        if out.shape != (n, len(self.channels_)):
            raise RuntimeError(f"{type(self).__name__} produced shape {out.shape}, expected {(n, len(self.channels_))}")
        if not np.isfinite(out.sum()) and not np.isfinite(out).all():  # one reduction when all is finite
            raise RuntimeError(f"{type(self).__name__} produced non-finite values for {alignment!r}")
        return out

    def _predict(self, alignment: Alignment, n_frames: int) -> np.ndarray:  # pragma: no cover
        raise NotImplementedError

    def _predict_audio(self, source, n_frames: int) -> np.ndarray:  # pragma: no cover - audio models only
        """Prediction from an Utterance with audio or an AudioClip (models whose :meth:`reads` has "audio")."""
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
                raise ValueError(
                    f"{type(self).__name__}: parameter 'unknown_phone' is {unknown_phone!r}; use 'error' or 'fallback'"
                )
            if sub is None:
                raise UnknownPhoneError(
                    alignment.source,
                    f"segment {i} label",
                    lab,
                    "phone not seen in training",
                    f"known phones: {' '.join(counts)}; pass unknown_phone='fallback' "
                    "to substitute a phone of the same class",
                )
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
    def load(cls, path) -> Synthesizer:
        model = load(path)
        if not isinstance(model, cls):
            raise ModelFileError(f"{path}: holds a {type(model).__name__}, not a {cls.__name__}")
        return model


class Transformer(Estimator):
    """Base class of the frame-to-frame estimators (:mod:`dam.crossmap`): ``fit(X)`` learns
    attributes ending in ``_`` and returns ``self``; ``transform(X)`` maps frames; ``X`` is an
    array of frames or a :class:`~dam.Corpus`. The same hyperparameter machinery as
    :class:`Synthesizer` (:class:`Estimator`), so ``dam.clone`` and scikit-learn's ``clone``
    and pipelines work on both.
    """

    def fit(self, X, y=None) -> Transformer:  # pragma: no cover - abstract
        raise NotImplementedError

    def transform(self, X):  # pragma: no cover - abstract
        raise NotImplementedError

    def fit_transform(self, X, y=None):
        """``fit(X)`` then ``transform(X)``."""
        return self.fit(X, y).transform(X)


def predict_inputs(model, corpus: Corpus) -> list:
    """What ``model.predict`` reads for every utterance of ``corpus`` (see
    :meth:`Synthesizer.predict_inputs`); alignments for a model without that method."""
    method = getattr(model, "predict_inputs", None)
    return method(corpus) if method is not None else corpus.alignments


def clone(estimator: Estimator) -> Estimator:
    """An unfitted copy of ``estimator`` with the same hyperparameters (deep-copied).

    Examples
    --------
    >>> import dam
    >>> model = dam.make("dam", degree=2)
    >>> copy = dam.clone(model)
    >>> copy is model, copy.get_params() == model.get_params()
    (False, True)
    """
    return type(estimator)(**copy.deepcopy(estimator.get_params()))


def _apply_preset(cls: type, preset: dict) -> None:
    """Give ``cls`` its parent's ``__init__`` with the defaults of ``preset`` (see ``Estimator._preset``)."""
    if "__init__" in cls.__dict__:
        raise TypeError(f"{cls.__name__}: a preset declares _preset and no __init__ of its own")
    parent_init = cls.__init__
    sig = inspect.signature(parent_init)
    unknown = sorted(set(preset) - set(sig.parameters) - {"self"})
    if unknown:
        raise TypeError(
            f"{cls.__name__}: _preset names {unknown}, which are not parameters of {cls.__mro__[1].__name__}"
        )

    def __init__(self, **params):
        parent_init(self, **{**preset, **params})

    __init__.__signature__ = sig.replace(
        parameters=[p.replace(default=preset[p.name]) if p.name in preset else p for p in sig.parameters.values()]
    )
    __init__.__qualname__ = f"{cls.__qualname__}.__init__"
    __init__.__module__ = cls.__module__
    __init__.__doc__ = (
        f"Parameters as :class:`{cls.__mro__[1].__name__}`, with the defaults "
        + ", ".join(f"{k}={v!r}" for k, v in preset.items())
        + "."
    )
    cls.__init__ = __init__


def _same(a, b) -> bool:
    try:
        return bool(a == b) if not isinstance(a, np.ndarray) else False
    except Exception:
        return False
