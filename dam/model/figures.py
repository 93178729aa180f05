"""What a fitted DAM learned, as figures in the style of :mod:`dam.plotting`.

* :func:`plot_dominance`: every segment's dominance function ``D_j`` (Eq. 1)
  and dominated animeme ``D_j A_j`` over one utterance, their combination
  (Eq. 2) against the measured trajectory, the phones underneath;
* :func:`plot_animemes`: the animeme ``A(t)`` of every mode of a few phones,
  on [0, 1] and a little beyond (where the dominance still reaches);
* :func:`plot_modes`: what mode clustering saw: the mean resampled training
  occurrence of each mode;
* :func:`plot_astar`: the animeme graph of an utterance and the path A* chose.

Modes are labelled ``iy/mode 1``, never ``iy1``, which would read as an
ARPAbet stress digit.
"""

from __future__ import annotations

import numpy as np

from dam import plotting

__all__ = ["mode_label", "plot_dominance", "plot_animemes", "plot_modes", "plot_astar", "inspected_phones"]


def mode_label(phone: str, mode: int, n_modes: int | None = None) -> str:
    """``"iy/mode 1"`` (modes counted from 1), or just ``"iy"`` for a phone with one mode."""
    return str(phone) if n_modes == 1 else f"{phone}/mode {int(mode) + 1}"


def inspected_phones(model, n: int = 4) -> list[str]:
    """The ``n`` phones with the most modes (then the most occurrences): the interesting ones."""
    return sorted(model.phone_modes_, key=lambda p: (-model.phone_modes_[p][1], -model.phone_counts_[p]))[:n]


def plot_dominance(model, utterance, channel: int = 0, *, corpus: str = "", metadata=None):
    """Dominance functions and dominated animemes of one utterance, for one channel.

    Parameters
    ----------
    model : DAM, fitted
    utterance : Utterance
        Its alignment drives the synthesis; its trajectory is the measured truth.
    channel : int, default 0
    corpus : str
        Where the utterance comes from, for the title.
    metadata : dict, optional
        Corpus metadata (channel ``units``).

    Returns
    -------
    matplotlib.figure.Figure
    """
    a = utterance.alignment
    rows = model.explain(a)
    ch = model.channels_[channel]
    t = np.arange(utterance.n_frames) / model.frame_rate_
    how = "weighted average" if getattr(model, "normalize", True) else "sum"
    fig, axes, _ = plotting.time_grid(
        2,
        1,
        a,
        panel_size=(10.0, 2.0),
        title=f"DAM dominance functions and dominated animemes, {utterance.name}"
        f"{' of ' + corpus if corpus else ''}, channel {ch}",
    )
    ax1, ax2 = axes[0, 0], axes[1, 0]
    for j, r in enumerate(rows):
        d = a.ends[j] - a.starts[j]
        tl = (t - a.starts[j]) / d
        D = model.dominance_curve(r["phone"], r["mode"], tl)[:, channel]
        A = model.animeme_curve(r["phone"], r["mode"], tl)[:, channel]
        color = plotting.model_color(j)
        ax1.plot(t, D, lw=1, color=color)
        ax2.plot(t, D * A, lw=0.8, color=color, alpha=0.75)
        if r["n_modes"] > 1:  # which mode A* chose, where several exist
            ax1.text(
                0.5 * (a.starts[j] + a.ends[j]), 1.04, f"mode {r['mode'] + 1}", ha="center", fontsize=6, color=color
            )
    pred = model.predict(a)[:, channel]
    (h1,) = ax2.plot(t, utterance.trajectory[:, channel], color=plotting.TRUTH, lw=2)
    (h2,) = ax2.plot(t, pred, color=plotting.PALETTE[1], lw=1.6, ls="--")
    from matplotlib.lines import Line2D

    h3 = Line2D([], [], color="0.5", lw=0.8)
    ax1.set_ylabel("dominance D_j\n(no unit)")
    ax1.set_ylim(0, 1.12)
    ax1.set_title("dominance of each segment (Eq. 1; the label says the mode A* chose)", fontsize=9)
    ax2.set_ylabel(plotting.channel_label(ch, metadata, wrap=True))
    ax2.set_title(f"dominated animemes D_j A_j and their {how} (Eq. 2)", fontsize=9)
    plotting.legend_outside(
        fig, [h1, h2, h3], ["measured", f"DAM (Eq. 2, {how})", "D_j A_j, one per segment"], where="lower"
    )
    return fig


def plot_animemes(model, phones, channel: int = 0, *, corpus: str = "", metadata=None):
    """The animeme of every mode of ``phones``, one panel per phone.

    Returns
    -------
    matplotlib.figure.Figure
    """
    ch = model.channels_[channel]
    tt = np.linspace(-0.5, 1.5, 201)
    fig, axes = plotting.figure(
        1,
        len(phones),
        sharey=True,
        panel_size=(3.0, 2.6),
        title=f"DAM animemes A(t) of every mode, channel {ch}"
        f"{' (trained on ' + corpus + ')' if corpus else ''}; grey: the phone itself",
    )
    for ax, p in zip(axes[0], phones):
        info = model.modes_of(p)
        for g in range(info["n_modes"]):
            ax.plot(
                tt,
                model.animeme_curve(p, g, tt)[:, channel],
                color=plotting.model_color(g),
                label=f"{mode_label(p, g, info['n_modes'])}: n={int(info['counts'][g])}, "
                f"σ={info['sigma'][g, channel]:.2f}",
            )
        ax.axvspan(0, 1, color="0.93", zorder=0)
        ax.set_title(f"/{p}/ ({info['n_modes']} mode{'s' if info['n_modes'] != 1 else ''})")
        ax.set_xlabel("local time t (segment = [0, 1])")
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.32), fontsize=7)
    axes[0, 0].set_ylabel(plotting.channel_label(ch, metadata, what="A(t),"))
    return fig


def plot_modes(model, phones, channel: int = 0, *, corpus: str = "", metadata=None):
    """Mean resampled training occurrence of each mode of ``phones`` (what affinity propagation grouped).

    Returns
    -------
    matplotlib.figure.Figure
    """
    ch = model.channels_[channel]
    fig, axes = plotting.figure(
        1,
        len(phones),
        sharey=True,
        panel_size=(3.0, 2.6),
        title=f"DAM modes: mean training occurrence of each mode, channel {ch}{' (' + corpus + ')' if corpus else ''}",
    )
    for ax, p in zip(axes[0], phones):
        first, n_modes = model.phone_modes_[p]
        for g in range(n_modes):
            shape = model.mode_shapes_[first + g][:, channel]
            ax.plot(
                np.linspace(0, 1, len(shape)),
                shape,
                marker=".",
                color=plotting.model_color(g),
                label=mode_label(p, g, n_modes),
            )
        ax.set_title(f"/{p}/")
        ax.set_xlabel("local time t (segment = [0, 1])")
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.32), fontsize=7)
    axes[0, 0].set_ylabel(plotting.channel_label(ch, metadata))
    return fig


def plot_astar(model, alignment, *, name: str = ""):
    """The animeme graph of ``alignment`` (one column per segment, one node per mode, coloured by
    the context cost ``w_c E_c``) and the path A* chose.

    Returns
    -------
    matplotlib.figure.Figure
    """
    rows = model.explain(alignment)
    labels = [r["phone"] for r in rows]
    nodes, _, _ = model._graph(labels, alignment.durations)
    fig, axes = plotting.figure(
        1,
        1,
        panel_size=(max(6.0, 0.42 * len(rows)), 2.6),
        title=f"DAM animeme graph and the A* path{', ' + name if name else ''} (total cost {rows[-1]['total']:.1f})",
    )
    ax = axes[0, 0]
    finite = nodes[np.isfinite(nodes)]
    vmax = max(float(finite.max()), 1.0) if finite.size else 1.0
    sc = None
    for j, r in enumerate(rows):
        for g in range(r["n_modes"]):
            sc = ax.scatter(
                j,
                g + 1,
                s=110,
                c=[nodes[j, g]],
                cmap="cividis",
                vmin=0,
                vmax=vmax,
                edgecolors=plotting.PALETTE[1] if g == r["mode"] else "none",
                linewidths=2,
            )
        if j:
            ax.plot([j - 1, j], [rows[j - 1]["mode"] + 1, r["mode"] + 1], color=plotting.PALETTE[1], lw=1.5, zorder=0)
    ax.set_yticks(range(1, nodes.shape[1] + 1))
    ax.set_xticks(range(len(rows)), labels, fontsize=8)
    ax.set_xlabel("segment (phone)")
    ax.set_ylabel("mode")
    if sc is not None:
        fig.colorbar(sc, ax=ax, label="context cost w_c E_c (no unit)")
    from matplotlib.lines import Line2D

    plotting.legend_outside(
        fig, [Line2D([], [], color=plotting.PALETTE[1], marker="o", mfc="none")], ["path chosen by A*"], where="lower"
    )
    return fig
