"""What a Dominated Animeme Model learned, in four figures.

Fits a DAM (Chen et al. 2012) on the training part of a bundled corpus and,
for one held-out utterance, saves (figure functions: :mod:`dam.model.figures`)

1. ``dam_dominance.png``: every segment's dominance function ``D_j`` (Eq. 1)
   and its dominated animeme ``D_j A_j`` on the time axis, their combination
   (Eq. 2) and the measured trajectory, for one channel, phones underneath;
2. ``dam_animemes.png``: the animeme ``A(t)`` of every mode of a few phones,
   inside [0, 1] and a little beyond (where the dominance still reaches);
3. ``dam_modes.png``: what mode clustering saw: the mean resampled training
   occurrence of each mode of those phones (modes are labelled ``iy/mode 1``);
4. ``dam_astar.png``: the animeme graph of the utterance (one column per
   segment, one node per mode, coloured by ``w_c E_c``) and the path A* chose.

    python examples/dam_inspect.py [--corpus tiny] [--channel 0] [--out DIR] [--quick]

Figures go to ``--out`` (default ``dam-examples/dam_inspect/`` in the working
directory, which git ignores). About 10 s on ``tiny``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import dam
from dam import plotting
from dam.model.figures import inspected_phones, plot_animemes, plot_astar, plot_dominance, plot_modes

NAME = "dam_inspect"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--corpus", default="tiny", help="bundled corpus name or corpus directory (default: tiny)")
    ap.add_argument("--channel", type=int, default=0, help="channel index to draw (default 0)")
    ap.add_argument("--utterance", type=int, default=0, help="index in the held-out part")
    ap.add_argument(
        "--out",
        default=str(Path.cwd() / "dam-examples" / NAME),
        help=f"output directory (default: ./dam-examples/{NAME})",
    )
    ap.add_argument("--quick", action="store_true", help="the tiny corpus and a short EM (a smoke test)")
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    corpus = dam.datasets.resolve("tiny" if args.quick else args.corpus)
    train, test = corpus.train_test_split(0.25, random_state=0)
    model = dam.make("dam", max_iter=5 if args.quick else 50).fit(train)
    utt = test[args.utterance]
    c = args.channel
    where = corpus.name or str(args.corpus)
    print(f"fitted {model!r} on {train!r}; inspecting {utt.name!r}, channel {model.channels_[c]!r}")

    phones = inspected_phones(model)
    meta = corpus.metadata
    paths = [
        plotting.save(plot_dominance(model, utt, c, corpus=where, metadata=meta), out / "dam_dominance.png"),
        plotting.save(plot_animemes(model, phones, c, corpus=where, metadata=meta), out / "dam_animemes.png"),
        plotting.save(plot_modes(model, phones, c, corpus=where, metadata=meta), out / "dam_modes.png"),
        plotting.save(plot_astar(model, utt.alignment, name=f"{utt.name} of {where}"), out / "dam_astar.png"),
    ]
    err = np.sqrt(np.mean((model.predict(utt.alignment) - utt.trajectory) ** 2))
    print(f"RMSE on {utt.name}: {err:.4g}; figures: {', '.join(str(p) for p in paths)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
