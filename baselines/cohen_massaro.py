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
(:func:`normal_equations`), which is what makes a 10-minute, 19-channel
corpus fit in minutes: scipy's ``least_squares`` factorises the dense
corpus-long Jacobian at every step, some 10x slower here. The weighted average is
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

    ``tau`` has shape (n_frames, n_segments) (every ``stride``-th frame
    from ``start``);
    ``phone`` (n_segments,) indexes the phone table. Adjacent segments of the
    same phone are merged first.
    """

    __slots__ = ("tau", "abs_tau", "log_abs_tau", "before", "phone", "present", "onehot")

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
        first = np.r_[True, phone_rows[1:] != phone_rows[:-1]]
        last = np.r_[first[1:], True]
        seg_start, seg_end = alignment.starts[first], alignment.ends[last]
        phone_rows = phone_rows[first]
        t = np.arange(start, n_frames, stride) / frame_rate
        # the segments overlapping these frames, and NEIGHBOURS more on either side
        lo = max(int(np.searchsorted(seg_end, t[0] if t.size else 0.0, side="left")) - NEIGHBOURS, 0)
        hi = int(np.searchsorted(seg_start, t[-1] if t.size else 0.0, side="right")) + NEIGHBOURS
        centres = 0.5 * (seg_start[lo:hi] + seg_end[lo:hi])
        self.tau = centres[None, :] - t[:, None]
        self.abs_tau = np.abs(self.tau)
        self.before = self.tau > 0
        self.phone = np.asarray(phone_rows[lo:hi], dtype=np.intp)
        self.log_abs_tau = self.present = self.onehot = None
        if jacobian:
            with np.errstate(divide="ignore"):
                self.log_abs_tau = np.where(self.abs_tau > 0, np.log(np.maximum(self.abs_tau, 1e-300)), 0.0)
            # the phones present, and which of them each segment is (for the Jacobian)
            self.present, local = np.unique(self.phone, return_inverse=True)
            self.onehot = np.zeros((len(self.phone), len(self.present)))
            self.onehot[np.arange(len(self.phone)), local] = 1.0

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


def _weights(design: _Design, log_alpha, theta_l, theta_r, c):
    """Normalised dominance (n_frames, n_segments) and ``theta |tau|^c`` per entry.

    Computed in the log domain with the per-frame maximum subtracted, so far
    frames never divide 0 by 0.
    """
    p = design.phone
    theta = np.where(design.before, theta_l[p], theta_r[p])
    power = design.abs_tau ** c[p]
    log_d = log_alpha[p] - theta * power
    log_d -= log_d.max(axis=1, keepdims=True)
    w = np.exp(log_d)
    w /= w.sum(axis=1, keepdims=True)
    return w, theta * power


def cohen_massaro_trajectory(design: _Design, target, log_alpha, theta_l, theta_r, c) -> np.ndarray:
    """``F(t)`` of one channel at every frame of ``design``; parameters per phone, shape (n_phones,)."""
    w, _ = _weights(design, log_alpha, theta_l, theta_r, c)
    return w @ target[design.phone]


def _unpack(x: np.ndarray, n_phones: int):
    T, la, ll, lr, lc = x.reshape(len(BLOCKS), n_phones)
    return T, la, np.exp(ll), np.exp(lr), np.exp(lc)


def _utterance_terms(params, d: _Design, y: np.ndarray, n_phones: int):
    """Residuals of one utterance and the Jacobian columns of the phones it contains.

    Returns ``r`` (n_frames,), ``J`` (n_frames, 5 * n_present) and ``cols``
    (5 * n_present,), the columns of the full Jacobian that ``J`` holds (the
    others are zero: a phone absent from the utterance does not touch it).
    """
    T, la, th_l, th_r, c = params
    w, tpow = _weights(d, la, th_l, th_r, c)
    Tseg = T[d.phone]
    F = w @ Tseg
    onehot = d.onehot
    # dF/dphi = sum_s w_s dlogD_s/dphi (T_s - F) for a dominance parameter phi.
    wdev = w * (Tseg[None, :] - F[:, None])
    J = np.hstack(
        [
            w @ onehot,  # dF/dT_p
            wdev @ onehot,  # dlogD/dlog alpha = 1
            (wdev * -np.where(d.before, tpow, 0.0)) @ onehot,  # left rate, before the centre
            (wdev * -np.where(d.before, 0.0, tpow)) @ onehot,  # right rate, after it
            (wdev * -(tpow * c[d.phone] * d.log_abs_tau)) @ onehot,
        ]
    )  # d|tau|^c/dlog c
    cols = (np.arange(len(BLOCKS))[:, None] * n_phones + d.present[None, :]).ravel()
    return F - y, J, cols


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
    params = _unpack(x, n_phones)
    rs, Js = [], []
    for d, y in zip(designs, targets):
        r, Jc, cols = _utterance_terms(params, d, y, n_phones)
        J = np.zeros((len(r), len(BLOCKS) * n_phones))
        J[:, cols] = Jc
        rs.append(r)
        Js.append(J)
    return np.concatenate(rs), np.vstack(Js)


def normal_equations(x: np.ndarray, designs: list, targets: list, n_phones: int):
    """``(sum r^2, J^T r, J^T J)`` of :func:`residuals_and_jacobian`, without forming ``J``.

    Accumulated utterance by utterance over the columns of the phones each
    one contains: the cost is that of the utterances' small Jacobians, not of
    the corpus-long dense one.
    """
    params = _unpack(x, n_phones)
    n = len(BLOCKS) * n_phones
    cost, g, H = 0.0, np.zeros(n), np.zeros((n, n))
    for d, y in zip(designs, targets):
        r, Jc, cols = _utterance_terms(params, d, y, n_phones)
        cost += float(r @ r)
        g[cols] += Jc.T @ r
        H[np.ix_(cols, cols)] += Jc.T @ Jc
    return cost, g, H


def levenberg_marquardt(
    normal_eq, x0: np.ndarray, lower: np.ndarray, upper: np.ndarray, *, max_nfev: int = 200, tol: float = 1e-4
):
    """Minimise a sum of squares from its normal equations, within box bounds.

    Steps solve ``(H + mu diag(H)) step = -g`` (Marquardt's scaling) over the
    parameters not held at a bound by the gradient; a step is clipped to the
    bounds and taken only if the cost falls, else ``mu``
    grows tenfold, so the cost never increases. Stops when an accepted step
    lowers the cost by less than ``tol`` relatively or moves ``x`` by less
    than ``tol`` relatively, when ``mu`` exceeds 1e10, or after ``max_nfev``
    evaluations.

    Parameters
    ----------
    normal_eq : callable
        ``x -> (cost, g, H)`` with ``g = J^T r`` and ``H = J^T J``.
    x0, lower, upper : ndarray, shape (n,)

    Returns
    -------
    x : ndarray, shape (n,)
    cost : float
    nfev : int
    """
    x = np.clip(x0, lower, upper)
    cost, g, H = normal_eq(x)
    nfev, mu = 1, 1e-3
    while nfev < max_nfev:
        # Parameters held at a bound by the gradient stay out of the step (projected Newton).
        free = ~(((x <= lower) & (g > 0)) | ((x >= upper) & (g < 0)))
        if not free.any():
            break
        Hf = H[np.ix_(free, free)]
        scale = np.maximum(np.diag(Hf), 1e-12 * max(np.max(np.diag(Hf)), 1e-300))
        step = np.zeros_like(x)
        try:
            step[free] = np.linalg.solve(Hf + mu * np.diag(scale), -g[free])
        except np.linalg.LinAlgError:
            mu *= 10.0
            continue
        x_new = np.clip(x + step, lower, upper)
        new = normal_eq(x_new)
        nfev += 1
        if new[0] < cost:
            done = cost - new[0] <= tol * cost or np.linalg.norm(x_new - x) <= tol * (np.linalg.norm(x) + tol)
            x, (cost, g, H) = x_new, new
            mu = max(mu / 10.0, 1e-12)
            if done:
                break
        else:
            mu *= 10.0
            if mu > 1e10:
                break
    return x, cost, nfev


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
    tol : float, default 1e-4
        Stop when an accepted step lowers the cost, or moves the
        parameters, by less than this, relatively.
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
        tol: float = 1e-4,
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
        n_total = sum(len(d.tau) for d in designs)
        dur = np.mean(np.concatenate([u.alignment.durations for u in corpus]))
        # Start: dominance falls to 1/e one mean segment duration from the centre.
        x0_dom = np.concatenate([np.zeros(P), np.full(P, -np.log(dur)), np.full(P, -np.log(dur)), np.zeros(P)])
        lo = np.concatenate([np.full(P, -np.inf), np.full(P, -20.0), np.full(3 * P, -np.inf)])
        hi = np.concatenate([np.full(P, np.inf), np.full(P, 20.0), np.full(3 * P, np.inf)])
        lo[4 * P :], hi[4 * P :] = np.log(self.c_bounds[0]), np.log(self.c_bounds[1])
        lo[2 * P : 4 * P], hi[2 * P : 4 * P] = np.log(1e-3), np.log(1e6)
        means = PhoneMean().fit(corpus).table_  # rows in the order of phone_counts_, as ours
        out = {k: np.zeros((P, C)) for k in ("target", "alpha", "theta_left", "theta_right", "c")}
        self.cost_ = np.zeros(C)
        self.n_fev_ = np.zeros(C, dtype=int)
        lam = np.sqrt(self.ridge * n_total)
        for ch in progress.track(range(C), "Cohen-Massaro", unit="channel", labels=list(corpus.channels)):
            ys = [u.trajectory[::stride, ch] for u in corpus]
            mu, sd = np.mean(np.concatenate(ys)), np.std(np.concatenate(ys)) + 1e-12
            # standardised (one ridge weight fits every channel), cut as the designs' blocks
            ys = [part for y, ds in zip(ys, per_utt) for part in _split(np.asarray((y - mu) / sd), ds)]
            x0 = np.concatenate([(means[:, ch] - mu) / sd, x0_dom])
            x0 = np.clip(x0, lo + 1e-9, hi - 1e-9)

            dom = np.arange(P, 5 * P)

            def penalised(x, ys=ys, x0=x0, dom=dom):
                cost, g, H = normal_equations(x, designs, ys, P)
                dev = x[dom] - x0[dom]
                g[dom] += lam**2 * dev
                H[dom, dom] += lam**2
                return cost + lam**2 * float(dev @ dev), g, H

            x, cost, nfev = levenberg_marquardt(penalised, x0, lo, hi, max_nfev=self.max_nfev, tol=self.tol)
            T, la, th_l, th_r, c = _unpack(x, P)
            out["target"][:, ch] = mu + sd * T
            out["alpha"][:, ch] = np.exp(la)
            out["theta_left"][:, ch], out["theta_right"][:, ch], out["c"][:, ch] = th_l, th_r, c
            self.cost_[ch] = normal_equations(x, designs, ys, P)[0] / n_total * sd**2
            self.n_fev_[ch] = nfev
        self.target_, self.alpha_ = out["target"], out["alpha"]
        self.theta_left_, self.theta_right_, self.c_ = out["theta_left"], out["theta_right"], out["c"]

    def _predict(self, alignment: Alignment, n_frames: int) -> np.ndarray:
        index = {p: i for i, p in enumerate(self.phone_counts_)}
        rows = np.fromiter((index[p] for p in self._known_labels(alignment, self.unknown_phone)), dtype=np.intp)
        parts = []
        for d in _Design.blocks(alignment, rows, self.frame_rate_, n_frames, jacobian=False):
            # all channels at once: (frames, segments, channels)
            p = d.phone
            theta = np.where(d.before[:, :, None], self.theta_left_[p], self.theta_right_[p])
            log_d = np.log(self.alpha_[p]) - theta * d.abs_tau[:, :, None] ** self.c_[p]
            log_d -= log_d.max(axis=1, keepdims=True)
            w = np.exp(log_d)
            parts.append(np.einsum("fsc,sc->fc", w, self.target_[p]) / w.sum(axis=1))
        return np.concatenate(parts)


def _split(y: np.ndarray, designs: list) -> list:
    """``y`` (one utterance's fitted frames) cut into the frames of each block design."""
    cuts = np.cumsum([len(d.tau) for d in designs])[:-1]
    return np.split(y, cuts)
