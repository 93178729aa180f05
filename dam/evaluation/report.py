"""The report of a comparison: its typed summary row, the Markdown table, the CSV files, the figures.

:func:`dam.evaluation.compare.compare` measures; this module shows what it measured:

* :class:`ModelScore`: one model's row of the summary (:data:`SUMMARY_COLUMNS`);
* :func:`markdown_table`: the summary as a Markdown table with a note on the tests;
* :func:`write_report`: ``summary.csv``, ``per_channel.csv``, ``per_utterance.csv``
  (``per_sensor.csv`` when the channels form sensors), ``summary.md`` and the figures,
  each written atomically;
* :func:`plot_report`: ``predictions.png`` and ``rmse.png`` (drawn by
  :mod:`dam.evaluation.figures`).

Each takes a :class:`~dam.evaluation.compare.ComparisonResult` (anything with its
attributes), so a new file or figure goes here without touching the comparison.
"""

from __future__ import annotations

import csv
import math
import os
from dataclasses import asdict, dataclass, fields

from dam.corpus.atomic import atomic_write

__all__ = ["ModelScore", "SUMMARY_COLUMNS", "markdown_table", "write_report", "plot_report"]


@dataclass
class ModelScore:
    """One model's row of a comparison summary.

    Measurements a model did not get (it was skipped or failed; the best model
    is not tested against itself; the channels form no sensors) are None, an
    empty cell in ``summary.csv``. A row reads like the dict it used to be:
    ``row["rmse"]`` is ``row.rmse``.

    Attributes
    ----------
    model : str
        The row's label.
    rmse, rmse_ci_low, rmse_ci_high : float or None
        Held-out RMSE (channel units, all frames and channels pooled) and its
        95% bootstrap interval over utterances.
    pearson_r : float or None
        Per channel over all frames pooled, averaged over channels.
    sensor_error : float or None
        Mean Euclidean distance per sensor and frame (Medina et al. 2022, Eq. 1).
    fit_seconds : float or None
        Mean over folds.
    predict_us_per_phone, frames_per_second : float or None
        Synthesis speed (median of warm runs).
    wilcoxon_p, wilcoxon_p_holm : float or None
        Paired test of per-utterance RMSE against the best model, raw and Holm-corrected.
    n_utterances : int or None
    status : {"ok", "skipped", "failed"}
    reason : str
        Why a model was skipped or failed.
    """

    model: str
    rmse: float | None = None
    rmse_ci_low: float | None = None
    rmse_ci_high: float | None = None
    pearson_r: float | None = None
    sensor_error: float | None = None
    fit_seconds: float | None = None
    predict_us_per_phone: float | None = None
    frames_per_second: float | None = None
    wilcoxon_p: float | None = None
    wilcoxon_p_holm: float | None = None
    n_utterances: int | None = None
    status: str = "ok"
    reason: str = ""

    def __getitem__(self, key: str):
        if key not in SUMMARY_COLUMNS:
            raise KeyError(key)
        return getattr(self, key)

    def get(self, key: str, default=None):
        """``row[key]``, or ``default`` for a column it does not have or a measurement it did not get."""
        value = getattr(self, key, None) if key in SUMMARY_COLUMNS else None
        return default if value is None else value

    def keys(self):
        return list(SUMMARY_COLUMNS)

    def as_dict(self) -> dict:
        return asdict(self)


#: The columns of ``summary.csv``: the fields of :class:`ModelScore`, in order.
SUMMARY_COLUMNS = tuple(f.name for f in fields(ModelScore))
PER_CHANNEL_COLUMNS = ("model", "channel", "rmse", "pearson_r")
PER_UTTERANCE_COLUMNS = ("model", "fold", "utterance", "n_frames", "rmse", "pearson_r", "sensor_error")
PER_SENSOR_COLUMNS = ("model", "sensor", "channels", "distance")


def markdown_table(result) -> str:
    """The summary of ``result`` as a Markdown table, with a note on the tests.

    Parameters
    ----------
    result : ComparisonResult

    Returns
    -------
    str
    """
    head = (
        "| model | RMSE | 95% CI | Pearson r | fit s | µs/phone | frames/s | p vs best (Holm) |\n"
        "|---|---:|---:|---:|---:|---:|---:|---:|"
    )
    lines = [head]
    for r in result.summary:
        if r["status"] != "ok":
            lines.append(f"| {r['model']} | {r['status']}: {r['reason']} | | | | | | |")
            continue
        p = "best" if r["model"] == result.best else _fmt_p(r["wilcoxon_p_holm"])
        lines.append(
            f"| {r['model']} | {r['rmse']:.4g} | {r['rmse_ci_low']:.4g}–{r['rmse_ci_high']:.4g} | "
            f"{r['pearson_r']:.3f} | {r['fit_seconds']:.2f} | {r['predict_us_per_phone']:.1f} | "
            f"{r['frames_per_second']:.3g} | {p} |"
        )
    n_utt = max([r["n_utterances"] for r in result.summary if r["status"] == "ok"] or [0])
    lines.append("")
    if result.per_sensor:
        unit = f" ({result.length_unit})" if result.length_unit else ""
        errs = ", ".join(f"{r['model']} {r['sensor_error']:.4g}" for r in result.summary if r["status"] == "ok")
        lines.append("")
        lines.append(
            f"Sensor error{unit}, mean Euclidean distance per sensor and frame (Medina et al. 2022, "
            f"Eq. 1), averaged over utterances: {errs}."
        )
    lines.append(
        f"Held-out {result.corpus}: {n_utt} utterances. RMSE in channel units over all frames and "
        "channels; 95% CI by bootstrap over utterances; Pearson r per channel, averaged; "
        "p: two-sided paired Wilcoxon signed-rank test of per-utterance RMSE against the best "
        "model, Holm-corrected."
    )
    # The exact two-sided signed-rank test cannot go below 2 / 2^n; Holm multiplies the smallest p.
    n_tests = sum(r["status"] == "ok" for r in result.summary) - 1
    floor = min(1.0, n_tests * 2.0 / 2.0**n_utt) if n_utt else 1.0
    if n_tests > 0 and floor > 0.05:
        lines.append(
            f"With {n_utt} utterances and {n_tests} comparisons no Holm-corrected p can fall below "
            f"{floor:.2g}: use more test utterances or --cv for significance."
        )
    return "\n".join(lines)


def write_report(result, out) -> list[str]:
    """Write the CSVs, the Markdown table and the figures of ``result`` into directory ``out``.

    Returns
    -------
    list of str
        The paths written.
    """
    os.makedirs(out, exist_ok=True)
    paths = [
        _write_csv(os.path.join(out, "summary.csv"), result.summary, SUMMARY_COLUMNS),
        _write_csv(os.path.join(out, "per_channel.csv"), result.per_channel, PER_CHANNEL_COLUMNS),
        _write_csv(os.path.join(out, "per_utterance.csv"), result.per_utterance, PER_UTTERANCE_COLUMNS),
    ]
    if result.per_sensor:
        paths.append(_write_csv(os.path.join(out, "per_sensor.csv"), result.per_sensor, PER_SENSOR_COLUMNS))
    md = os.path.join(out, "summary.md")
    with atomic_write(md, "w", encoding="utf-8") as fh:
        fh.write(markdown_table(result) + "\n")
    paths.append(md)
    paths += plot_report(result, out)
    return paths


def plot_report(result, out) -> list[str]:
    """``predictions.png`` and ``rmse.png`` in ``out`` (:mod:`dam.evaluation.figures`); returns their paths."""
    import dam.plotting as plotting
    from dam.evaluation.figures import plot_predictions, plot_rmse

    ok = [r for r in result.summary if r["status"] == "ok"]
    units = {"units": result.example.get("units")} if result.example.get("units") else {}
    paths = []
    if result.example and ok:
        fig = plot_predictions(result.example, result.summary, corpus=result.corpus)
        paths.append(plotting.save(fig, os.path.join(out, "predictions.png")))
    if ok:
        fig = plot_rmse(result.summary, result.per_channel, best=result.best, corpus=result.corpus, metadata=units)
        paths.append(plotting.save(fig, os.path.join(out, "rmse.png")))
    return paths


def _fmt_p(p) -> str:
    return "" if p == "" or p is None else (f"{p:.2g}" if p >= 1e-4 else f"{p:.1e}")


def _write_csv(path, rows, columns) -> str:
    with atomic_write(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, fieldnames=list(columns), extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: _csv_value(r.get(k, "")) for k in columns})
    return path


def _csv_value(v):
    if v is None:
        return ""
    if isinstance(v, float):
        return "" if not math.isfinite(v) else repr(v)
    return v
