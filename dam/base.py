"""The one interface every synthesizer follows, and the model file format.

A synthesizer is a scikit-learn style estimator: ``__init__`` stores
keyword-only hyperparameters and does nothing else; ``fit(corpus)`` learns
attributes whose names end in ``_`` and returns ``self``;
``predict(alignment)`` returns an array of shape ``(n_frames, n_channels)``
at the training frame rate (a list in, a list out).

Subclasses implement ``_fit(corpus)`` and ``_predict(alignment, n_frames)``;
the base class does the validation, the bookkeeping and the file format.

Model file format (version 1)
-----------------------------
A ``.npz`` archive (zip of ``.npy`` arrays, read with ``allow_pickle=False``):

* ``__dam__``: uint8 array holding UTF-8 JSON
  ``{"format": "dam-model", "version": 1, "model": <registry name>,
  "params": {...}, "state": {...}, "dam_version": ...}``.
  In ``state``, an array is referenced as ``{"__array__": "<key>"}``.
* every other key: a numeric array of the learned state.

Nothing is ever unpickled; a file that is not such an archive is refused.
"""
from __future__ import annotations

import inspect
import json
import os
import zipfile
from typing import Any

import numpy as np

from .data import Alignment, Corpus, DataError

FORMAT = "dam-model"
FORMAT_VERSION = 1
META_KEY = "__dam__"

__all__ = ["Synthesizer", "NotFittedError", "ModelFileError", "UnknownPhoneError", "ConvergenceWarning",
           "load", "FORMAT_VERSION"]


class NotFittedError(RuntimeError, AttributeError):
    """Raised when ``predict`` (or similar) is called before ``fit``."""


class ConvergenceWarning(UserWarning):
    """An iterative fit stopped at its iteration limit before meeting its tolerance
    (as scikit-learn's, without importing scikit-learn)."""


class ModelFileError(ValueError):
    """A model file that is corrupt, foreign or from an unknown version."""


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
                from .phonetics import fallback_phone
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
        from .metrics import evaluate
        return -evaluate(self, corpus).rmse

    # -- persistence -------------------------------------------------------
    def _get_state(self) -> dict:
        """Learned state as JSON-able values and numpy arrays (override for exotic state)."""
        return {k: v for k, v in vars(self).items() if k.endswith("_") and not k.startswith("_")}

    def _set_state(self, state: dict) -> None:
        for k, v in state.items():
            setattr(self, k, v)

    def save(self, path: str | os.PathLike) -> None:
        """Write the fitted model to ``path`` (npz + JSON; see module docstring)."""
        self._check_fitted()
        arrays: dict[str, np.ndarray] = {}
        meta = {"format": FORMAT, "version": FORMAT_VERSION, "model": self.name or type(self).__name__,
                "class": f"{type(self).__module__}.{type(self).__qualname__}",
                "dam_version": _version(), "params": _encode(self.get_params(), arrays),
                "state": _encode(self._get_state(), arrays)}
        arrays[META_KEY] = np.frombuffer(json.dumps(meta).encode("utf-8"), dtype=np.uint8)
        path = os.fspath(path)
        with open(path, "wb") as fh:  # a file handle keeps numpy from appending ".npz"
            np.savez_compressed(fh, **arrays)

    @classmethod
    def load(cls, path) -> "Synthesizer":
        model = load(path)
        if not isinstance(model, cls):
            raise ModelFileError(f"{path}: holds a {type(model).__name__}, not a {cls.__name__}")
        return model


def _same(a, b) -> bool:
    try:
        return bool(a == b) if not isinstance(a, np.ndarray) else False
    except Exception:
        return False


def _version() -> str:
    from . import __version__
    return __version__


def _encode(obj: Any, arrays: dict) -> Any:
    """JSON-able form of ``obj``; arrays go to ``arrays`` and are referenced."""
    if isinstance(obj, np.ndarray) or (hasattr(obj, "__array__") and not isinstance(obj, (str, bytes))
                                       and not np.isscalar(obj)):
        arr = np.asarray(obj)
        if arr.dtype == object:
            raise TypeError("object arrays cannot be saved; convert to numeric or a list of str")
        key = f"a{len(arrays)}"
        arrays[key] = arr
        return {"__array__": key}
    if isinstance(obj, dict):
        if not all(isinstance(k, str) for k in obj):
            return {"__dict_items__": [[_encode(k, arrays), _encode(v, arrays)] for k, v in obj.items()]}
        return {k: _encode(v, arrays) for k, v in obj.items()}
    if isinstance(obj, tuple):
        return {"__tuple__": [_encode(v, arrays) for v in obj]}
    if isinstance(obj, list):
        return [_encode(v, arrays) for v in obj]
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, (np.floating,)):
        return float(obj)
    if isinstance(obj, (np.bool_,)):
        return bool(obj)
    if obj is None or isinstance(obj, (str, int, float, bool)):
        return obj
    raise TypeError(f"cannot save a value of type {type(obj).__name__}; override _get_state")


def _decode(obj: Any, arrays) -> Any:
    if isinstance(obj, dict):
        if "__array__" in obj and len(obj) == 1:
            return np.array(arrays[obj["__array__"]])
        if "__tuple__" in obj and len(obj) == 1:
            return tuple(_decode(v, arrays) for v in obj["__tuple__"])
        if "__dict_items__" in obj and len(obj) == 1:
            return {_decode(k, arrays): _decode(v, arrays) for k, v in obj["__dict_items__"]}
        return {k: _decode(v, arrays) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_decode(v, arrays) for v in obj]
    return obj


def read_model_file(path) -> tuple[dict, Any]:
    """Open and check a model file; return ``(meta, arrays)``. numpy only."""
    path = os.fspath(path)
    if not os.path.exists(path):
        raise ModelFileError(f"{path}: no such model file")
    with open(path, "rb") as fh:
        magic = fh.read(4)
    if magic != b"PK\x03\x04":
        raise ModelFileError(f"{path}: not a dam model file (it is not an npz archive; first bytes {magic!r}); "
                             "write model files with model.save(path) or `dam fit`")
    try:
        arrays = np.load(path, allow_pickle=False)
    except (zipfile.BadZipFile, ValueError, OSError, EOFError) as exc:
        raise ModelFileError(f"{path}: not a dam model file (not a readable npz archive: {exc})") from None
    if not hasattr(arrays, "files") or META_KEY not in arrays.files:
        raise ModelFileError(f"{path}: not a dam model file (field {META_KEY!r} missing); "
                             "write model files with model.save(path) or `dam fit`")
    try:
        meta = json.loads(bytes(arrays[META_KEY]).decode("utf-8"))
    except Exception as exc:
        raise ModelFileError(f"{path}: field {META_KEY!r} is not valid JSON ({exc})") from None
    if not isinstance(meta, dict) or meta.get("format") != FORMAT:
        raise ModelFileError(f"{path}: field 'format' is {meta.get('format') if isinstance(meta, dict) else meta!r}, "
                             f"expected {FORMAT!r}")
    version = meta.get("version")
    if not isinstance(version, int) or version > FORMAT_VERSION or version < 1:
        raise ModelFileError(f"{path}: field 'version' is {version!r}; this dam reads versions 1..{FORMAT_VERSION}"
                             " (upgrade dam to read newer files)")
    for fld in ("model", "params", "state"):
        if fld not in meta:
            raise ModelFileError(f"{path}: field {fld!r} missing")
    return meta, arrays


def load(path) -> Synthesizer:
    """Load a model written by ``Synthesizer.save``.

    Raises
    ------
    ModelFileError
        The file is missing, corrupt, foreign or of an unknown version.
    """
    from .registry import get
    meta, arrays = read_model_file(path)
    try:
        cls = get(meta["model"])
    except KeyError as exc:
        raise ModelFileError(f"{path}: field 'model' is {meta['model']!r}, which is not registered ({exc})") from None
    try:
        params = _decode(meta["params"], arrays)
        state = _decode(meta["state"], arrays)
        model = cls(**params)
        model._set_state(state)
    except (KeyError, TypeError, ValueError) as exc:
        raise ModelFileError(f"{path}: the stored {meta['model']!r} model is damaged ({type(exc).__name__}: {exc})") from None
    return model
