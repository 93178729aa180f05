"""The figures of docs/models.rst: every registered model on one held-out utterance of ``tiny``.

    python docs/make_model_figures.py            # the missing figures
    python docs/make_model_figures.py --all      # all of them again
    python docs/make_model_figures.py dam mmm    # just these

Each model is fitted with its default parameters on the ``tiny`` training split (24 of 30
utterances, ``train_test_split(0.2, random_state=0)``) and drawn on the first test utterance,
channel ``lip_protrusion``, against the recording; the held-out RMSE of the whole test split is in
the title. Models that read audio are fitted on the ``vtl`` training phrases that have audio
(channels JA LP TTY TBY) and drawn on the first such test phrase, channel TTY. Figures are small
PNGs in docs/models/ (committed: building the docs fits nothing).
Neural models need ``dam[jax]`` and take a minute or two each on a laptop.
"""

from __future__ import annotations

import sys
import time
import warnings
from pathlib import Path

HERE = Path(__file__).resolve().parent
OUT = HERE / "models"
CHANNEL = "lip_protrusion"


def figure_path(name: str) -> Path:
    return OUT / f"{name}.png"


def audio_data():
    """For models that read audio: the vtl phrases that have audio (4 channels), TTY drawn."""
    import dam

    channels = ["JA", "LP", "TTY", "TBY"]
    train = dam.datasets.load("vtl", "train").select_channels(channels)
    test = dam.datasets.load("vtl", "test").select_channels(channels)
    tr = train.subset([i for i, u in enumerate(train) if u.audio])
    te = test.subset([i for i, u in enumerate(test) if u.audio])
    return tr, te, te[0], "TTY", "vtl (phrases with audio)", train.metadata


def main(argv=None) -> int:
    import dam
    from dam import plotting
    from dam.evaluation.textbook import plot_sequence

    argv = sys.argv[1:] if argv is None else argv
    names = [a for a in argv if not a.startswith("-")] or dam.registry.names()
    corpus = dam.datasets.load("tiny")
    train, test = corpus.train_test_split(0.2, random_state=0)
    u = test[0]
    OUT.mkdir(exist_ok=True)
    for name in names:
        path = figure_path(name)
        if path.exists() and "--all" not in argv and not [a for a in argv if not a.startswith("-")]:
            continue
        t0 = time.perf_counter()
        data = (train, test, u, CHANNEL, "tiny", corpus.metadata)
        if "audio" in dam.registry.get(name).get_tags().get("reads", ()):
            data = audio_data()
        tr, te, utt, channel, where, meta = data
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            model = dam.make(name).fit(tr)
        rmse = float(dam.evaluate(model, te).rmse)
        fig = plot_sequence(
            {name: model},
            utt,
            [channel],
            truth=utt.trajectory,
            metadata=meta,
            title=f"{name} on held-out {where} utterance {utt.name} (test RMSE {rmse:.3f})",
            panel_size=(5.6, 1.5),
            legend="lower",
        )
        plotting.save(fig, path, dpi=64)
        print(f"{name}: fitted in {time.perf_counter() - t0:.1f} s, RMSE {rmse:.4f} -> {path.name}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
