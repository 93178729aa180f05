"""Audio beside a corpus's trajectories: which files count, and their headers.

A corpus directory may hold ``<stem>.wav`` or ``<stem>.flac`` beside each
utterance (:func:`dam.load_corpus` puts its path in ``Utterance.audio``).
Only the header is read here, with the standard library (``wave`` for WAV,
the STREAMINFO block for FLAC), so loading a corpus needs no audio library;
the samples are read by whoever needs them (``soundfile``, the ``audio`` extra).
"""

from __future__ import annotations

import os
import wave

from ..data import DataError

__all__ = ["AUDIO_SUFFIXES", "audio_header", "AudioClip"]

#: Audio file suffixes a corpus directory may hold, in order of preference.
AUDIO_SUFFIXES = (".flac", ".wav")


def _flac_header(path: str) -> tuple[int, int, int]:
    with open(path, "rb") as fh:
        head = fh.read(4 + 4 + 34)
    # "fLaC", then the first metadata block, which must be STREAMINFO (type 0, 34 bytes).
    if len(head) < 42 or head[:4] != b"fLaC" or (head[4] & 0x7F) != 0:
        raise DataError(path, "audio", os.path.basename(path), "not a FLAC file (no fLaC STREAMINFO header)")
    info = int.from_bytes(head[8 + 10 : 8 + 18], "big")  # sample rate 20 bits, channels-1 3, bps-1 5, samples 36
    rate = info >> 44
    channels = ((info >> 41) & 0x7) + 1
    n_samples = info & ((1 << 36) - 1)
    return rate, n_samples, channels


def audio_header(path) -> tuple[int, int, int]:
    """Sample rate, number of samples (per channel) and channels of a WAV or FLAC file.

    Parameters
    ----------
    path : path-like
        A ``.wav`` (PCM) or ``.flac`` file.

    Returns
    -------
    sample_rate : int
        Hz.
    n_samples : int
        Samples per channel (0 when a FLAC encoder left it unknown).
    n_channels : int

    Raises
    ------
    DataError
        Naming the file when the header is not that of its suffix.
    """
    path = os.fspath(path)
    suffix = os.path.splitext(path)[1].lower()
    if suffix == ".flac":
        return _flac_header(path)
    if suffix == ".wav":
        try:
            with wave.open(path, "rb") as w:
                return w.getframerate(), w.getnframes(), w.getnchannels()
        except (wave.Error, EOFError) as exc:
            raise DataError(path, "audio", os.path.basename(path), f"not a PCM WAV file ({exc})") from None
    raise DataError(path, "audio", suffix, f"audio files are {' or '.join(AUDIO_SUFFIXES)}")


class AudioClip:
    """Audio samples with their rate: what an audio-driven model predicts from without any alignment.

    Parameters
    ----------
    samples : array-like, shape (n_samples,) or (n_samples, n_channels)
        Channels are averaged.
    sample_rate : float
        Hz.
    name : str, optional
        Named in errors.

    Examples
    --------
    >>> import numpy as np, dam
    >>> clip = dam.corpus.AudioClip(np.zeros(16000), 16000, name="one-second")
    >>> clip.duration, clip.n_frames(100.0)
    (1.0, 101)
    """

    __slots__ = ("samples", "sample_rate", "name")

    def __init__(self, samples, sample_rate: float, *, name: str | None = None):
        import numpy as np

        from ..data import real_array

        x = real_array(samples, name or "<audio>", "samples")
        if x.ndim == 2:
            x = x.mean(axis=1)
        if x.ndim != 1 or len(x) == 0:
            raise DataError(name or "<audio>", "samples", x.shape, "need a non-empty 1-D (or 2-D) array")
        if not np.all(np.isfinite(x)):
            i = int(np.argmin(np.isfinite(x)))
            raise DataError(name or "<audio>", f"samples[{i}]", float(x[i]), "value is not finite")
        sr = float(sample_rate)
        if not (np.isfinite(sr) and sr > 0):
            raise DataError(name or "<audio>", "sample rate", sample_rate, "must be a positive number")
        x.setflags(write=False)
        self.samples, self.sample_rate, self.name = x, sr, name

    @property
    def duration(self) -> float:
        """Seconds."""
        return len(self.samples) / self.sample_rate

    def n_frames(self, frame_rate: float) -> int:
        """Frames at ``i / frame_rate`` up to the end of the audio: ``floor(duration * frame_rate) + 1``."""
        from ..data import _n_frames

        return _n_frames(self.duration, frame_rate)

    def __repr__(self) -> str:
        return f"AudioClip({self.name!r}, {self.duration:.3f} s @ {self.sample_rate:g} Hz)"
