"""The one figure style of dam: every figure the toolkit draws goes through here.

Rules every figure follows (issue 13): a title that says what is shown and on
which data; units on every axis (a corpus keeps its channels' units in its
metadata, ``corpus.json``: ``"units": {"JA": "deg", "LD": "cm", ...}``); phone
boundaries and labels under every time axis; legends outside the data; small
multiples (one panel per channel or per model) instead of many overlapping
lines; the colour-blind-safe Okabe–Ito palette, the truth always black.

matplotlib is imported only when a figure is drawn (``import dam`` stays light).

Examples
--------
>>> from dam import plotting
>>> plotting.channel_label("JA", {"units": {"JA": "deg"}})
'JA (deg)'
"""

from __future__ import annotations

import os

__all__ = [
    "PALETTE",
    "TRUTH",
    "pyplot",
    "channel_unit",
    "channel_label",
    "figure",
    "time_grid",
    "phone_tier",
    "phone_boundaries",
    "legend_outside",
    "save",
    "model_color",
    "check_figure",
]

#: Okabe & Ito (2008) colour-blind-safe palette, black left out (it is the truth's colour).
PALETTE = ("#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#F0E442", "#999999")
#: The measured trajectory is always drawn in this colour.
TRUTH = "#000000"

STYLE = {
    "axes.prop_cycle": None,  # filled in by pyplot() (needs matplotlib's cycler)
    "axes.spines.top": False,
    "axes.spines.right": False,
    "axes.titlesize": 10,
    "axes.labelsize": 9,
    "xtick.labelsize": 8,
    "ytick.labelsize": 8,
    "legend.fontsize": 8,
    "legend.frameon": False,
    "figure.titlesize": 12,
    "figure.dpi": 100,
    "savefig.dpi": 120,
    "lines.linewidth": 1.4,
}


def pyplot():
    """``matplotlib.pyplot`` with dam's style; a non-interactive backend when none was chosen."""
    import matplotlib

    if matplotlib.get_backend().lower() not in (
        "agg",
        "pdf",
        "svg",
        "ps",
        "cairo",
        "module://matplotlib_inline.backend_inline",
    ):
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from cycler import cycler

    matplotlib.rcParams.update({**STYLE, "axes.prop_cycle": cycler(color=list(PALETTE))})
    return plt


def model_color(i: int) -> str:
    """The colour of the ``i``-th model of a figure (stable across a figure's panels)."""
    return PALETTE[i % len(PALETTE)]


# -- units -----------------------------------------------------------------
def channel_unit(channel: str, metadata=None) -> str | None:
    """The unit of ``channel`` from corpus metadata (``units``: a dict per channel, or one string
    for all; ``length_unit`` as a fallback), ``""`` for a dimensionless channel, None if unknown."""
    meta = metadata or {}
    units = meta.get("units")
    if isinstance(units, dict) and channel in units:
        return units[channel]
    if isinstance(units, str):
        return units
    return meta.get("length_unit")


def channel_label(channel: str, metadata=None, *, what: str = "", wrap: bool = False) -> str:
    """Axis label ``"JA (deg)"``; ``"VS (no unit)"`` for a dimensionless channel and
    ``"x (channel units)"`` when the corpus does not say; ``wrap`` puts the unit on a second line."""
    unit = channel_unit(channel, metadata)
    unit = "channel units" if unit is None else (unit or "no unit")
    return f"{what + ' ' if what else ''}{channel}{chr(10) if wrap else ' '}({unit})"


# -- figures ---------------------------------------------------------------
def figure(nrows: int = 1, ncols: int = 1, *, title: str, panel_size=(3.2, 2.2), **kw):
    """A figure of ``nrows x ncols`` panels with a title (required) and constrained layout.

    Returns
    -------
    fig, axes : Figure, ndarray of Axes, shape (nrows, ncols)
    """
    if not title:
        raise ValueError("every figure needs a title saying what it shows and on which data")
    plt = pyplot()
    fig, axes = plt.subplots(
        nrows,
        ncols,
        figsize=(panel_size[0] * ncols + 1.5, panel_size[1] * nrows + 0.8),
        squeeze=False,
        layout="constrained",
        **kw,
    )
    fig.suptitle(title)
    return fig, axes


def time_grid(nrows: int, ncols: int, alignments, *, title: str, panel_size=(4.0, 1.5)):
    """Small multiples over time: ``nrows x ncols`` data panels and, under each column, a phone tier.

    Parameters
    ----------
    nrows, ncols : int
    alignments : Alignment or list of Alignment (one per column)
        The phones drawn under each column (and as boundaries on its panels).
    title : str

    Returns
    -------
    fig : Figure
    axes : ndarray of Axes, shape (nrows, ncols)
        Sharing the time axis within a column; boundaries already drawn.
    tiers : list of Axes, one per column
        The phone tiers, x label "time (s)".
    """
    if not title:
        raise ValueError("every figure needs a title saying what it shows and on which data")
    if not isinstance(alignments, (list, tuple)):
        alignments = [alignments] * ncols
    plt = pyplot()
    fig = plt.figure(figsize=(panel_size[0] * ncols + 1.8, panel_size[1] * nrows + 1.3), layout="constrained")
    gs = fig.add_gridspec(nrows + 1, ncols, height_ratios=[1.0] * nrows + [0.32])
    axes = [[None] * ncols for _ in range(nrows)]
    tiers = []
    for j in range(ncols):
        tier = fig.add_subplot(gs[nrows, j])
        for i in range(nrows):
            axes[i][j] = fig.add_subplot(gs[i, j], sharex=tier)
            axes[i][j].tick_params(labelbottom=False)
            phone_boundaries(axes[i][j], alignments[j])
        phone_tier(tier, alignments[j], name=j == 0)
        tiers.append(tier)
    fig.suptitle(title)
    import numpy as np

    return fig, np.array(axes, dtype=object), tiers


def phone_boundaries(ax, alignment) -> None:
    """Thin grey lines at the phone boundaries of ``alignment`` on a data panel."""
    for s in alignment.starts[1:]:
        ax.axvline(float(s), color="0.82", lw=0.6, zorder=0)


def phone_tier(ax, alignment, *, xlabel: str = "time (s)", name: bool = True) -> None:
    """Draw ``alignment`` as a Praat-like tier on ``ax``: boundaries and a label per phone.

    Labels of short segments alternate between two heights so neighbours do not collide.
    """
    ax.set_ylim(0, 1)
    ax.set_yticks([])
    for side in ("left", "right", "top"):
        ax.spines[side].set_visible(False)
    ends = alignment.ends
    width = float(ends[-1] - alignment.starts[0]) or 1.0
    for k, (lab, s, e) in enumerate(zip(alignment.labels, alignment.starts, ends)):
        ax.axvline(float(s), color="0.55", lw=0.6)
        short = (e - s) / width < 0.035
        y = (0.72 if k % 2 else 0.28) if short else 0.5
        ax.text(0.5 * (s + e), y, str(lab), ha="center", va="center", fontsize=7 if short else 8, clip_on=True)
    ax.axvline(float(ends[-1]), color="0.55", lw=0.6)
    ax.set_xlim(float(alignment.starts[0]), float(ends[-1]))
    if name:
        ax.set_ylabel("phones", rotation=0, ha="right", va="center", fontsize=8)
    ax.set_xlabel(xlabel)


def legend_outside(fig, handles, labels, *, title: str | None = None, where: str = "right") -> None:
    """One legend for the whole figure, outside every panel (``where``: "right" or "lower")."""
    loc = "outside right upper" if where == "right" else "outside lower center"
    fig.legend(handles, labels, loc=loc, title=title, ncols=1 if where == "right" else min(len(labels), 5))


def save(fig, path, *, dpi: int = 120) -> str:
    """Save ``fig`` to ``path`` atomically (a complete file or none) and close it; return the path."""
    from dam.corpus.atomic import atomic_path

    plt = pyplot()
    path = os.fspath(path)
    fmt = os.path.splitext(path)[1].lstrip(".") or "png"
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi, format=fmt, bbox_inches="tight")  # legends outside stay in the file
    plt.close(fig)
    return path


def check_figure(fig) -> list[str]:
    """What in ``fig`` breaks the style rules; an empty list when nothing does.

    Checks: a title (the figure's, or the only panel's); an x label on every panel that shows
    x tick labels and a y label on every panel that shows y ticks (panels drawn with the axis
    off, such as outline drawings, are exempt); every legend outside every panel; every line in
    the palette, black or a grey.
    """
    from matplotlib.colors import to_rgb

    fig.canvas.draw()
    problems = []
    panels = [ax for ax in fig.axes if ax.get_visible() and ax.axison]
    title = fig._suptitle.get_text() if fig._suptitle is not None else ""
    if not title and not (len(panels) == 1 and panels[0].get_title()):
        problems.append("no title")
    allowed = {to_rgb(c) for c in PALETTE} | {to_rgb(TRUTH)}
    for k, ax in enumerate(panels):
        if getattr(ax, "_colorbar", None) is not None or ax.get_label() == "<colorbar>":
            continue
        name = ax.get_title() or f"panel {k}"
        shows_x = any(t.get_visible() and t.get_text() for t in ax.get_xticklabels())
        if shows_x and not ax.get_xlabel():
            problems.append(f"{name}: no x label")
        shows_y = any(t.get_visible() and t.get_text().strip() for t in ax.get_yticklabels())
        if shows_y and not ax.get_ylabel():
            problems.append(f"{name}: no y label")
        for line in ax.get_lines():
            rgb = to_rgb(line.get_color())
            if rgb not in allowed and not (abs(rgb[0] - rgb[1]) < 1e-6 and abs(rgb[1] - rgb[2]) < 1e-6):
                problems.append(f"{name}: line colour {line.get_color()} outside the palette")
    renderer = fig.canvas.get_renderer()
    legends = list(fig.legends) + [ax.get_legend() for ax in panels if ax.get_legend() is not None]
    for leg in legends:
        box = leg.get_window_extent(renderer)
        for ax in panels:
            if ax.get_label() == "<colorbar>":
                continue
            if box.overlaps(ax.get_window_extent(renderer)):
                problems.append(f"a legend covers panel {ax.get_title() or fig.axes.index(ax)}")
                break
    return problems
