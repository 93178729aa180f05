"""Train the neural predictors and look at what they learned: loss curves and one held-out utterance.

Fits Taylor et al.'s sliding-window network, Medina et al.'s causal MLP, a
GRU and a bidirectional GRU, and their Transformer on the bundled corpus,
then saves two figures: training and validation loss per epoch (early
stopping keeps the best epoch, marked), and the predictions of one test
utterance against the truth. Needs the ``jax`` extra.

    python examples/neural_predictors.py [--corpus tiny|vtl] [--out examples/out/neural]

On ``tiny`` (the default) it runs in about a minute with small settings; on
``vtl`` the models keep their defaults (a few minutes each on a CPU).
"""
from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import dam  # noqa: E402
from dam.evaluation.metrics import evaluate  # noqa: E402

SMALL = {  # for the tiny corpus: small networks, more epochs
    "sliding-dnn": {"hidden_layer_sizes": (64, 64), "dropout": 0.2, "max_epochs": 60, "patience": 8},
    "causal-mlp": {"hidden_layer_sizes": (64,), "max_epochs": 60, "patience": 8},
    "gru": {"hidden_size": 32, "seq_len": 50, "max_epochs": 60, "patience": 8},
    "bi-gru": {"hidden_size": 32, "seq_len": 50, "bidirectional": True, "max_epochs": 60, "patience": 8},
    "transformer": {"d_model": 32, "d_ff": 64, "n_layers": 2, "max_epochs": 60, "patience": 8},
}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--corpus", default="tiny", help="tiny (hold-out quarter) or vtl (train/test)")
    ap.add_argument("--out", default=str(Path(__file__).parent / "out" / "neural"))
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if args.corpus == "tiny":
        train, test = dam.datasets.load("tiny").train_test_split(0.25, random_state=0)
    else:
        train, test = dam.datasets.load(args.corpus, split="train"), dam.datasets.load(args.corpus, split="test")

    models = {}
    for label, small in SMALL.items():
        name = "gru" if label == "bi-gru" else label
        params = small if args.corpus == "tiny" else {k: v for k, v in small.items() if k == "bidirectional"}
        models[label] = dam.make(name, unknown_phone="fallback", **params).fit(train)
        print(f"{label:12s} held-out RMSE {evaluate(models[label], test).rmse:.4g} "
              f"({models[label].n_epochs_} epochs, best {models[label].best_epoch_})")

    fig, axes = plt.subplots(1, len(models), figsize=(3.2 * len(models), 3), sharey=True)
    for ax, (label, m) in zip(axes, models.items()):
        epochs = np.arange(1, m.n_epochs_ + 1)
        ax.semilogy(epochs, m.loss_curve_, label="training (dropout on)")
        ax.semilogy(epochs, m.validation_curve_, label="validation")
        ax.axvline(m.best_epoch_, color="k", lw=0.8, ls=":", label="kept")
        ax.set_title(label)
        ax.set_xlabel("epoch")
    axes[0].set_ylabel("MSE (standardized channels)")
    axes[0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out / "loss_curves.png", dpi=120)

    u = test[0]
    t = np.arange(u.n_frames) / u.frame_rate
    n_ch = min(4, u.n_channels)
    fig, axes = plt.subplots(n_ch, 1, figsize=(8, 1.8 * n_ch), sharex=True)
    for c, ax in enumerate(np.atleast_1d(axes)):
        ax.plot(t, u.trajectory[:, c], "k", lw=2, label="truth")
        for label, m in models.items():
            ax.plot(t, m.predict(u.alignment)[:, c], lw=1, label=label)
        ax.set_ylabel(u.channels[c])
    np.atleast_1d(axes)[0].legend(fontsize=7, ncol=3)
    np.atleast_1d(axes)[-1].set_xlabel("time (s)")
    fig.tight_layout()
    fig.savefig(out / "predictions.png", dpi=120)
    print(f"wrote {out / 'loss_curves.png'} and {out / 'predictions.png'}")


if __name__ == "__main__":
    main()
