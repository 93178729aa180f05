"""Textbook figures for a phone sequence you type, in the style of :mod:`dam.plotting`.

* :func:`phone_sequence`: ``"sil h a l o: sil"`` with durations -> an :class:`~dam.Alignment`;
* :func:`plot_dominance_sum`: the dominance function ``D_j`` of every segment
  (Eq. 1 of Chen et al. 2012), the weight ``D_j / sum_k D_k`` each one gets,
  and how the animemes ``A_j`` combine into the trajectory (Eq. 2): the
  picture of coarticulation as overlapping gestures (Cohen & Massaro 1993);
* :func:`plot_sequence`: the same sequence under several fitted models
  (DAM, Cohen-Massaro, MMM, phone-mean ...), a column per model, a row per
  channel, the recorded trajectory in black when there is one.

Each returns the matplotlib Figure.
"""

from __future__ import annotations

import numpy as np

from dam import plotting
from dam.corpus import Alignment, DataError

__all__ = ["phone_sequence", "plot_dominance_sum", "plot_sequence"]


def phone_sequence(phones, durations=0.1) -> Alignment:
    """An alignment of typed phones laid end to end from time 0.

    Parameters
    ----------
    phones : str or sequence of str
        Phones separated by spaces (``"sil h a l o: sil"``), or a list.
    durations : float or sequence of float, default 0.1
        Seconds per phone: one for all, or one each.

    Returns
    -------
    Alignment

    Examples
    --------
    >>> a = phone_sequence("sil a i sil", [0.2, 0.1, 0.15, 0.2])
    >>> [round(float(e), 2) for e in a.ends]
    [0.2, 0.3, 0.45, 0.65]
    """
    labels = phones.split() if isinstance(phones, str) else [str(p) for p in phones]
    if not labels:
        raise DataError(None, "phones", phones, "type at least one phone")
    d = (
        np.broadcast_to(np.asarray(durations, dtype=float), (len(labels),))
        if np.ndim(durations) == 0
        else np.asarray(durations, dtype=float)
    )
    if d.shape != (len(labels),) or not np.all(np.isfinite(d) & (d > 0)):
        raise DataError(None, "durations", durations, f"need {len(labels)} positive durations (or one for all)")
    ends = np.cumsum(d)
    return Alignment(labels, ends - d, ends)


def plot_dominance_sum(model, alignment: Alignment, channel: int = 0, *, metadata=None, name: str = ""):
    """Dominance functions of a phone sequence and the trajectory they weigh together (DAM).

    Three panels over time: every segment's dominance ``D_j(t)`` (Eq. 1, the
    mode A* chose); the share ``D_j / sum_k D_k`` each segment has at every
    instant (stacked; what the weighted average of Eq. 2 uses); every
    segment's animeme ``A_j(t)`` where its dominance reaches, and their
    combination, the model's output.

    Parameters
    ----------
    model : DAM, fitted
    alignment : Alignment
        E.g. from :func:`phone_sequence`; its phones must be the model's.
    channel : int, default 0
    metadata : dict, optional
        Corpus metadata (channel ``units``).
    name : str
        What the sequence is, for the title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    rows = model.explain(alignment)
    ch = model.channels_[channel]
    n = alignment.n_frames(model.frame_rate_)
    t = np.arange(n) / model.frame_rate_
    D = np.empty((len(rows), n))
    A = np.empty((len(rows), n))
    for j, r in enumerate(rows):
        tl = (t - r["start"]) / (r["end"] - r["start"])
        D[j] = model.dominance_curve(r["phone"], r["mode"], tl)[:, channel]
        A[j] = model.animeme_curve(r["phone"], r["mode"], tl)[:, channel]
    total = D.sum(axis=0)
    share = D / np.where(total > 0, total, 1.0)
    out = model.predict(alignment)[:, channel]
    how = "weighted average" if getattr(model, "normalize", True) else "sum"
    seq = name or " ".join(alignment.labels)
    fig, axes, _ = plotting.time_grid(
        3,
        1,
        alignment,
        panel_size=(8.0, 1.6),
        title=f"Coarticulation in the DAM: dominance of each segment and their {how}, /{seq}/, channel {ch}",
    )
    ax1, ax2, ax3 = axes[:, 0]
    colors = [plotting.model_color(j) for j in range(len(rows))]
    for j in range(len(rows)):
        ax1.plot(t, D[j], color=colors[j], lw=1.1)
        reach = D[j] > 0.02
        ax3.plot(np.where(reach, t, np.nan), np.where(reach, A[j], np.nan), color=colors[j], lw=0.9, alpha=0.8)
    ax1.plot(t, total, color="0.4", lw=1.0, ls=":")
    ax2.stackplot(t, share, colors=colors, alpha=0.85)
    (h_out,) = ax3.plot(t, out, color=plotting.TRUTH, lw=2.0)
    ax1.set_ylabel("dominance D_j\n(no unit)")
    ax1.set_title("dominance of each segment, Eq. (1) (dotted: their sum)", fontsize=9)
    ax2.set_ylabel("share D_j / ΣD\n(no unit)")
    ax2.set_ylim(0, 1)
    ax2.set_title("how much each segment counts at every instant", fontsize=9)
    ax3.set_ylabel(plotting.channel_label(ch, metadata, wrap=True))
    ax3.set_title(f"animemes A_j where their dominance reaches, and their {how} (Eq. 2)", fontsize=9)
    from matplotlib.lines import Line2D

    plotting.legend_outside(
        fig,
        [Line2D([], [], color=colors[0], lw=1), h_out],
        ["one colour per segment (D_j, share, A_j)", f"DAM output (Eq. 2, {how})"],
        where="lower",
    )
    return fig


def plot_sequence(
    models: dict,
    alignment,
    channels=None,
    *,
    truth=None,
    metadata=None,
    name: str = "",
    title: str | None = None,
    panel_size=(3.4, 1.3),
    legend: str = "right",
):
    """One phone sequence under several fitted models: a column per model, a row per channel.

    Parameters
    ----------
    models : dict
        Label -> fitted synthesizer (same channels and frame rate).
    alignment : Alignment or Utterance
        The phones; an Utterance (its alignment, and its audio for models that read audio).
    channels : sequence of str, optional
        Rows; default all channels of the first model (at most 6).
    truth : ndarray, shape (n_frames, n_channels), optional
        The recorded trajectory, drawn in black in every panel.
    metadata : dict, optional
        Corpus metadata (channel ``units``).
    name : str
        What the sequence is, for the title.
    title : str, optional
        The whole title instead (default: the sequence, the number of models, whether truth is drawn).
    panel_size : (float, float), default (3.4, 1.3)
        Inches per panel.
    legend : {"right", "lower"}, default "right"
        Where the legend goes, outside the panels.

    Returns
    -------
    matplotlib.figure.Figure
    """
    if not models:
        raise DataError(None, "models", models, "give at least one fitted model")
    first = next(iter(models.values()))
    names = list(first.channels_)
    channels = names[:6] if channels is None else list(channels)
    for c in channels:
        if c not in names:
            raise DataError(None, "channels", c, f"not a channel of the models ({', '.join(names)})")
    cols = [names.index(c) for c in channels]
    fr = first.frame_rate_
    preds = {label: np.asarray(m.predict(alignment)) for label, m in models.items()}
    alignment = getattr(alignment, "alignment", alignment)  # an Utterance: its phones
    seq = name or " ".join(alignment.labels)
    what = "against the recording (black)" if truth is not None else "(no recording: the models only)"
    title = title or f"/{seq}/ under {len(models)} model{'s' if len(models) > 1 else ''} {what}"
    fig, axes, _ = plotting.time_grid(len(cols), len(models), alignment, panel_size=panel_size, title=title)
    handles = {}
    for j, (label, y) in enumerate(preds.items()):
        t = np.arange(len(y)) / fr
        for i, c in enumerate(cols):
            ax = axes[i, j]
            if truth is not None:
                tr = np.asarray(truth)[:, c]
                (handles["recorded"],) = ax.plot(np.arange(len(tr)) / fr, tr, color=plotting.TRUTH, lw=1.8)
            (handles[label],) = ax.plot(t, y[:, c], color=plotting.model_color(j), lw=1.4)
            if j == 0:
                ax.set_ylabel(plotting.channel_label(names[c], metadata, wrap=True), fontsize=8)
        axes[0, j].set_title(label)
    for i in range(len(cols)):  # one y range per channel, so the columns compare at a glance
        lo = min(a.get_ylim()[0] for a in axes[i])
        hi = max(a.get_ylim()[1] for a in axes[i])
        for a in axes[i]:
            a.set_ylim(lo, hi)
    plotting.legend_outside(fig, list(handles.values()), list(handles), title="trajectory", where=legend)
    return fig
