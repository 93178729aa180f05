"""The crossmap showcase (examples/crossmap_pipeline.py) by amount of training data.

Runs the whole pipeline (outlines, key shapes, NNLS weights, bounded controls, the DAM and
phone-mean trained on the controls, five held-out phrases) with half a minute and with two
minutes of training phrases, and writes ``results/crossmap_pipeline.json`` / ``.md``: whether the
DAM wins depends on the data (it overfits half a minute). ``benchmarks/update_readme.py`` fills the
README's crossmap paragraph from the JSON.

    python benchmarks/bench_crossmap.py [--minutes 0.5 2]
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import machine  # noqa: E402


def _example():
    spec = importlib.util.spec_from_file_location("crossmap_pipeline", ROOT / "examples" / "crossmap_pipeline.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--minutes", type=float, nargs="+", default=[0.5, 2.0])
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"))
    args = ap.parse_args(argv)
    example = _example()
    runs = []
    with tempfile.TemporaryDirectory() as tmp:
        for minutes in args.minutes:
            out = os.path.join(tmp, f"{minutes:g}")
            example.main(["--out", out, "--minutes", str(minutes)])
            with open(os.path.join(out, "metrics.json")) as fh:
                runs.append(json.load(fh))
    rec = {"machine": machine(), "runs": runs}
    from dam.corpus.atomic import atomic_write

    with atomic_write(Path(args.out) / "crossmap_pipeline.json") as fh:
        json.dump(rec, fh, indent=1)
    models = list(runs[-1]["held_out"]["scores"])
    lines = [
        "# The crossmap showcase by minutes of training phrases",
        "",
        f"Machine: {rec['machine']['cpu']}, {rec['machine']['date']}. `examples/crossmap_pipeline.py`; "
        "held-out RMSE of the rig controls (clipped to [0, 1]) on the same held-out phrases.",
        "",
        "| minutes | phrases | key shapes | " + " | ".join(models) + " | DAM values outside [0, 1] |",
        "|---:|---:|---:|" + "---:|" * (len(models) + 1),
    ]
    for r in runs:
        sc = r["held_out"]["scores"]
        lines.append(
            f"| {r['minutes']:g} | {r['captured']['train_utterances']} | {r['key_shapes']} | "
            + " | ".join(f"{sc[m]['rmse']:.4f}" for m in models)
            + f" | {100 * sc[models[0]]['outside_0_1_share']:.1f}% |"
        )
    with atomic_write(Path(args.out) / "crossmap_pipeline.md") as fh:
        fh.write("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
