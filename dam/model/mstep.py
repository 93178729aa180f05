"""The M-step of Chen et al. (2012), Eqs. (8)-(9): each mode's sigma by Gauss-Newton.

With the animeme coefficients fixed (the paper; see ``projected`` in
:func:`gauss_newton_sigma` for the variable-projection step used by default), the residual ``f = y - C*(sigma)`` is
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

import warnings

import numpy as np

from dam.model.dominance import dominance_dsigma
from dam.model.estep import Occurrences, fitted_values

__all__ = ["SIGMA_MIN", "SIGMA_MAX", "jacobian", "jacobian_values", "gauss_newton_sigma"]

# sigma is in phone durations: below 1e-3 the fall-off is a step; beyond 2
# durations (a reach of 6 durations at the default truncation) a phone, a long
# pause above all, would stand in for a slowly varying offset over many neighbours.
SIGMA_MIN = 1e-3
SIGMA_MAX = 2.0


def jacobian_values(occ: Occurrences, parts, sigma: np.ndarray) -> np.ndarray:
    """``dC*/d log(sigma)`` at every (occurrence, frame) pair of ``parts``, shape (n_pairs,).

    ``parts`` is ``(pred, parts)`` from :func:`dam.estep.fitted_values`; the
    pair's column is its occurrence's mode (see the module docstring).
    """
    pred, (k, row, t, D, A, S) = parts
    s = sigma[occ.mode[k]]
    dD = dominance_dsigma(t, s, occ.eps, occ.tol) * s
    return dD * A if not occ.normalize else dD * (A - pred[row]) / S[row]


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
    k, row = parts[1][:2]
    mode = occ.mode[k]
    vals = jacobian_values(occ, parts, sigma)
    nz = vals != 0.0
    J = sparse.csr_matrix((vals[nz], (row[nz], mode[nz])), shape=(occ.n_rows, occ.n_modes))
    J.sum_duplicates()
    return J


def _reduced(occ, y, sigma, lam, weights=None):
    """The objective with the coefficients re-solved at ``sigma`` (an E-step).

    Returns ``(objective, coef, fitted, factor)``: ``fitted`` as from
    :func:`dam.estep.fitted_values`, ``factor`` the Cholesky factor of
    ``X^T X + lam I`` (None if singular).
    """
    from dam.model.estep import normal_equations, pairs, solve_normal_equations

    pr = pairs(occ, sigma)
    G, Xty = normal_equations(occ, sigma, y, pr, weights)
    a, fac = solve_normal_equations(G, Xty[:, 0], lam)
    a = a.reshape(occ.n_modes, occ.degree + 1)
    cur = fitted_values(occ, a, sigma, pr)
    return _objective(y, cur[0], a, lam, weights), a, cur, fac


def _objective(y, fitted, a, lam, weights=None) -> float:
    """``sum_i w_i (y_i - fitted_i)^2 + lam ||a||^2`` (``w`` = 1 without weights)."""
    r = y - fitted
    return float((r @ r if weights is None else r @ (weights * r)) + lam * np.sum(a * a))


def _products(occ, y, cur, coef, sigma, projected, weights=None):
    """``H = Jp^T Jp``, ``g = Jp^T f`` and, if projected, ``K = X^T Jp`` in one pass over the utterances."""
    from dam.model.estep import design_values, gram

    pred, (k, row, t, D, A, S) = cur
    jv = jacobian_values(occ, cur, sigma)
    f = y - pred
    if not projected:
        blocks, off = [(jv[:, None], 0)], 0
    else:
        blocks, off = [(design_values(occ, (k, row, t, D))[0], 0), (jv[:, None], occ.n_coef)], occ.n_coef
    ZtZ, Ztf = gram(occ, k, row, blocks, f, weights)
    H = ZtZ[off:, off:]
    g = Ztf[off:, 0]
    K = ZtZ[:off, off:] if projected else None
    return H, g, K


def gauss_newton_sigma(
    occ: Occurrences,
    y: np.ndarray,
    coef: np.ndarray,
    sigma: np.ndarray,
    *,
    lam: float = 0.0,
    projected: bool = True,
    n_steps: int = 1,
    mu: float = 1e-3,
    rtol: float = 1e-6,
    max_tries: int = 8,
    weights=None,
):
    """Damped Gauss-Newton on log(sigma) for one channel.

    Two flavours of the same step:

    * ``projected=False`` (the paper's M-step): the coefficients stay fixed;
      the objective is ``||y - C*(sigma; a)||^2 + lam ||a||^2``.
    * ``projected=True`` (default): variable projection (Golub & Pereyra
      1973, with Kaufman's 1975 Jacobian). The objective is the one left after
      the E-step, ``min_a ||y - X(sigma) a||^2 + lam ||a||^2``; its gradient is
      exactly ``-2 J^T f`` (envelope theorem) and its Gauss-Newton matrix is
      ``J^T (I - Q)^2 J`` with ``Q = X (X^T X + lam I)^-1 X^T``: the sigma step
      anticipates how the coefficients will move, so the alternation needs
      far fewer iterations than with ``a`` frozen. Each accepted step comes
      with the re-solved coefficients.

    Parameters
    ----------
    occ : Occurrences
    y : ndarray, shape (n_rows,)
        The channel's training signal.
    coef : ndarray, shape (n_modes, degree + 1)
        Animeme coefficients (the E-step's solution at ``sigma`` when projected).
    sigma : ndarray, shape (n_modes,)
        Starting sigmas.
    lam : float, default 0.0
        The ridge of the E-step.
    projected : bool, default True
    n_steps : int, default 1
        Accepted Gauss-Newton steps at most.
    mu : float, default 1e-3
        Initial Levenberg-Marquardt damping (relative to the diagonal).
    rtol : float, default 1e-6
        Stop when a step improves the objective by less than this fraction.
    max_tries : int, default 8
        Rejected (damped-up) tries per step before giving up.
    weights : ndarray, shape (n_rows,), optional
        Row weights of the squared residuals (0 for a missing value).

    Returns
    -------
    sigma : ndarray, shape (n_modes,)
    coef : ndarray, shape (n_modes, degree + 1)
        ``coef`` unchanged, or re-solved at the returned sigma when projected.
    objective : float
        Never above the objective at the starting point.
    mu : float
        The damping reached (pass it back in to carry it across M-steps).
    """
    from scipy import linalg

    theta = np.log(np.clip(sigma, SIGMA_MIN, SIGMA_MAX))
    a = np.asarray(coef, dtype=float)
    if projected:
        obj, a, cur, fac = _reduced(occ, y, np.exp(theta), lam, weights)
    else:
        cur = fitted_values(occ, a, np.exp(theta))
        obj = _objective(y, cur[0], a, lam, weights)
    obj0 = obj
    for _ in range(n_steps):
        H, g, K = _products(occ, y, cur, a, np.exp(theta), projected and fac is not None, weights)
        # g = Jp^T f = -J^T f for the residual's Jacobian J = -Jp
        if K is not None:
            W = linalg.cho_solve(fac, K, check_finite=False)
            H = H - K.T @ W - lam * (W.T @ W)
            H = 0.5 * (H + H.T)
        diag = np.maximum(np.diag(H), 1e-12 * max(1.0, float(np.max(np.abs(np.diag(H))))))
        accepted = False
        for _ in range(max_tries):
            try:
                with warnings.catch_warnings():
                    # a clamped sigma has a zero row; the damping keeps the step finite
                    warnings.simplefilter("ignore", linalg.LinAlgWarning)
                    delta = linalg.solve(H + mu * np.diag(diag), g, assume_a="sym", check_finite=False)
            except (linalg.LinAlgError, ValueError):
                mu *= 10.0
                continue
            new_theta = np.clip(theta + delta, np.log(SIGMA_MIN), np.log(SIGMA_MAX))
            if projected:
                new_obj, new_a, trial, new_fac = _reduced(occ, y, np.exp(new_theta), lam, weights)
            else:
                new_a, new_fac = a, None
                trial = fitted_values(occ, a, np.exp(new_theta))
                new_obj = _objective(y, trial[0], a, lam, weights)
            if new_obj < obj:
                accepted = True
                gain = obj - new_obj
                theta, a, obj, cur, fac = new_theta, new_a, new_obj, trial, new_fac
                mu = max(mu / 10.0, 1e-9)
                break
            mu *= 10.0
        if not accepted or gain <= rtol * max(obj0, 1e-300):
            break
    return np.exp(theta), a, obj, mu
