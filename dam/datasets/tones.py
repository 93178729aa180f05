"""Toy audio for any alignment: every phone a chord of its own, so audio-driven models can be tested.

The bundled ``tiny`` corpus has no audio; the tests and the conformance
suite of audio-driven models need a small corpus with audio that carries
the phones. :func:`phone_tones` renders an alignment as a sum of three
sinusoids per phone (frequencies drawn from the phone's label with a fixed
hash, so the same phone always sounds the same), with 5 ms raised-cosine
ramps at segment edges and silence as silence. It is not speech: it makes
phone identity recoverable from the spectrum, nothing more.

>>> import dam
>>> from dam.datasets.tones import phone_tones
>>> a = dam.Alignment(["sil", "m", "a", "sil"], [0, 0.1, 0.2, 0.4], [0.1, 0.2, 0.4, 0.5])
>>> phone_tones(a, 16000).shape
(8000,)
"""

from __future__ import annotations

import os
import zlib
from pathlib import Path

import numpy as np

from dam.corpus.data import Alignment, Corpus

__all__ = ["phone_tones", "tone_frequencies", "tiny_with_audio", "TONES_RATE"]

#: Sample rate of the rendered audio.
TONES_RATE = 16000


def tone_frequencies(label: str) -> np.ndarray:
    """The three frequencies (Hz) of ``label``: one in each of 200-900, 900-2500 and 2500-5000 Hz."""
    rng = np.random.default_rng(zlib.crc32(label.encode("utf-8")))
    return np.array([rng.uniform(200, 900), rng.uniform(900, 2500), rng.uniform(2500, 5000)])


def phone_tones(alignment: Alignment, sample_rate: int = TONES_RATE, *, amplitude: float = 0.3) -> np.ndarray:
    """Render ``alignment`` as phone chords, float64 in [-1, 1].

    Parameters
    ----------
    alignment : Alignment
    sample_rate : int, default 16000
    amplitude : float, default 0.3
        Peak of each sinusoid (three per phone).

    Returns
    -------
    ndarray, shape (ceil(duration * sample_rate),)
        Sample ``n`` is at ``n / sample_rate``; silence segments are zeros.
    """
    n = int(np.ceil(alignment.duration * sample_rate - 1e-9))
    t = np.arange(n) / sample_rate
    out = np.zeros(n)
    ramp = 0.005
    for lab, s, e in zip(alignment.labels, alignment.starts, alignment.ends):
        if lab == alignment.silence:
            continue
        i0, i1 = int(round(s * sample_rate)), min(n, int(round(e * sample_rate)))
        tt = t[i0:i1]
        env = np.clip(np.minimum(tt - s, e - tt) / ramp, 0.0, 1.0)
        env = 0.5 - 0.5 * np.cos(np.pi * env)
        out[i0:i1] += amplitude * env * np.sin(2 * np.pi * tone_frequencies(lab)[:, None] * tt[None, :]).sum(axis=0)
    return np.clip(out, -1.0, 1.0)


def tiny_with_audio(directory=None, *, sample_rate: int = TONES_RATE) -> Corpus:
    """The ``tiny`` corpus with :func:`phone_tones` audio beside every utterance.

    Parameters
    ----------
    directory : path-like, optional
        Where to write it (created; existing files replaced atomically).
        Default: ``dam-tiny-audio`` in the system's temporary directory.

    Returns
    -------
    Corpus
        Loaded back with :func:`dam.load_corpus`: every ``Utterance.audio`` is a 16-bit WAV.
    """
    import tempfile

    from scipy.io import wavfile

    from dam.corpus.atomic import atomic_write
    from dam.corpus.io import load_corpus, save_corpus
    from dam.datasets import load

    user = getattr(os, "getuid", lambda: 0)()
    d = Path(directory) if directory is not None else Path(tempfile.gettempdir()) / f"dam-tiny-audio-{user}"
    corpus = load("tiny")
    save_corpus(corpus, d, metadata={"audio_rate": int(sample_rate)})
    for u in corpus:
        x = np.round(phone_tones(u.alignment, sample_rate) * 32767).astype(np.int16)
        with atomic_write(d / f"{u.name}.wav", "wb") as fh:
            wavfile.write(fh, int(sample_rate), x)
    return load_corpus(d)
