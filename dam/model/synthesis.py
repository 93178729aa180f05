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
disagree on what the model is. A call with a few phones sums over every
(frame, segment) pair instead: the pairs the windows leave out have a
dominance below the tolerance, which truncation zeroes, so the sum is the same
(``tests/model/test_paper_steps.py`` holds both to Eq. (2) written out by hand).

numpy only: a saved DAM loads and synthesizes with this module, without
scipy or scikit-learn.
"""

from __future__ import annotations

import numpy as np

from dam.model.animeme import EXTRAPOLATE, animeme_time, legendre_to_monomial
from dam.model.dominance import dominance_of_distance, outside_distance, reach

__all__ = ["segment_windows", "concatenate"]

#: :func:`concatenate` evaluates every (frame, segment) pair when there are at most this
#: many (one to three phones), else only the pairs of :func:`segment_windows`: about where
#: the two cost the same (a few phones pay for numpy steps, not for pairs).
DENSE_PAIRS = 400


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
    if tol <= 0.0:  # no truncation: the window is the whole utterance
        r = np.asarray(n_frames) / frame_rate / np.maximum(dur, 1e-12) + 1.0
    else:
        r = reach(sigma_max, eps, tol)
    r = r * dur
    # (np.minimum/np.maximum rather than np.clip: cheaper per call, same values)
    lo = np.minimum(np.maximum(np.ceil((starts - r) * frame_rate - 1e-9), 0), n_frames).astype(np.int64)
    hi = np.minimum(np.maximum(np.floor((ends + r) * frame_rate + 1e-9) + 1, lo), n_frames).astype(np.int64)
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
    support=None,
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
    extrapolate : {"polynomial", "hold", "trained"}
        The animeme outside [0, 1] (:func:`dam.model.animeme.animeme_time`).
    eps, tol : float
        Dominance constant and truncation tolerance.
    support : ndarray, shape (n_segments, 2), optional
        For ``extrapolate="trained"``: the local-time range training evaluated
        each segment's animeme at (:func:`dam.model.animeme.trained_support`);
        None: the polynomial on the whole time line.

    Returns
    -------
    ndarray, shape (n_frames, n_channels)
    """
    if extrapolate not in EXTRAPOLATE:
        raise ValueError(f"parameter 'extrapolate' is {extrapolate!r}; use one of {EXTRAPOLATE}")
    coef = np.asarray(coef, dtype=float)
    sigma = np.asarray(sigma, dtype=float)
    starts = np.asarray(starts, dtype=float)
    n_seg, n_ch = sigma.shape
    if n_frames * n_seg <= DENSE_PAIRS:
        # A few phones (a streaming caller's): every (frame, segment) pair, in
        # fewer numpy steps than windowing. Pairs outside the windows have
        # dominance below tol, which truncation zeroes: the same sum.
        t = (np.arange(n_frames)[:, None] / frame_rate - starts) / (np.asarray(ends, dtype=float) - starts)
        # one segment holding every frame (a one-phone call): its dominance is 1 at
        # every frame, so Eq. (2), plain sum and average alike, is its animeme
        lone = n_seg == 1 and t[0, 0] >= 0.0 and t[-1, 0] <= 1.0

        def per_pair(x):  # (n_seg, ...) broadcasts against (n_frames, n_seg, ...)
            return x

    else:
        lone = False
        seg, frame, t = segment_windows(starts, ends, sigma.max(axis=1), frame_rate, n_frames, eps, tol)

        def per_pair(x):  # x.take(seg, axis=0): much faster than x[seg] on a 2-D x
            return x.take(seg, axis=0)

    # Per segment first (small arrays), then per pair: the animeme from the
    # power-series coefficients a^0 .. a^M (the same polynomial), the dominance
    # from u^2 per pair and sigma^2 + eps per segment.
    power = legendre_to_monomial(coef.transpose(1, 0, 2))  # (M+1, n_seg, C)
    if support is not None:  # "trained": each segment's range, per pair
        support = np.asarray(support, dtype=float)
        support = (per_pair(support[:, 0]), per_pair(support[:, 1]))
    ta = animeme_time(t, extrapolate, support)[..., None]
    deg = power.shape[0] - 1
    if t.ndim == 2:  # every pair: sum_m a^m t^m as one product per pair (fewer steps than Horner's)
        A = np.matmul(ta[..., None] ** np.arange(deg + 1), power.transpose(1, 0, 2))[:, :, 0]
    else:  # Horner's rule, in place on the (pairs, C) arrays
        A = per_pair(power[deg]) * (ta if deg else np.ones_like(ta))
        for m in range(deg - 1, -1, -1):
            A += per_pair(power[m])
            if m:
                A *= ta
    if lone:
        return A[:, 0]
    u = outside_distance(t)
    u *= u
    D = dominance_of_distance(u[..., None], per_pair(sigma * sigma + eps), tol)
    A *= D
    if A.ndim == 3:
        num, den = np.add.reduce(A, axis=1), np.add.reduce(D, axis=1)
    else:
        flat = ((frame * n_ch)[:, None] + np.arange(n_ch)).ravel()
        num = np.bincount(flat, weights=A.ravel(), minlength=n_frames * n_ch).reshape(n_frames, n_ch)
        if not normalize:
            return num
        den = np.bincount(flat, weights=D.ravel(), minlength=n_frames * n_ch).reshape(n_frames, n_ch)
    if not normalize:
        return num
    # every frame lies inside some segment (D = 1 there), so den >= 1
    den = np.maximum(den, 1e-300, out=den)
    return np.divide(num, den, out=num)
