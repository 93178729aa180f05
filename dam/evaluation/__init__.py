"""Scoring and comparing synthesizers: metrics, statistics, the comparison table, its figures.

- :mod:`~dam.evaluation.metrics`: RMSE and Pearson r, overall, per channel and per utterance.
- :mod:`~dam.evaluation.compare`: :func:`compare`, the cross-validated table: planning,
  running, scoring (a new step of a comparison goes here);
- :mod:`~dam.evaluation.statistics`: bootstrap intervals, paired Wilcoxon tests, Holm's
  correction (a new statistic goes here);
- :mod:`~dam.evaluation.report`: the typed summary row, the Markdown table, the CSV files
  and the figures of a comparison (a new file or figure goes here).
"""

from __future__ import annotations

from dam._lazy import lazy_exports

_EXPORTS = {
    **dict.fromkeys(["evaluate", "Evaluation", "rmse", "rmse_per_channel", "pearson_per_channel"], ".metrics"),
    **dict.fromkeys(
        ["compare", "ComparisonResult", "run_demo", "DEMO_MODELS", "plan_comparison", "run_tasks", "score_results"],
        ".compare",
    ),
    **dict.fromkeys(["holm", "bootstrap_rmse_ci", "paired_wilcoxon", "tests_against"], ".statistics"),
    **dict.fromkeys(["ModelScore", "markdown_table", "write_report"], ".report"),
}
__getattr__, __dir__ = lazy_exports(
    __name__, _EXPORTS, ("metrics", "compare", "statistics", "report", "figures", "textbook")
)

__all__ = list(_EXPORTS)
