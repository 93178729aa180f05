"""The EM-style alternation of Chen et al. (2012), Section V-D, in one place.

Per channel (the paper trains "per control"): start with every sigma at
``sigma_init``; E-step (animeme coefficients by least squares, Eq. 5);
then repeat M-step (sigmas by damped Gauss-Newton, Eq. 9) and E-step until
the relative improvement of the objective falls below ``tol`` or
``max_iter`` iterations have run.

The objective is ``sum_i f_i^2 + lambda ||a||^2`` (Eq. 4 plus the ridge, with
``lambda`` fixed for the whole fit), divided by the number of frames. Both
steps minimise it (the E-step exactly, the M-step by accepted descent steps
only), so it never increases; :class:`ConvergenceMonitor` records it.
"""
from __future__ import annotations

import sys
from dataclasses import dataclass, field

import numpy as np

from .estep import Occurrences, design_matrix, pairs, solve_normal_equations
from .mstep import gauss_newton_sigma

__all__ = ["ConvergenceMonitor", "ridge_lambda", "fit_em"]


@dataclass
class ConvergenceMonitor:
    """Objective history and the stopping rule (as in hmmlearn).

    Parameters
    ----------
    tol : float
        Stop when ``(previous - current) / |previous| < tol``.
    max_iter : int
        Stop after this many M+E iterations.
    """

    tol: float
    max_iter: int
    history: list = field(default_factory=list)
    iter: int = 0

    def report(self, value: float) -> None:
        self.history.append(float(value))

    @property
    def converged(self) -> bool:
        if len(self.history) < 2:
            return False
        prev, cur = self.history[-2], self.history[-1]
        return (prev - cur) < self.tol * max(abs(prev), 1e-300)

    @property
    def done(self) -> bool:
        return self.converged or self.iter >= self.max_iter


def ridge_lambda(X, ridge: float) -> float:
    """The ridge as a fraction of the mean diagonal of ``X^T X`` (scale-free)."""
    sq = X.multiply(X).sum(axis=0)
    return float(ridge * max(np.mean(sq), 1e-300))


def fit_em(occ: Occurrences, Y: np.ndarray, *, sigma_init: float = 1.0, ridge: float = 1e-6,
           tol: float = 1e-4, max_iter: int = 50, gn_steps: int = 5, verbose: int = 0,
           fixed_sigma: bool = False):
    """Fit every channel's animeme coefficients and sigmas.

    Parameters
    ----------
    occ : Occurrences
    Y : ndarray, shape (n_rows, n_channels)
    sigma_init : float, default 1.0
        Starting sigma of every mode (the paper uses 1).
    ridge : float, default 1e-6
        See :func:`ridge_lambda`.
    tol, max_iter : float, int
        Stopping rule of :class:`ConvergenceMonitor`.
    gn_steps : int, default 5
        Gauss-Newton steps per M-step.
    verbose : int, default 0
        > 0 shows a progress bar over channels on stderr (when it is a TTY).
    fixed_sigma : bool, default False
        Only the first E-step (for tests and ablations).

    Returns
    -------
    coef : ndarray, shape (n_modes, degree + 1, n_channels)
        Shifted-Legendre coefficients.
    sigma : ndarray, shape (n_modes, n_channels)
    curves : list of ndarray
        Objective per iteration (first entry: after the first E-step), per channel.
    n_iter : ndarray of int, shape (n_channels,)
    converged : ndarray of bool, shape (n_channels,)
    """
    Y = np.asarray(Y, dtype=float)
    n_ch = Y.shape[1]
    M1 = occ.degree + 1
    sigma0 = np.full(occ.n_modes, float(sigma_init))
    # First E-step: every channel has the same sigmas, so one solve serves all.
    pr0 = pairs(occ, sigma0)
    X0 = design_matrix(occ, sigma0, pr0)
    lam = ridge_lambda(X0, ridge)
    A0 = solve_normal_equations(X0, Y, lam).reshape(occ.n_modes, M1, n_ch)
    R0 = Y - X0 @ A0.reshape(-1, n_ch)
    coef = A0.copy()
    sigma = np.repeat(sigma0[:, None], n_ch, axis=1)
    curves, n_iter, converged = [], np.zeros(n_ch, dtype=int), np.zeros(n_ch, dtype=bool)

    from tqdm.auto import tqdm
    bar = tqdm(range(n_ch), desc="DAM EM (channels)", file=sys.stderr, leave=False,
               disable=not (verbose and sys.stderr.isatty()))
    for c in bar:
        y = Y[:, c]
        a = A0[:, :, c]
        s = sigma0.copy()
        mon = ConvergenceMonitor(tol, max_iter)
        mon.report((np.sum(R0[:, c] ** 2) + lam * np.sum(a * a)) / occ.n_rows)
        while not fixed_sigma and not mon.done:
            s, _ = gauss_newton_sigma(occ, y, a, s, n_steps=gn_steps)
            X = design_matrix(occ, s)
            a = solve_normal_equations(X, y, lam).reshape(occ.n_modes, M1)
            mon.iter += 1
            mon.report((np.sum((y - X @ a.ravel()) ** 2) + lam * np.sum(a * a)) / occ.n_rows)
        coef[:, :, c] = a
        sigma[:, c] = s
        curves.append(np.array(mon.history))
        n_iter[c] = mon.iter
        converged[c] = mon.converged
        if verbose > 1:
            print(f"channel {c}: {mon.iter} iterations, objective {mon.history[0]:.4g} -> "
                  f"{mon.history[-1]:.4g}", file=sys.stderr)
    return coef, sigma, curves, n_iter, converged
