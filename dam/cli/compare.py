"""``dam compare`` and ``dam demo``: several models on held-out data."""

from __future__ import annotations

import os
import sys

from dam.cli.common import info, parse_param
from dam.evaluation.compare import compare, run_demo


def add_compare(sub) -> None:
    p = sub.add_parser(
        "compare",
        help="fit several models and compare them on held-out data",
        description="Fit every model of --models on --train, score it on --test (or by --cv K-fold "
        "cross-validation on --train) and write summary.csv, per_channel.csv, per_utterance.csv, "
        "summary.md and figures to --out. Prints the Markdown table.",
        epilog="example: dam compare --models dam,dam-m0,cohen-massaro,mmm,dtree --train vtl:train "
        "--test vtl:test --out results/ --jobs 2",
    )
    p.add_argument(
        "--models",
        required=True,
        help="comma-separated registry names (see `dam models`); LABEL=NAME gives a variant its "
        "own row, e.g. dtree,dtree-ling=dtree with --param dtree-ling.features=linguistic",
    )
    p.add_argument("--train", required=True, metavar="CORPUS", help="corpus directory or bundled name (e.g. vtl:train)")
    p.add_argument("--test", metavar="CORPUS", help="held-out corpus directory or bundled name")
    p.add_argument("--cv", type=int, metavar="K", help="K-fold cross-validation on --train instead of --test")
    p.add_argument("--out", metavar="DIR", help="directory for the tables and figures")
    p.add_argument("--jobs", type=int, default=1, help="parallel joblib workers over models and folds (-1: all cores)")
    p.add_argument(
        "-p",
        "--param",
        action="append",
        default=[],
        metavar="LABEL.KEY=VALUE",
        help="hyperparameter of one model (repeatable), e.g. mmm.order=1",
    )
    p.add_argument("--seed", type=int, default=0, help="seed of the split, folds and bootstrap (default 0)")
    p.add_argument("--channels", metavar="C1,C2,...", help="compare on these channels only (default: all)")
    p.set_defaults(func=cmd_compare)


def cmd_compare(args) -> int:
    if args.test and args.cv:
        raise ValueError("give --test or --cv, not both")
    specs = []
    for item in (m.strip() for m in args.models.split(",") if m.strip()):
        label, _, name = item.partition("=")
        specs.append((label, name or label, {}))
    by_label = {s[0]: s for s in specs}
    for text in args.param:
        key, value = parse_param(text)
        label, dot, k = key.partition(".")
        if not dot or label not in by_label:
            raise ValueError(f"--param {text!r}: expected LABEL.KEY=VALUE with LABEL one of {list(by_label)}")
        by_label[label][2][k] = value
    channels = [c.strip() for c in args.channels.split(",") if c.strip()] if args.channels else None
    res = compare(
        specs,
        args.train,
        args.test,
        cv=args.cv,
        n_jobs=args.jobs,
        out=args.out,
        random_state=args.seed,
        channels=channels,
        verbose=0 if args.quiet else 1,
    )
    print(res.table())
    if args.out and not args.quiet:
        print(
            f"wrote {os.path.join(args.out, 'summary.csv')}, per_channel.csv, per_utterance.csv, "
            f"{'per_sensor.csv, ' if res.per_sensor else ''}summary.md, predictions.png, rmse.png",
            file=sys.stderr,
        )
    return 1 if any(r["status"] == "failed" for r in res.summary) else 0


def add_demo(sub) -> None:
    p = sub.add_parser(
        "demo",
        help="fit the models on the bundled corpus and compare them (under a minute)",
        description="Fit the DAM and the classical models it is compared with on the bundled "
        "VocalTractLab corpus's training part, score them on its held-out part on "
        "three channels (jaw, lips, tongue tip) and print the comparison table; tables "
        "and figures go to --out. Under a minute on two cores; --full adds the 1993 "
        "Cohen-Massaro model and the linguistic decision tree on six channels "
        "(several minutes).",
    )
    p.add_argument("--corpus", default="vtl", help="bundled corpus (default: vtl; 'tiny' takes seconds)")
    p.add_argument("--out", default="dam-demo", help="directory for the tables and figures (default: dam-demo)")
    p.add_argument("--jobs", type=int, default=2, help="parallel workers (default 2; -1: all cores)")
    p.add_argument(
        "--full",
        action="store_true",
        help="six channels and eight models, Cohen-Massaro (1993) and the linguistic tree too (slower)",
    )
    p.add_argument("--all-channels", action="store_true", help="every channel of the corpus (slower)")
    p.set_defaults(func=cmd_demo)


def cmd_demo(args) -> int:
    from dam.corpus.atomic import check_output

    check_output(args.out, directory=True, merge=True, option="--out")
    run_demo(
        args.out,
        corpus=args.corpus,
        n_jobs=args.jobs,
        channels=None if args.all_channels else "demo",
        full=args.full,
        verbose=0 if args.quiet else 1,
    )
    info(
        args,
        f"\ntables and figures: {os.path.join(args.out, '')} (summary.md, per_channel.csv, predictions.png, rmse.png)",
    )
    return 0
