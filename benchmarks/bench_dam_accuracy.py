"""Held-out accuracy of the DAM, its variants and dam-m0 (Cohen-Massaro as the paper built it).

Fits on the training part of a bundled corpus (its ``train`` split, or 75% of
the utterances), scores on the held-out part (its ``test`` split, or the other
25%), and writes ``benchmarks/results/dam_accuracy_<corpus>.json`` and ``.md``:
overall and per-channel RMSE, mean Pearson r, fit seconds, and per phone the
RMSE of the DAM against dam-m0 on the frames of that phone (where the DAM
loses). The paper reports average L2 norms of 0.4724 (DAM) vs 0.6297
(Cohen-Massaro) on one utterance.

    python benchmarks/bench_dam_accuracy.py [--corpus tiny|vtl|DIR] [--quick] [--variants LABEL ...] [--append]

``dam`` and ``dam-m0`` are the defaults (the weighted average,
``normalize=True``); "plain sum" rows are Eq. (2) as printed.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")


sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _machine import machine  # noqa: E402

import dam  # noqa: E402
from dam.corpus.data import frame_labels  # noqa: E402
from dam.evaluation.metrics import evaluate  # noqa: E402

VARIANTS = [
    ("phone-mean", "phone-mean", {}),
    ("dam-m0", "dam-m0", {}),
    ("dam", "dam", {}),
    ("dam hold", "dam", {"extrapolate": "hold"}),
    ("dam single-mode", "dam", {"modes": "single"}),
    ("dam hold single-mode", "dam", {"extrapolate": "hold", "modes": "single"}),
    ("dam preference=median", "dam", {"mode_preference": "median"}),
    ("dam plain sum", "dam", {"normalize": False}),
    ("dam-paper", "dam-paper", {}),
    ("dam-paper, modes by context alone (w_s=0)", "dam-paper", {"w_s": 0.0}),
    ("dam-paper, quartic on the whole time line", "dam-paper", {"extrapolate": "polynomial"}),
    ("dam-m0 plain sum, modes by context alone (w_s=0)", "dam-m0", {"normalize": False, "w_s": 0.0}),
    ("dam-m0 plain sum", "dam-m0", {"normalize": False}),
    ("dam-m0 single-mode", "dam-m0", {"modes": "single"}),
]


def split(name: str):
    """The corpus's own train/test splits (bundled, or ``train/`` and ``test/`` of a directory),
    or a 75/25 utterance split."""
    if os.path.isdir(name):
        from dam.corpus.io import load_corpus

        return load_corpus(os.path.join(name, "train")), load_corpus(os.path.join(name, "test"))
    try:
        return dam.datasets.load(name, "train"), dam.datasets.load(name, "test")
    except KeyError:
        return dam.datasets.load(name).train_test_split(0.25, random_state=0)


def per_phone_sq(model, corpus):
    """Sum of squared errors and frame counts per phone (all channels pooled)."""
    sq, n = {}, {}
    for u in corpus:
        err = ((model.predict(u.alignment) - u.trajectory) ** 2).mean(axis=1)
        for lab, e in zip(frame_labels(u.alignment, u.frame_rate, u.n_frames), err):
            sq[lab] = sq.get(lab, 0.0) + float(e)
            n[lab] = n.get(lab, 0) + 1
    return sq, n


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--corpus", default="tiny", help="bundled corpus name, or a directory with train/ and test/")
    ap.add_argument("--quick", action="store_true", help="only phone-mean, dam-m0 and dam")
    ap.add_argument(
        "--variants",
        nargs="+",
        default=None,
        metavar="LABEL",
        help=f"labels of the variants to run (default all): {', '.join(v[0] for v in VARIANTS)}",
    )
    ap.add_argument(
        "--append",
        action="store_true",
        help="merge the rows into the corpus's existing result file instead of replacing it "
        "(e.g. variants run by a second process)",
    )
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"))
    args = ap.parse_args(argv)
    chosen = VARIANTS[:3] if args.quick else VARIANTS
    if args.variants:
        unknown = set(args.variants) - {v[0] for v in VARIANTS}
        if unknown:
            ap.error(f"unknown variant label(s) {sorted(unknown)}; known: {[v[0] for v in VARIANTS]}")
        chosen = [v for v in VARIANTS if v[0] in args.variants]
    train, test = split(args.corpus)
    res = {
        "machine": machine(),
        "corpus": args.corpus,
        "train": repr(train),
        "test": repr(test),
        "channels": list(train.channels),
        "models": {},
    }
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    stem = out / ("dam_accuracy_" + Path(args.corpus.rstrip("/")).name)
    per_phone = {}
    for label, name, params in chosen:
        t0 = time.perf_counter()
        model = dam.make(name, **params).fit(train)
        fit_s = time.perf_counter() - t0
        ev = evaluate(model, test)
        res["models"][label] = {
            "model": name,
            "params": params,
            "fit_seconds": fit_s,
            "rmse": ev.rmse,
            "pearson_r": ev.pearson_r,
            "rmse_per_channel": [float(v) for v in ev.rmse_per_channel],
            "train_rmse": evaluate(model, train).rmse,
        }
        if label in ("dam", "dam-m0"):
            per_phone[label] = per_phone_sq(model, test)
        if len(per_phone) == 2:
            (sq_d, n), (sq_m, _) = per_phone["dam"], per_phone["dam-m0"]
            res["per_phone"] = {
                p: {"frames": n[p], "dam": (sq_d[p] / n[p]) ** 0.5, "dam-m0": (sq_m[p] / n[p]) ** 0.5}
                for p in sorted(n)
            }
        print(f"{label:<24} held-out RMSE {ev.rmse:.4g}  r {ev.pearson_r:.3f}  fit {fit_s:.1f} s", file=sys.stderr)
        _write(res, stem, args.append)  # after every model: a long run keeps what it has
    print(f"wrote {stem}.json and .md", file=sys.stderr)


def _write(res: dict, stem: Path, append: bool) -> None:
    """Write ``stem``.json/.md; with ``append``, merged over the rows already in the file."""
    if append and stem.with_suffix(".json").exists():
        old = json.loads(stem.with_suffix(".json").read_text())
        merged = {**old, "models": {**old.get("models", {}), **res["models"]}}
        if "per_phone" in res:
            merged["per_phone"] = res["per_phone"]
        res = merged
    order = [v[0] for v in VARIANTS]
    res = {
        **res,
        "models": dict(
            sorted(res["models"].items(), key=lambda kv: order.index(kv[0]) if kv[0] in order else len(order))
        ),
    }
    m = res["models"]
    if "dam" in m and "dam-m0" in m:
        res["dam_vs_dam_m0"] = {"rmse_ratio": m["dam"]["rmse"] / m["dam-m0"]["rmse"], "paper_ratio": 0.4724 / 0.6297}
    stem.with_suffix(".json").write_text(json.dumps(res, indent=2))
    stem.with_suffix(".md").write_text(_markdown(res))


def _markdown(r) -> str:
    ch = r["channels"]
    lines = [
        f"# DAM held-out accuracy on the bundled corpus `{r['corpus']}`",
        "",
        f"train: {r['train']}  ",
        f"test: {r['test']}  ",
        f"machine: {r['machine']['cpu']}, {r['machine']['date']}",
        "",
        "| model | held-out RMSE | mean r | training RMSE | fit s | " + " | ".join(ch) + " |",
        "|---|---:|---:|---:|---:|" + "---:|" * len(ch),
    ]
    for label, v in r["models"].items():
        lines.append(
            f"| {label} | {v['rmse']:.4g} | {v['pearson_r']:.3f} | {v['train_rmse']:.4g} | "
            f"{v['fit_seconds']:.1f} | " + " | ".join(f"{x:.3g}" for x in v["rmse_per_channel"]) + " |"
        )
    if "dam_vs_dam_m0" in r:
        d = r["dam_vs_dam_m0"]
        lines += [
            "",
            f"DAM / dam-m0 held-out RMSE: {d['rmse_ratio']:.3f} (the paper: 0.4724 / 0.6297 = {d['paper_ratio']:.3f}).",
        ]
    if "per_phone" in r:
        lines += [
            "",
            "Phones where the DAM loses to dam-m0 (RMSE on that phone's frames):",
            "",
            "| phone | frames | dam | dam-m0 |",
            "|---|---:|---:|---:|",
        ]
        losing = [(p, v) for p, v in r["per_phone"].items() if v["dam"] > v["dam-m0"]]
        for p, v in sorted(losing, key=lambda pv: pv[1]["dam-m0"] - pv[1]["dam"]):
            lines.append(f"| {p} | {v['frames']} | {v['dam']:.4g} | {v['dam-m0']:.4g} |")
        if not losing:
            lines.append("| (none) | | | |")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    main()
