"""Figures of a comparison and of a trained network, in the style of :mod:`dam.plotting`.

* :func:`plot_predictions`: one held-out utterance, small multiples: a row per
  channel, a column per model (the best ones), the truth in black in every
  panel, the phones under every column;
* :func:`plot_rmse`: held-out RMSE per model with its 95% interval, overall
  (mixed units) and per channel in the channel's own unit;
* :func:`plot_loss_curves`: training and validation loss per epoch of
  neural predictors, one panel per model.

Each returns the matplotlib Figure; :meth:`ComparisonResult.plot` saves them.
"""

from __future__ import annotations

import numpy as np

from dam import plotting

__all__ = ["plot_predictions", "plot_rmse", "plot_loss_curves"]


def plot_predictions(
    example: dict, summary, *, corpus: str = "", max_models: int = 4, max_channels: int = 6, metadata=None
):
    """Predictions against the truth on one held-out utterance.

    Parameters
    ----------
    example : dict
        ``utterance``, ``frame_rate``, ``channels``, ``truth`` (n_frames, n_channels),
        ``predictions`` {model: array}, ``alignment``, optionally ``units``
        (:attr:`ComparisonResult.example`).
    summary : list of dict
        Rows with ``model``, ``status``, ``rmse``, sorted best first.
    corpus : str
        What was compared on, for the title.
    max_models, max_channels : int
        Columns are the best ``max_models`` models; rows the ``max_channels``
        channels that move most in this utterance (all when there are fewer).

    Returns
    -------
    matplotlib.figure.Figure
    """
    meta = {"units": example.get("units")} if example.get("units") else (metadata or {})
    truth = np.asarray(example["truth"])
    ok = [r for r in summary if r.get("status") == "ok" and r["model"] in example["predictions"]]
    shown = ok[:max_models]
    n_ch = truth.shape[1]
    rows = np.arange(n_ch) if n_ch <= max_channels else np.sort(np.argsort(-truth.std(axis=0))[:max_channels])
    t = np.arange(len(truth)) / example["frame_rate"]
    which = f"best {len(shown)} of {len(ok)} models" if len(shown) < len(ok) else f"{len(ok)} models"
    chans = "" if len(rows) == n_ch else f", the {len(rows)} of {n_ch} channels that move most"
    title = (
        f"Held-out utterance {example['utterance']}{' of ' + corpus if corpus else ''}: "
        f"{which} (colour) against the measured trajectory (black){chans}"
    )
    fig, axes, _ = plotting.time_grid(
        len(rows), max(len(shown), 1), example["alignment"], title=title, panel_size=(3.6, 1.35)
    )
    handles = {}
    for j, r in enumerate(shown):
        pred = np.asarray(example["predictions"][r["model"]])
        for i, c in enumerate(rows):
            ax = axes[i, j]
            (h_truth,) = ax.plot(t, truth[:, c], color=plotting.TRUTH, lw=1.8)
            (h,) = ax.plot(t, pred[:, c], color=plotting.model_color(j), lw=1.3)
            handles.setdefault("measured", h_truth)
            handles[r["model"]] = h
            if j == 0:
                ax.set_ylabel(plotting.channel_label(example["channels"][c], meta, wrap=True), fontsize=8)
        axes[0, j].set_title(f"{r['model']} (RMSE {r['rmse']:.3g})")
    # one y range per channel across the models, so columns compare at a glance
    for i in range(len(rows)):
        lo = min(a.get_ylim()[0] for a in axes[i])
        hi = max(a.get_ylim()[1] for a in axes[i])
        for j, a in enumerate(axes[i]):
            a.set_ylim(lo, hi)
            if j:  # one scale per row: its labels on the first column only
                a.tick_params(labelleft=False)
    plotting.legend_outside(fig, list(handles.values()), list(handles), title="trajectory")
    return fig


def plot_rmse(summary, per_channel, *, best: str | None, corpus: str = "", metadata=None):
    """Held-out RMSE per model: overall with its bootstrap 95% interval, and per channel.

    Parameters
    ----------
    summary : list of dict
        ``model, status, rmse, rmse_ci_low, rmse_ci_high``.
    per_channel : list of dict
        ``model, channel, rmse``.
    best : str or None
        The model with the lowest RMSE (drawn in its own colour, said in the legend).
    corpus : str
    metadata : dict, optional
        Corpus metadata with the channel ``units``.

    Returns
    -------
    matplotlib.figure.Figure
    """
    ok = [r for r in summary if r.get("status") == "ok"]
    channels = list(dict.fromkeys(r["channel"] for r in per_channel))
    units = {plotting.channel_unit(c, metadata) for c in channels}
    mixed = ", ".join(sorted(u or "no unit" for u in units if u is not None)) or "channel units"
    n_panels = 1 + len(channels)
    ncols = min(4, n_panels)
    nrows = -(-n_panels // ncols)
    title = (
        f"Held-out RMSE per model on {corpus or 'the test data'} "
        f"({len(channels)} channel{'s' if len(channels) != 1 else ''}: {', '.join(channels)}); lower is better"
    )
    fig, axes = plotting.figure(nrows, ncols, title=title, panel_size=(3.3, 0.28 * len(ok) + 1.0))
    y = np.arange(len(ok))[::-1]
    names = [r["model"] for r in ok]
    colors = [plotting.PALETTE[1] if r["model"] == best else plotting.PALETTE[0] for r in ok]
    ax = axes.flat[0]
    vals = np.array([r["rmse"] for r in ok])
    err = np.array([[r["rmse"] - r["rmse_ci_low"] for r in ok], [r["rmse_ci_high"] - r["rmse"] for r in ok]])
    ax.barh(y, vals, xerr=err, color=colors, capsize=2, error_kw={"lw": 0.8})
    ax.set_yticks(y, names)
    ax.set_ylabel("model")
    ax.set_title("all channels (95% CI)")
    ax.set_xlabel(f"RMSE ({mixed}{', pooled' if len(units) > 1 else ''})")
    by = {(r["model"], r["channel"]): r["rmse"] for r in per_channel}
    for k, c in enumerate(channels, start=1):
        ax = axes.flat[k]
        v = [by.get((m, c), np.nan) for m in names]
        ax.barh(y, v, color=colors)
        ax.set_yticks(y, names if k % ncols == 0 else [""] * len(names))
        ax.set_ylabel("model" if k % ncols == 0 else "")
        ax.set_title(c)
        unit = plotting.channel_unit(c, metadata)
        ax.set_xlabel(f"RMSE ({'channel units' if unit is None else unit or 'no unit'})")
    for ax in list(axes.flat)[n_panels:]:
        ax.set_visible(False)
    from matplotlib.patches import Patch

    plotting.legend_outside(
        fig,
        [Patch(color=plotting.PALETTE[1]), Patch(color=plotting.PALETTE[0])],
        ["best (lowest overall RMSE)", "other models"],
        where="lower",
    )
    return fig


def plot_loss_curves(models: dict, *, corpus: str = ""):
    """Training and validation loss per epoch of neural predictors, one panel per model.

    Parameters
    ----------
    models : dict
        label -> fitted network with ``loss_curve_``, ``validation_curve_`` and ``best_epoch_``.
    corpus : str
        What they were trained on, for the title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    n = len(models)
    fig, axes = plotting.figure(
        1,
        n,
        title=f"Loss per epoch of the neural predictors"
        f"{' on ' + corpus if corpus else ''} (early stopping keeps the "
        "marked epoch)",
        sharey=True,
    )
    from matplotlib.ticker import MaxNLocator

    handles, labels = [], []
    for ax, (label, m) in zip(axes[0], models.items()):
        epochs = np.arange(1, len(m.loss_curve_) + 1)
        handles, labels = [ax.semilogy(epochs, m.loss_curve_, color=plotting.PALETTE[0])[0]], ["training (dropout on)"]
        if len(getattr(m, "validation_curve_", [])):
            handles.append(
                ax.semilogy(np.arange(1, len(m.validation_curve_) + 1), m.validation_curve_, color=plotting.PALETTE[1])[
                    0
                ]
            )
            labels.append("validation")
        handles.append(ax.axvline(m.best_epoch_, color="0.3", lw=0.8, ls=":"))
        labels.append("epoch kept")
        ax.set_title(label)
        ax.set_xlabel("epoch")
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    axes[0, 0].set_ylabel("MSE (standardized\nchannels, no unit)")
    plotting.legend_outside(fig, handles, labels, where="lower")
    return fig
