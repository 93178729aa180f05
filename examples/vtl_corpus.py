"""The bundled VocalTractLab corpus: what is in it, and one utterance drawn.

Loads the ``vtl`` corpus (German phrases articulated by VocalTractLab, 19
tract parameters at 100 Hz), prints its description and size, and plots four
articulators of one utterance under its phone alignment: lip distance (the
lips close for /p b m/), jaw angle, tongue-tip height (up for /t d n l s/)
and velum opening (open for nasals). Coarticulation shows as movements that
start before their phone and carry over into the next.

Run::

    python examples/vtl_corpus.py [OUT_DIR] [UTTERANCE]

The figure goes to ``OUT_DIR/vtl_corpus.png`` (default ``examples/out``).
"""
import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import dam  # noqa: E402

CHANNELS = {
    "LD": "lip distance (cm)",
    "JA": "jaw angle (deg)",
    "TTY": "tongue tip height (cm)",
    "VO": "velum opening",
}


def plot_utterance(utt, channels=CHANNELS, ax=None):
    """Draw ``channels`` of ``utt`` stacked, with phone boundaries and labels."""
    if ax is None:
        _, ax = plt.subplots(len(channels), 1, sharex=True, figsize=(11, 1.9 * len(channels)))
    t = np.arange(utt.n_frames) / utt.frame_rate
    a = utt.alignment
    for k, (axis, (name, label)) in enumerate(zip(ax, channels.items())):
        axis.plot(t, utt.trajectory[:, utt.channels.index(name)], color="C0", lw=1.6)
        axis.set_ylabel(label, fontsize=8)
        for s in a.starts[1:]:
            axis.axvline(s, color="0.8", lw=0.6, zorder=0)
        if k == 0:
            top = axis.get_ylim()[1]
            for lab, s, e in zip(a.labels, a.starts, a.ends):
                axis.text(0.5 * (s + e), top, lab, ha="center", va="bottom", fontsize=8)
    ax[-1].set_xlabel("time (s)")
    return ax


def main(out_dir="examples/out", name=None):
    train = dam.datasets.load("vtl", "train")
    test = dam.datasets.load("vtl", "test")
    print(dam.datasets.describe("vtl"))
    print(f"\ntrain: {train!r}\ntest:  {test!r}")
    utt = train[name] if name else train[0]
    words = train.metadata["utterances"][utt.name]["words"]
    print(f"\nplotting {utt!r}: {' '.join(words)}")
    ax = plot_utterance(utt)
    ax[0].set_title(f"{utt.name}: {' '.join(words)}", pad=16)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    path = out / "vtl_corpus.png"
    plt.tight_layout()
    plt.savefig(path, dpi=120)
    print(f"saved {path}")
    return path


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out_dir", nargs="?", default="examples/out", help="where the figure goes (default: examples/out)")
    ap.add_argument("utterance", nargs="?", help="name of a training utterance (default: the first)")
    args = ap.parse_args()
    main(args.out_dir, args.utterance)
