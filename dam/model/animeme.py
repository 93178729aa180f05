"""The animeme function: a degree-M polynomial of local time (Chen et al. 2012, Eq. 3).

The paper writes ``A(t) = sum_m a^m t^m`` (monomials, M = 4). Internally the
same polynomial is held in the shifted Legendre basis ``P_m(2t - 1)``, which is
orthogonal on [0, 1] and keeps the normal equations well conditioned; the
fitted function is identical. :func:`legendre_to_monomial` converts the
coefficients to the paper's ``a^0 .. a^M`` for inspection.

Outside [0, 1] the animeme is either the polynomial itself (the paper:
``extrapolate="polynomial"``) or the value at the nearer edge
(``extrapolate="hold"``).

numpy only: this module is on the load + predict path of a saved model.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

__all__ = ["EXTRAPOLATE", "basis", "evaluate", "boundary_derivatives", "legendre_to_monomial", "monomial_to_legendre"]

EXTRAPOLATE = ("polynomial", "hold")


def _check_extrapolate(extrapolate: str) -> None:
    if extrapolate not in EXTRAPOLATE:
        raise ValueError(f"parameter 'extrapolate' is {extrapolate!r}; use one of {EXTRAPOLATE}")


def basis(t, degree: int, extrapolate: str = "polynomial") -> np.ndarray:
    """Shifted Legendre basis ``P_m(2t - 1)``, m = 0..degree, at local times ``t``.

    Parameters
    ----------
    t : array-like, shape (n,)
    degree : int
        Polynomial degree M >= 0.
    extrapolate : {"polynomial", "hold"}, default "polynomial"
        "hold" evaluates at ``clip(t, 0, 1)``.

    Returns
    -------
    ndarray, shape (n, degree + 1)
    """
    _check_extrapolate(extrapolate)
    t = np.asarray(t, dtype=float).ravel()
    if extrapolate == "hold":
        t = np.clip(t, 0.0, 1.0)
    x = 2.0 * t - 1.0
    out = np.empty((t.size, degree + 1))
    out[:, 0] = 1.0
    if degree >= 1:
        out[:, 1] = x
    # Bonnet's recursion: (n+1) P_{n+1} = (2n+1) x P_n - n P_{n-1}
    for n in range(1, degree):
        out[:, n + 1] = ((2 * n + 1) * x * out[:, n] - n * out[:, n - 1]) / (n + 1)
    return out


def evaluate(coef, t, extrapolate: str = "polynomial") -> np.ndarray:
    """Animeme values ``A(t)`` from shifted-Legendre coefficients.

    Parameters
    ----------
    coef : array-like, shape (degree + 1,) or (degree + 1, n_channels)
    t : array-like, shape (n,)

    Returns
    -------
    ndarray, shape (n,) or (n, n_channels)
    """
    coef = np.asarray(coef, dtype=float)
    return basis(t, coef.shape[0] - 1, extrapolate) @ coef


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
