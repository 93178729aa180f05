"""Dynamic features and maximum-likelihood parameter generation (Tokuda et al. 2000).

The observation of frame ``t`` stacks the static value and the outputs of
the dynamic-feature windows (:data:`WINDOWS`: HTS's delta ``[-0.5, 0, 0.5]``
and delta-delta ``[1, -2, 1]``). Written as ``o = W c`` for one channel
``c`` of length ``T``, with ``W`` of shape ``(3T, T)``, MLPG finds the
trajectory that maximizes the likelihood of the per-frame Gaussian means
``mu`` and precisions ``p`` (diagonal)::

    (W' P W) c = W' P mu

``W' P W`` is symmetric positive definite with half bandwidth 2 (the
widest window reaches one frame either side), so each channel is one
banded Cholesky solve (:func:`scipy.linalg.solveh_banded`), O(T); without
scipy (a saved model runs on numpy alone) the same factorization in numpy,
all channels at once (:func:`solveh_banded_numpy`).

Edges: a window tap that falls outside the utterance reads the nearest frame
(edge frames repeated), both when the training observations are computed
(:func:`dynamic_features`) and inside ``W`` here, so training and
generation use the same ``W``.
"""

from __future__ import annotations

import numpy as np

__all__ = ["WINDOWS", "dynamic_features", "mlpg", "window_matrix", "solveh_banded_numpy"]

#: (offsets, coefficients) of the static, delta and delta-delta windows.
WINDOWS = (((0,), (1.0,)), ((-1, 1), (-0.5, 0.5)), ((-1, 0, 1), (1.0, -2.0, 1.0)))


def dynamic_features(x, windows=WINDOWS) -> np.ndarray:
    """Static and dynamic features of a trajectory.

    Parameters
    ----------
    x : array-like, shape (T, C)
    windows : sequence of (offsets, coefficients), default :data:`WINDOWS`

    Returns
    -------
    ndarray, shape (T, len(windows) * C)
        Window ``k`` of channel ``c`` in column ``k * C + c``; taps beyond the
        ends read the first/last frame.

    Examples
    --------
    >>> dynamic_features(np.array([[0.0], [1.0], [4.0]]))[:, 1]
    array([0.5, 2. , 1.5])
    """
    x = np.asarray(x, dtype=float)
    if x.ndim == 1:
        x = x[:, None]
    T = len(x)
    t = np.arange(T)
    out = []
    for offsets, coefs in windows:
        acc = np.zeros_like(x)
        for o, w in zip(offsets, coefs):
            acc += w * x[np.clip(t + o, 0, T - 1)]
        out.append(acc)
    return np.concatenate(out, axis=1)


def window_matrix(T: int, windows=WINDOWS):
    """The sparse ``W`` of shape ``(len(windows) * T, T)`` (rows window-major) with the edge rule above."""
    from scipy.sparse import coo_matrix

    rows, cols, vals = [], [], []
    t = np.arange(T)
    for k, (offsets, coefs) in enumerate(windows):
        for o, w in zip(offsets, coefs):
            rows.append(k * T + t)
            cols.append(np.clip(t + o, 0, T - 1))
            vals.append(np.full(T, w))
    return coo_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(len(windows) * T, T)
    ).tocsr()


def mlpg(mean, precision, windows=WINDOWS) -> np.ndarray:
    """Maximum-likelihood trajectory for per-frame Gaussian means and precisions.

    Parameters
    ----------
    mean : array-like, shape (T, K * C)
        Means of the static and dynamic features, layout of
        :func:`dynamic_features` (``K = len(windows)``).
    precision : array-like, shape (T, K * C)
        Inverse variances (diagonal covariance), same layout; positive.
    windows : sequence of (offsets, coefficients), default :data:`WINDOWS`

    Returns
    -------
    ndarray, shape (T, C)
        ``c = (W' P W)^{-1} W' P mu`` per channel, by a banded solve.

    Examples
    --------
    >>> mu = np.array([[1.0, 0, 0], [3.0, 0, 0]])          # static 1 then 3, zero velocity
    >>> c = mlpg(mu, np.ones_like(mu))
    >>> bool(c[0, 0] < c[1, 0]) and bool(1 < c[0, 0] < c[1, 0] < 3)
    True
    """
    mean = np.asarray(mean, dtype=float)
    precision = np.asarray(precision, dtype=float)
    T = mean.shape[0]
    K = len(windows)
    C = mean.shape[1] // K
    if mean.shape != (T, K * C) or precision.shape != mean.shape:
        raise ValueError(f"mean {mean.shape} and precision {precision.shape} must both be (T, {K} * C)")
    if T == 0:
        return np.zeros((0, C))
    width = max(max(abs(o) for o in offs) for offs, _ in windows)
    u = 2 * width  # half bandwidth of W' P W
    # Every (window, tap a, tap b) term p w_a w_b lands on A[col_a, col_b]; one bincount adds them all.
    t = np.arange(T)
    chan = np.arange(C)
    band_idx, band_w, rhs_idx, rhs_w = [], [], [], []
    for k, (offsets, coefs) in enumerate(windows):
        p = precision[:, k * C : (k + 1) * C]
        pm = p * mean[:, k * C : (k + 1) * C]
        cols = [np.clip(t + o, 0, T - 1) for o in offsets]
        for a, wa in zip(cols, coefs):
            rhs_idx.append(a[:, None] * C + chan)
            rhs_w.append(wa * pm)
            for b, wb in zip(cols, coefs):
                keep = a <= b  # each unordered pair lands once in the upper triangle
                band_idx.append(((u + a[keep] - b[keep]) * T + b[keep])[:, None] * C + chan)
                band_w.append(wa * wb * p[keep])
    ab = np.bincount(
        np.concatenate(band_idx).ravel(), np.concatenate(band_w).ravel(), minlength=(u + 1) * T * C
    ).reshape(u + 1, T, C)  # upper form: ab[u + i - j, j] = A[i, j]
    rhs = np.bincount(np.concatenate(rhs_idx).ravel(), np.concatenate(rhs_w).ravel(), minlength=T * C).reshape(T, C)
    try:
        from scipy.linalg import solveh_banded
    except ImportError:  # the numpy-only runtime
        return solveh_banded_numpy(ab, rhs)
    out = np.empty((T, C))
    for c in range(C):
        out[:, c] = solveh_banded(ab[:, :, c], rhs[:, c], lower=False, check_finite=False)
    return out


def solveh_banded_numpy(ab, b) -> np.ndarray:
    """Solve symmetric positive definite banded systems, one per column, in numpy.

    Parameters
    ----------
    ab : ndarray, shape (u + 1, T, C)
        Upper band of each matrix in LAPACK's layout (``ab[u + i - j, j] = A[i, j]``
        for ``i <= j``), as :func:`scipy.linalg.solveh_banded` takes it, with a
        trailing axis over the ``C`` systems.
    b : ndarray, shape (T, C)

    Returns
    -------
    ndarray, shape (T, C)
        ``x[:, c] = A_c^{-1} b[:, c]`` by the banded Cholesky factorization ``A = U' U``.
    """
    ab = np.asarray(ab, dtype=float)
    b = np.asarray(b, dtype=float)
    u1, T, _ = ab.shape
    u = u1 - 1
    U = np.zeros_like(ab)  # same layout: U[u + k - i, i] = U_{k i}, k <= i
    for j in range(T):
        lo = max(0, j - u)
        s = ab[u, j] - sum(U[u + k - j, j] ** 2 for k in range(lo, j))
        U[u, j] = np.sqrt(s)
        for i in range(j + 1, min(j + u, T - 1) + 1):
            acc = ab[u + j - i, i] - sum(U[u + k - j, j] * U[u + k - i, i] for k in range(max(0, i - u), j))
            U[u + j - i, i] = acc / U[u, j]
    y = np.empty_like(b)
    for i in range(T):  # U' y = b
        y[i] = (b[i] - sum(U[u + k - i, i] * y[k] for k in range(max(0, i - u), i))) / U[u, i]
    x = np.empty_like(b)
    for k in range(T - 1, -1, -1):  # U x = y
        x[k] = (y[k] - sum(U[u + k - i, i] * x[i] for i in range(k + 1, min(k + u, T - 1) + 1))) / U[u, k]
    return x
