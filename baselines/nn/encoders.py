"""The input-encoder slot of the neural predictors.

Medina et al. (2022) split a predictor into an *encoder* (phones, MFCC,
DeepSpeech2 or Wav2Vec features, one vector per frame) and a *decoder*
(MLP, RNN, Transformer). The decoders here read their input only through
an encoder object with two methods:

``frames(alignment, frame_rate, n_frames) -> (n_frames, n_features)``
    One feature vector per frame (the recurrent decoders read this).
``windows(alignment, frame_rate, n_frames, *, k, align, features, dilation) -> (n_frames, k * n_features')``
    The ``k``-frame input window of every frame, flattened frame by frame
    (the sliding-window decoders read this; reshaping to ``(n_frames, k, -1)``
    gives the per-frame vectors of the window when ``features="raw"``).

What the decoders pass as ``source`` is whatever the encoder reads: an
:class:`~dam.Alignment` or an :class:`~dam.Utterance` for ``phones``; an
:class:`~dam.Utterance` with audio (``Utterance.audio``) or an
:class:`AudioClip` for the audio encoders, which refuse anything else naming
the utterance. The encoders:

``phones``
    One-hot phone per frame (or Taylor et al.'s linguistic window features).
``mfcc``, ``fbank``, ``mfcc-mfb-ssc``
    MFCC, log mel filterbank energies, or VisemeNet's MFCC + filterbank +
    subband centroids, of the utterance's audio, one vector per trajectory
    frame (:mod:`baselines.nn.acoustic`), standardized with the training
    corpus's mean and standard deviation.
``features``
    User-supplied frame-wise features (wav2vec 2.0, DeepSpeech activations,
    ...) read from ``<stem>.features.npy`` beside each utterance, shape
    ``(n, dim)`` at ``features_rate`` Hz (default: the trajectory frame
    rate); the toolkit never downloads a model.

An encoder is rebuilt from JSON-able state (``state()`` / ``from_state``),
so a saved model never pickles it. A new encoder registers in
:data:`ENCODERS` and needs no decoder change.
"""

from __future__ import annotations

import os

import numpy as np

from dam import Alignment, Corpus, DataError, Options, Utterance
from dam.corpus import AudioClip

__all__ = [
    "PhoneEncoder",
    "AudioClip",
    "AudioEncoder",
    "MFCCEncoder",
    "FbankEncoder",
    "ZhouEncoder",
    "FeaturesEncoder",
    "ENCODERS",
    "make_encoder",
    "encoder_from_state",
    "encoder_reads",
    "has_audio",
    "EncoderSpec",
    "FEATURES_SUFFIX",
]


class PhoneEncoder:
    """One-hot phone identity per frame (Taylor et al.'s raw features), or
    their linguistic indicator features over a window.

    Parameters
    ----------
    vocabulary : list of str
        The phone set (:func:`dam.features.phone_vocabulary`), silence included.

    Notes
    -----
    Features are 0/1 indicators, so they are returned as ``uint8``
    (``binary = True``); the networks cast them to float32 per batch, which
    keeps the 2,379-wide linguistic windows of a 10-minute corpus in memory.
    """

    name = "phones"
    reads = ("phones",)
    binary = True

    def __init__(self, vocabulary):
        self.vocabulary = list(vocabulary)

    @classmethod
    def fit(cls, corpus: Corpus) -> PhoneEncoder:
        from dam.corpus import phone_vocabulary

        return cls(phone_vocabulary(corpus))

    def state(self) -> dict:
        return {"name": self.name, "vocabulary": list(self.vocabulary)}

    @property
    def n_features(self) -> int:
        return len(self.vocabulary)

    def frames(self, source, frame_rate: float, n_frames: int) -> np.ndarray:
        """One-hot phone of every frame, shape (n_frames, len(vocabulary)), uint8."""
        from dam.corpus import frame_phone_indices

        alignment = _alignment_of(source)
        idx = frame_phone_indices(alignment, frame_rate, n_frames, self.vocabulary)
        out = np.zeros((n_frames, len(self.vocabulary)), np.uint8)
        out[np.arange(n_frames), idx] = 1
        return out

    def windows(
        self,
        alignment: Alignment,
        frame_rate: float,
        n_frames: int,
        *,
        k: int,
        align: str = "center",
        features: str = "raw",
        dilation: int = 1,
    ) -> np.ndarray:
        """Features of the ``k``-frame window of every frame (:func:`dam.features.window_features`), uint8.

        ``dilation`` spaces the window frames that many frames apart.
        """
        from dam.corpus import window_features

        alignment = _alignment_of(alignment)
        return window_features(
            alignment, frame_rate, n_frames, self.vocabulary, kx=k, features=features, align=align, dilation=dilation
        ).astype(np.uint8)


def _alignment_of(source) -> Alignment:
    """The alignment a phone encoder reads: an Alignment, or an Utterance's."""
    if isinstance(source, Alignment):
        return source
    if isinstance(source, Utterance):
        return source.alignment
    raise TypeError(
        f"the 'phones' encoder reads a dam.Alignment or dam.Utterance, got {type(source).__name__}"
        " (audio alone needs an audio encoder: encoder='mfcc')"
    )


def has_audio(utterance) -> bool:
    """Whether ``utterance`` (an Utterance or AudioClip) carries audio."""
    return isinstance(utterance, AudioClip) or getattr(utterance, "audio", None) is not None


def _name_of(source) -> str:
    if isinstance(source, Utterance):
        return source.name or source.alignment.source or "<utterance>"
    if isinstance(source, AudioClip):
        return source.name or "<audio clip>"
    return getattr(source, "source", None) or "<alignment>"


# Acoustic features of a file are computed once per settings (fit, validation and repeated predictions
# read the same files); keyed by path, size and mtime so an edited file is read again.
_CACHE: dict = {}
_CACHE_SIZE = 2048


def _cached(key, compute):
    if key in _CACHE:
        return _CACHE[key]
    value = compute()
    value.setflags(write=False)
    if len(_CACHE) >= _CACHE_SIZE:
        _CACHE.pop(next(iter(_CACHE)))
    _CACHE[key] = value
    return value


def _parse_spec(spec: str) -> tuple[str, dict]:
    """``"mfcc:n_mfcc=27,window=0.02"`` -> ``("mfcc", {"n_mfcc": 27, "window": 0.02})``."""
    name, _, opts = str(spec).partition(":")
    options = {}
    for item in filter(None, (o.strip() for o in opts.split(","))):
        key, eq, value = item.partition("=")
        if not eq:
            raise ValueError(f"encoder option {item!r} in {spec!r} is not key=value")
        key = key.strip()
        try:
            options[key] = int(value) if value.strip().lstrip("-").isdigit() else float(value)
        except ValueError:
            raise ValueError(f"encoder option {key}={value!r} in {spec!r} is not a number") from None
    return name.strip(), options


class AudioEncoder:
    """Base of the encoders that read audio: per-frame features, standardized on the training corpus.

    Parameters
    ----------
    mean, scale : list of float, optional
        Feature standardization (set by :meth:`fit`).
    **options
        Feature settings of the subclass (see :attr:`OPTIONS`).

    Notes
    -----
    The audio of an :class:`~dam.Utterance` (``Utterance.audio``, a WAV or
    FLAC file) is read as mono at :attr:`sample_rate` Hz (resampled when it
    is not), needs the ``audio`` extra (soundfile), and its features are
    cached in memory per file and settings.
    """

    name = ""
    reads = ("audio",)
    binary = False
    #: Feature settings and their defaults (subclasses).
    OPTIONS: dict = {}
    #: Rate the audio is read at.
    sample_rate = 16000

    def __init__(self, mean=None, scale=None, **options):
        unknown = set(options) - set(self.OPTIONS)
        if unknown:
            raise ValueError(
                f"encoder {self.name!r} has no option {sorted(unknown)[0]!r}; its options: "
                f"{', '.join(f'{k} (default {v})' for k, v in self.OPTIONS.items())}"
            )
        self.options = {**self.OPTIONS, **options}
        self.mean = None if mean is None else np.asarray(mean, dtype=np.float32)
        self.scale = None if scale is None else np.asarray(scale, dtype=np.float32)

    @classmethod
    def check_corpus(cls, corpus, what: str = "fit") -> None:
        """Refuse a corpus with an utterance without audio, naming it."""
        for u in corpus:
            if not has_audio(u):
                n = sum(not has_audio(v) for v in corpus)
                raise DataError(
                    _name_of(u),
                    "audio",
                    None,
                    f"encoder {cls.name!r} reads audio and this utterance has none "
                    f"({n} of {len(corpus)} utterances of {corpus.name or corpus.source or 'the corpus'} "
                    "have no audio)",
                    "give every utterance a <stem>.wav or <stem>.flac, or keep the utterances with "
                    "audio: corpus.subset([i for i, u in enumerate(corpus) if u.audio])",
                )

    @classmethod
    def fit(cls, corpus: Corpus, **options) -> AudioEncoder:
        cls.check_corpus(corpus)
        enc = cls(**options)
        X = np.concatenate([enc.raw_frames(u, corpus.frame_rate, u.n_frames) for u in corpus])
        enc.mean = X.mean(axis=0).astype(np.float32)
        std = X.std(axis=0)
        enc.scale = np.where(std > 1e-8, std, 1.0).astype(np.float32)
        return enc

    def state(self) -> dict:
        return {"name": self.name, "mean": self.mean.tolist(), "scale": self.scale.tolist(), **self.options}

    @property
    def n_features(self) -> int:
        return int(len(self.mean))

    def _samples(self, source) -> tuple[np.ndarray, str]:
        if isinstance(source, AudioClip):
            from dam.speech import load_audio

            return load_audio(source.samples, source.sample_rate, rate=self.sample_rate, source=_name_of(source))
        if isinstance(source, Utterance):
            if source.audio is None:
                raise DataError(
                    _name_of(source), "audio", None, f"encoder {self.name!r} reads audio and this utterance has none"
                )
            from dam.speech import load_audio

            return load_audio(source.audio, rate=self.sample_rate)
        raise TypeError(
            f"encoder {self.name!r} reads audio: give a dam.Utterance with audio or a "
            f"dam.corpus.AudioClip, not a {type(source).__name__} ({_name_of(source)})"
        )

    def _compute(self, samples: np.ndarray, frame_rate: float, n_frames: int) -> np.ndarray:  # pragma: no cover
        raise NotImplementedError

    def raw_frames(self, source, frame_rate: float, n_frames: int) -> np.ndarray:
        """Unstandardized features, shape (n_frames, n_features), float32."""
        if isinstance(source, Utterance) and source.audio is not None:
            st = os.stat(source.audio)
            key = (
                self.name,
                source.audio,
                st.st_size,
                st.st_mtime_ns,
                float(frame_rate),
                int(n_frames),
                tuple(sorted(self.options.items())),
            )
            return _cached(key, lambda: self._compute(self._samples(source)[0], frame_rate, n_frames))
        return self._compute(self._samples(source)[0], frame_rate, n_frames)

    def frames(self, source, frame_rate: float, n_frames: int) -> np.ndarray:
        """Standardized features of every frame, shape (n_frames, n_features), float32."""
        return (self.raw_frames(source, frame_rate, n_frames) - self.mean) / self.scale

    def windows(
        self,
        source,
        frame_rate: float,
        n_frames: int,
        *,
        k: int,
        align: str = "center",
        features: str = "raw",
        dilation: int = 1,
    ) -> np.ndarray:
        """The ``k``-frame window of every frame, flattened frame by frame, shape (n_frames, k * n_features).

        Window frames are ``dilation`` frames apart; frames outside the utterance repeat its
        first or last frame (as the targets do, :func:`dam.corpus.window_targets`).
        """
        from dam.corpus import window_offsets

        if features != "raw":
            raise ValueError(
                f"features={features!r} (linguistic window features) needs the 'phones' encoder; "
                f"encoder {self.name!r} gives raw per-frame features"
            )
        X = self.frames(source, frame_rate, n_frames)
        pos = np.clip(np.arange(n_frames)[:, None] + window_offsets(k, align, dilation)[None, :], 0, n_frames - 1)
        return X[pos].reshape(n_frames, -1)


class MFCCEncoder(AudioEncoder):
    """MFCC of the utterance's audio, one vector per trajectory frame (Medina et al.'s ``MFCC`` encoder).

    Options (``encoder="mfcc:n_mfcc=27,window=0.025"``): ``n_mfcc`` (13),
    ``n_mels`` (40), ``window`` (0.025 s), ``hop`` (0: one analysis frame
    per trajectory frame; else seconds, dividing the frame period, the
    analysis frames of a trajectory frame concatenated), ``fmin`` (0 Hz),
    ``fmax`` (0: half the sample rate), ``preemphasis`` (0.97). See
    :func:`baselines.nn.acoustic.mfcc`.
    """

    name = "mfcc"
    OPTIONS = {"n_mfcc": 13, "n_mels": 40, "window": 0.025, "hop": 0.0, "fmin": 0.0, "fmax": 0.0, "preemphasis": 0.97}

    def _settings(self) -> dict:
        o = dict(self.options)
        o["hop"] = o["hop"] or None
        o["fmax"] = o["fmax"] or None
        return o

    def _analysis(self, frame_rate, n_frames) -> dict:
        """The keywords every function of :mod:`baselines.nn.acoustic` shares, from the options."""
        o = self._settings()
        return dict(
            frame_rate=frame_rate,
            n_frames=n_frames,
            n_mels=int(o["n_mels"]),
            window=o["window"],
            hop=o["hop"],
            fmin=o["fmin"],
            fmax=o["fmax"],
            preemphasis=o["preemphasis"],
        )

    def _compute(self, samples, frame_rate, n_frames):
        from .acoustic import mfcc

        kw = self._analysis(frame_rate, n_frames)
        return mfcc(samples, self.sample_rate, n_mfcc=int(self.options["n_mfcc"]), **kw).astype(np.float32)


class FbankEncoder(MFCCEncoder):
    """Log mel filterbank energies of the utterance's audio, one vector per trajectory frame.

    Options as :class:`MFCCEncoder` without ``n_mfcc``: ``n_mels`` (40) is the number of coefficients.
    """

    name = "fbank"
    OPTIONS = {k: v for k, v in MFCCEncoder.OPTIONS.items() if k != "n_mfcc"}

    def _compute(self, samples, frame_rate, n_frames):
        from .acoustic import log_mel

        return log_mel(samples, self.sample_rate, **self._analysis(frame_rate, n_frames)).astype(np.float32)


class ZhouEncoder(MFCCEncoder):
    """VisemeNet's input (Zhou et al. 2018, Sec. 4): MFCC, raw mel filterbank (MFB) energies and
    spectral subband centroids (SSC) of every frame, concatenated: 13 + 26 + 26 = 65 features.

    Options: ``n_mfcc`` (13), ``n_mels`` (26; MFB and SSC bands), ``window`` (0.025 s), ``hop``,
    ``fmin``, ``fmax``, ``preemphasis`` as :class:`MFCCEncoder`.
    """

    name = "mfcc-mfb-ssc"
    OPTIONS = {**MFCCEncoder.OPTIONS, "n_mels": 26}

    def _compute(self, samples, frame_rate, n_frames):
        from .acoustic import log_mel, mfcc, subband_centroids

        kw = self._analysis(frame_rate, n_frames)
        parts = [
            mfcc(samples, self.sample_rate, n_mfcc=int(self.options["n_mfcc"]), **kw),
            log_mel(samples, self.sample_rate, **kw),
            subband_centroids(samples, self.sample_rate, **kw),
        ]
        return np.concatenate(parts, axis=1).astype(np.float32)


#: Suffix of the user-supplied feature files of the ``features`` encoder.
FEATURES_SUFFIX = ".features.npy"


class FeaturesEncoder(AudioEncoder):
    """User-supplied frame-wise features (wav2vec 2.0, DeepSpeech2 ...): ``<stem>.features.npy``.

    The file sits beside the utterance's alignment (or its audio), holds
    float features of shape ``(n, dim)`` at ``features_rate`` Hz (option;
    0 means the trajectory frame rate), feature row ``j`` describing the
    audio from ``j / features_rate`` on. Trajectory frame ``i`` (at
    ``i / frame_rate``) reads row ``floor(i * features_rate / frame_rate)``
    (nearest-neighbour, as Medina et al. align their features); the rows
    must cover the utterance to within one row. The toolkit never
    downloads or runs a feature model: compute the features with the tool
    of your choice and save them with ``numpy.save``.
    """

    name = "features"
    reads = ("audio",)
    OPTIONS = {"features_rate": 0.0}

    @staticmethod
    def path_of(utterance) -> str | None:
        """Where the features of ``utterance`` are (None if it has no file of them)."""
        if not isinstance(utterance, Utterance):
            return None
        dirs = [os.path.dirname(p) for p in (utterance.alignment.source, utterance.audio) if p]
        for d in dirs:
            path = os.path.join(d, f"{utterance.name}{FEATURES_SUFFIX}")
            if os.path.isfile(path):
                return path
        return None

    @classmethod
    def check_corpus(cls, corpus, what: str = "fit") -> None:
        for u in corpus:
            if cls.path_of(u) is None:
                n = sum(cls.path_of(v) is None for v in corpus)
                raise DataError(
                    _name_of(u),
                    "features",
                    f"{u.name}{FEATURES_SUFFIX}",
                    f"encoder 'features' reads <stem>{FEATURES_SUFFIX} beside each utterance and "
                    f"this one has none ({n} of {len(corpus)} utterances lack it)",
                )

    def raw_frames(self, source, frame_rate, n_frames):
        path = self.path_of(source)
        if path is None:
            raise DataError(
                _name_of(source),
                "features",
                None,
                f"encoder 'features' reads <stem>{FEATURES_SUFFIX} beside the utterance; there is none"
                if isinstance(source, Utterance)
                else f"encoder 'features' reads <stem>{FEATURES_SUFFIX} beside a dam.Utterance, "
                f"not a {type(source).__name__}",
            )
        try:
            F = np.load(path, allow_pickle=False)
        except (OSError, ValueError) as exc:
            raise DataError(path, "features", os.path.basename(path), f"not a readable .npy file ({exc})") from None
        if F.ndim != 2 or F.shape[0] == 0 or F.dtype.kind not in "iuf":
            raise DataError(path, "shape", F.shape, "features must be a non-empty 2-D array of numbers (n, dim)")
        if not np.all(np.isfinite(F)):
            i, j = (int(v) for v in np.argwhere(~np.isfinite(F))[0])
            raise DataError(path, f"features[{i}, {j}]", float(F[i, j]), "value is not finite")
        rate = float(self.options["features_rate"]) or float(frame_rate)
        rows = np.floor(np.arange(n_frames) * rate / frame_rate + 1e-9).astype(np.int64)
        if rows[-1] > F.shape[0]:  # more than one row short
            raise DataError(
                path,
                "rows",
                F.shape[0],
                f"{n_frames} frames at {frame_rate:g} Hz need {rows[-1] + 1} rows at {rate:g} Hz",
            )
        if self.mean is not None and F.shape[1] != len(self.mean):
            raise DataError(path, "columns", F.shape[1], f"the model was trained on {len(self.mean)} feature columns")
        return F[np.minimum(rows, F.shape[0] - 1)].astype(np.float32)


ENCODERS = {
    "phones": PhoneEncoder,
    "mfcc": MFCCEncoder,
    "fbank": FbankEncoder,
    "mfcc-mfb-ssc": ZhouEncoder,
    "features": FeaturesEncoder,
}


class EncoderSpec(Options):
    """The ``encoder`` parameter: a name of :data:`ENCODERS`, optionally with
    numeric options, ``"mfcc:n_mfcc=27,window=0.02"``."""

    def is_satisfied_by(self, value) -> bool:
        if not isinstance(value, str):
            return False
        try:
            name, options = _parse_spec(value)
        except ValueError:
            return False
        if name not in ENCODERS:
            return False
        allowed = getattr(ENCODERS[name], "OPTIONS", {})
        return set(options) <= set(allowed)

    def __str__(self) -> str:
        return super().__str__() + " (audio encoders may add options: 'mfcc:n_mfcc=27,window=0.02')"


def encoder_reads(spec: str) -> tuple:
    """What the encoder of ``spec`` reads: ``("phones",)`` or ``("audio",)``."""
    name, _ = _parse_spec(spec)
    return tuple(getattr(ENCODERS.get(name), "reads", ("phones",)))


def make_encoder(spec: str, corpus: Corpus):
    """Fit the encoder ``spec`` (a name, optionally with options: ``"mfcc:n_mfcc=27"``) on ``corpus``."""
    name, options = _parse_spec(spec)
    if name not in ENCODERS:
        raise ValueError(f"parameter 'encoder' is {spec!r}; available encoders: {', '.join(ENCODERS)}")
    if options and not issubclass(ENCODERS[name], AudioEncoder):
        raise ValueError(f"parameter 'encoder' is {spec!r}; encoder {name!r} takes no options")
    return ENCODERS[name].fit(corpus, **options) if options else ENCODERS[name].fit(corpus)


def encoder_from_state(state: dict):
    """Rebuild an encoder from its ``state()``."""
    state = dict(state)
    name = state.pop("name")
    if name not in ENCODERS:
        raise ValueError(f"the saved encoder is {name!r}; available encoders: {', '.join(ENCODERS)}")
    return ENCODERS[name](**state)
