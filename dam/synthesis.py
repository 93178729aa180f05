"""Eq. (2) of Chen et al. (2012): concatenating dominated animemes.

``C*(t) = sum_j D_j(t_j) A_j(t_j)`` (Eq. 2 as printed, the plain sum,
``normalize=False``) or the Cohen-Massaro weighted average
``sum_j D_j A_j / sum_j D_j`` (``normalize=True``, what the paper's text
describes as "the summation of their normalized values", and the default of
:class:`dam.model.DAM`: see its Notes), with ``t_j`` the local
time of segment ``j``. Dominance is truncated (see :mod:`dam.dominance`), so
each segment touches a bounded window of frames and the cost per phone is
constant.

The same frame/segment pairs (:func:`segment_windows`) build the E-step's
design matrix and the M-step's Jacobian, so training and synthesis cannot
disagree on what the model is.

numpy only: a saved DAM loads and synthesizes with this module, without
scipy or scikit-learn.
"""
from __future__ import annotations

import numpy as np

from .animeme import basis
from .dominance import dominance, reach

__all__ = ["segment_windows", "concatenate"]


def segment_windows(starts, ends, sigma_max, frame_rate: float, n_frames: int,
                    eps: float = 1e-8, tol: float = 1e-4):
    """All (segment, frame) pairs where a segment's truncated dominance may be non-zero.

    Parameters
    ----------
    starts, ends : ndarray, shape (n_segments,)
        Segment times in seconds.
    sigma_max : ndarray, shape (n_segments,)
        The largest sigma the segment uses (over channels).
    frame_rate : float
    n_frames : int or ndarray of int, shape (n_segments,)
        Frames of the utterance (of each segment's utterance, when the
        segments of several utterances are handled at once).
    eps, tol : float
        As in :func:`dam.dominance.dominance`.

    Returns
    -------
    seg : ndarray of int, shape (n_pairs,)
    frame : ndarray of int, shape (n_pairs,)
        Frame index within the segment's utterance.
    t : ndarray of float, shape (n_pairs,)
        Local time of the frame in the segment.
    """
    starts = np.asarray(starts, dtype=float)
    ends = np.asarray(ends, dtype=float)
    dur = ends - starts
    r = reach(sigma_max, eps, tol)
    n_frames = np.asarray(n_frames)
    r = np.where(np.isfinite(r), r, n_frames / frame_rate / np.maximum(dur, 1e-12) + 1.0)
    lo = np.clip(np.ceil((starts - r * dur) * frame_rate - 1e-9), 0, n_frames).astype(np.int64)
    hi = np.clip(np.floor((ends + r * dur) * frame_rate + 1e-9) + 1, 0, n_frames).astype(np.int64)
    hi = np.maximum(hi, lo)
    counts = hi - lo
    seg = np.repeat(np.arange(len(starts)), counts)
    # frame = lo[seg] + position within the segment's window
    first = np.cumsum(counts) - counts
    frame = lo[seg] + (np.arange(seg.size) - first[seg])
    t = (frame / frame_rate - starts[seg]) / dur[seg]
    return seg, frame, t


def concatenate(starts, ends, coef, sigma, frame_rate: float, n_frames: int, *,
                normalize: bool = False, extrapolate: str = "polynomial",
                eps: float = 1e-8, tol: float = 1e-4) -> np.ndarray:
    """Eq. (2): the control trajectories of a sequence of chosen animemes.

    Parameters
    ----------
    starts, ends : ndarray, shape (n_segments,)
        Segment times in seconds.
    coef : ndarray, shape (n_segments, degree + 1, n_channels)
        Shifted-Legendre coefficients of each segment's chosen animeme.
    sigma : ndarray, shape (n_segments, n_channels)
        Dominance fall-off of each segment, per channel.
    frame_rate : float
    n_frames : int
    normalize : bool, default False
        False: plain sum (the paper). True: divide by the summed dominance.
    extrapolate : {"polynomial", "hold"}
    eps, tol : float
        Dominance constant and truncation tolerance.

    Returns
    -------
    ndarray, shape (n_frames, n_channels)
    """
    coef = np.asarray(coef, dtype=float)
    sigma = np.asarray(sigma, dtype=float)
    n_ch = coef.shape[2]
    seg, frame, t = segment_windows(starts, ends, sigma.max(axis=1), frame_rate, n_frames, eps, tol)
    D = dominance(t[:, None], sigma[seg], eps, tol)                    # (pairs, C)
    B = basis(t, coef.shape[1] - 1, extrapolate)                       # (pairs, M+1)
    A = np.einsum("pm,pmc->pc", B, coef[seg])                          # (pairs, C)
    flat = (frame[:, None] * n_ch + np.arange(n_ch)).ravel()
    num = np.bincount(flat, weights=(D * A).ravel(), minlength=n_frames * n_ch).reshape(n_frames, n_ch)
    if not normalize:
        return num
    den = np.bincount(flat, weights=D.ravel(), minlength=n_frames * n_ch).reshape(n_frames, n_ch)
    # every frame lies inside some segment (D = 1 there), so den >= 1
    return num / np.maximum(den, 1e-300)
