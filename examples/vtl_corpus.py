"""The bundled VocalTractLab corpus: what is in it, and one utterance drawn.

Loads the ``vtl`` corpus (German phrases articulated by VocalTractLab, 19
tract parameters at 100 Hz), prints its description and size, and plots four
articulators of one utterance over its phone alignment: lip distance (the
lips close for /p b m/), jaw angle, tongue-tip height (up for /t d n l s/)
and velum opening (open for nasals). Coarticulation shows as movements that
start before their phone and carry over into the next.

    python examples/vtl_corpus.py [--out DIR] [--utterance NAME] [--quick]

The figure goes to ``--out``/vtl_corpus.png (default ``dam-examples/vtl_corpus/``
in the working directory, which git ignores). A few seconds; ``--quick`` is
accepted for symmetry with the other examples.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import dam
from dam import plotting

NAME = "vtl_corpus"
#: channel -> what it is (the unit comes from the corpus metadata)
CHANNELS = {"LD": "lip distance", "JA": "jaw angle", "TTY": "tongue tip height", "VO": "velum opening"}


def plot_utterance(utt, metadata=None, channels=CHANNELS, *, title: str):
    """``channels`` of ``utt`` in stacked panels over its phones (small multiples, one per channel)."""
    fig, axes, _ = plotting.time_grid(len(channels), 1, utt.alignment, title=title, panel_size=(10.0, 1.3))
    t = np.arange(utt.n_frames) / utt.frame_rate
    for ax, (name, what) in zip(axes[:, 0], channels.items()):
        ax.plot(t, utt.trajectory[:, utt.channels.index(name)], color=plotting.TRUTH, lw=1.5)
        ax.set_ylabel(f"{what}\n{plotting.channel_label(name, metadata)}", fontsize=8)
    return fig


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument(
        "--out",
        default=str(Path.cwd() / "dam-examples" / NAME),
        help=f"output directory (default: ./dam-examples/{NAME})",
    )
    ap.add_argument("--utterance", help="name of a training utterance (default: the first)")
    ap.add_argument("--quick", action="store_true", help="(the example is quick already)")
    args = ap.parse_args(argv)
    train = dam.datasets.load("vtl", "train")
    test = dam.datasets.load("vtl", "test")
    print(dam.datasets.describe("vtl"))
    print(f"\ntrain: {train!r}\ntest:  {test!r}")
    utt = train[args.utterance] if args.utterance else train[0]
    words = " ".join(train.metadata["utterances"][utt.name]["words"])
    print(f"\nplotting {utt!r}: {words}")
    fig = plot_utterance(
        utt,
        train.metadata,
        title=f"VocalTractLab corpus vtl:train, utterance {utt.name} "
        f"(\u201c{words}\u201d): four articulators over the phones",
    )
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    path = plotting.save(fig, out / "vtl_corpus.png")
    print(f"saved {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
