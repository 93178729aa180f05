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

from dam.model.animeme import EXTRAPOLATE, legendre_to_monomial
from dam.model.dominance import dominance_of_distance, outside_distance, reach

__all__ = ["segment_windows", "concatenate"]


def segment_windows(starts, ends, sigma_max, frame_rate: float, n_frames: int, eps: float = 1e-8, tol: float = 1e-4):
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
    if tol <= 0.0:  # no truncation: the window is the whole utterance
        r = np.asarray(n_frames) / frame_rate / np.maximum(dur, 1e-12) + 1.0
    # (np.minimum/np.maximum rather than np.clip: cheaper per call, same values)
    lo = np.minimum(np.maximum(np.ceil((starts - r * dur) * frame_rate - 1e-9), 0), n_frames).astype(np.int64)
    hi = np.minimum(np.maximum(np.floor((ends + r * dur) * frame_rate + 1e-9) + 1, lo), n_frames).astype(np.int64)
    counts = hi - lo
    seg = np.repeat(np.arange(len(starts)), counts)
    # frame = lo[seg] + position within the segment's window
    first = np.cumsum(counts) - counts
    frame = np.arange(seg.size) + (lo - first)[seg]
    t = (frame / frame_rate - starts[seg]) / dur[seg]
    return seg, frame, t


def concatenate(
    starts,
    ends,
    coef,
    sigma,
    frame_rate: float,
    n_frames: int,
    *,
    normalize: bool = False,
    extrapolate: str = "polynomial",
    eps: float = 1e-8,
    tol: float = 1e-4,
) -> np.ndarray:
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
        False: plain sum (Eq. 2 as printed). True: divide by the summed
        dominance (the weighted average; :class:`dam.model.DAM`'s default).
    extrapolate : {"polynomial", "hold"}
    eps, tol : float
        Dominance constant and truncation tolerance.

    Returns
    -------
    ndarray, shape (n_frames, n_channels)
    """
    if extrapolate not in EXTRAPOLATE:
        raise ValueError(f"parameter 'extrapolate' is {extrapolate!r}; use one of {EXTRAPOLATE}")
    coef = np.asarray(coef, dtype=float)
    sigma = np.asarray(sigma, dtype=float)
    n_ch = coef.shape[2]
    seg, frame, t = segment_windows(starts, ends, sigma.max(axis=1), frame_rate, n_frames, eps, tol)
    # Per segment first (small arrays), then one gather per pair: the animeme
    # by Horner's rule on the power-series coefficients (the same polynomial),
    # the dominance from u^2 per pair and sigma^2 + eps per segment
    # (x.take(seg, axis=0): much faster than x[seg] on a 2-D x).
    power = legendre_to_monomial(coef.transpose(1, 0, 2))  # (M+1, n_seg, C)
    ta = (t if extrapolate == "polynomial" else np.minimum(np.maximum(t, 0.0), 1.0))[:, None]
    A = power[-1].take(seg, axis=0)  # (pairs, C)
    for m in range(power.shape[0] - 2, -1, -1):
        A *= ta
        A += power[m].take(seg, axis=0)
    u = outside_distance(t)
    D = dominance_of_distance((u * u)[:, None], (sigma * sigma + eps).take(seg, axis=0), tol)  # (pairs, C)
    A *= D
    flat = ((frame * n_ch)[:, None] + np.arange(n_ch)).ravel()
    num = np.bincount(flat, weights=A.ravel(), minlength=n_frames * n_ch).reshape(n_frames, n_ch)
    if not normalize:
        return num
    den = np.bincount(flat, weights=D.ravel(), minlength=n_frames * n_ch).reshape(n_frames, n_ch)
    # every frame lies inside some segment (D = 1 there), so den >= 1
    return num / np.maximum(den, 1e-300)
