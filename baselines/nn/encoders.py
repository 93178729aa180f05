"""The input-encoder slot of the neural predictors.

Medina et al. (2022) split a predictor into an *encoder* (phones, MFCC,
DeepSpeech2 or Wav2Vec features, one vector per frame) and a *decoder*
(MLP, RNN, Transformer). The decoders here read their input only through
an encoder object with two methods:

``frames(alignment, frame_rate, n_frames) -> (n_frames, n_features)``
    One feature vector per frame (the recurrent decoders read this).
``windows(alignment, frame_rate, n_frames, *, k, align, features) -> (n_frames, k * n_features')``
    The ``k``-frame input window of every frame, flattened frame by frame
    (the sliding-window decoders read this; reshaping to ``(n_frames, k, -1)``
    gives the per-frame vectors of the window when ``features="raw"``).

An encoder is rebuilt from JSON-able state (``state()`` / ``from_state``),
so a saved model never pickles it. Only phone features exist today; an audio
encoder (MFCC, ...) registers in :data:`ENCODERS` and needs no decoder change.
"""
from __future__ import annotations

import numpy as np

from dam import Alignment, Corpus

__all__ = ["PhoneEncoder", "ENCODERS", "make_encoder", "encoder_from_state"]


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
    def fit(cls, corpus: Corpus) -> "PhoneEncoder":
        from dam.corpus import phone_vocabulary
        return cls(phone_vocabulary(corpus))

    def state(self) -> dict:
        return {"name": self.name, "vocabulary": list(self.vocabulary)}

    @property
    def n_features(self) -> int:
        return len(self.vocabulary)

    def frames(self, alignment: Alignment, frame_rate: float, n_frames: int) -> np.ndarray:
        """One-hot phone of every frame, shape (n_frames, len(vocabulary)), uint8."""
        from dam.corpus import frame_phone_indices
        idx = frame_phone_indices(alignment, frame_rate, n_frames, self.vocabulary)
        out = np.zeros((n_frames, len(self.vocabulary)), np.uint8)
        out[np.arange(n_frames), idx] = 1
        return out

    def windows(self, alignment: Alignment, frame_rate: float, n_frames: int, *, k: int,
                align: str = "center", features: str = "raw") -> np.ndarray:
        """Features of the ``k``-frame window of every frame (:func:`dam.features.window_features`), uint8."""
        from dam.corpus import window_features
        return window_features(alignment, frame_rate, n_frames, self.vocabulary, kx=k, features=features,
                               align=align).astype(np.uint8)


ENCODERS = {"phones": PhoneEncoder}


def make_encoder(name: str, corpus: Corpus):
    """Fit the encoder called ``name`` on ``corpus``."""
    if name not in ENCODERS:
        raise ValueError(f"parameter 'encoder' is {name!r}; available encoders: {', '.join(ENCODERS)}")
    return ENCODERS[name].fit(corpus)


def encoder_from_state(state: dict):
    """Rebuild an encoder from its ``state()``."""
    state = dict(state)
    name = state.pop("name")
    if name not in ENCODERS:
        raise ValueError(f"the saved encoder is {name!r}; available encoders: {', '.join(ENCODERS)}")
    return ENCODERS[name](**state)
