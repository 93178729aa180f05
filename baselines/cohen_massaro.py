"""The Cohen–Massaro (1993) coarticulation model, fitted by nonlinear least squares.

Every phone ``p`` has, for every control channel, a target ``T_p``, a
magnitude ``alpha_p``, an anticipatory (left) rate ``theta_l_p``, a
carry-over (right) rate ``theta_r_p`` and an exponent ``c_p``. Segment ``s``
(phone ``p``, centre ``m_s``) dominates time ``t`` by the negative exponential

    D_s(t) = alpha_p * exp(-theta * |tau|^c),  tau = m_s - t,
    theta = theta_l_p before the centre (tau > 0), theta_r_p after it,

and the trajectory is the dominance-weighted average of the targets

    F(t) = sum_s D_s(t) T_p(s) / sum_s D_s(t).

Neighbouring segments with the same label (a pause cut in two by an
alignment gap) count as one segment, so a leading gap does not add a second
silence dominance function.

This is the 1993 model itself, with one dominance function per phone and per
articulatory parameter (channel), as in the original paper; ``dam-m0`` (the DAM
with constant animemes, the way Chen et al. built their comparison) is a
different model and keeps its own row.

Fitting: per channel, nonlinear least squares over ``(T, log alpha,
log theta_l, log theta_r, log c)`` of every phone with the exact Jacobian
(:func:`residuals_and_jacobian`), by Levenberg-Marquardt on the normal
equations (:func:`levenberg_marquardt`). The normal equations are summed
utterance by utterance over the phones each one contains
(:func:`normal_equations`): the cost is that of the utterances' small
Jacobians, where scipy's ``least_squares`` would factorise the dense
corpus-long one at every step. The channels' fits are independent but run
in lockstep, so one pass over the corpus evaluates every channel still
running (each keeps its own damping and stops on its own), in (channels x
segments x frames) arrays a few megabytes large that are reused from one
utterance to the next. The weighted average is
invariant to scaling every ``alpha`` together; a weak ridge on the log
dominance parameters (towards the starting values) fixes that gauge, so the
geometric mean of the fitted ``alpha`` is 1, and keeps phones seen only once
identifiable. Synthesis is numpy only.
"""

from __future__ import annotations

import numpy as np

from dam import Alignment, Corpus, Interval, StateArray, Synthesizer, TupleOf, progress

from .reference import PhoneMean

__all__ = [
    "CohenMassaro",
    "dominance",
    "cohen_massaro_trajectory",
    "residuals_and_jacobian",
    "normal_equations",
    "levenberg_marquardt",
]

# Fit and synthesis see an utterance in blocks of this many frames, each with the
# segments that overlap it and NEIGHBOURS more on either side: a (frames x segments)
# array per block, so memory and time grow linearly with the utterance's length
# instead of quadratically. A segment further away than that from every frame of
# a block is left out there: its weight, normalised against the 30 nearer ones,
# is negligible (and a phrase-length utterance is one block with all its segments).
BLOCK_FRAMES = 1000
NEIGHBOURS = 30
# Channels are evaluated together, as many as keep a (channels x segments x frames) work
# array under this many numbers (a megabyte).
WORK_SIZE = 1 << 17
# Parameter blocks of one channel, each of length n_phones, in this order.
BLOCKS = ("target", "log_alpha", "log_theta_left", "log_theta_right", "log_c")


def dominance(tau, alpha, theta_left, theta_right, c):
    """Cohen–Massaro dominance ``alpha * exp(-theta |tau|^c)``.

    Parameters
    ----------
    tau : array-like
        Segment centre minus time, in seconds (positive before the centre).
    alpha, theta_left, theta_right, c : float or array-like (broadcast)

    Returns
    -------
    ndarray, the shape of ``tau`` broadcast with the parameters
    """
    tau = np.asarray(tau, dtype=float)
    theta = np.where(tau > 0, theta_left, theta_right)
    return alpha * np.exp(-theta * np.abs(tau) ** c)


class _Design:
    """What the fit needs from one utterance: segment phones and centre-to-frame times.

    The arrays have shape (n_segments, n_frames) (every ``stride``-th frame
    from ``start``; frames last, so that sums over segments run along whole rows);
    ``phone`` (n_segments,) indexes the phone table. Adjacent
    segments of the same phone are merged first. ``log_abs_tau`` is
    ``log max(|tau|, 1e-300)``: where a frame falls on a centre,
    ``|tau|^c = exp(c log |tau|)`` is 0 to double precision.
    """

    __slots__ = ("log_abs_tau", "before", "phone", "present", "onehot")

    def __init__(
        self,
        alignment: Alignment,
        phone_rows: np.ndarray,
        frame_rate: float,
        n_frames: int,
        stride: int = 1,
        start: int = 0,
        jacobian: bool = True,
    ):
        # Neighbouring segments of one phone (a pause cut in two) act as one segment.
        phone_rows = np.asarray(phone_rows)
        first = np.ones(len(phone_rows), dtype=bool)
        np.not_equal(phone_rows[1:], phone_rows[:-1], out=first[1:])
        last = np.ones_like(first)
        last[:-1] = first[1:]
        seg_start, seg_end = alignment.starts[first], alignment.ends[last]
        phone_rows = phone_rows[first]
        t = np.arange(start, n_frames, stride) / frame_rate
        # the segments overlapping these frames, and NEIGHBOURS more on either side
        lo = max(int(np.searchsorted(seg_end, t[0] if t.size else 0.0, side="left")) - NEIGHBOURS, 0)
        hi = int(np.searchsorted(seg_start, t[-1] if t.size else 0.0, side="right")) + NEIGHBOURS
        centres = 0.5 * (seg_start[lo:hi] + seg_end[lo:hi])
        tau = centres[:, None] - t[None, :]
        self.before = tau > 0
        self.log_abs_tau = np.log(np.maximum(np.abs(tau, out=tau), 1e-300, out=tau), out=tau)
        self.phone = np.asarray(phone_rows[lo:hi], dtype=np.intp)
        self.present = self.onehot = None
        if jacobian:
            # the phones present, and which of them each segment is (for the Jacobian)
            self.present, local = np.unique(self.phone, return_inverse=True)
            self.onehot = np.zeros((len(self.present), len(self.phone)))  # phone x segment
            self.onehot[local, np.arange(len(self.phone))] = 1.0

    @classmethod
    def blocks(
        cls, alignment: Alignment, phone_rows, frame_rate: float, n_frames: int, stride: int = 1, jacobian: bool = True
    ) -> list:
        """The designs of an utterance's frames ``0, stride, ...`` in blocks of about
        :data:`BLOCK_FRAMES` frames (see there); each block's frames are one slice of the output."""
        step = max(BLOCK_FRAMES // stride, 1) * stride
        return [
            cls(alignment, phone_rows, frame_rate, min(b + step, n_frames), stride, b, jacobian)
            for b in range(0, n_frames, step)
        ]


class _Scratch:
    """Work arrays reused from one design to the next (one allocation per evaluation, not per utterance)."""

    def __init__(self):
        self.buf = np.empty(0)

    def take(self, *shapes: tuple) -> list:
        """Uninitialised arrays of these shapes, consecutive views of one buffer."""
        sizes = [int(np.prod(sh)) for sh in shapes]
        if self.buf.size < sum(sizes):
            self.buf = np.empty(sum(sizes))
        ends = np.cumsum(sizes)
        return [self.buf[e - n : e].reshape(sh) for e, n, sh in zip(ends, sizes, shapes)]


def _weights(log_abs_tau, before, log_alpha, theta_l, theta_r, c, out=None, normalise: bool = True):
    """Normalised dominance of every segment at every frame, for ``k`` parameter sets at once.

    Parameters
    ----------
    log_abs_tau, before : ndarray, shape (n_segments, n_frames)
        Of a :class:`_Design`.
    log_alpha, theta_l, theta_r, c : ndarray, shape (k, n_segments)
        Per segment of the design (the phone's values), one row per parameter set.
    out : list of 3 ndarray, shape (k, n_segments, n_frames), optional
        Where to write ``w``, ``rate`` and ``exponent``.
    normalise : bool, default True
        False: leave ``w`` unnormalised (its columns sum to at least 1).

    Returns
    -------
    w : ndarray, shape (k, n_segments, n_frames)
        Columns sum to 1. Computed in the log domain with the per-frame maximum
        subtracted, so far frames never divide 0 by 0.
    rate : ndarray, shape (k, n_segments, n_frames)
        ``theta |tau|^c`` (minus the log dominance, but for ``log alpha``).
    exponent : ndarray, shape (k, n_segments, n_frames)
        ``c log |tau|``.
    """
    if out is None:
        out = [np.empty((len(c),) + log_abs_tau.shape) for _ in range(3)]
    w, rate, exponent = out
    np.multiply(c[:, :, None], log_abs_tau, out=exponent)
    np.copyto(rate, theta_r[:, :, None])
    np.copyto(rate, theta_l[:, :, None], where=before)
    np.exp(exponent, out=w)
    rate *= w
    np.subtract(log_alpha[:, :, None], rate, out=w)
    w -= w.max(axis=1, keepdims=True)
    # Weights below e^-100 of the largest count as e^-100 (nothing, to double precision):
    # subnormal numbers would slow every operation on them a hundredfold.
    np.maximum(w, -100.0, out=w)
    np.exp(w, out=w)
    if normalise:
        w /= w.sum(axis=1, keepdims=True)
    return w, rate, exponent


def cohen_massaro_trajectory(design: _Design, target, log_alpha, theta_l, theta_r, c) -> np.ndarray:
    """``F(t)`` of one channel at every frame of ``design``; parameters per phone, shape (n_phones,)."""
    p = design.phone
    par = (np.asarray(v, dtype=float)[None, p] for v in (log_alpha, theta_l, theta_r, c))
    w, _, _ = _weights(design.log_abs_tau, design.before, *par)
    return np.asarray(target, dtype=float)[p] @ w[0]


def _unpack(x: np.ndarray, n_phones: int):
    """Per-phone parameters of ``x`` (k, 5 * n_phones): ``T, log alpha, theta_l, theta_r, c``, each (k, n_phones)."""
    T, la, ll, lr, lc = (x[:, b * n_phones : (b + 1) * n_phones] for b in range(len(BLOCKS)))
    return T, la, np.exp(ll), np.exp(lr), np.exp(lc)


def _utterance_terms(params, d: _Design, y: np.ndarray, n_phones: int, jacobian: bool = True, scratch=None):
    """Residuals of one design for ``k`` parameter sets, and the Jacobian columns of its phones.

    ``params`` are :func:`_unpack`'s arrays (k, n_phones) and ``y`` (k, n_frames);
    ``scratch`` an optional :class:`_Scratch`.
    Returns ``r`` (k, n_frames), ``Jt`` (k, 5 * n_present, n_frames), the
    transposed Jacobian, and ``cols`` (5 * n_present,), the columns of the
    full Jacobian that ``Jt`` holds (the others are zero: a phone absent from
    the utterance does not touch it); ``Jt`` and ``cols`` are None unless
    ``jacobian``.
    """
    p = d.phone
    T, la, th_l, th_r, c = (v[:, p] for v in params)
    k, (S, n) = len(T), d.log_abs_tau.shape
    scratch = scratch or _Scratch()
    shape = (k, S, n)
    if jacobian:  # the weights are written straight into the first slot of z (below)
        rate, exponent, z = scratch.take(shape, shape, (k, len(BLOCKS), S, n))
        w = z[:, 0]
    else:
        w, rate, exponent = scratch.take(shape, shape, shape)
    _weights(d.log_abs_tau, d.before, la, th_l, th_r, c, out=[w, rate, exponent])
    F = np.matmul(T[:, None, :], w)[:, 0]
    if not jacobian:
        return F - y, None, None
    # dF/dphi = sum_s w_s dlogD_s/dphi (T_s - F) for a dominance parameter phi;
    # dlogD/dlog alpha = 1, dlogD/dlog theta = -theta |tau|^c (its side only),
    # dlogD/dlog c = -theta |tau|^c c log|tau|. One product with the phone-to-segment
    # map gives all five blocks: z holds w, w dev, w dev theta |tau|^c before the centre,
    # after it, and times c log|tau| (the last three with their signs flipped).
    wdev = np.subtract(T[:, :, None], F[:, None, :], out=z[:, 1])
    wdev *= w
    rate *= wdev
    np.multiply(rate, d.before, out=z[:, 2])
    np.subtract(rate, z[:, 2], out=z[:, 3])
    np.multiply(rate, exponent, out=z[:, 4])
    m = len(d.present)
    Jt = np.matmul(d.onehot, z).reshape(k, len(BLOCKS) * m, n)
    Jt[:, 2 * m :] *= -1.0
    cols = (np.arange(len(BLOCKS))[:, None] * n_phones + d.present[None, :]).ravel()
    return F - y, Jt, cols


def residuals_and_jacobian(x: np.ndarray, designs: list, targets: list, n_phones: int):
    """Residuals ``F - y`` over all frames of one channel and their exact Jacobian.

    Parameters
    ----------
    x : ndarray, shape (5 * n_phones,)
        Blocks in the order of :data:`BLOCKS`.
    designs : list of _Design
    targets : list of ndarray, shape (n_frames,) each
    n_phones : int

    Returns
    -------
    r : ndarray, shape (n_total_frames,)
    J : ndarray, shape (n_total_frames, 5 * n_phones)
    """
    params = _unpack(np.asarray(x, dtype=float)[None, :], n_phones)
    rs, Js = [], []
    for d, y in zip(designs, targets):
        r, Jt, cols = _utterance_terms(params, d, np.asarray(y, dtype=float)[None, :], n_phones)
        J = np.zeros((r.shape[1], len(BLOCKS) * n_phones))
        J[:, cols] = Jt[0].T
        rs.append(r[0])
        Js.append(J)
    return np.concatenate(rs), np.vstack(Js)


def normal_equations(x: np.ndarray, designs: list, targets: list, n_phones: int, jacobian: bool = True):
    """``(sum r^2, J^T r, J^T J)`` of :func:`residuals_and_jacobian`, without forming ``J``.

    Accumulated utterance by utterance over the columns of the phones each
    one contains: the cost is that of the utterances' small Jacobians, not of
    the corpus-long dense one. Several channels (parameter sets) are
    evaluated together.

    Parameters
    ----------
    x : ndarray, shape (5 * n_phones,) or (k, 5 * n_phones)
    designs : list of _Design
    targets : list of ndarray, shape (n_frames,) each, or (k, n_frames) with a 2-d ``x``
    n_phones : int
    jacobian : bool, default True
        False: the cost alone (``g`` and ``H`` are None).

    Returns
    -------
    cost : float, or ndarray (k,)
    g : ndarray, shape (5 * n_phones,) or (k, 5 * n_phones)
    H : ndarray, shape (5 * n_phones, 5 * n_phones) or (k, 5 * n_phones, 5 * n_phones)
    """
    x = np.asarray(x, dtype=float)
    single = x.ndim == 1
    X = x[None, :] if single else x
    params = _unpack(X, n_phones)
    k, n = len(X), len(BLOCKS) * n_phones
    cost = np.zeros(k)
    g = H = None
    if jacobian:
        g, H = np.zeros((k, n)), np.zeros((k, n, n))
    scratch = _Scratch()
    for d, y in zip(designs, targets):
        y = np.asarray(y, dtype=float)
        y = y[None, :] if single else y
        # channels a few at a time: work arrays of at most WORK_SIZE numbers stay in cache
        step = max(1, WORK_SIZE // max(d.log_abs_tau.size, 1))
        for a in range(0, k, step):
            part = slice(a, a + step)
            r, Jt, cols = _utterance_terms([v[part] for v in params], d, y[part], n_phones, jacobian, scratch)
            cost[part] += np.einsum("kf,kf->k", r, r)
            if jacobian:
                g[part, cols] += np.matmul(Jt, r[:, :, None])[:, :, 0]
                flat = H.reshape(k, -1)  # a view: H[part, cols, cols] += ... through flat indices
                G = np.matmul(Jt, Jt.transpose(0, 2, 1))
                flat[part, (cols[:, None] * n + cols[None, :]).ravel()] += G.reshape(len(G), -1)
    if single:
        return float(cost[0]), (None if g is None else g[0]), (None if H is None else H[0])
    return cost, g, H


def levenberg_marquardt(
    normal_eq,
    x0: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    *,
    max_nfev: int = 200,
    tol: float = 1e-4,
    on_stop=None,
):
    """Minimise sums of squares from their normal equations, within box bounds.

    Steps solve ``(H + mu diag(H)) step = -g`` (Marquardt's scaling) over the
    parameters not held at a bound by the gradient; a step is clipped to the
    bounds and taken only if the cost falls, so the cost never increases.
    ``mu`` follows Nielsen's rule: after a step taken it shrinks by
    ``max(1/3, 1 - (2 rho - 1)^3)``, ``rho`` the ratio of the actual to the
    predicted decrease; after a step refused it grows by ``nu``, which
    doubles with every refusal in a row. Stops when an accepted step lowers
    the cost by less than ``tol`` relatively or moves ``x`` by less than
    ``tol`` relatively, when ``mu`` exceeds 1e10, or after ``max_nfev``
    evaluations.

    Several independent problems (one per row of a 2-d ``x0``) run in
    lockstep: each has its own ``mu`` and stops on its own, and every
    evaluation handles all the problems still running at once.

    Parameters
    ----------
    normal_eq : callable
        1-d ``x0``: ``x -> (cost, g, H)`` with ``g = J^T r`` and ``H = J^T J``.
        2-d ``x0``: ``(X, rows) -> (cost, g, H)`` for the problems ``rows``
        (int array) at ``X`` (len(rows), n), with shapes (len(rows),),
        (len(rows), n) and (len(rows), n, n).
    x0, lower, upper : ndarray, shape (n,) or (k, n) (bounds: (n,), shared)
    max_nfev : int, default 200
    tol : float, default 1e-4
    on_stop : callable, optional
        Called with the problem's row (0 for a 1-d ``x0``) as each one stops.

    Returns
    -------
    x : ndarray, shape of ``x0``
    cost : float or ndarray (k,)
    nfev : int or ndarray of int (k,)

    Examples
    --------
    >>> t = np.linspace(0, 1, 20); y = 3 * np.exp(-2 * t)
    >>> def ne(x):
    ...     e = np.exp(-x[1] * t); r = x[0] * e - y; J = np.stack([e, -x[0] * t * e], 1)
    ...     return float(r @ r), J.T @ r, J.T @ J
    >>> x, cost, nfev = levenberg_marquardt(ne, np.array([1.0, 1.0]), np.zeros(2), np.full(2, 9.0), tol=1e-12)
    >>> np.round(x, 6).tolist()
    [3.0, 2.0]
    """
    x0 = np.asarray(x0, dtype=float)
    single = x0.ndim == 1
    if single:

        def batched(X, rows, f=normal_eq):
            c, g, H = f(X[0])
            return np.array([c]), g[None], H[None]

        X = np.clip(x0, lower, upper)[None, :]
        evaluate = batched
    else:
        X = np.clip(x0, lower, upper)
        evaluate = normal_eq
    k = len(X)
    rows = np.arange(k)
    cost, g, H = (np.array(v, dtype=float) for v in evaluate(X, rows))
    nfev = np.ones(k, dtype=int)
    mu, nu = np.full(k, 1e-3), np.full(k, 2.0)
    running = nfev < max_nfev
    reported = np.zeros(k, dtype=bool)

    def report():
        for i in np.flatnonzero(~running & ~reported):
            reported[i] = True
            if on_stop is not None:
                on_stop(int(i))

    while running.any():
        report()
        trial, predicted = {}, {}
        for i in np.flatnonzero(running):
            x = X[i]
            # Parameters held at a bound by the gradient stay out of the step (projected Newton).
            free = ~(((x <= lower) & (g[i] > 0)) | ((x >= upper) & (g[i] < 0)))
            if not free.any():
                running[i] = False
                continue
            Hf = H[i][np.ix_(free, free)]
            scale = np.maximum(np.diag(Hf), 1e-12 * max(np.max(np.diag(Hf)), 1e-300))
            step = np.zeros_like(x)
            try:
                step[free] = np.linalg.solve(Hf + mu[i] * np.diag(scale), -g[i][free])
            except np.linalg.LinAlgError:
                mu[i] *= nu[i]
                nu[i] *= 2.0
                running[i] = mu[i] <= 1e10
                continue
            trial[i] = np.clip(x + step, lower, upper)
            s = trial[i] - x
            predicted[i] = -(2.0 * s @ g[i] + s @ H[i] @ s)  # decrease of the Gauss-Newton model
        if not trial:
            continue
        ids = np.fromiter(trial, dtype=int)
        new_cost, new_g, new_H = evaluate(np.stack([trial[i] for i in ids]), ids)
        for j, i in enumerate(ids):
            nfev[i] += 1
            if new_cost[j] < cost[i]:
                gain = (cost[i] - new_cost[j]) / predicted[i] if predicted[i] > 0 else 0.0
                done = cost[i] - new_cost[j] <= tol * cost[i] or np.linalg.norm(trial[i] - X[i]) <= tol * (
                    np.linalg.norm(X[i]) + tol
                )
                X[i], cost[i], g[i], H[i] = trial[i], new_cost[j], new_g[j], new_H[j]
                mu[i] = max(mu[i] * max(1.0 / 3.0, 1.0 - (2.0 * gain - 1.0) ** 3), 1e-12)
                nu[i] = 2.0
                running[i] = not done
            else:
                mu[i] *= nu[i]
                nu[i] *= 2.0
                running[i] = mu[i] <= 1e10
            running[i] &= nfev[i] < max_nfev
    report()
    if single:
        return X[0], float(cost[0]), int(nfev[0])
    return X, cost, nfev


class CohenMassaro(Synthesizer):
    """Cohen & Massaro (1993): negative-exponential dominance and weighted-average targets.

    Parameters
    ----------
    ridge : float, default 1e-4
        Weight of the penalty pulling the log dominance parameters towards
        their starting values, relative to the mean squared (standardised)
        data residual. Fixes the scale gauge of ``alpha``; keep it small.
    max_nfev : int, default 200
        Maximum cost evaluations of the least-squares fit per channel.
    tol : float, default 1e-3
        Stop when an accepted step lowers the cost, or moves the
        parameters, by less than this, relatively. Past 1e-3 the fit creeps:
        on the bundled ``vtl`` corpus, 1e-4 took 2-4 times the evaluations on
        a third of the channels for a training RMSE 0.25% lower and a
        held-out RMSE no better.
    c_bounds : tuple of float, default (0.25, 4.0)
        Bounds on the exponent ``c``.
    fit_rate : float or None, default 100.0
        Fit on frames thinned to about this rate (Hz): every
        ``round(frame_rate / fit_rate)``-th frame (None: every frame). Cost
        grows with the fitted frames, and 400 Hz articulography holds little
        the model can use beyond 100 Hz.
    unknown_phone : {"error", "fallback"}, default "error"

    Attributes
    ----------
    target_, alpha_, theta_left_, theta_right_, c_ : ndarray, shape (n_phones, n_channels)
        Rows in the order of ``phones_``; rates in 1/s^c, times in seconds.
    cost_ : ndarray, shape (n_channels,)
        Final mean squared residual of each channel (channel units squared).
    n_fev_ : ndarray of int, shape (n_channels,)
    """

    name = "cohen-massaro"
    _tags = {"deterministic": True, "numpy_runtime": True}
    _parameter_constraints = {
        "ridge": [Interval(float, 0, None, closed="left")],
        "max_nfev": [Interval(int, 1, None, closed="left")],
        "tol": [Interval(float, 0, None, closed="left")],
        "c_bounds": [TupleOf(Interval(float, 0, None, closed="neither"), min_len=2, max_len=2, increasing=True)],
        "fit_rate": [Interval(float, 0, None, closed="neither"), None],
    }
    _state_schema = {  # checked at save and load (dam.modelfile.check_state)
        "cost_": StateArray("float", ("n_channels",), low=0),
        "n_fev_": StateArray("int", ("n_channels",), low=0),
        "target_": StateArray("float", ("n_phones", "n_channels")),
        **dict.fromkeys(
            ["alpha_", "theta_left_", "theta_right_", "c_"], StateArray("float", ("n_phones", "n_channels"), low=0)
        ),
    }

    def __init__(
        self,
        *,
        ridge: float = 1e-4,
        max_nfev: int = 200,
        tol: float = 1e-3,
        c_bounds: tuple = (0.25, 4.0),
        fit_rate: float | None = 100.0,
        unknown_phone: str = "error",
    ):
        self.ridge = ridge
        self.max_nfev = max_nfev
        self.tol = tol
        self.fit_rate = fit_rate
        self.c_bounds = c_bounds
        self.unknown_phone = unknown_phone

    @classmethod
    def get_test_params(cls) -> list[dict]:
        return [{"max_nfev": 8}, {"max_nfev": 5, "ridge": 1e-3, "unknown_phone": "fallback"}]

    def _stride(self, frame_rate: float) -> int:
        return 1 if self.fit_rate is None else max(1, int(round(frame_rate / self.fit_rate)))

    def _designs(self, corpus: Corpus) -> list:
        """One list of block designs per utterance (see :data:`BLOCK_FRAMES`)."""
        index = {p: i for i, p in enumerate(self.phone_counts_)}
        stride = self._stride(corpus.frame_rate)
        return [
            _Design.blocks(
                u.alignment, np.array([index[lab] for lab in u.alignment.labels]), u.frame_rate, u.n_frames, stride
            )
            for u in corpus
        ]

    def _fit(self, corpus: Corpus) -> None:
        P, C = len(self.phone_counts_), corpus.n_channels
        per_utt = self._designs(corpus)
        designs = [d for ds in per_utt for d in ds]
        stride = self._stride(corpus.frame_rate)
        n_total = sum(d.log_abs_tau.shape[1] for d in designs)
        dur = np.mean(np.concatenate([u.alignment.durations for u in corpus]))
        # Start: dominance falls to 1/e one mean segment duration from the centre.
        x0_dom = np.concatenate([np.zeros(P), np.full(P, -np.log(dur)), np.full(P, -np.log(dur)), np.zeros(P)])
        lo = np.concatenate([np.full(P, -np.inf), np.full(P, -20.0), np.full(3 * P, -np.inf)])
        hi = np.concatenate([np.full(P, np.inf), np.full(P, 20.0), np.full(3 * P, np.inf)])
        lo[4 * P :], hi[4 * P :] = np.log(self.c_bounds[0]), np.log(self.c_bounds[1])
        lo[2 * P : 4 * P], hi[2 * P : 4 * P] = np.log(1e-3), np.log(1e6)
        means = PhoneMean().fit(corpus).table_  # rows in the order of phone_counts_, as ours
        # Every channel standardised (one ridge weight fits them all), cut as the designs'
        # blocks, channels first: the channels' fits run in lockstep, evaluated together.
        Y = [u.trajectory[::stride] for u in corpus]
        mu = np.mean(np.concatenate(Y), axis=0)
        sd = np.std(np.concatenate(Y), axis=0) + 1e-12
        ys = [np.ascontiguousarray(part.T) for y, ds in zip(Y, per_utt) for part in _split((y - mu) / sd, ds)]
        X0 = np.concatenate([(means - mu) / sd, np.broadcast_to(x0_dom[:, None], (4 * P, C))]).T
        X0 = np.clip(X0, lo + 1e-9, hi - 1e-9)
        lam2 = self.ridge * n_total
        dom = np.arange(P, 5 * P)

        def penalised(X, rows):
            cost, g, H = normal_equations(X, designs, [y[rows] for y in ys], P)
            dev = X[:, dom] - X0[rows][:, dom]
            g[:, dom] += lam2 * dev
            H[:, dom, dom] += lam2
            cost += lam2 * np.einsum("kp,kp->k", dev, dev)
            return cost, g, H

        with progress.task("Cohen-Massaro", C, unit="channel") as bar:
            X, _, nfev = levenberg_marquardt(
                penalised,
                X0,
                lo,
                hi,
                max_nfev=self.max_nfev,
                tol=self.tol,
                on_stop=lambda ch: bar.step(str(corpus.channels[ch]), index=ch),
            )
        T, la, th_l, th_r, c = _unpack(X, P)
        self.target_ = mu + sd * T.T
        self.alpha_ = np.exp(la.T)
        self.theta_left_, self.theta_right_, self.c_ = th_l.T, th_r.T, c.T
        self.cost_ = normal_equations(X, designs, ys, P, jacobian=False)[0] / n_total * sd**2
        self.n_fev_ = np.asarray(nfev, dtype=int)

    def _predict(self, alignment: Alignment, n_frames: int) -> np.ndarray:
        index = {p: i for i, p in enumerate(self.phone_counts_)}
        rows = np.fromiter((index[p] for p in self._known_labels(alignment, self.unknown_phone)), dtype=np.intp)
        if rows.size and (rows == rows[0]).all():  # one segment (after merging): its target throughout
            return np.repeat(self.target_[rows[:1]], n_frames, axis=0)
        log_alpha, scratch, parts = np.log(self.alpha_), _Scratch(), []
        for d in _Design.blocks(alignment, rows, self.frame_rate_, n_frames, jacobian=False):
            # all channels at once: (channels, segments, frames)
            p = d.phone
            la, th_l, th_r, c = log_alpha[p].T, self.theta_left_[p].T, self.theta_right_[p].T, self.c_[p].T
            work = scratch.take(*[(len(self.channels_),) + d.log_abs_tau.shape] * 3)
            w, _, _ = _weights(d.log_abs_tau, d.before, la, th_l, th_r, c, out=work, normalise=False)
            parts.append((np.matmul(self.target_[p].T[:, None, :], w)[:, 0] / w.sum(axis=1)).T)
        return np.concatenate(parts)


def _split(y: np.ndarray, designs: list) -> list:
    """``y`` (one utterance's fitted frames) cut into the frames of each block design."""
    cuts = np.cumsum([d.log_abs_tau.shape[1] for d in designs])[:-1]
    return np.split(y, cuts)
