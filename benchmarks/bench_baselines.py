"""Fit time and synthesis speed of the classical baselines on a bundled corpus.

Writes ``benchmarks/results/baselines.json`` and ``baselines.md``. The
reference measured in the same run is ``phone-mean`` (a table look-up per
frame), so the ratios say what each model's synthesis costs on top of
reading its parameters. Synthesis is timed over the held-out alignments,
median of ``--repeat`` runs; MMM is timed on both of its solvers (LAPACK
through scipy, and the banded Cholesky in numpy alone that a deployment
without scipy uses).

    python benchmarks/bench_baselines.py [--corpus tiny] [--repeat 5]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from unittest import mock

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from _machine import machine, median_time  # noqa: E402

import dam  # noqa: E402
from baselines import mmm as mmm_module  # noqa: E402

MODELS = [("phone-mean", {}), ("cohen-massaro", {}), ("mmm", {}), ("dtree", {}), ("dtree", {"features": "linguistic"})]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--corpus", default="tiny")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"))
    args = ap.parse_args(argv)
    train, test = dam.datasets.load(args.corpus).train_test_split(0.25, random_state=0)
    n_phones = sum(len(a) for a in test.alignments)
    n_frames = sum(u.n_frames for u in test)
    rows = []
    for name, params in MODELS:
        model = dam.make(name, **params)
        t0 = time.perf_counter()
        model.fit(train)
        fit_s = time.perf_counter() - t0
        variants = [("", None)]
        if name == "mmm":
            variants.append((" (numpy solver)", mmm_module.banded_cholesky_solve))
        for suffix, solver in variants:
            if solver is None:
                t = median_time(lambda: model.predict(test.alignments), repeat=args.repeat)
            else:
                with mock.patch.object(mmm_module, "solve_banded_spd", solver):
                    t = median_time(lambda: model.predict(test.alignments), repeat=args.repeat)
            label = name + ("" if not params else "[" + ",".join(f"{k}={v}" for k, v in params.items()) + "]")
            rows.append(
                {
                    "model": label + suffix,
                    "fit_seconds": fit_s,
                    "predict_seconds_median": t,
                    "us_per_phone": 1e6 * t / n_phones,
                    "frames_per_second": n_frames / t,
                }
            )
    ref = rows[0]["us_per_phone"]
    for r in rows:
        r["ratio_to_phone_mean"] = r["us_per_phone"] / ref
    res = {
        "machine": machine(),
        "corpus": args.corpus,
        "train_utterances": len(train),
        "test_utterances": len(test),
        "test_phones": n_phones,
        "test_frames": n_frames,
        "rows": rows,
    }
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "baselines.json").write_text(json.dumps(res, indent=2) + "\n")
    lines = [
        "| model | fit (s) | synthesis (µs/phone, median) | frames/s | × phone-mean |",
        "|---|---:|---:|---:|---:|",
    ]
    lines += [
        f"| {r['model']} | {r['fit_seconds']:.2f} | {r['us_per_phone']:.1f} | {r['frames_per_second']:.3g} "
        f"| {r['ratio_to_phone_mean']:.1f} |"
        for r in rows
    ]
    m = res["machine"]
    lines += [
        "",
        f"Corpus {args.corpus}: fit on {len(train)} utterances, synthesis of {len(test)} held-out "
        f"utterances ({n_phones} phones, {n_frames} frames). Machine: {m['cpu']}, {m['cores']} cores, "
        f"numpy {m['numpy']}, {m['date']}. The paper's DAM: 0.8 ms per phone.",
    ]
    (out / "baselines.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
