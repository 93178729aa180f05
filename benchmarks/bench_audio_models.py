"""Audio-driven models beside phone-driven ones on the bundled vtl corpus (issue 15).

Writes ``benchmarks/results/audio_models.json`` and ``audio_models.md``:

* held-out RMSE and Pearson r (:func:`dam.evaluation.compare.compare`, one
  table) of phone-driven rows (phone-mean, the DAM, the GRU on phones) and
  audio-driven rows (the Medina et al. decoders on MFCC: causal MLP, GRU,
  Transformer; VisemeNet on MFCC + filterbank + subband centroids), all
  trained on the vtl ``train`` utterances that have audio and scored on the
  ``test`` utterances that have audio (``compare`` keeps those for every row);
* VisemeNet's activation precision and recall (Zhou et al.'s Table 1 measures)
  and its phone-group accuracy on the same test utterances;
* inference milliseconds per second of audio of untrained networks in Medina
  et al.'s configurations (MLP 15:5 with 512 units; GRU-2L and Bi-GRU-5L with
  256 units), decoder only (MFCC precomputed and cached) and the MFCC
  extraction alone, beside the paper's Table 2 (their GPU): MLP 0.232 ms,
  GRU-2L 2.193 ms, Bi-GRU-5L 10.955 ms.

CPU is scarce on the machine this ran on: the neural rows train a few epochs
with small networks on a subset of the channels (``--channels``); the .md
says so.

    python benchmarks/bench_audio_models.py [--epochs 15] [--channels JA,LD,LP,TTY,TBY,TCY]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import machine  # noqa: E402

import dam  # noqa: E402
from dam.corpus.atomic import atomic_write  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results"
#: Medina et al. (2022), Table 2: inference ms per second of audio on their GPU.
PAPER_MS = {"MLP 15:5": 0.232, "GRU-2L": 2.193, "Bi-GRU-5L": 10.955}


def with_audio(corpus):
    return corpus.subset([i for i, u in enumerate(corpus) if u.audio is not None])


def model_rows(epochs: int) -> list:
    nn = {"max_epochs": epochs, "verbose": 0}
    return [
        "phone-mean",
        "dam",
        ("gru (phones)", "gru", {"n_layers": 2, "hidden_size": 32, **nn}),
        ("causal-mlp (mfcc)", "causal-mlp", {"encoder": "mfcc", "hidden_layer_sizes": (128,), **nn}),
        ("gru (mfcc)", "gru", {"encoder": "mfcc", "n_layers": 2, "hidden_size": 32, **nn}),
        (
            "transformer (mfcc)",
            "transformer",
            {"encoder": "mfcc", "n_layers": 2, "d_model": 32, "d_ff": 64, "n_heads": 4, **nn},
        ),
        ("visemenet", "visemenet", {"hidden_size": 32, "n_layers": 2, "fc_size": 32, "pretrain_epochs": 5, **nn}),
    ]


def inference_ms(train, test) -> dict:
    """ms per second of audio: untrained networks in the paper's configurations (weights do not change the cost)."""
    from baselines.nn.acoustic import mfcc

    small = train.subset(range(min(4, len(train))))
    configs = {
        "MLP 15:5": ("causal-mlp", {"kx": 15, "ky": 5, "hidden_layer_sizes": (512,)}),
        "GRU-2L": ("gru", {"n_layers": 2, "hidden_size": 256}),
        "Bi-GRU-5L": ("gru", {"n_layers": 5, "hidden_size": 256, "bidirectional": True}),
    }
    seconds = sum(u.duration for u in test)
    out = {}
    for label, (name, params) in configs.items():
        m = dam.registry.make(name, encoder="mfcc", max_epochs=0, verbose=0, **params).fit(small)
        m.predict(list(test))  # compile, and cache the features
        times = []
        for _ in range(3):
            t0 = time.perf_counter()
            m.predict(list(test))
            times.append(time.perf_counter() - t0)
        out[label] = {
            "ms_per_audio_second": 1000 * float(np.median(times)) / seconds,
            "n_parameters": m.n_parameters_,
            "paper_ms": PAPER_MS[label],
        }
    from dam.speech import load_audio

    x = np.concatenate([load_audio(u.audio)[0] for u in test])
    t0 = time.perf_counter()
    mfcc(x, 16000, frame_rate=100.0)
    out["MFCC extraction"] = {"ms_per_audio_second": 1000 * (time.perf_counter() - t0) / (len(x) / 16000)}
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--epochs", type=int, default=15)
    ap.add_argument("--channels", default="JA,LD,LP,TTY,TBY,TCY")
    args = ap.parse_args(argv)
    from dam.evaluation.compare import compare
    from dam.evaluation.metrics import evaluate

    channels = args.channels.split(",")
    full_train, full_test = (dam.datasets.load("vtl", split=s) for s in ("train", "test"))
    train, test = (with_audio(c).select_channels(channels) for c in (full_train, full_test))
    t0 = time.time()
    res = compare(model_rows(args.epochs), train, test, n_jobs=1)
    rows = [
        {
            k: r[k]
            for k in (
                "model",
                "rmse",
                "rmse_ci_low",
                "rmse_ci_high",
                "pearson_r",
                "fit_seconds",
                "frames_per_second",
                "status",
                "reason",
            )
        }
        for r in res.summary
    ]
    for r in rows:
        r["reads"] = "audio" if "(mfcc)" in r["model"] or r["model"] == "visemenet" else "phones"
    vis = dam.registry.make("visemenet", **model_rows(args.epochs)[-1][2]).fit(train)
    scores = vis.activation_scores(test)
    vis_eval = evaluate(vis, test)
    result = {
        "machine": machine(),
        "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
        "corpus": {
            "train": f"{len(train)} of {len(full_train)} vtl train utterances have audio "
            f"({sum(u.duration for u in train) / 60:.1f} min)",
            "test": f"{len(test)} of {len(full_test)} vtl test utterances have audio "
            f"({sum(u.duration for u in test) / 60:.1f} min)",
            "channels": channels,
        },
        "epochs": args.epochs,
        "rows": rows,
        "visemenet": {
            "activation_precision": scores["precision"],
            "activation_recall": scores["recall"],
            "phone_group_accuracy": scores["phone_group_accuracy"],
            "rmse": vis_eval.rmse,
            "thresholds": dict(zip(vis.channels_, map(float, vis.thresholds_))),
        },
        "inference": inference_ms(train, test),
        "seconds": time.time() - t0,
    }
    RESULTS.mkdir(exist_ok=True)
    with atomic_write(RESULTS / "audio_models.json", "w", encoding="utf-8") as fh:
        json.dump(result, fh, indent=1, default=float)
    with atomic_write(RESULTS / "audio_models.md", "w", encoding="utf-8") as fh:
        fh.write(markdown(result))
    print(markdown(result))
    return 0


def _f(x, fmt="{:.4f}"):
    return "" if x is None or (isinstance(x, float) and not np.isfinite(x)) else fmt.format(x)


def markdown(r) -> str:
    lines = ["| model | reads | held-out RMSE | 95% CI | Pearson r | fit (s) |", "|---|---|---:|---:|---:|---:|"]
    for row in r["rows"]:
        if row["status"] != "ok":
            lines.append(f"| {row['model']} | {row['reads']} | {row['status']}: {row['reason']} | | | |")
            continue
        lines.append(
            f"| {row['model']} | {row['reads']} | {_f(row['rmse'])} | {_f(row['rmse_ci_low'])}-"
            f"{_f(row['rmse_ci_high'])} | {_f(row['pearson_r'], '{:.3f}')} | "
            f"{_f(row['fit_seconds'], '{:.1f}')} |"
        )
    c = r["corpus"]
    v = r["visemenet"]
    lines += [
        "",
        f"Train: {c['train']}; test: {c['test']}; channels {', '.join(c['channels'])} "
        f"(a subset: CPU is scarce); neural rows trained {r['epochs']} epochs with small networks. "
        "Every row, phone- or audio-driven, uses the same utterances (those with audio).",
        "",
        f"VisemeNet activations (a control is active more than 0.5 std from its rest): precision "
        f"{_f(v['activation_precision'], '{:.3f}')}, recall {_f(v['activation_recall'], '{:.3f}')}; "
        f"phone-group accuracy from audio {_f(v['phone_group_accuracy'], '{:.3f}')}.",
        "",
        "| inference, ms per second of audio | ours (CPU) | Medina et al. (GPU) | parameters |",
        "|---|---:|---:|---:|",
    ]
    for label, x in r["inference"].items():
        lines.append(
            f"| {label} | {_f(x['ms_per_audio_second'], '{:.2f}')} | "
            f"{_f(x.get('paper_ms'), '{:.3f}')} | {x.get('n_parameters', '')} |"
        )
    m = r["machine"]
    lines += [
        "",
        "Decoder rows: MFCC (13 per frame at 100 Hz) precomputed and cached, networks untrained (the "
        "cost does not depend on the weights), 256 units per GRU layer (the paper's size is not stated; its "
        "GRU-2L has 3.95e6 parameters, its MLP 15:5 6.62e7). MFCC extraction is numpy on one core. Machine: "
        f"{m.get('cpu', '')}, {m.get('cores', '')} cores, shared with other jobs; {r['date']}.",
        "",
    ]
    return "\n".join(lines)


if __name__ == "__main__":
    sys.exit(main())
