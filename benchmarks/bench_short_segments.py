"""Very short phones in every context: which models that render segments overshoot, on the bundled vtl corpus.

Fits each model on ``vtl:train`` (19 channels), then, in the first 20
``vtl:test`` utterances, inserts a phone of 3, 10 or 30 ms at the start of every
inner segment longer than that plus 10 ms (one insertion per alignment, the
phone rotating through the phone set; :func:`dam.datasets.synthetic.insert_segment`).
An insertion *overshoots* when a frame of the prediction leaves, by more than a
quarter of the training data's range, the range spanned by the training data
and the model's own prediction without the insertion (the criterion of
``tests/model/test_short_segments.py``). 30 ms is as short as the shortest
training phones: what a model does with a phone in a new context at an
ordinary length, the baseline for the two shorter ones.

Writes ``benchmarks/results/short_segments.json`` and ``.md``.

    python benchmarks/bench_short_segments.py [--models dam dam-paper ...] [--utterances 20]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _machine import machine  # noqa: E402

import dam  # noqa: E402
from dam.corpus.atomic import atomic_write  # noqa: E402
from dam.datasets.synthetic import insert_segment  # noqa: E402
from dam.evaluation.metrics import evaluate  # noqa: E402

MODELS = ["dam", "dam-paper", "dam-m0", "cohen-massaro", "mmm", "hmm"]
LENGTHS = (0.003, 0.010, 0.030)


def overshoots(model, test, lo_data, hi_data, span, phones, length: float, n_utt: int):
    """(insertions that overshoot, insertions) for one inserted length."""
    bad = total = 0
    for u in list(test)[:n_utt]:
        a = u.alignment
        base = model.predict(a)
        lo, hi = np.minimum(lo_data, base.min(axis=0)), np.maximum(hi_data, base.max(axis=0))
        for j in range(1, len(a) - 1):
            if a.durations[j] <= length + 0.01:
                continue
            y = model.predict(insert_segment(a, j, phones[total % len(phones)], length))
            total += 1
            bad += bool(np.any((y < lo - 0.25 * span) | (y > hi + 0.25 * span)))
    return bad, total


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--models", nargs="+", default=MODELS)
    ap.add_argument("--utterances", type=int, default=20)
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"))
    args = ap.parse_args(argv)
    train, test = dam.datasets.load("vtl", "train"), dam.datasets.load("vtl", "test")
    Y = np.concatenate(train.trajectories)
    lo, hi = Y.min(axis=0), Y.max(axis=0)
    phones = sorted(train.phones - {train[0].alignment.silence})
    rows = []
    for name in args.models:
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            model = dam.make(name).fit(train)
        row = {"model": name, "fit_seconds": time.perf_counter() - t0, "heldout_rmse": evaluate(model, test).rmse}
        for length in LENGTHS:
            row[f"{length * 1000:.0f} ms"] = overshoots(model, test, lo, hi, hi - lo, phones, length, args.utterances)
        rows.append(row)
        print(name, {k: v for k, v in row.items() if k.endswith("ms")}, file=sys.stderr)
    res = {"machine": machine(), "utterances": args.utterances, "lengths_ms": [x * 1000 for x in LENGTHS], "rows": rows}
    out = Path(args.out)
    with atomic_write(out / "short_segments.json", "w") as fh:
        json.dump(res, fh, indent=2)
    with atomic_write(out / "short_segments.md", "w") as fh:
        fh.write(_markdown(res))
    print(f"wrote {out / 'short_segments.md'}", file=sys.stderr)


def summary(res: dict) -> str:
    """What it measured, and the table (the README quotes this)."""
    m = res["machine"]
    keys = [f"{x:.0f} ms" for x in res["lengths_ms"]]
    lines = [
        f"`benchmarks/results/short_segments.md` ({m['date']}, {m['cpu']}): a phone inserted at every inner "
        f"position of {res['utterances']} held-out `vtl` utterances; *overshooting*: some frame leaves the range "
        "of the training data and of the model's prediction without the insertion by more than a quarter of "
        "the data's range.",
        "",
        "| model | held-out RMSE | " + " | ".join(f"overshooting, {k} phone" for k in keys) + " |",
        "|---|---:|" + "---:|" * len(keys),
    ]
    for r in res["rows"]:
        cells = [f"{r[k][0]} / {r[k][1]} ({100 * r[k][0] / max(r[k][1], 1):.1f}%)" for k in keys]
        lines.append(f"| {r['model']} | {r['heldout_rmse']:.4f} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def _markdown(res: dict) -> str:
    return "# Very short phones on the bundled `vtl` corpus\n\n" + summary(res)


if __name__ == "__main__":
    main()
