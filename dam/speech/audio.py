"""Reading audio for the aligner: any common rate and bit depth in, 16 kHz mono out."""

from __future__ import annotations

import math
import os

import numpy as np

from dam.corpus import DataError

__all__ = ["load_audio", "to_pcm16", "ALIGN_RATE"]

#: The sample rate of pocketsphinx's en-us acoustic model.
ALIGN_RATE = 16000


def load_audio(
    audio, sample_rate: float | None = None, *, rate: int = ALIGN_RATE, source=None
) -> tuple[np.ndarray, str]:
    """Audio as mono float64 in [-1, 1] at ``rate`` Hz.

    Parameters
    ----------
    audio : path or array-like, shape (n_samples,) or (n_samples, n_channels)
        A sound file that libsndfile reads (WAV of any bit depth, FLAC, OGG,
        AIFF ...) or samples. Integer samples are scaled by their type's range.
    sample_rate : float, optional
        The rate of ``audio`` when it is an array (required then).
    rate : int, default 16000
        The output rate. Channels are averaged (stereo mixed down), then
        resampled with a polyphase anti-aliasing filter.
    source : str, optional
        Named in errors (default: the path).

    Returns
    -------
    samples : ndarray of float64, shape (n_out,)
    source : str
        What errors should name.

    Raises
    ------
    DataError
        Unreadable file, no samples, non-finite samples, bad rate.
    """
    from scipy.signal import resample_poly

    if isinstance(audio, (str, os.PathLike)):
        source = source or os.fspath(audio)
        try:
            import soundfile
        except ImportError as exc:  # pragma: no cover - depends on the install
            raise ImportError('reading audio files needs soundfile: pip install "dam[audio]"') from exc
        if not os.path.exists(audio):
            raise DataError(source, "audio", os.fspath(audio), "no such file")
        try:
            x, sr = soundfile.read(os.fspath(audio), dtype="float64", always_2d=True)
        except Exception as exc:  # libsndfile's own errors: say what failed
            raise DataError(
                source, "audio", os.path.basename(os.fspath(audio)), f"not a readable sound file ({exc})"
            ) from None
    else:
        source = source or "<audio array>"
        if sample_rate is None:
            raise DataError(source, "sample_rate", None, "an audio array needs its sample rate")
        x = np.asarray(audio)
        if np.issubdtype(x.dtype, np.integer):
            info = np.iinfo(x.dtype)
            x = (x.astype(np.float64) - (info.max + info.min + 1) / 2) / (
                -(info.min) if info.min < 0 else (info.max + 1) / 2
            )
        x = np.asarray(x, dtype=np.float64)
        if x.ndim == 1:
            x = x[:, None]
        elif x.ndim != 2:
            raise DataError(source, "audio", x.shape, "expected shape (n_samples,) or (n_samples, n_channels)")
        sr = sample_rate
    if not (isinstance(sr, (int, float, np.integer, np.floating)) and np.isfinite(sr) and sr > 0):
        raise DataError(source, "sample_rate", sr, "not a positive number")
    if x.shape[0] == 0:
        raise DataError(source, "audio", 0, "no samples")
    if not np.all(np.isfinite(x)):
        raise DataError(source, "audio", "NaN/inf", "samples are not finite")
    mono = x.mean(axis=1)
    if float(sr) != float(rate):
        num, den = _ratio(float(sr), rate)
        mono = resample_poly(mono, num, den)
    return np.clip(mono, -1.0, 1.0), source


def _ratio(sr: float, rate: int) -> tuple[int, int]:
    if float(sr).is_integer():
        g = math.gcd(int(sr), rate)
        return rate // g, int(sr) // g
    from fractions import Fraction

    f = Fraction(rate / sr).limit_denominator(1000)
    return f.numerator, f.denominator


def to_pcm16(samples: np.ndarray) -> bytes:
    """Little-endian signed 16-bit PCM bytes, as pocketsphinx reads them."""
    return (np.clip(samples, -1.0, 1.0) * 32767.0).round().astype("<i2").tobytes()
