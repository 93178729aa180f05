"""Acoustic features for the audio encoders: MFCC and log-mel filterbank (numpy + scipy).

Medina et al. (2022), Sec. 5, feed their decoders MFCC frames at the
animation's frame rate ("20 ms as the common frame duration for the encoding
of the input signal for all audio encoding methods"); VisemeNet (Zhou et al.
2018) concatenates MFCCs with raw mel filterbank energies. Both are computed
here, one analysis frame per *trajectory* frame so audio frames and animation
frames line up:

* analysis frame ``i`` is centred on ``t_i = i / frame_rate``, the time of
  trajectory frame ``i`` (:func:`dam.corpus.frame_times`); with ``hop``
  shorter than the frame period, ``k = round(1 / (frame_rate * hop))``
  analysis frames centred on ``t_i + (j - (k - 1) / 2) * hop`` are
  concatenated (as Medina et al. concatenate two 10 ms Wav2Vec vectors into
  one 20 ms frame);
* samples outside the signal are zeros, so the first and last frames exist;
* the signal is pre-emphasised (``y[n] = x[n] - p x[n-1]``), each frame is
  multiplied by a Hamming window of ``window`` seconds, zero-padded to the
  next power of two (``n_fft``) and its power spectrum ``|DFT|^2`` taken;
* ``n_mels`` triangular filters, equally spaced on the HTK mel scale
  ``m(f) = 2595 log10(1 + f / 700)`` between ``fmin`` and ``fmax``, each
  rising from the centre of its lower neighbour to 1 at its own centre and
  falling to the centre of its upper neighbour, weight the power spectrum
  (:func:`mel_filterbank`); ``fbank`` is the natural log of the band energies
  (floored at 1e-10);
* ``mfcc`` is the orthonormal DCT-II of the log band energies, coefficients
  ``0 .. n_mfcc - 1`` (coefficient 0 included: it carries the loudness);
* ``subband_centroids`` (Paliwal 1998, VisemeNet's third feature) is, per
  filter, the power-weighted mean frequency under it, in kHz.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "hz_to_mel",
    "mel_to_hz",
    "mel_filterbank",
    "analysis_times",
    "power_frames",
    "log_mel",
    "mfcc",
    "subband_centroids",
    "LOG_FLOOR",
]

#: Band energies are floored here before the log (silence gives exact zeros).
LOG_FLOOR = 1e-10


def hz_to_mel(f):
    """HTK mel scale: ``2595 log10(1 + f / 700)``."""
    return 2595.0 * np.log10(1.0 + np.asarray(f, dtype=float) / 700.0)


def mel_to_hz(m):
    """Inverse of :func:`hz_to_mel`."""
    return 700.0 * (10.0 ** (np.asarray(m, dtype=float) / 2595.0) - 1.0)


def mel_filterbank(
    n_mels: int, n_fft: int, sample_rate: float, fmin: float = 0.0, fmax: float | None = None
) -> np.ndarray:
    """Triangular mel filters on the bins of an ``n_fft``-point real DFT.

    Parameters
    ----------
    n_mels : int
        Number of filters.
    n_fft : int
        DFT length; the bins are at ``k * sample_rate / n_fft``, ``k = 0 .. n_fft // 2``.
    sample_rate : float
    fmin, fmax : float, default 0 and ``sample_rate / 2``
        Lower edge of the first filter and upper edge of the last (Hz).

    Returns
    -------
    ndarray, shape (n_mels, n_fft // 2 + 1)
        Peak weight 1 at each filter's centre frequency (unnormalized).

    Examples
    --------
    >>> fb = mel_filterbank(20, 512, 16000)
    >>> fb.shape, float(fb.max()) <= 1.0
    ((20, 257), True)
    """
    fmax = sample_rate / 2.0 if fmax is None else float(fmax)
    if not 0 <= fmin < fmax <= sample_rate / 2.0 + 1e-9:
        raise ValueError(
            f"mel filters need 0 <= fmin < fmax <= sample_rate/2; got fmin={fmin}, fmax={fmax}, "
            f"sample_rate={sample_rate}"
        )
    edges = mel_to_hz(np.linspace(hz_to_mel(fmin), hz_to_mel(fmax), n_mels + 2))
    freqs = np.arange(n_fft // 2 + 1) * (sample_rate / n_fft)
    lo, mid, hi = edges[:-2, None], edges[1:-1, None], edges[2:, None]
    rise = (freqs - lo) / (mid - lo)
    fall = (hi - freqs) / (hi - mid)
    return np.clip(np.minimum(rise, fall), 0.0, None)


def analysis_times(n_frames: int, frame_rate: float, hop: float | None = None) -> np.ndarray:
    """Centres of the analysis frames of ``n_frames`` trajectory frames.

    Returns
    -------
    ndarray, shape (n_frames, k)
        ``k = round(1 / (frame_rate * hop))`` analysis frames per trajectory
        frame (1 when ``hop`` is None), centred on frame ``i``'s time ``i / frame_rate``.
    """
    period = 1.0 / float(frame_rate)
    k = 1 if hop is None else int(round(period / float(hop)))
    if k < 1 or (hop is not None and abs(k * hop - period) > 1e-6 * period):
        raise ValueError(f"hop {hop!r} s must divide the frame period 1/{frame_rate:g} s")
    step = period / k
    offsets = (np.arange(k) - (k - 1) / 2.0) * step
    return np.arange(n_frames)[:, None] * period + offsets[None, :]


def power_frames(
    x, sample_rate: float, times, *, window: float = 0.025, preemphasis: float = 0.97
) -> tuple[np.ndarray, int]:
    """Power spectra of Hamming-windowed frames of ``x`` centred on ``times``.

    Parameters
    ----------
    x : array-like, shape (n_samples,)
    sample_rate : float
    times : array-like of float, any shape
        Frame centres in seconds (sample ``n`` is at ``n / sample_rate``).
    window : float, default 0.025
        Window length in seconds.
    preemphasis : float, default 0.97
        0 disables it.

    Returns
    -------
    power : ndarray, shape times.shape + (n_fft // 2 + 1,)
    n_fft : int
    """
    x = np.asarray(x, dtype=float)
    if preemphasis:
        x = np.concatenate([x[:1], x[1:] - preemphasis * x[:-1]])
    length = max(2, int(round(window * sample_rate)))
    n_fft = 1 << (length - 1).bit_length()
    times = np.asarray(times, dtype=float)
    starts = np.round(times.reshape(-1) * sample_rate).astype(np.int64) - length // 2
    # Zero-pad so that every window, even at the edges, reads real indices.
    pad = int(max(0, -starts.min(initial=0), starts.max(initial=0) + length - len(x)))
    xp = np.concatenate([np.zeros(pad), x, np.zeros(pad)])
    idx = starts[:, None] + pad + np.arange(length)[None, :]
    frames = xp[idx] * np.hamming(length)[None, :]
    spec = np.fft.rfft(frames, n=n_fft, axis=1)
    power = spec.real**2 + spec.imag**2
    return power.reshape(times.shape + (n_fft // 2 + 1,)), n_fft


def log_mel(
    x,
    sample_rate: float,
    *,
    frame_rate: float,
    n_frames: int | None = None,
    window: float = 0.025,
    hop: float | None = None,
    n_mels: int = 40,
    fmin: float = 0.0,
    fmax: float | None = None,
    preemphasis: float = 0.97,
) -> np.ndarray:
    """Log mel filterbank energies, one row per trajectory frame.

    Parameters
    ----------
    x : array-like, shape (n_samples,)
        Mono samples.
    sample_rate : float
    frame_rate : float
        The trajectory frame rate; row ``i`` describes the audio around ``i / frame_rate``.
    n_frames : int, optional
        Default: the frames up to the end of the signal, ``floor(duration * frame_rate) + 1``.
    window : float, default 0.025
        Analysis window, seconds.
    hop : float, optional
        Analysis hop, seconds; must divide the frame period. Default: the frame period.
    n_mels : int, default 40
    fmin, fmax : float, default 0 and ``sample_rate / 2``
    preemphasis : float, default 0.97

    Returns
    -------
    ndarray, shape (n_frames, k * n_mels)
        ``k`` analysis frames per trajectory frame (see :func:`analysis_times`), earliest first.

    Examples
    --------
    >>> t = np.arange(16000) / 16000
    >>> log_mel(np.sin(2 * np.pi * 440 * t), 16000, frame_rate=100).shape
    (101, 40)
    """
    power, fb, n_frames = _filtered(x, sample_rate, frame_rate, n_frames, window, hop, n_mels, fmin, fmax, preemphasis)
    return np.log(np.maximum(power @ fb.T, LOG_FLOOR)).reshape(n_frames, -1)


def _filtered(x, sample_rate, frame_rate, n_frames, window, hop, n_mels, fmin, fmax, preemphasis):
    """Power spectra of the analysis frames, the mel filters, and the number of trajectory frames."""
    x = np.asarray(x, dtype=float)
    if n_frames is None:
        n_frames = int(math.floor(len(x) / sample_rate * frame_rate + 1e-9)) + 1
    times = analysis_times(n_frames, frame_rate, hop)
    power, n_fft = power_frames(x, sample_rate, times, window=window, preemphasis=preemphasis)
    return power, mel_filterbank(n_mels, n_fft, sample_rate, fmin, fmax), n_frames


def subband_centroids(
    x,
    sample_rate: float,
    *,
    frame_rate: float,
    n_frames: int | None = None,
    window: float = 0.025,
    hop: float | None = None,
    n_mels: int = 26,
    fmin: float = 0.0,
    fmax: float | None = None,
    preemphasis: float = 0.97,
) -> np.ndarray:
    """Spectral subband centroids: the power-weighted mean frequency under each mel filter, kHz.

    ``sum_f f w_k(f) P(f) / sum_f w_k(f) P(f)``; a silent band gives its
    filter's own weighted centre (a tiny power floor is added to every bin).
    Parameters as :func:`log_mel` (default 26 bands, as VisemeNet's input).

    Returns
    -------
    ndarray, shape (n_frames, k * n_mels)
    """
    power, fb, n_frames = _filtered(x, sample_rate, frame_rate, n_frames, window, hop, n_mels, fmin, fmax, preemphasis)
    freqs = np.arange(fb.shape[1]) * (sample_rate / (2 * (fb.shape[1] - 1))) / 1000.0
    power = power + LOG_FLOOR
    return ((power @ (fb * freqs).T) / (power @ fb.T)).reshape(n_frames, -1)


def mfcc(
    x,
    sample_rate: float,
    *,
    frame_rate: float,
    n_frames: int | None = None,
    n_mfcc: int = 13,
    window: float = 0.025,
    hop: float | None = None,
    n_mels: int = 40,
    fmin: float = 0.0,
    fmax: float | None = None,
    preemphasis: float = 0.97,
) -> np.ndarray:
    """Mel-frequency cepstral coefficients, one row per trajectory frame.

    The orthonormal DCT-II of :func:`log_mel`, coefficients ``0 .. n_mfcc - 1``.
    Parameters as :func:`log_mel`, plus

    n_mfcc : int, default 13
        Coefficients kept (at most ``n_mels``).

    Returns
    -------
    ndarray, shape (n_frames, k * n_mfcc)

    Examples
    --------
    >>> t = np.arange(8000) / 16000
    >>> mfcc(np.sin(2 * np.pi * 440 * t), 16000, frame_rate=50, n_mfcc=27).shape
    (26, 27)
    """
    from scipy.fft import dct

    if not 1 <= n_mfcc <= n_mels:
        raise ValueError(f"n_mfcc is {n_mfcc}; it must be between 1 and n_mels={n_mels}")
    lm = log_mel(
        x,
        sample_rate,
        frame_rate=frame_rate,
        n_frames=n_frames,
        window=window,
        hop=hop,
        n_mels=n_mels,
        fmin=fmin,
        fmax=fmax,
        preemphasis=preemphasis,
    )
    n = lm.shape[0]
    c = dct(lm.reshape(n, -1, n_mels), type=2, norm="ortho", axis=-1)[..., :n_mfcc]
    return c.reshape(n, -1)
