"""Trajectory synthesis of the Multidimensional Morphable Model (Ezzat, Geiger & Poggio 2002).

Each phone ``p`` is a Gaussian in control space: mean ``mu_p`` and a
diagonal covariance ``Sigma_p``. For an utterance of ``n`` frames, ``mu`` and
``Sigma`` stack the Gaussian of the phone at every frame; the trajectory is

    y* = argmin_y (y - mu)^T D^T Sigma^-1 D (y - mu) + lambda y^T W^T W y,

with ``D`` the diagonal duration weighting (every frame of a segment of
``n_s`` frames weighs ``1/sqrt(n_s)``, so short phones count as much as long
ones, as Ezzat et al. do; ``duration_weighting=False`` weighs frames equally)
and ``W`` the first- or second-order difference operator. With diagonal
covariances the channels decouple and each one solves the banded symmetric
positive definite system

    (D^2 Sigma^-1 + lambda W^T W) y = D^2 Sigma^-1 mu,

tridiagonal (order 1) or pentadiagonal (order 2). Training follows Ezzat et
al.: means and variances start from the per-phone statistics of the
training frames and are then trained by gradient descent (L-BFGS, with the
exact adjoint gradient of :func:`synthesis_loss_and_gradient`) to minimise
the synthesis error on the training corpus. The smoothness weight
``lambda`` is chosen among ``smoothness`` candidates on a held-out part of
the training corpus (``validation_fraction``), then the model is refitted on
all of it.

Fitting uses ``scipy.linalg.solveh_banded``; synthesis uses it too when
scipy is installed and otherwise :func:`banded_cholesky_solve`, a banded
Cholesky in numpy alone (same result, slower).
"""

from __future__ import annotations

import math

import numpy as np

from dam import Alignment, Corpus, Interval, StateArray, Synthesizer, TupleOf, progress

__all__ = [
    "MMM",
    "difference_gram_banded",
    "banded_cholesky_solve",
    "solve_banded_spd",
    "mmm_system",
    "synthesis_loss_and_gradient",
]


def difference_gram_banded(n: int, order: int) -> np.ndarray:
    """``W^T W`` for the ``order``-th difference operator ``W`` on ``n`` frames, in lower band form.

    Returns
    -------
    ndarray, shape (order + 1, n)
        ``ab[k, i] = (W^T W)[i + k, i]`` (``scipy.linalg.solveh_banded(..., lower=True)``
        layout; entries past the end are 0).
    """
    if order not in (1, 2):
        raise ValueError(f"difference order is {order!r}; use 1 or 2")
    stencil = np.array([-1.0, 1.0]) if order == 1 else np.array([1.0, -2.0, 1.0])
    ab = np.zeros((order + 1, n))
    # (W^T W)[i+k, i] = sum over rows r of W of stencil[i+k-r] * stencil[i-r]
    rows = max(n - order, 0)  # row r of W touches frames r .. r + order
    for a in range(order + 1):
        for b in range(a, order + 1):
            ab[b - a, a : a + rows] += stencil[a] * stencil[b]
    return ab


def banded_cholesky_solve(ab: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Solve symmetric positive definite banded systems, in numpy alone.

    Parameters
    ----------
    ab : ndarray, shape (..., u + 1, n)
        Lower band form: ``ab[..., k, i] = M[i + k, i]``; leading axes are a batch.
    b : ndarray, shape (..., n)

    Returns
    -------
    ndarray, shape (..., n)
        ``M^-1 b`` via the banded Cholesky factor ``M = L L^T`` (O(n u^2)).
    """
    ab = np.asarray(ab, dtype=float)
    b = np.asarray(b, dtype=float)
    flat_ab = ab.reshape(-1, *ab.shape[-2:])
    flat_b = b.reshape(-1, b.shape[-1])
    out = np.array([_cholesky_solve_one(a.tolist(), v.tolist()) for a, v in zip(flat_ab, flat_b)])
    return out.reshape(b.shape)


def _cholesky_solve_one(ab: list, b: list) -> list:
    """One banded system, on Python floats: the recurrences are sequential, and
    scalar arithmetic beats numpy calls on length-1 slices by an order of magnitude."""
    u, n = len(ab) - 1, len(b)
    L = [[0.0] * n for _ in range(u + 1)]  # L[k][i] = factor[i + k, i]
    sqrt = math.sqrt
    for i in range(n):
        d = ab[0][i]
        for k in range(1, min(u, i) + 1):
            d -= L[k][i - k] ** 2
        if d <= 0.0:
            raise np.linalg.LinAlgError("banded matrix is not positive definite")
        piv = L[0][i] = sqrt(d)
        for j in range(1, min(u, n - 1 - i) + 1):
            s = ab[j][i]
            for k in range(1, min(u - j, i) + 1):
                s -= L[j + k][i - k] * L[k][i - k]
            L[j][i] = s / piv
    z = list(b)
    for i in range(n):  # L z = b
        s = z[i]
        for k in range(1, min(u, i) + 1):
            s -= L[k][i - k] * z[i - k]
        z[i] = s / L[0][i]
    for i in range(n - 1, -1, -1):  # L^T x = z
        s = z[i]
        for k in range(1, min(u, n - 1 - i) + 1):
            s -= L[k][i] * z[i + k]
        z[i] = s / L[0][i]
    return z


def solve_banded_spd(ab: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Batched banded SPD solve: LAPACK (scipy) when installed, else :func:`banded_cholesky_solve`.

    Same arguments as :func:`banded_cholesky_solve`; the numpy path loops over
    frames in Python and is several times slower, but needs nothing beyond numpy.
    """
    try:
        # LAPACK's banded Cholesky itself: scipy.linalg.solveh_banded's checks cost
        # several times the solve of a phrase (a per-utterance call solves one per channel)
        from scipy.linalg.lapack import dpbsv
    except ImportError:
        return banded_cholesky_solve(ab, b)
    ab, b = np.asarray(ab, dtype=float), np.asarray(b, dtype=float)
    flat_ab = ab.reshape(-1, *ab.shape[-2:])
    flat_b = b.reshape(-1, b.shape[-1])
    out = np.empty(flat_b.shape)
    for i in range(len(flat_b)):
        _, out[i], info = dpbsv(flat_ab[i], flat_b[i], lower=1)
        if info > 0:
            raise np.linalg.LinAlgError(f"banded matrix is not positive definite (leading minor {info})")
    return out.reshape(b.shape)


def _frame_weights(alignment: Alignment, frame_rate: float, n_frames: int, duration_weighting: bool):
    """Segment of every frame, and the squared duration weight ``D_tt^2`` of every frame."""
    seg = alignment.segment_index(frame_rate, n_frames)
    if not duration_weighting:
        return seg, np.ones(n_frames)
    counts = np.bincount(seg, minlength=len(alignment))
    return seg, 1.0 / counts[seg]


def mmm_system(precision_frames: np.ndarray, gram_ab: np.ndarray, lam: float) -> np.ndarray:
    """Band form of ``D^2 Sigma^-1 + lambda W^T W`` given the diagonal ``D^2 Sigma^-1`` per frame.

    ``precision_frames`` has shape (..., n); returns (..., u + 1, n).
    """
    ab = np.broadcast_to(lam * gram_ab, precision_frames.shape[:-1] + gram_ab.shape).copy()
    ab[..., 0, :] += precision_frames
    return ab


def synthesis_loss_and_gradient(mu, log_var, utterances, lam: float):
    """Squared synthesis error of one channel and its gradient (adjoint method).

    Parameters
    ----------
    mu, log_var : ndarray, shape (n_phones,)
        Phone means and log variances of the channel.
    utterances : list of (rows, dw, gram_ab, y)
        ``rows`` the phone of every frame, ``dw`` the squared duration weights,
        ``gram_ab`` from :func:`difference_gram_banded`, ``y`` the truth (n_frames,).
    lam : float

    Returns
    -------
    loss : float
        ``sum_t (y*_t - y_t)^2`` over every frame.
    grad_mu, grad_log_var : ndarray, shape (n_phones,)

    Notes
    -----
    With ``M y* = A mu_f`` (``A = D^2 Sigma^-1`` diagonal, ``mu_f`` the frame means),
    ``g = 2 (y* - y)`` and the adjoint ``v = M^-1 g``: ``dL/dmu_f = A v`` and
    ``dL/dA = v (mu_f - y*)``; ``dA/dlog var = -A``.
    """
    from scipy.linalg import solveh_banded

    loss = 0.0
    g_mu = np.zeros_like(mu)
    g_lv = np.zeros_like(log_var)
    prec = np.exp(-log_var)
    for rows, dw, gram_ab, y in utterances:
        A = dw * prec[rows]
        mu_f = mu[rows]
        M = mmm_system(A, gram_ab, lam)
        ys = solveh_banded(M, A * mu_f, lower=True, check_finite=False)
        g = 2.0 * (ys - y)
        loss += float(np.sum((ys - y) ** 2))
        v = solveh_banded(M, g, lower=True, check_finite=False)
        g_mu += np.bincount(rows, weights=A * v, minlength=len(mu))
        g_lv += np.bincount(rows, weights=-A * v * (mu_f - ys), minlength=len(mu))
    return loss, g_mu, g_lv


class MMM(Synthesizer):
    """Ezzat et al. (2002) MMM trajectory synthesis: phone Gaussians and a smoothness prior.

    Parameters
    ----------
    smoothness : tuple of float, default (1, 10, 100, 1000)
        Candidate values of ``lambda`` (the model works on standardised
        channels and frame differences, so ``lambda`` depends on the frame
        rate); one value skips the validation. Scaling ``lambda`` and every
        variance together leaves the trajectory unchanged, so once the
        variances are trained ``lambda`` mostly sets where their training
        starts; the held-out choice still picks the better start.
    order : {1, 2}, default 2
        Order of the difference operator ``W``.
    duration_weighting : bool, default True
        Weigh each frame by ``1/sqrt(segment frames)`` in the target term.
    max_iter : int, default 100
        L-BFGS iterations of the training per channel and candidate.
    validation_fraction : float, default 0.2
        Share of the training utterances held out to choose ``lambda``.
    var_floor : float, default 1e-4
        Lower bound of the (standardised) variances.
    random_state : int, default 0
        Seed of the validation split.
    unknown_phone : {"error", "fallback"}, default "error"

    Attributes
    ----------
    mean_, var_ : ndarray, shape (n_phones, n_channels)
        Trained phone means and variances (channel units), rows in the order of ``phones_``.
    smoothness_ : float
        The chosen ``lambda``.
    validation_rmse_ : dict
        Held-out RMSE (standardised units) of every candidate ``lambda``.
    loss_ : ndarray, shape (n_channels,)
        Final training mean squared error per channel (channel units squared).
    channel_scale_ : ndarray, shape (n_channels,)
        Standard deviation of each training channel (``lambda`` is per standardised channel).
    """

    name = "mmm"
    _tags = {"deterministic": True, "numpy_runtime": True}
    _parameter_constraints = {
        "smoothness": [TupleOf(Interval(float, 0, None, closed="neither")), Interval(float, 0, None, closed="neither")],
        "order": [Interval(int, 1, 2, closed="both")],
        "duration_weighting": ["boolean"],
        "max_iter": [Interval(int, 0, None, closed="left")],
        "validation_fraction": [Interval(float, 0, 1, closed="neither")],
        "var_floor": [Interval(float, 0, None, closed="neither")],
    }
    _state_schema = {  # checked at save and load (dam.modelfile.check_state)
        "validation_rmse_": None,
        "smoothness_": Interval(float, 0, None, closed="neither"),
        "mean_": StateArray("float", ("n_phones", "n_channels")),
        "var_": StateArray("float", ("n_phones", "n_channels"), low=0),
        "loss_": StateArray("float", ("n_channels",), low=0),
        "channel_scale_": StateArray("float", ("n_channels",), low=0),
    }

    def __init__(
        self,
        *,
        smoothness: tuple = (1.0, 10.0, 100.0, 1000.0),
        order: int = 2,
        duration_weighting: bool = True,
        max_iter: int = 100,
        validation_fraction: float = 0.2,
        var_floor: float = 1e-4,
        random_state: int = 0,
        unknown_phone: str = "error",
    ):
        self.smoothness = smoothness
        self.order = order
        self.duration_weighting = duration_weighting
        self.max_iter = max_iter
        self.validation_fraction = validation_fraction
        self.var_floor = var_floor
        self.random_state = random_state
        self.unknown_phone = unknown_phone

    @classmethod
    def get_test_params(cls) -> list[dict]:
        return [
            {"smoothness": (1.0, 100.0), "max_iter": 20},
            {"smoothness": (10.0,), "order": 1, "max_iter": 10, "unknown_phone": "fallback"},
        ]

    # -- fitting -----------------------------------------------------------
    def _prepare(self, corpus: Corpus, index: dict, loc, scale) -> list:
        """Per utterance: frame phone rows, duration weights, W^T W band, standardised truth."""
        out = []
        for u in corpus:
            seg, dw = _frame_weights(u.alignment, u.frame_rate, u.n_frames, self.duration_weighting)
            rows = np.array([index[lab] for lab in u.alignment.labels])[seg]
            out.append((rows, dw, difference_gram_banded(u.n_frames, self.order), (u.trajectory - loc) / scale))
        return out

    def _train(self, data: list, mu0: np.ndarray, lv0: np.ndarray, lam: float):
        """Train means and log variances of every channel for one ``lambda``; returns (mu, lv, mse)."""
        from scipy.optimize import minimize

        P, C = mu0.shape
        lo = np.log(self.var_floor)
        mu, lv, mse = mu0.copy(), lv0.copy(), np.zeros(C)
        n_total = sum(len(d[0]) for d in data)
        for ch in progress.track(range(C), f"MMM (lambda {lam:g})", unit="channel"):
            utts = [(rows, dw, gab, y[:, ch]) for rows, dw, gab, y in data]

            def fun(x, utts=utts):
                loss, gm, gl = synthesis_loss_and_gradient(x[:P], x[P:], utts, lam)
                return loss / n_total, np.concatenate([gm, gl]) / n_total

            x0 = np.concatenate([mu0[:, ch], np.maximum(lv0[:, ch], lo)])
            bounds = [(None, None)] * P + [(lo, None)] * P
            res = minimize(fun, x0, jac=True, method="L-BFGS-B", bounds=bounds, options={"maxiter": self.max_iter})
            mu[:, ch], lv[:, ch], mse[ch] = res.x[:P], res.x[P:], res.fun
        return mu, lv, mse

    def _synthesize_std(self, data: list, mu: np.ndarray, lv: np.ndarray, lam: float) -> list:
        from scipy.linalg import solveh_banded

        out = []
        for rows, dw, gab, _ in data:
            A = dw[:, None] * np.exp(-lv[rows])
            out.append(
                np.stack(
                    [
                        solveh_banded(
                            mmm_system(A[:, c], gab, lam), A[:, c] * mu[rows, c], lower=True, check_finite=False
                        )
                        for c in range(mu.shape[1])
                    ],
                    axis=1,
                )
            )
        return out

    def _fit(self, corpus: Corpus) -> None:
        index = {p: i for i, p in enumerate(self.phone_counts_)}
        Y = np.concatenate(corpus.trajectories)
        loc, scale = Y.mean(axis=0), Y.std(axis=0) + 1e-12
        data = self._prepare(corpus, index, loc, scale)
        P = len(index)
        cands = [float(v) for v in np.atleast_1d(np.asarray(self.smoothness, dtype=float))]
        self.validation_rmse_ = {}
        if len(cands) > 1 and len(corpus) >= 2:
            rng = np.random.default_rng(self.random_state)
            order = rng.permutation(len(corpus))
            n_val = min(max(1, int(round(self.validation_fraction * len(corpus)))), len(corpus) - 1)
            val, trn = order[:n_val], order[n_val:]
            # Start and train on the training part only: the held-out frames must not
            # leak into the choice of lambda (phones it lacks start at mean 0, variance 1).
            part = [data[i] for i in trn]
            mu0, lv0 = _phone_start(part, P, self.var_floor)
            for lam in cands:
                mu, lv, _ = self._train(_concatenated(part), mu0, lv0, lam)
                held_out = _concatenated([data[i] for i in val])
                err = np.concatenate([p - d[3] for p, d in zip(self._synthesize_std(held_out, mu, lv, lam), held_out)])
                self.validation_rmse_[lam] = float(np.sqrt(np.mean(err**2)))
            lam = min(cands, key=lambda v: (self.validation_rmse_[v], v))
        else:
            lam = cands[0]
        mu0, lv0 = _phone_start(data, P, self.var_floor)
        mu, lv, mse = self._train(_concatenated(data), mu0, lv0, lam)
        self.smoothness_ = lam
        self.mean_ = loc + scale * mu
        self.var_ = np.exp(lv) * scale**2
        self.loss_ = mse * scale**2
        self.channel_scale_ = scale

    # -- synthesis (numpy only) ----------------------------------------------
    def _predict(self, alignment: Alignment, n_frames: int) -> np.ndarray:
        index = {p: i for i, p in enumerate(self.phone_counts_)}
        labels = self._known_labels(alignment, self.unknown_phone)
        seg, dw = _frame_weights(alignment, self.frame_rate_, n_frames, self.duration_weighting)
        rows = np.array([index[lab] for lab in labels])[seg]
        A = (dw[:, None] / self.var_[rows]).T  # (n_channels, n_frames)
        # lambda was chosen on standardised channels: in channel units it is lambda / scale^2.
        lam = (self.smoothness_ / self.channel_scale_**2)[:, None, None]
        M = mmm_system(A, difference_gram_banded(n_frames, self.order), lam)
        return solve_banded_spd(M, A * self.mean_[rows].T).T


def _concatenated(data: list) -> list:
    """Utterances as one block-diagonal banded system (one LAPACK call instead of one per utterance).

    ``W^T W`` of each utterance has no entry past its last frame, so stacking
    the bands end to end couples nothing across utterances.
    """
    rows, dw, gab, y = zip(*data)
    return [(np.concatenate(rows), np.concatenate(dw), np.concatenate(gab, axis=1), np.concatenate(y))]


def _phone_start(data: list, n_phones: int, var_floor: float):
    """Mean and log variance of the (standardised) frames of every phone in ``data``.

    The starting point of the training. A phone that owns no frame here starts
    at the standardised corpus mean 0 and variance 1.

    Returns
    -------
    mu0, lv0 : ndarray, shape (n_phones, n_channels)
    """
    C = data[0][3].shape[1]
    sums, sq, counts = np.zeros((n_phones, C)), np.zeros((n_phones, C)), np.zeros(n_phones)
    for rows, _, _, y in data:
        np.add.at(sums, rows, y)
        np.add.at(counts, rows, 1.0)
    seen = counts[:, None] > 0
    mu0 = np.where(seen, sums / np.maximum(counts, 1)[:, None], 0.0)
    for rows, _, _, y in data:
        np.add.at(sq, rows, (y - mu0[rows]) ** 2)
    var = np.where(seen, sq / np.maximum(counts, 1)[:, None], 1.0)
    return mu0, np.log(np.maximum(var, var_floor))
