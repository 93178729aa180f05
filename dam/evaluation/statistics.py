"""The statistics of a comparison: bootstrap intervals, paired tests, multiple-testing correction.

* :func:`bootstrap_rmse_ci`: percentile bootstrap interval of a pooled RMSE,
  resampling whole utterances (frames within an utterance are not independent);
* :func:`paired_wilcoxon`: two-sided paired Wilcoxon signed-rank test of
  per-utterance scores (scipy);
* :func:`holm`: Holm–Bonferroni step-down adjustment of several p-values;
* :func:`tests_against`: the last two together, as :func:`dam.evaluation.compare`
  reports them: every model against the best one, Holm-corrected.

A new statistic of a comparison goes here; :mod:`dam.evaluation.compare` calls it
and :mod:`dam.evaluation.report` shows it.
"""

from __future__ import annotations

import numpy as np

__all__ = ["holm", "bootstrap_rmse_ci", "paired_wilcoxon", "tests_against"]


def holm(pvalues) -> np.ndarray:
    """Holm–Bonferroni adjusted p-values (step-down, monotone, capped at 1).

    Parameters
    ----------
    pvalues : array-like, shape (m,)

    Returns
    -------
    ndarray, shape (m,), in the input order

    Examples
    --------
    >>> from dam.evaluation.statistics import holm
    >>> holm([0.01, 0.04, 0.03, 0.5]).tolist()
    [0.04, 0.09, 0.09, 0.5]
    """
    p = np.asarray(pvalues, dtype=float)
    m = len(p)
    order = np.argsort(p, kind="stable")
    adjusted = np.minimum(1.0, np.maximum.accumulate((m - np.arange(m)) * p[order]))
    out = np.empty(m)
    out[order] = adjusted
    return out


def bootstrap_rmse_ci(sse, counts, *, n_boot: int = 2000, level: float = 0.95, random_state: int = 0):
    """Percentile bootstrap interval of the pooled RMSE, resampling utterances.

    Parameters
    ----------
    sse : array-like, shape (n_utterances,)
        Sum of squared errors of every utterance (all frames and channels).
    counts : array-like, shape (n_utterances,)
        Number of values (frames x channels) of every utterance.
    n_boot : int, default 2000
        Resamples.
    level : float, default 0.95
    random_state : int, default 0

    Returns
    -------
    (low, high) : tuple of float

    Examples
    --------
    >>> from dam.evaluation.statistics import bootstrap_rmse_ci
    >>> bootstrap_rmse_ci([8.0, 8.0, 8.0], [2.0, 2.0, 2.0])   # no spread to resample
    (2.0, 2.0)
    """
    sse, counts = np.asarray(sse, dtype=float), np.asarray(counts, dtype=float)
    rng = np.random.default_rng(random_state)
    idx = rng.integers(0, len(sse), size=(n_boot, len(sse)))
    boot = np.sqrt(sse[idx].sum(axis=1) / counts[idx].sum(axis=1))
    tail = 100 * (1 - level) / 2
    return float(np.percentile(boot, tail)), float(np.percentile(boot, 100 - tail))


def paired_wilcoxon(a, b) -> float:
    """Two-sided paired Wilcoxon signed-rank p-value; 1 when every difference is zero.

    Parameters
    ----------
    a, b : array-like, shape (n,)
        Paired scores (e.g. per-utterance RMSE of two models).

    Returns
    -------
    float

    Examples
    --------
    >>> from dam.evaluation.statistics import paired_wilcoxon
    >>> paired_wilcoxon([1.0, 2.0, 3.0], [1.0, 2.0, 3.0])
    1.0
    >>> paired_wilcoxon([1, 2, 3, 4, 5, 6], [2, 4, 6, 8, 10, 12])   # exact: all six lower, 2 / 2^6
    0.03125
    """
    from scipy.stats import wilcoxon

    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if np.allclose(a, b, rtol=0, atol=0):
        return 1.0
    return float(wilcoxon(a, b).pvalue)


def tests_against(reference, scores: dict) -> dict:
    """Paired Wilcoxon test of every model's per-utterance scores against ``reference``,
    Holm-corrected over the models tested.

    Parameters
    ----------
    reference : array-like, shape (n_utterances,)
        The scores of the model compared against (the best one, in :func:`dam.compare`).
    scores : dict
        ``{model: array-like of shape (n_utterances,)}``, the same utterances in the same order.

    Returns
    -------
    dict
        ``{model: (p, p_holm)}``, in the order of ``scores``.

    Examples
    --------
    >>> from dam.evaluation.statistics import tests_against
    >>> tests_against([1.0, 2.0, 3.0], {"same": [1.0, 2.0, 3.0]})
    {'same': (1.0, 1.0)}
    """
    names = list(scores)
    p = [paired_wilcoxon(scores[m], reference) for m in names]
    return {m: (pv, float(ph)) for m, pv, ph in zip(names, p, holm(p) if p else [])}
