"""The animeme function: a degree-M polynomial of local time (Chen et al. 2012, Eq. 3).

The paper writes ``A(t) = sum_m a^m t^m`` (monomials, M = 4). Internally the
same polynomial is held in the shifted Legendre basis ``P_m(2t - 1)``, which is
orthogonal on [0, 1] and keeps the normal equations well conditioned; the
fitted function is identical. :func:`legendre_to_monomial` converts the
coefficients to the paper's ``a^0 .. a^M`` for inspection.

Outside [0, 1] the animeme is the polynomial itself (the paper:
``extrapolate="polynomial"``), the value at the nearer edge
(``extrapolate="hold"``), or the polynomial over the local times where
training evaluated the mode and the value at the nearer edge of that range
beyond it (``extrapolate="trained"``, :func:`trained_support`): a mode fitted
only where no frame preceded it (an utterance's first silence) has a left
tail no data constrained, and a quartic grows fast there.

numpy only: this module is on the load + predict path of a saved model.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

__all__ = [
    "EXTRAPOLATE",
    "basis",
    "evaluate",
    "animeme_time",
    "trained_support",
    "boundary_derivatives",
    "legendre_to_monomial",
    "monomial_to_legendre",
]

EXTRAPOLATE = ("polynomial", "hold", "trained")


def _check_extrapolate(extrapolate: str) -> None:
    if extrapolate not in EXTRAPOLATE:
        raise ValueError(f"parameter 'extrapolate' is {extrapolate!r}; use one of {EXTRAPOLATE}")


def animeme_time(t, extrapolate: str = "polynomial", support=None) -> np.ndarray:
    """The local time the animeme polynomial is evaluated at, for local time ``t``.

    Parameters
    ----------
    t : ndarray, shape (n,)
    extrapolate : {"polynomial", "hold", "trained"}, default "polynomial"
        "polynomial": ``t`` itself; "hold": ``clip(t, 0, 1)``; "trained":
        ``clip(t, lo, hi)`` with ``support = (lo, hi)``.
    support : tuple of (ndarray, ndarray), each broadcastable to ``t``, optional
        The range training evaluated each animeme at (:func:`trained_support`);
        None for "trained" means no range is known (a model given its
        parameters, not fitted): the polynomial on the whole time line.

    Returns
    -------
    ndarray, shape (n,)

    Examples
    --------
    >>> animeme_time(np.array([-2.0, 0.5, 3.0]), "trained", (-1.0, 2.0)).tolist()
    [-1.0, 0.5, 2.0]
    """
    if extrapolate == "hold":
        return np.minimum(np.maximum(t, 0.0), 1.0)
    if extrapolate == "trained" and support is not None:
        return np.minimum(np.maximum(t, support[0]), support[1])
    return t


def trained_support(mode, t, n_modes: int) -> np.ndarray:
    """Per mode, the range of local times where training evaluated its animeme, [0, 1] included.

    Within an utterance every occurrence is evaluated over its whole
    (truncated) dominance window; only the utterance's edges cut a window
    short, so a mode whose occurrences all open an utterance was never
    evaluated before t = 0. With ``extrapolate="trained"`` the animeme is
    held at its value at the edge of this range beyond it, and rendering the
    training utterances with their training modes is unchanged.

    Parameters
    ----------
    mode : ndarray of int, shape (n_pairs,)
        Mode of every (occurrence, frame) pair training evaluated.
    t : ndarray, shape (n_pairs,)
        Local time of every pair.
    n_modes : int

    Returns
    -------
    ndarray, shape (n_modes, 2)
        ``[:, 0]`` the lowest local time (<= 0), ``[:, 1]`` the highest (>= 1).

    Examples
    --------
    >>> trained_support(np.array([0, 0, 1]), np.array([-0.5, 1.75, 0.5]), 3).tolist()
    [[-0.5, 1.75], [0.0, 1.0], [0.0, 1.0]]
    """
    out = np.tile([0.0, 1.0], (n_modes, 1))
    np.minimum.at(out[:, 0], mode, t)
    np.maximum.at(out[:, 1], mode, t)
    return out


def basis(t, degree: int, extrapolate: str = "polynomial", support=None) -> np.ndarray:
    """Shifted Legendre basis ``P_m(2t - 1)``, m = 0..degree, at local times ``t``.

    Parameters
    ----------
    t : array-like, shape (n,)
    degree : int
        Polynomial degree M >= 0.
    extrapolate : {"polynomial", "hold", "trained"}, default "polynomial"
        "hold" evaluates at ``clip(t, 0, 1)``, "trained" at ``clip(t, *support)``
        (:func:`animeme_time`).
    support : tuple of (lo, hi), optional
        For "trained"; None evaluates the polynomial itself (as in training,
        which by definition stays inside the range it evaluates).

    Returns
    -------
    ndarray, shape (n, degree + 1)
    """
    _check_extrapolate(extrapolate)
    t = animeme_time(np.asarray(t, dtype=float).ravel(), extrapolate, support)
    x = 2.0 * t - 1.0
    out = np.empty((t.size, degree + 1))
    out[:, 0] = 1.0
    if degree >= 1:
        out[:, 1] = x
    # Bonnet's recursion: (n+1) P_{n+1} = (2n+1) x P_n - n P_{n-1}
    for n in range(1, degree):
        out[:, n + 1] = ((2 * n + 1) * x * out[:, n] - n * out[:, n - 1]) / (n + 1)
    return out


def evaluate(coef, t, extrapolate: str = "polynomial", support=None) -> np.ndarray:
    """Animeme values ``A(t)`` from shifted-Legendre coefficients.

    Parameters
    ----------
    coef : array-like, shape (degree + 1,) or (degree + 1, n_channels)
    t : array-like, shape (n,)
    extrapolate, support
        As in :func:`basis`.

    Returns
    -------
    ndarray, shape (n,) or (n, n_channels)
    """
    coef = np.asarray(coef, dtype=float)
    return basis(t, coef.shape[0] - 1, extrapolate, support) @ coef


@lru_cache(maxsize=32)
def _monomial_matrix(degree: int) -> np.ndarray:
    """T with ``monomial = T @ legendre``: column k holds P_k(2t-1) in powers of t."""
    T = np.zeros((degree + 1, degree + 1))
    for k in range(degree + 1):
        poly = np.polynomial.Legendre.basis(k, domain=[0.0, 1.0]).convert(kind=np.polynomial.Polynomial)
        T[: len(poly.coef), k] = poly.coef
    T.setflags(write=False)
    return T


def legendre_to_monomial(coef) -> np.ndarray:
    """The paper's coefficients ``a^0 .. a^M`` (``A(t) = sum_m a^m t^m``).

    Parameters
    ----------
    coef : array-like, shape (degree + 1, ...)
        Shifted-Legendre coefficients (leading axis is the degree).
    """
    coef = np.asarray(coef, dtype=float)
    return (_monomial_matrix(coef.shape[0] - 1) @ coef.reshape(coef.shape[0], -1)).reshape(coef.shape)


def monomial_to_legendre(coef) -> np.ndarray:
    """Inverse of :func:`legendre_to_monomial`."""
    coef = np.asarray(coef, dtype=float)
    return np.tensordot(np.linalg.inv(_monomial_matrix(coef.shape[0] - 1)), coef, axes=1)


@lru_cache(maxsize=32)
def _edge_derivative_matrix(degree: int, order: int) -> np.ndarray:
    """E[edge, k, m] = k-th derivative of P_m(2t-1) at t = edge (0 or 1)."""
    E = np.zeros((2, order + 1, degree + 1))
    for m in range(degree + 1):
        p = np.polynomial.Legendre.basis(m, domain=[0.0, 1.0])
        for k in range(order + 1):
            E[:, k, m] = p.deriv(k)(np.array([0.0, 1.0])) if k else p(np.array([0.0, 1.0]))
    E.setflags(write=False)
    return E


def boundary_derivatives(coef, order: int = 2) -> np.ndarray:
    """Value and derivatives (wrt local time) of the animeme at t = 0 and t = 1.

    One-sided from inside [0, 1], so the same for both ``extrapolate`` modes.

    Parameters
    ----------
    coef : array-like, shape (..., degree + 1, n_channels)
    order : int, default 2

    Returns
    -------
    ndarray, shape (..., 2, order + 1, n_channels)
        ``[..., 0, k, c]`` is ``A^(k)(0)``, ``[..., 1, k, c]`` is ``A^(k)(1)``.
    """
    coef = np.asarray(coef, dtype=float)
    E = _edge_derivative_matrix(coef.shape[-2] - 1, order)
    out = E.reshape(-1, E.shape[-1]) @ coef  # (..., 2 (order + 1), C): matmul broadcasts
    return out.reshape(coef.shape[:-2] + E.shape[:2] + coef.shape[-1:])
