"""Train the neural predictors and look at what they learned: loss curves and one held-out utterance.

Fits Taylor et al.'s sliding-window network, Medina et al.'s causal MLP, a
GRU and a bidirectional GRU, and their Transformer on the bundled corpus,
then saves two figures (:mod:`dam.evaluation.figures`): training and
validation loss per epoch (early stopping keeps the best epoch, marked), and
the predictions of one test utterance against the truth, one panel per model
and channel. Needs the ``jax`` extra (``pip install "dam[jax]"``).

    python examples/neural_predictors.py [--corpus tiny|vtl] [--out DIR] [--quick]

On ``tiny`` (the default) it runs in about a minute with small settings;
``--quick`` trains two small networks for a few epochs (seconds, a smoke
test); on ``vtl`` the models keep their defaults (a few minutes each on a
CPU). Figures go to ``--out`` (default ``dam-examples/neural_predictors/`` in
the working directory, which git ignores).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import dam
from dam import plotting
from dam.evaluation.figures import plot_loss_curves, plot_predictions
from dam.evaluation.metrics import evaluate

NAME = "neural_predictors"
SMALL = {  # for the tiny corpus: small networks, more epochs
    "sliding-dnn": {"hidden_layer_sizes": (64, 64), "dropout": 0.2, "max_epochs": 60, "patience": 8},
    "causal-mlp": {"hidden_layer_sizes": (64,), "max_epochs": 60, "patience": 8},
    "gru": {"hidden_size": 32, "seq_len": 50, "max_epochs": 60, "patience": 8},
    "bi-gru": {"hidden_size": 32, "seq_len": 50, "bidirectional": True, "max_epochs": 60, "patience": 8},
    "transformer": {"d_model": 32, "d_ff": 64, "n_layers": 2, "max_epochs": 60, "patience": 8},
}
QUICK = {
    "sliding-dnn": {"hidden_layer_sizes": (16,), "max_epochs": 3},
    "causal-mlp": {"hidden_layer_sizes": (16,), "max_epochs": 3},
}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--corpus", default="tiny", help="tiny (hold-out quarter) or vtl (train/test)")
    ap.add_argument(
        "--out",
        default=str(Path.cwd() / "dam-examples" / NAME),
        help=f"output directory (default: ./dam-examples/{NAME})",
    )
    ap.add_argument(
        "--quick", action="store_true", help="two small feed-forward networks, three epochs, tiny (a smoke test)"
    )
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    corpus = "tiny" if args.quick else args.corpus
    if corpus == "tiny":
        train, test = dam.datasets.load("tiny").train_test_split(0.25, random_state=0)
        where = "tiny (held-out quarter)"
    else:
        train, test = dam.datasets.load(corpus, split="train"), dam.datasets.load(corpus, split="test")
        where = f"{corpus}:test"

    settings = QUICK if args.quick else SMALL
    models, rows = {}, []
    for label, small in settings.items():
        name = "gru" if label == "bi-gru" else label
        params = small if corpus == "tiny" else {k: v for k, v in small.items() if k == "bidirectional"}
        models[label] = dam.make(name, unknown_phone="fallback", **params).fit(train)
        rmse = evaluate(models[label], test).rmse
        rows.append({"model": label, "status": "ok", "rmse": rmse})
        print(
            f"{label:12s} held-out RMSE {rmse:.4g} ({models[label].n_epochs_} epochs, best {models[label].best_epoch_})"
        )
    rows.sort(key=lambda r: r["rmse"])

    u = test[0]
    example = {
        "utterance": u.name,
        "frame_rate": u.frame_rate,
        "channels": list(u.channels),
        "truth": u.trajectory,
        "alignment": u.alignment,
        "units": test.metadata.get("units"),
        "predictions": {label: m.predict(u.alignment) for label, m in models.items()},
    }
    paths = [
        plotting.save(plot_loss_curves(models, corpus=where), out / "loss_curves.png"),
        plotting.save(plot_predictions(example, rows, corpus=where, max_models=len(models)), out / "predictions.png"),
    ]
    print(f"wrote {paths[0]} and {paths[1]}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
