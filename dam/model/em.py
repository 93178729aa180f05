"""The EM-style alternation of Chen et al. (2012), Section V-D, in one place.

Per channel (the paper trains "per control"): start with every sigma at
``sigma_init``; E-step (animeme coefficients by least squares, Eq. 5);
then repeat M-step (sigmas by damped Gauss-Newton, Eq. 9) and E-step until
the relative improvement of the objective falls below ``tol`` or
``max_iter`` iterations have run. By default the M-step is the
variable-projection form of the Gauss-Newton step (the sigma step accounts
for how the E-step will move the animemes, and the E-step is solved inside
it); ``projected=False`` is the paper's step with the animemes frozen, which
needs many more iterations (see :func:`dam.mstep.gauss_newton_sigma`).

The objective is ``sum_i f_i^2 + lambda ||a||^2`` (Eq. 4 plus the ridge, with
``lambda`` fixed for the whole fit), divided by the number of frames. Both
steps minimise it (the E-step exactly, the M-step by accepted descent steps
only), so it never increases; :class:`ConvergenceMonitor` records it.
"""

from __future__ import annotations

import sys
import warnings
from dataclasses import dataclass, field

import numpy as np

from dam.model.estep import Occurrences, fitted_values, normal_equations, pairs, solve_normal_equations
from dam.model.mstep import gauss_newton_sigma

__all__ = ["ConvergenceMonitor", "ridge_lambda", "fit_em", "SIGMA_GRID"]

# Starting sigmas tried by sigma_init="auto" (the paper's 1.0 among them): the
# objective is not convex in sigma and a start above the truth can stall in a
# local minimum where the polynomial tails compensate.
SIGMA_GRID = (0.15, 0.3, 0.5, 0.75, 1.0, 1.5)


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

    @property
    def last_improvement(self) -> float:
        """Relative improvement of the last iteration (nan before the second report)."""
        if len(self.history) < 2:
            return float("nan")
        prev, cur = self.history[-2], self.history[-1]
        return (prev - cur) / max(abs(prev), 1e-300)


def ridge_lambda(n_rows: int, ridge: float) -> float:
    """``lambda = ridge * n_rows``: per frame the objective is MSE + ridge ||a||^2.

    (Relative to the diagonal of ``X^T X`` would be scale-free too, but with
    polynomial extrapolation the high-order columns are huge in the dominance
    tails and such a ridge would swamp the low-order coefficients.)
    """
    return float(ridge * n_rows)


def fitted_values_all(occ: Occurrences, coef: np.ndarray, sigma: np.ndarray, pr) -> np.ndarray:
    """Eq. (2) on the training rows for every channel sharing ``sigma``, shape (n_rows, n_channels)."""
    return np.stack([fitted_values(occ, coef[:, :, c], sigma, pr)[0] for c in range(coef.shape[2])], axis=1)


def fit_em(
    occ: Occurrences,
    Y: np.ndarray,
    *,
    sigma_init="auto",
    ridge: float = 1e-6,
    tol: float = 1e-3,
    max_iter: int = 50,
    gn_steps: int = 1,
    verbose: int = 0,
    fixed_sigma: bool = False,
    projected: bool = True,
    channels=None,
    weights=None,
):
    """Fit every channel's animeme coefficients and sigmas.

    Parameters
    ----------
    occ : Occurrences
    Y : ndarray, shape (n_rows, n_channels)
    sigma_init : float or "auto", default "auto"
        Starting sigma of every mode (the paper uses 1), or "auto": per
        channel, the best common start of ``SIGMA_GRID`` by the first E-step's
        objective.
    ridge : float, default 1e-6
        See :func:`ridge_lambda`.
    tol, max_iter : float, int
        Stopping rule of :class:`ConvergenceMonitor`.
    gn_steps : int, default 1
        Gauss-Newton steps per M-step (the damping carries over between M-steps).
    verbose : int, default 0
        > 1 prints every channel's iterations on stderr. Progress over channels
        goes to :mod:`dam.progress` (shown by the command line; see ``progress.reporting``).
    fixed_sigma : bool, default False
        Only the first E-step (for tests and ablations).
    projected : bool, default True
        M-step by variable projection (True) or with the coefficients frozen
        as in the paper (False); see :func:`dam.mstep.gauss_newton_sigma`.
    channels : sequence of str, optional
        Channel names for the :class:`dam.base.ConvergenceWarning` (issued
        when a channel stops at ``max_iter`` with its last relative
        improvement still >= ``tol``); default "channel 0", "channel 1", ...
    weights : ndarray, shape (n_rows, n_channels), optional
        Weights of the squared residuals: 0 where a value is missing
        (``Utterance.mask``), so missing frames are skipped exactly rather
        than fitted at their interpolated values. Default: all 1.

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
    # First E-step: every channel starts with all sigmas equal, so one solve per
    # candidate start serves all channels; "auto" keeps each channel's best.
    starts = SIGMA_GRID if isinstance(sigma_init, str) else (float(sigma_init),)
    if isinstance(sigma_init, str) and sigma_init != "auto":
        raise ValueError(f"parameter 'sigma_init' is {sigma_init!r}; use a number > 0 or 'auto'")
    lam = None
    best = np.full(n_ch, np.inf)
    A0 = np.zeros((occ.n_modes, M1, n_ch))
    S0 = np.zeros(n_ch)
    for s0 in starts:
        sig = np.full(occ.n_modes, s0)
        pr = pairs(occ, sig)
        if lam is None:  # fixed for the whole fit, so every step minimises one objective
            lam = ridge_lambda(occ.n_rows, ridge)
        if weights is None:
            G, XtY = normal_equations(occ, sig, Y, pr)
            A, _ = solve_normal_equations(G, XtY, lam)
        else:  # each channel has its own missing frames, hence its own normal equations
            A = np.column_stack(
                [
                    solve_normal_equations(*normal_equations(occ, sig, Y[:, c], pr, weights[:, c]), lam)[0]
                    for c in range(n_ch)
                ]
            )
        R = Y - fitted_values_all(occ, A.reshape(occ.n_modes, M1, n_ch), sig, pr)
        R2 = R**2 if weights is None else weights * R**2
        obj = (np.sum(R2, axis=0) + lam * np.sum(A * A, axis=0)) / occ.n_rows
        better = obj < best
        best[better] = obj[better]
        A0[:, :, better] = A.reshape(occ.n_modes, M1, n_ch)[:, :, better]
        S0[better] = s0
    coef = A0.copy()
    sigma = np.repeat(S0[None, :], occ.n_modes, axis=0)
    curves, n_iter, converged = [], np.zeros(n_ch, dtype=int), np.zeros(n_ch, dtype=bool)
    unconverged = []  # (channel, last relative improvement) stopped by max_iter

    from dam.progress import track

    for c in track(
        range(n_ch), "DAM EM", unit="channel", labels=None if channels is None else [str(ch) for ch in channels]
    ):
        y = Y[:, c]
        w = None if weights is None else weights[:, c]
        a = A0[:, :, c]
        s = sigma[:, c].copy()
        mon = ConvergenceMonitor(tol, max_iter)
        mon.report(best[c])
        mu = 1e-3
        while not fixed_sigma and not mon.done:
            s, a, obj, mu = gauss_newton_sigma(
                occ, y, a, s, lam=lam, projected=projected, n_steps=gn_steps, mu=mu, weights=w
            )
            if not projected:  # the E-step (the projected M-step re-solves a itself)
                pr = pairs(occ, s)
                G, Xty = normal_equations(occ, s, y, pr, w)
                a = solve_normal_equations(G, Xty, lam)[0].reshape(occ.n_modes, M1)
                r = y - fitted_values(occ, a, s, pr)[0]
                obj = float(np.sum(r * r if w is None else w * r * r) + lam * np.sum(a * a))
            mon.iter += 1
            mon.report(obj / occ.n_rows)
        coef[:, :, c] = a
        sigma[:, c] = s
        curves.append(np.array(mon.history))
        n_iter[c] = mon.iter
        converged[c] = mon.converged
        if not fixed_sigma and not mon.converged and len(mon.history) >= 2:
            unconverged.append((c, mon.last_improvement))
        if verbose > 1:
            print(
                f"channel {c}: {mon.iter} iterations, objective {mon.history[0]:.4g} -> {mon.history[-1]:.4g}",
                file=sys.stderr,
            )
    if unconverged:
        warn_not_converged(unconverged, channels, tol, max_iter)
    return coef, sigma, curves, n_iter, converged


def warn_not_converged(unconverged, channels, tol: float, max_iter: int) -> None:
    """One :class:`dam.base.ConvergenceWarning` naming every channel EM left unconverged.

    Parameters
    ----------
    unconverged : list of (int, float)
        Channel index and its last relative improvement.
    channels : sequence of str or None
    """
    from dam.base import ConvergenceWarning

    names = [str(channels[c]) if channels is not None else f"channel {c}" for c, _ in unconverged]
    which = ", ".join(f"{n} (last relative improvement {imp:.3g})" for n, (_, imp) in zip(names, unconverged))
    warnings.warn(
        f"DAM EM stopped at max_iter={max_iter} before the relative improvement fell below "
        f"tol={tol:g} on {len(names)} channel(s): {which}. Raise max_iter, or raise tol to "
        "accept this precision.",
        ConvergenceWarning,
        stacklevel=3,
    )
