"""What a Dominated Animeme Model learned, in four figures.

Fits a DAM (Chen et al. 2012) on the training part of a bundled corpus and,
for one held-out utterance, plots

1. ``dam_dominance.png``: every segment's dominance function ``D_j`` (Eq. 1)
   and its dominated animeme ``D_j A_j`` on the time axis, their sum (Eq. 2)
   and the measured trajectory, for one channel;
2. ``dam_animemes.png``: the animeme ``A(t)`` of every mode of a few phones,
   inside [0, 1] and a little beyond (where the dominance still reaches);
3. ``dam_modes.png``: what mode clustering saw: the mean resampled training
   occurrence of each mode of those phones;
4. ``dam_astar.png``: the animeme graph of the utterance (one column per
   segment, one node per mode, coloured by ``w_c E_c``) and the path A* chose.

    python examples/dam_inspect.py [--corpus tiny] [--channel 0] [--out examples/out]
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import dam  # noqa: E402
from dam.model.estimator import DAM  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--corpus", default="tiny", help="bundled corpus name or corpus directory")
    ap.add_argument("--channel", type=int, default=0)
    ap.add_argument("--utterance", type=int, default=0, help="index in the held-out part")
    ap.add_argument("--out", default=str(Path(__file__).parent / "out"))
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    corpus = dam.datasets.resolve(args.corpus)
    train, test = corpus.train_test_split(0.25, random_state=0)
    model = DAM(verbose=1).fit(train)
    utt = test[args.utterance]
    a, c = utt.alignment, args.channel
    ch = model.channels_[c]
    print(f"fitted {model!r} on {train!r}; inspecting {utt.name!r}, channel {ch!r}")

    # 1. dominance functions and dominated animemes on the time axis
    rows = model.explain(a)
    fr = model.frame_rate_
    t = np.arange(utt.n_frames) / fr
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(11, 6), sharex=True)
    total = np.zeros_like(t)
    for j, r in enumerate(rows):
        d = a.ends[j] - a.starts[j]
        tl = (t - a.starts[j]) / d
        D = model.dominance_curve(r["phone"], r["mode"], tl)[:, c]
        A = model.animeme_curve(r["phone"], r["mode"], tl)[:, c]
        line, = ax1.plot(t, D, lw=1)
        ax2.plot(t, D * A, lw=0.8, color=line.get_color(), alpha=0.7)
        total += D * A if not model.normalize else 0
        ax1.text(0.5 * (a.starts[j] + a.ends[j]), 1.03, f"{r['phone']}{r['mode'] if r['n_modes'] > 1 else ''}",
                 ha="center", fontsize=7)
    pred = model.predict(a)[:, c]
    ax2.plot(t, utt.trajectory[:, c], "k", lw=2, label="measured")
    ax2.plot(t, pred, "r--", lw=1.5, label="DAM (Eq. 2)")
    for s in a.starts:
        ax1.axvline(s, color="0.85", lw=0.5)
        ax2.axvline(s, color="0.85", lw=0.5)
    ax1.set_ylabel("dominance D_j")
    ax1.set_ylim(0, 1.12)
    ax2.set_ylabel(f"{ch}: D_j A_j, sum")
    ax2.set_xlabel("time (s)")
    ax2.legend(loc="upper right", fontsize=8)
    fig.suptitle(f"Dominance and dominated animemes, {utt.name}")
    fig.tight_layout()
    fig.savefig(out / "dam_dominance.png", dpi=120)
    plt.close(fig)

    # 2. animemes of the modes of the most frequent multi-mode phones; 3. their mode shapes
    phones = sorted(model.phone_modes_, key=lambda p: (-model.phone_modes_[p][1], -model.phone_counts_[p]))[:4]
    tt = np.linspace(-0.5, 1.5, 201)
    fig, axes = plt.subplots(1, len(phones), figsize=(3.2 * len(phones), 3), sharey=True)
    fig2, axes2 = plt.subplots(1, len(phones), figsize=(3.2 * len(phones), 3), sharey=True)
    for ax, ax2_, p in zip(np.atleast_1d(axes), np.atleast_1d(axes2), phones):
        info = model.modes_of(p)
        for g in range(info["n_modes"]):
            lab = f"mode {g} (n={int(info['counts'][g])}, sigma={info['sigma'][g, c]:.2f})"
            ax.plot(tt, model.animeme_curve(p, g, tt)[:, c], label=lab)
            shape = model.mode_shapes_[model.phone_modes_[p][0] + g][:, c]
            ax2_.plot(np.linspace(0, 1, len(shape)), shape, marker=".", label=f"mode {g}")
        ax.axvspan(0, 1, color="0.93")
        ax.set_title(f"/{p}/", fontsize=10)
        ax.set_xlabel("local time t")
        ax.legend(fontsize=6)
        ax2_.set_title(f"/{p}/ training occurrences, mode means", fontsize=9)
        ax2_.set_xlabel("local time t")
        ax2_.legend(fontsize=6)
    np.atleast_1d(axes)[0].set_ylabel(f"A(t), {ch}")
    np.atleast_1d(axes2)[0].set_ylabel(ch)
    fig.tight_layout()
    fig.savefig(out / "dam_animemes.png", dpi=120)
    fig2.tight_layout()
    fig2.savefig(out / "dam_modes.png", dpi=120)
    plt.close(fig)
    plt.close(fig2)

    # 4. the animeme graph and the A* path
    labels = [r["phone"] for r in rows]
    nodes, _, _ = model._graph(labels, a.durations)
    fig, ax = plt.subplots(figsize=(max(6, 0.45 * len(rows)), 3.5))
    finite = nodes[np.isfinite(nodes)]
    vmax = max(float(finite.max()), 1.0)
    for j, r in enumerate(rows):
        for g in range(r["n_modes"]):
            ax.scatter(j, g, s=120, c=[nodes[j, g]], cmap="viridis", vmin=0, vmax=vmax,
                       edgecolors="r" if g == r["mode"] else "none", linewidths=2)
        if j:
            ax.plot([j - 1, j], [rows[j - 1]["mode"], r["mode"]], "r-", lw=1.5, zorder=0)
    ax.set_yticks(range(nodes.shape[1]))
    ax.set_xticks(range(len(rows)))
    ax.set_xticklabels(labels, fontsize=8)
    ax.set_ylabel("mode")
    ax.set_title(f"Animeme graph and A* path (node colour: w_c E_c, max {vmax:.0f}); "
                 f"total cost {rows[-1]['total']:.1f}", fontsize=9)
    fig.tight_layout()
    fig.savefig(out / "dam_astar.png", dpi=120)
    plt.close(fig)
    err = np.sqrt(np.mean((model.predict(a) - utt.trajectory) ** 2))
    print(f"RMSE on {utt.name}: {err:.4g}; figures in {out}/dam_*.png")


if __name__ == "__main__":
    main()
