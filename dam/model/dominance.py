"""The dominance function of Chen et al. (2012), Eq. (1), and its derivative.

A phone's dominance is 1 while the phone is active and falls off like a
Gaussian on either side::

    D(t) = 1                                 for t in [0, 1]
    D(t) = exp(-t^2 / (sigma^2 + eps))       for t < 0
    D(t) = exp(-(t - 1)^2 / (sigma^2 + eps)) for t > 1

with the phone's local time ``t = (time - start) / duration``; ``sigma`` is in
units of the phone's own duration.

Truncation: where ``D`` falls below ``tol`` it is set to exactly 0, so a phone
influences only a bounded window of frames (``reach`` durations beyond each
edge) and synthesis costs the same per phone however long the utterance.
The jump this leaves at the window edge is at most ``tol``.

numpy only: this module is on the load + predict path of a saved model.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["dominance", "dominance_of_distance", "dominance_dsigma", "reach", "outside_distance"]


def outside_distance(t):
    """Distance of local time ``t`` from the active interval [0, 1] (0 inside)."""
    t = np.asarray(t, dtype=float)
    return np.maximum(np.maximum(-t, t - 1.0), 0.0)  # at most one of -t and t - 1 is positive


def reach(sigma, eps: float = 1e-8, tol: float = 0.0):
    """How far beyond [0, 1] (in durations) the dominance stays >= ``tol``.

    Solves ``exp(-u^2 / (sigma^2 + eps)) = tol`` for ``u``; infinite when
    ``tol <= 0`` (no truncation).
    """
    sigma = np.asarray(sigma, dtype=float)
    if tol <= 0.0:
        return np.full(sigma.shape, np.inf)
    if tol >= 1.0:
        return np.zeros(sigma.shape)
    return np.sqrt((sigma * sigma + eps) * -math.log(tol))


def dominance(t, sigma, eps: float = 1e-8, tol: float = 0.0):
    """Eq. (1): dominance at local time ``t``.

    Parameters
    ----------
    t : array-like
        Local time(s), ``(time - start) / duration``.
    sigma : float or array-like broadcastable with ``t``
        Fall-off, in durations; must be >= 0.
    eps : float, default 1e-8
        Keeps the division finite at ``sigma = 0``.
    tol : float, default 0.0
        Values below ``tol`` are set to 0 (truncation); 0 keeps every value.

    Returns
    -------
    ndarray, broadcast shape of ``t`` and ``sigma``
    """
    u = outside_distance(t)
    return dominance_of_distance(u * u, np.asarray(sigma, dtype=float) ** 2 + eps, tol)


def dominance_of_distance(u2, s2, tol: float = 0.0) -> np.ndarray:
    """Eq. (1) from the squared distance ``u2`` outside [0, 1] and ``s2 = sigma^2 + eps``.

    The core of :func:`dominance`, for callers that hold ``u^2`` per frame and
    ``s2`` per segment already (synthesis evaluates it for every frame/segment
    pair). Broadcasts ``u2`` against ``s2``.
    """
    d = np.asarray(np.exp(-u2 / s2))
    if tol > 0.0:
        d[d < tol] = 0.0
    return d


def dominance_dsigma(t, sigma, eps: float = 1e-8, tol: float = 0.0):
    """Analytic derivative of :func:`dominance` with respect to ``sigma``.

    ``dD/dsigma = D * 2 sigma u^2 / (sigma^2 + eps)^2`` with ``u`` the distance
    outside [0, 1]; 0 inside [0, 1] and where the dominance is truncated
    (the truncated model is flat in sigma there).
    """
    u = outside_distance(t)
    sigma = np.asarray(sigma, dtype=float)
    s2 = sigma * sigma + eps
    u2 = u * u
    d = np.exp(-u2 / s2)
    g = d * 2.0 * sigma * u2 / (s2 * s2)
    if tol > 0.0:
        g = np.where(d < tol, 0.0, g)
    return g
