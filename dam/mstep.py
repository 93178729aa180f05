"""The M-step of Chen et al. (2012), Eqs. (8)-(9): each mode's sigma by Gauss-Newton.

With the animeme coefficients fixed, the residual ``f = y - C*(sigma)`` is
non-linear in the sigmas. We optimise ``theta = log sigma`` (keeps sigma
positive) with Gauss-Newton steps ``(J^T J + mu diag(J^T J)) delta = -J^T f``,
damped Levenberg-Marquardt style: a step is taken only if the squared error
falls, otherwise ``mu`` grows tenfold and the step is retried; so the error
never increases. The Jacobian is analytic::

    dC*/dtheta_b = sum_{h in b} sigma_b dD/dsigma (t_h) A_b(t_h)            (plain sum)
    dC*/dtheta_b = sum_{h in b} sigma_b dD/dsigma (t_h) (A_b(t_h) - C*) / S   (weighted average)

Sigma is also kept within [SIGMA_MIN, SIGMA_MAX] durations.
"""
from __future__ import annotations

import numpy as np

from .dominance import dominance_dsigma
from .estep import Occurrences, fitted_values

__all__ = ["SIGMA_MIN", "SIGMA_MAX", "jacobian", "gauss_newton_sigma"]

# sigma is in phone durations: below 1e-3 the fall-off is a step; beyond 5
# durations a phone would reach over dozens of neighbours.
SIGMA_MIN = 1e-3
SIGMA_MAX = 5.0


def jacobian(occ: Occurrences, coef: np.ndarray, sigma: np.ndarray, parts=None):
    """``dC*/d log(sigma)`` on the training rows, sparse.

    Parameters
    ----------
    occ : Occurrences
    coef : ndarray, shape (n_modes, degree + 1)
    sigma : ndarray, shape (n_modes,)
    parts : tuple, optional
        ``(pred, parts)`` from :func:`dam.estep.fitted_values` at ``sigma``.

    Returns
    -------
    scipy.sparse.csr_matrix, shape (n_rows, n_modes)
        Note: the residual's Jacobian is the negative of this.
    """
    from scipy import sparse

    if parts is None:
        parts = fitted_values(occ, coef, sigma)
    pred, (k, row, t, D, A, S) = parts
    mode = occ.mode[k]
    s = sigma[mode]
    dD = dominance_dsigma(t, s, occ.eps, occ.tol) * s
    vals = dD * A if not occ.normalize else dD * (A - pred[row]) / S[row]
    nz = vals != 0.0
    J = sparse.csr_matrix((vals[nz], (row[nz], mode[nz])), shape=(occ.n_rows, occ.n_modes))
    J.sum_duplicates()
    return J


def gauss_newton_sigma(occ: Occurrences, y: np.ndarray, coef: np.ndarray, sigma: np.ndarray, *,
                       n_steps: int = 5, mu: float = 1e-3, rtol: float = 1e-6, max_tries: int = 8):
    """Damped Gauss-Newton on log(sigma) for one channel.

    Parameters
    ----------
    occ : Occurrences
    y : ndarray, shape (n_rows,)
        The channel's training signal.
    coef : ndarray, shape (n_modes, degree + 1)
        Fixed animeme coefficients.
    sigma : ndarray, shape (n_modes,)
        Starting sigmas.
    n_steps : int, default 5
        Accepted Gauss-Newton steps at most.
    mu : float, default 1e-3
        Initial Levenberg-Marquardt damping.
    rtol : float, default 1e-6
        Stop when a step improves the squared error by less than this fraction.
    max_tries : int, default 8
        Rejected (damped-up) tries per step before giving up.

    Returns
    -------
    sigma : ndarray, shape (n_modes,)
    sse : float
        Squared error at the returned sigma (never above the starting one).
    """
    from scipy import linalg

    theta = np.log(np.clip(sigma, SIGMA_MIN, SIGMA_MAX))
    cur = fitted_values(occ, coef, np.exp(theta))
    sse = float(np.sum((y - cur[0]) ** 2))
    sse0 = sse
    for _ in range(n_steps):
        Jp = jacobian(occ, coef, np.exp(theta), cur)
        f = y - cur[0]
        JTJ = (Jp.T @ Jp).toarray()
        g = Jp.T @ f          # = -J^T f for the residual's Jacobian J = -Jp
        diag = np.maximum(np.diag(JTJ), 1e-12 * max(1.0, float(np.max(np.diag(JTJ)))))
        accepted = False
        for _ in range(max_tries):
            A = JTJ + mu * np.diag(diag)
            try:
                delta = linalg.solve(A, g, assume_a="pos", check_finite=False)
            except (linalg.LinAlgError, ValueError):
                mu *= 10.0
                continue
            new_theta = np.clip(theta + delta, np.log(SIGMA_MIN), np.log(SIGMA_MAX))
            trial = fitted_values(occ, coef, np.exp(new_theta))
            new_sse = float(np.sum((y - trial[0]) ** 2))
            if new_sse < sse:
                accepted = True
                gain = sse - new_sse
                theta, cur, sse = new_theta, trial, new_sse
                mu = max(mu / 10.0, 1e-9)
                break
            mu *= 10.0
        if not accepted or gain <= rtol * max(sse0, 1e-300):
            break
    return np.exp(theta), sse
