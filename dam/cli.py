"""The ``dam`` command line.

Conventions: ``--help`` on every command; results on standard output,
progress and messages on standard error; exit status 0 on success, 1 on bad
input (a one-line ``dam: error: ...`` naming the file, the field and the
value, never a traceback; ``--debug`` shows it), 2 on bad usage.

A subcommand is a function ``add_<name>(subparsers)`` that registers its
parser and sets ``func``; commands that live in other modules are listed in
``_EXTERNAL`` as ``"module:function"`` and imported when the parser is built
(keep heavy imports inside their handlers).
"""
from __future__ import annotations

import argparse
import json
import sys

from . import __version__

# "module:function" adders of subcommands that live beside their code.
_EXTERNAL: list[str] = [
    "dam.cli_rig:add_crossmap", "dam.cli_rig:add_retarget", "dam.cli_rig:add_rigsolve",
    "dam.datasets.vtl:add_generate_vtl",
    "dam.compare:add_compare",
    "dam.model:add_inspect",
]


def _corpus(spec):
    from .datasets import resolve
    return resolve(spec)


def parse_param(text: str) -> tuple[str, object]:
    """``key=value`` with value read as JSON when it can be (numbers, true/false, null, lists)."""
    if "=" not in text:
        raise argparse.ArgumentTypeError(f"--param expects key=value, got {text!r}")
    key, _, raw = text.partition("=")
    lowered = {"true": True, "false": False, "none": None, "null": None}
    if raw.lower() in lowered:
        return key.strip(), lowered[raw.lower()]
    try:
        return key.strip(), json.loads(raw)
    except json.JSONDecodeError:
        return key.strip(), raw


def _info(args, msg: str) -> None:
    if not getattr(args, "quiet", False):
        print(msg, file=sys.stderr)


# -- models ---------------------------------------------------------------
def add_models(sub) -> None:
    p = sub.add_parser("models", help="list the registered synthesizers",
                       description="List every registered synthesizer, what it reads and what it needs.")
    p.set_defaults(func=cmd_models)


def cmd_models(args) -> int:
    from .registry import _REGISTRY, available, get
    width = max(len(n) for n in _REGISTRY)
    for name in _REGISTRY:
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
    from . import make
    model = make(args.model)
    model.set_params(**dict(args.param))
    corpus = _corpus(args.corpus)
    _info(args, f"fitting {model!r} on {corpus!r}")
    t0 = time.perf_counter()
    model.fit(corpus)
    _info(args, f"fitted in {time.perf_counter() - t0:.2f} s; training RMSE {-model.score(corpus):.4g}")
    model.save(args.output)
    _info(args, f"saved {args.output}")
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
    from .base import load
    from .io import read_alignment, write_csv
    model = load(args.model_file)
    alignment = read_alignment(args.alignment, tier=args.tier)
    y = model.predict(alignment)
    write_csv(y, model.channels_, sys.stdout if args.output == "-" else args.output,
              frame_rate=model.frame_rate_)
    if args.output != "-":
        _info(args, f"wrote {len(y)} frames x {y.shape[1]} channels to {args.output}")
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
    from .base import load
    from .metrics import evaluate
    model = load(args.model_file)
    ev = evaluate(model, _corpus(args.corpus))
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


# -- demo -----------------------------------------------------------------
def add_demo(sub) -> None:
    p = sub.add_parser("demo", help="fit the models on the bundled corpus and compare them",
                       description="Fit the DAM and the models it is compared with on the bundled "
                                   "VocalTractLab corpus's training part, score them on its held-out part "
                                   "and print the comparison table; tables and figures go to --out.")
    p.add_argument("--corpus", default="vtl", help="bundled corpus (default: vtl; 'tiny' takes a minute)")
    p.add_argument("--out", default="dam-demo", help="directory for the tables and figures (default: dam-demo)")
    p.add_argument("--jobs", type=int, default=2, help="parallel workers (default 2; -1: all cores)")
    p.add_argument("--all-channels", action="store_true", help="every channel, not the demo's six (slower)")
    p.set_defaults(func=cmd_demo)


def cmd_demo(args) -> int:
    from .compare import run_demo
    run_demo(args.out, corpus=args.corpus, n_jobs=args.jobs, channels=None if args.all_channels else "demo",
             verbose=0 if args.quiet else 1)
    _info(args, f"\ntables and figures: {args.out}/ (summary.md, per_channel.csv, predictions.png, rmse.png)")
    return 0


# -- parser and main ------------------------------------------------------
def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="dam", description="Speech animation and coarticulation modelling: fit, predict, evaluate "
                                "and compare synthesizers that turn phone timings into trajectories.")
    parser.add_argument("--version", action="version", version=f"dam {__version__}")
    parser.add_argument("-q", "--quiet", action="store_true", help="no progress or messages on standard error")
    parser.add_argument("--debug", action="store_true", help="show Python tracebacks on errors")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for adder in (add_models, add_fit, add_predict, add_evaluate, add_demo):
        adder(sub)
    import importlib
    for spec in _EXTERNAL:
        module, _, fn = spec.partition(":")
        getattr(importlib.import_module(module), fn)(sub)
    return parser


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except KeyboardInterrupt:
        print("dam: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return 0
    except Exception as exc:
        if args.debug:
            raise
        msg = exc.args[0] if isinstance(exc, KeyError) and exc.args else str(exc)
        print(f"dam: error: {msg}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
