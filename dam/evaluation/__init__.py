"""Scoring and comparing synthesizers: metrics, statistics, the comparison table, its figures.

- :mod:`~dam.evaluation.metrics`: RMSE and Pearson r, overall, per channel and per utterance.
- :mod:`~dam.evaluation.compare`: :func:`compare`, the cross-validated table with bootstrap
  intervals and paired tests.
"""
from __future__ import annotations

from dam._lazy import lazy_exports

_EXPORTS = {
    **dict.fromkeys(["evaluate", "Evaluation", "rmse", "rmse_per_channel", "pearson_per_channel"], ".metrics"),
    **dict.fromkeys(["compare", "ComparisonResult", "holm", "bootstrap_rmse_ci", "run_demo", "DEMO_MODELS"],
                    ".compare"),
}
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, ("metrics", "compare"))

__all__ = list(_EXPORTS)
