"""Compare coarticulation models on held-out data, the way a speech scientist would.

Fits the DAM, the DAM with constant animemes (the paper's Cohen-Massaro row),
the 1993 Cohen-Massaro model, MMM and the sliding-window decision tree (raw
and linguistic features) on the bundled corpus, scores them on its held-out
part and writes the tables and figures (``summary.md``, ``per_channel.csv``,
``predictions.png``, ``rmse.png``, ...).

    python examples/compare_models.py [--corpus tiny|vtl] [--out DIR] [--jobs 2] [--quick]

Output goes to ``--out`` (default ``dam-examples/compare_models/`` in the
working directory, which git ignores). ``--quick``: three fast models on
``tiny`` (seconds, a smoke test). The same from the shell:

    dam compare --models dam,dam-m0,cohen-massaro,mmm,dtree --train tiny --out DIR
"""

from __future__ import annotations

import argparse
from pathlib import Path

from dam.evaluation.compare import DEMO_MODELS, compare

NAME = "compare_models"
QUICK_MODELS = ("phone-mean", "target-interpolation", ("dam", "dam", {"max_iter": 5}))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--corpus", default="tiny", help="bundled corpus: tiny (hold-out quarter) or vtl (train/test)")
    ap.add_argument(
        "--out",
        default=str(Path.cwd() / "dam-examples" / NAME),
        help=f"output directory (default: ./dam-examples/{NAME})",
    )
    ap.add_argument("--jobs", type=int, default=1, help="joblib workers over models")
    ap.add_argument("--quick", action="store_true", help="three fast models on tiny (a smoke test)")
    args = ap.parse_args(argv)
    models = QUICK_MODELS if args.quick else DEMO_MODELS
    corpus = "tiny" if args.quick else args.corpus
    if corpus == "tiny":
        res = compare(models, "tiny", n_jobs=args.jobs, out=args.out)
    else:
        res = compare(models, f"{corpus}:train", f"{corpus}:test", n_jobs=args.jobs, out=args.out)
    print(res.table())
    print(f"\nbest: {res.best}; tables and figures in {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
