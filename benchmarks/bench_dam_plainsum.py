"""Why the paper's plain-sum Eq. (2) loses on the bundled corpus: a fitting problem or a modelling one?

Fits, on the bundled ``vtl`` corpus (train / test splits) and a few channels
(jaw, lips, tongue tip by default), the plain-sum DAM (``dam-paper``) and
variants that take one suspect away at a time, and writes training and
held-out RMSE per channel to ``benchmarks/results/dam_plainsum.json`` and
``.md``:

* ``E-step only, one sigma``: the crude fit of the issue (every mode shares one
  sigma, chosen per channel on a grid by training error; animemes by the
  E-step) - the EM's own starting point;
* ``dam-paper, fitted with the clustering's modes``: the full EM, every
  training occurrence fitted as the mode clustering gave it (before issue 11);
* ``dam-paper, fitted with the modes synthesis selects``: the same, every
  occurrence fitted as the mode synthesis will choose in its context
  (``fit_modes="selected"``, now the default);
* ``dam-paper, one mode per phone``: no mode choice at all;
* ``dam-paper, hold``: the animeme held at its edge value outside [0, 1]
  instead of the quartic extrapolated over the dominance tails;
* ``dam-paper, quartic on the whole time line``: the quartic also where
  training never evaluated it (``dam-paper`` holds it there since issue 11:
  ``extrapolate="trained"``);
* the weighted-average ``dam`` and ``dam-m0`` rows, for comparison.

    python benchmarks/bench_dam_plainsum.py [--channels JA LP TTY] [--variants LABEL ...] [--readme]

``--readme`` fills the README block between ``<!-- plainsum:start -->`` and
``<!-- plainsum:end -->`` from the results file (never typed by hand).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
import warnings
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _machine import machine  # noqa: E402

import dam  # noqa: E402
from dam.evaluation.metrics import evaluate  # noqa: E402

VARIANTS = [
    ("phone-mean", "phone-mean", {}),
    ("E-step only, one sigma", "dam-paper", {"max_iter": 0, "fit_modes": "clustered"}),
    ("dam-paper, fitted with the clustering's modes", "dam-paper", {"fit_modes": "clustered"}),
    ("dam-paper, fitted with the modes synthesis selects", "dam-paper", {}),
    ("dam-paper, one mode per phone", "dam-paper", {"modes": "single"}),
    ("dam-paper, hold", "dam-paper", {"extrapolate": "hold"}),
    ("dam-paper, quartic on the whole time line", "dam-paper", {"extrapolate": "polynomial"}),
    ("dam-paper, modes chosen by context alone (w_s = 0)", "dam-paper", {"w_s": 0.0}),
    ("dam-m0 plain sum", "dam-m0", {"normalize": False}),
    ("dam (weighted average), fitted with the clustering's modes", "dam", {"fit_modes": "clustered"}),
    ("dam (weighted average)", "dam", {}),
    ("dam (weighted average), modes chosen by context alone (w_s = 0)", "dam", {"w_s": 0.0}),
    ("dam-m0 (weighted average)", "dam-m0", {}),
]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--channels", nargs="+", default=["JA", "LP", "TTY"])
    ap.add_argument("--variants", nargs="+", help="labels of VARIANTS to run (default all)")
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"))
    ap.add_argument("--render", action="store_true", help="only rewrite the .md from the .json")
    ap.add_argument("--readme", action="store_true", help="only fill the README's plainsum block from the .json")
    args = ap.parse_args(argv)
    out = Path(args.out)
    if args.render:
        return write_markdown(json.loads((out / "dam_plainsum.json").read_text()), out)
    if args.readme:
        return write_readme(
            json.loads((out / "dam_plainsum.json").read_text()), Path(__file__).resolve().parents[1] / "README.md"
        )
    train = dam.datasets.load("vtl", "train").select_channels(args.channels)
    test = dam.datasets.load("vtl", "test").select_channels(args.channels)
    rows = []
    for label, name, params in VARIANTS:
        if args.variants and label not in args.variants:
            continue
        model = dam.make(name, **params)
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            model.fit(train)
        fit_s = time.perf_counter() - t0
        tr, te = evaluate(model, train), evaluate(model, test)
        row = {
            "label": label,
            "model": repr(model),
            "fit_seconds": fit_s,
            "train_rmse": tr.rmse,
            "test_rmse": te.rmse,
            "train_rmse_per_channel": list(map(float, tr.rmse_per_channel)),
            "test_rmse_per_channel": list(map(float, te.rmse_per_channel)),
        }
        if hasattr(model, "sigma_"):
            row["sigma_quantiles_50_90_100"] = np.quantile(model.sigma_, [0.5, 0.9, 1.0]).tolist()
            row["objective_first_last"] = [[float(c[0]), float(c[-1])] for c in model.loss_curve_]
        rows.append(row)
        print(f"{label:>34}: train {tr.rmse:.4f} test {te.rmse:.4f} ({fit_s:.0f} s)", file=sys.stderr)
    res = {
        "machine": machine(),
        "channels": args.channels,
        "rows": rows,
        "paper": {"dam": 0.4724, "cohen_massaro": 0.6297},
    }
    out.mkdir(parents=True, exist_ok=True)
    if args.variants and (out / "dam_plainsum.json").exists():  # merge into the previous run, in VARIANTS order
        old = json.loads((out / "dam_plainsum.json").read_text())
        if old["channels"] == args.channels:
            by = {r["label"]: r for r in old["rows"]}
            by.update({r["label"]: r for r in rows})
            res["rows"] = [by[v[0]] for v in VARIANTS if v[0] in by]
            res["merged_runs"] = [old["machine"]["date"], res["machine"]["date"]]
    (out / "dam_plainsum.json").write_text(json.dumps(res, indent=2))
    write_markdown(res, out)


def _table(res: dict) -> list:
    lines = ["| variant | fit-time RMSE (start -> end of EM) | training RMSE | held-out RMSE |", "|---|---|---:|---:|"]
    for r in res["rows"]:
        obj = r.get("objective_first_last")
        fit = (
            ""
            if not obj
            else (f"{np.sqrt(np.mean([o[0] for o in obj])):.3f} -> {np.sqrt(np.mean([o[1] for o in obj])):.3f}")
        )
        lines.append(f"| {r['label']} | {fit} | {r['train_rmse']:.3f} | {r['test_rmse']:.3f} |")
    return lines


def write_readme(res: dict, readme: Path) -> None:
    """Fill the README's plainsum block with the table of ``res``."""
    start, end = "<!-- plainsum:start -->", "<!-- plainsum:end -->"
    text = readme.read_text()
    if start not in text or end not in text:
        raise SystemExit(f"{readme}: no {start} ... {end} block to fill")
    block = "\n".join(
        [start, "", f"Channels {', '.join(res['channels'])}, {res['machine']['date']}:", "", *_table(res), "", end]
    )
    head, rest = text.split(start, 1)
    readme.write_text(head + block + rest.split(end, 1)[1])
    print(f"updated {readme}", file=sys.stderr)


def write_markdown(res: dict, out: Path) -> None:
    """``dam_plainsum.md``: one row per variant. "fit-time" is the EM's own training RMSE
    (square root of its final objective, averaged over channels), with the modes clustering gave
    each training occurrence; "training" re-synthesizes the training utterances through predict,
    modes chosen by the search of Section VI as on held-out data."""
    chans = res["channels"]
    lines = [
        "# The plain-sum Eq. (2) on the bundled `vtl` corpus",
        "",
        f"Channels {', '.join(chans)}; {res['machine']['date']}"
        + (
            f" (rows merged from the runs of {' and '.join(res['merged_runs'])}; *fit s* is each row's own run "
            "on a shared machine)"
            if "merged_runs" in res
            else ""
        )
        + ". RMSE over the channels. "
        "*fit-time*: the EM's objective (training modes from clustering); *training*: the training "
        "utterances through `predict` (modes chosen by the search, as on held-out data).",
        "",
        "| variant | fit-time RMSE (start -> end of EM) | training RMSE | held-out RMSE | "
        + " | ".join(f"held-out {c}" for c in chans)
        + " | median / max sigma | fit s |",
        "|---|---|---:|---:|" + "---:|" * len(chans) + "---|---:|",
    ]
    for r in res["rows"]:
        sig = r.get("sigma_quantiles_50_90_100")
        obj = r.get("objective_first_last")
        fit = (
            ""
            if not obj
            else (f"{np.sqrt(np.mean([o[0] for o in obj])):.4f} -> {np.sqrt(np.mean([o[1] for o in obj])):.4f}")
        )
        lines.append(
            f"| {r['label']} | {fit} | {r['train_rmse']:.4f} | {r['test_rmse']:.4f} | "
            + " | ".join(f"{v:.4f}" for v in r["test_rmse_per_channel"])
            + f" | {'' if sig is None else f'{sig[0]:.2f} / {sig[2]:.2f}'} | {r['fit_seconds']:.0f} |"
        )
    (out / "dam_plainsum.md").write_text("\n".join(lines) + "\n")
    print(f"wrote {out / 'dam_plainsum.md'}", file=sys.stderr)


if __name__ == "__main__":
    main()
