"""``dam models``, ``dam fit``, ``dam predict``, ``dam evaluate``: one model at a time."""
from __future__ import annotations

import json
import sys

from dam.cli.common import corpus_arg, info, parse_param


# -- models ---------------------------------------------------------------
def add_models(sub) -> None:
    p = sub.add_parser("models", help="list the registered synthesizers",
                       description="List every registered synthesizer, what it reads and what it needs.")
    p.set_defaults(func=cmd_models)


def cmd_models(args) -> int:
    from dam.registry import available, get, names
    width = max(len(n) for n in names())
    for name in names():
        ok, why = available(name)
        if ok:
            cls = get(name)
            tags = cls.get_tags()
            doc = (cls.__doc__ or "").strip().splitlines()[0] if cls.__doc__ else ""
            needs = f" [needs: {', '.join(tags['requires'])}]" if tags["requires"] else ""
            print(f"{name:<{width}}  reads {'+'.join(tags['reads']):<12} {doc}{needs}")
        else:
            print(f"{name:<{width}}  unavailable: {why}")
    return 0


# -- fit ------------------------------------------------------------------
def add_fit(sub) -> None:
    p = sub.add_parser("fit", help="fit a model on a corpus and save it",
                       description="Fit MODEL on the corpus in CORPUS (a directory, or a bundled corpus "
                                   "name such as 'tiny' or 'vtl:train') and save it to MODEL_FILE.",
                       epilog="example: dam fit dam corpus/train -o m.dam --param degree=4")
    p.add_argument("model", metavar="MODEL", help="registered model name (see `dam models`)")
    p.add_argument("corpus", metavar="CORPUS", help="corpus directory or bundled corpus name")
    p.add_argument("-o", "--output", required=True, metavar="MODEL_FILE", help="where to write the fitted model")
    p.add_argument("-p", "--param", action="append", default=[], type=parse_param, metavar="KEY=VALUE",
                   help="set a hyperparameter (repeatable); values are read as JSON when possible")
    p.set_defaults(func=cmd_fit)


def cmd_fit(args) -> int:
    import time
    from dam.registry import make
    model = make(args.model)
    model.set_params(**dict(args.param))
    corpus = corpus_arg(args.corpus)
    info(args, f"fitting {model!r} on {corpus!r}")
    t0 = time.perf_counter()
    model.fit(corpus)
    info(args, f"fitted in {time.perf_counter() - t0:.2f} s; training RMSE {-model.score(corpus):.4g}")
    model.save(args.output)
    info(args, f"saved {args.output}")
    return 0


# -- predict --------------------------------------------------------------
def add_predict(sub) -> None:
    p = sub.add_parser("predict", help="synthesize trajectories for an alignment",
                       description="Synthesize the trajectory for ALIGNMENT_FILE (.TextGrid or HTK .lab) "
                                   "with a fitted model and write it as CSV with a time column.")
    p.add_argument("model_file", metavar="MODEL_FILE")
    p.add_argument("alignment", metavar="ALIGNMENT_FILE")
    p.add_argument("-o", "--output", default="-", metavar="OUT.csv", help="output CSV (default: standard output)")
    p.add_argument("--tier", default="phones", help="TextGrid tier with the phones (default: phones)")
    p.set_defaults(func=cmd_predict)


def cmd_predict(args) -> int:
    from dam.modelfile import load
    from dam.corpus.io import read_alignment, write_csv
    model = load(args.model_file)
    alignment = read_alignment(args.alignment, tier=args.tier)
    y = model.predict(alignment)
    write_csv(y, model.channels_, sys.stdout if args.output == "-" else args.output,
              frame_rate=model.frame_rate_)
    if args.output != "-":
        info(args, f"wrote {len(y)} frames x {y.shape[1]} channels to {args.output}")
    return 0


# -- evaluate -------------------------------------------------------------
def add_evaluate(sub) -> None:
    p = sub.add_parser("evaluate", help="score a fitted model on a corpus",
                       description="RMSE (in channel units) and Pearson r, overall and per channel, "
                                   "of a fitted model on a corpus.")
    p.add_argument("model_file", metavar="MODEL_FILE")
    p.add_argument("corpus", metavar="CORPUS", help="corpus directory or bundled corpus name")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    p.add_argument("--per-utterance", action="store_true", help="also print one line per utterance")
    p.set_defaults(func=cmd_evaluate)


def cmd_evaluate(args) -> int:
    from dam.modelfile import load
    from dam.evaluation.metrics import evaluate
    model = load(args.model_file)
    ev = evaluate(model, corpus_arg(args.corpus))
    if args.json:
        print(json.dumps({"rmse": ev.rmse, "pearson_r": ev.pearson_r,
                          "channels": {c: {"rmse": float(e), "pearson_r": float(r)} for c, e, r in
                                       zip(ev.channels, ev.rmse_per_channel, ev.pearson_per_channel)},
                          "per_utterance": ev.per_utterance if args.per_utterance else None}, indent=2))
        return 0
    print(ev.table())
    if args.per_utterance:
        print()
        for row in ev.per_utterance:
            print(f"{row['utterance']}  frames={row['n_frames']}  rmse={row['rmse']:.4g}  r={row['pearson_r']:.3f}")
    return 0
