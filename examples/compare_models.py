"""Compare coarticulation models on held-out data, the way a speech scientist would.

Fits the DAM, the DAM with constant animemes (the paper's Cohen-Massaro row),
the 1993 Cohen-Massaro model, MMM and the sliding-window decision tree (raw
and linguistic features) on the bundled corpus, scores them on its held-out
part and writes the tables and figures.

    python examples/compare_models.py [--corpus tiny|vtl] [--out examples/out/compare] [--jobs 2]

The same from the shell:

    dam compare --models dam,dam-m0,cohen-massaro,mmm,dtree --train tiny --out examples/out/compare
"""
from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

from dam.evaluation.compare import DEMO_MODELS, compare  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--corpus", default="tiny", help="bundled corpus: tiny (hold-out quarter) or vtl (train/test)")
    ap.add_argument("--out", default=str(Path(__file__).parent / "out" / "compare"))
    ap.add_argument("--jobs", type=int, default=1, help="joblib workers over models")
    args = ap.parse_args(argv)
    if args.corpus == "tiny":
        res = compare(DEMO_MODELS, "tiny", n_jobs=args.jobs, out=args.out)
    else:
        res = compare(DEMO_MODELS, f"{args.corpus}:train", f"{args.corpus}:test", n_jobs=args.jobs, out=args.out)
    print(res.table())
    print(f"\nbest: {res.best}; tables and figures in {args.out}")


if __name__ == "__main__":
    main()
