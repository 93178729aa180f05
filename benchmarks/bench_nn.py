"""Neural predictors: training time, CPU synthesis speed and held-out accuracy.

Writes ``benchmarks/results/nn.json`` and ``nn.md``. Every network of
``baselines/nn`` (default settings) and the Medina et al. (2022) variants
that matter for speed (1- and 5-layer, uni- and bidirectional GRUs) are
fitted on the bundled corpus (``vtl:train``, 10 minutes at 100 Hz, 19
channels; ``--corpus tiny`` for a quick run) and scored on its test part.
Reported, beside the held-out RMSE with a bootstrap 95% interval:

* training seconds (one fit; epochs run and kept; trainable parameters);
* synthesis speed, warm (after the first call, which compiles): the median
  of ``--repeat`` passes over the test alignments, one alignment per call as
  a user would, in frames per second, microseconds per phone and
  milliseconds per second of speech. Taylor et al. (2017) report about 1000
  frames/s; Medina et al. (2022) 0.23 ms per second of audio for the MLP,
  11 ms for the 5-layer bidirectional GRU (GPU, their table 2);
* the first, compiling call separately;
* ``phone-mean`` measured in the same run as the reference (ratios divide by it).

The table's first columns are those of ``dam compare`` (:mod:`dam.compare`),
so the rows can be read beside the classical models'.

    python benchmarks/bench_nn.py [--corpus vtl] [--models sliding-dnn gru ...] [--repeat 5]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _machine import machine  # noqa: E402

import dam  # noqa: E402
from dam.evaluation.compare import bootstrap_rmse_ci  # noqa: E402
from dam.evaluation.metrics import evaluate  # noqa: E402

# label -> (registry name, params); the defaults of each network, plus Medina's GRU variants.
MODELS = {
    "phone-mean": ("phone-mean", {}),
    "sliding-dnn": ("sliding-dnn", {}),
    "sliding-dnn-linguistic": ("sliding-dnn", {"features": "linguistic"}),
    "lstm": ("lstm", {}),
    "causal-mlp": ("causal-mlp", {}),
    "gru": ("gru", {}),
    "gru-1L": ("gru", {"n_layers": 1}),
    "bi-gru-5L": ("gru", {"n_layers": 5, "bidirectional": True, "hidden_size": 32, "max_epochs": 20}),
    "transformer": ("transformer", {}),
}
PAPERS = {
    "taylor2017_frames_per_second": 1000.0,
    "medina2022_ms_per_second_mlp": 0.232,
    "medina2022_ms_per_second_bi_gru_5l": 10.955,
    "medina2022_ms_per_second_gru_5l": 5.339,
    "medina2022_ms_per_second_transformer": 3.515,
}


def load_corpus(name: str):
    from dam import datasets

    if name == "tiny":
        return dam.datasets.load("tiny").train_test_split(0.25, random_state=0)
    return datasets.load(name, split="train"), datasets.load(name, split="test")


def bench_model(label, name, params, train, test, repeat):
    cls = dam.registry.get(name)
    extra = {"verbose": 0} if "verbose" in cls._param_names() else {}
    if "unknown_phone" in cls._param_names():
        extra["unknown_phone"] = "fallback"
    model = cls(**params, **extra)
    t0 = time.perf_counter()
    model.fit(train)
    fit_s = time.perf_counter() - t0
    alignments = test.alignments
    t0 = time.perf_counter()
    preds = model.predict(alignments)  # first call: compiles the jitted networks
    first_s = time.perf_counter() - t0
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        for a in alignments:
            model.predict(a)
        times.append(time.perf_counter() - t0)
    pred_s = float(np.median(times))
    ev = evaluate(None, test, predictions=preds)
    sse = np.array([np.sum((u.trajectory - p) ** 2) for u, p in zip(test, preds)])
    cnt = np.array([u.trajectory.size for u in test], dtype=float)
    lo, hi = bootstrap_rmse_ci(sse, cnt)
    n_frames = sum(u.n_frames for u in test)
    seconds = n_frames / test.frame_rate
    row = {
        "model": label,
        "name": name,
        "params": params,
        "rmse": ev.rmse,
        "rmse_ci_low": lo,
        "rmse_ci_high": hi,
        "pearson_r": ev.pearson_r,
        "fit_seconds": fit_s,
        "predict_us_per_phone": 1e6 * pred_s / sum(len(a) for a in alignments),
        "frames_per_second": n_frames / pred_s,
        "ms_per_second_of_speech": 1e3 * pred_s / seconds,
        "first_call_seconds": first_s,
        "predict_seconds_median": pred_s,
        "predict_runs": repeat,
    }
    for attr in ("n_epochs_", "best_epoch_", "n_parameters_"):
        if hasattr(model, attr):
            row[attr.rstrip("_")] = int(getattr(model, attr))
    return row


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--corpus", default="vtl", help="bundled corpus with train/test splits, or 'tiny'")
    ap.add_argument("--models", nargs="+", default=list(MODELS), choices=list(MODELS))
    ap.add_argument("--repeat", type=int, default=5, help="warm synthesis passes (median)")
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"))
    args = ap.parse_args(argv)

    train, test = load_corpus(args.corpus)
    import jax

    res = {
        "machine": {**machine(), "jax": jax.__version__, "jax_backend": jax.default_backend()},
        "load_average_start": os.getloadavg(),
        "corpus": args.corpus,
        "train": {
            "utterances": len(train),
            "minutes": train.duration / 60,
            "channels": train.n_channels,
            "frame_rate": train.frame_rate,
        },
        "test": {"utterances": len(test), "minutes": test.duration / 60},
        "papers": PAPERS,
        "rows": [],
    }
    labels = ["phone-mean"] + [m for m in args.models if m != "phone-mean"]
    for label in labels:
        name, params = MODELS[label]
        print(f"{label}: fitting on {train.duration / 60:.1f} min ...", file=sys.stderr, flush=True)
        row = bench_model(label, name, params, train, test, args.repeat)
        res["rows"].append(row)
        print(
            f"  fit {row['fit_seconds']:.1f} s, RMSE {row['rmse']:.4g}, {row['frames_per_second']:.0f} frames/s, "
            f"{row['ms_per_second_of_speech']:.2f} ms per s of speech",
            file=sys.stderr,
            flush=True,
        )
    ref = res["rows"][0]
    for r in res["rows"]:
        r["synthesis_time_vs_phone_mean"] = r["predict_seconds_median"] / ref["predict_seconds_median"]
    res["load_average_end"] = os.getloadavg()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "nn.json").write_text(json.dumps(res, indent=2, default=float))
    (out / "nn.md").write_text(markdown(res))
    print(f"wrote {out / 'nn.json'} and {out / 'nn.md'}", file=sys.stderr)


def markdown(r) -> str:
    m = r["machine"]
    lines = [
        "# Neural predictors benchmark",
        "",
        f"Machine: {m['cpu']}, {m['cores']} cores (shared; load average {r['load_average_start'][0]:.1f} at "
        f"start, {r['load_average_end'][0]:.1f} at end), Python {m['python']}, jax {m['jax']} "
        f"({m['jax_backend']}), {m['date']}.",
        f"Corpus: `{r['corpus']}`, train {r['train']['minutes']:.1f} min ({r['train']['utterances']} utterances, "
        f"{r['train']['channels']} channels at {r['train']['frame_rate']:g} Hz), test "
        f"{r['test']['minutes']:.1f} min ({r['test']['utterances']} utterances).",
        "",
        "The first columns are those of `dam compare`. Synthesis is warm (median of "
        f"{r['rows'][0]['predict_runs']} passes over the test alignments, one per call); the first, "
        "compiling call is listed apart. Fit = one training run with early stopping on 10% of the "
        "training utterances.",
        "",
        "| model | RMSE | 95% CI | Pearson r | fit s | µs/phone | frames/s | ms per s of speech | "
        "first call s | x phone-mean time | epochs (kept) | parameters |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for x in r["rows"]:
        ep = f"{x['n_epochs']} ({x['best_epoch']})" if "n_epochs" in x else ""
        lines.append(
            f"| {x['model']} | {x['rmse']:.4g} | {x['rmse_ci_low']:.4g}–{x['rmse_ci_high']:.4g} | "
            f"{x['pearson_r']:.3f} | {x['fit_seconds']:.1f} | {x['predict_us_per_phone']:.0f} | "
            f"{x['frames_per_second']:.3g} | {x['ms_per_second_of_speech']:.2f} | "
            f"{x['first_call_seconds']:.2f} | {x['synthesis_time_vs_phone_mean']:.0f} | {ep} | "
            f"{x.get('n_parameters', '')} |"
        )
    p = r["papers"]
    lines += [
        "",
        f"Papers: Taylor et al. (2017) about {p['taylor2017_frames_per_second']:.0f} frames/s for the "
        f"sliding-window network (GPU); Medina et al. (2022), ms per second of audio: MLP 15:5 "
        f"{p['medina2022_ms_per_second_mlp']}, GRU-5L {p['medina2022_ms_per_second_gru_5l']}, "
        f"Bi-GRU-5L {p['medina2022_ms_per_second_bi_gru_5l']}, Transformer "
        f"{p['medina2022_ms_per_second_transformer']}.",
    ]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    main()
