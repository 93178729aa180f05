"""``dam models``, ``dam fit``, ``dam predict``, ``dam evaluate``: one model at a time."""

from __future__ import annotations

import json
import sys

from dam.cli.common import corpus_arg, info, parse_param


# -- models ---------------------------------------------------------------
def add_models(sub) -> None:
    p = sub.add_parser(
        "models",
        help="list the registered synthesizers",
        description="List every registered synthesizer, what it reads and what it needs.",
    )
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
            extra = f" [extra: {', '.join(tags['requires'])}, installed]" if tags["requires"] else ""
            print(f"{name:<{width}}  reads {'+'.join(tags['reads']):<12} {doc}{extra}")
        else:  # why names the missing module and the pip command (dam.registry.MissingExtraError)
            print(f"{name:<{width}}  unavailable: {why}")
    return 0


# -- fit ------------------------------------------------------------------
def add_fit(sub) -> None:
    p = sub.add_parser(
        "fit",
        help="fit a model on a corpus and save it",
        description="Fit MODEL on the corpus in CORPUS (a directory, or a bundled corpus "
        "name such as 'tiny' or 'vtl:train') and save it to MODEL_FILE.",
        epilog="example: dam fit dam corpus/train -o m.dam --param degree=4",
    )
    p.add_argument("model", metavar="MODEL", help="registered model name (see `dam models`)")
    p.add_argument("corpus", metavar="CORPUS", help="corpus directory or bundled corpus name")
    p.add_argument("-o", "--output", required=True, metavar="MODEL_FILE", help="where to write the fitted model")
    p.add_argument(
        "-p",
        "--param",
        action="append",
        default=[],
        type=parse_param,
        metavar="KEY=VALUE",
        help="set a hyperparameter (repeatable); values are read as JSON when possible",
    )
    p.set_defaults(func=cmd_fit)


def cmd_fit(args) -> int:
    import time

    from dam.corpus.atomic import check_output
    from dam.registry import check_params, make

    model = make(args.model)
    model.set_params(**dict(args.param))
    check_params(model)  # bad names, values and paths are refused before any work starts
    check_output(args.output, inputs=[args.corpus])
    corpus = corpus_arg(args.corpus)
    info(args, f"fitting {model!r} on {corpus!r}")
    t0 = time.perf_counter()
    from dam.progress import task

    with task("fit", 1, unit="model") as bar:  # on a terminal the clock runs from the first second
        bar.begin(args.model)
        model.fit(corpus)
        bar.step(args.model)
    info(args, f"fitted in {time.perf_counter() - t0:.2f} s; training RMSE {-model.score(corpus):.4g}")
    model.save(args.output)
    info(args, f"saved {args.output}")
    return 0


# -- predict --------------------------------------------------------------
def add_predict(sub) -> None:
    p = sub.add_parser(
        "predict",
        help="synthesize trajectories for an alignment",
        description="Synthesize the trajectory for ALIGNMENT_FILE (.TextGrid or HTK .lab) "
        "with a fitted model and write it as CSV with a time column.",
    )
    p.add_argument("model_file", metavar="MODEL_FILE", help="a fitted model (written by `dam fit` or model.save)")
    p.add_argument(
        "alignment",
        metavar="ALIGNMENT_FILE",
        help="the phone timings to animate: a Praat .TextGrid or an HTK/xwaves .lab file",
    )
    p.add_argument(
        "-o",
        "--output",
        default="-",
        metavar="OUT",
        help="output file, its extension picks the format (.csv, .json, .gltf, .glb, .TextGrid; "
        "see dam.export); default: CSV on standard output",
    )
    p.add_argument("--tier", default="phones", help="TextGrid tier with the phones (default: phones)")
    p.add_argument(
        "--overwrite", action="store_true", help="replace OUT even if it is a file of a corpus (never an input)"
    )
    from dam.cli.export import add_export_options

    add_export_options(p)
    p.set_defaults(func=cmd_predict, _parser=p)


def cmd_predict(args) -> int:
    from dam.cli.export import check_export_options, write_animation
    from dam.corpus.atomic import check_output
    from dam.corpus.io import read_alignment, write_csv
    from dam.modelfile import load

    check_export_options(args._parser, args, ".csv" if args.output == "-" else args.output)
    if args.output != "-":
        check_output(args.output, inputs=[args.model_file, args.alignment], overwrite=args.overwrite)
    model = load(args.model_file)
    alignment = read_alignment(args.alignment, tier=args.tier)
    y = model.predict(alignment)
    if args.output == "-":
        if args.map:
            from dam.cli.export import _linear_map

            m = _linear_map(args.map)
            y, names = m.apply(y, model.channels_), list(m.targets)
        else:
            names = model.channels_
        write_csv(y, names, sys.stdout, frame_rate=model.frame_rate_)
        return 0
    write_animation(
        args,
        y,
        model.channels_,
        model.frame_rate_,
        args.output,
        alignment=alignment,
        metadata={"model": model.name},
        model=model,
    )
    info(args, f"wrote {len(y)} frames x {y.shape[1]} channels to {args.output}")
    return 0


# -- evaluate -------------------------------------------------------------
def add_evaluate(sub) -> None:
    p = sub.add_parser(
        "evaluate",
        help="score a fitted model on a corpus",
        description="RMSE (in channel units) and Pearson r, overall and per channel, "
        "of a fitted model on a corpus; for EMA-like corpora also the mean "
        "Euclidean distance per sensor (Medina et al. 2022, Eq. 1). Frames "
        "masked as missing are not scored.",
    )
    p.add_argument("model_file", metavar="MODEL_FILE")
    p.add_argument("corpus", metavar="CORPUS", help="corpus directory or bundled corpus name")
    p.add_argument("--json", action="store_true", help="print JSON instead of a table")
    p.add_argument("--per-utterance", action="store_true", help="also print one line per utterance")
    p.set_defaults(func=cmd_evaluate)


def cmd_evaluate(args) -> int:
    from dam.evaluation.metrics import evaluate
    from dam.modelfile import load

    model = load(args.model_file)
    ev = evaluate(model, corpus_arg(args.corpus))
    if args.json:
        print(
            json.dumps(
                {
                    "rmse": ev.rmse,
                    "pearson_r": ev.pearson_r,
                    "channels": {
                        c: {"rmse": float(e), "pearson_r": float(r)}
                        for c, e, r in zip(ev.channels, ev.rmse_per_channel, ev.pearson_per_channel)
                    },
                    "sensor_error": None if not ev.sensors else ev.sensor_error,
                    "sensors": {
                        k: {"channels": list(v), "distance": float(e)}
                        for (k, v), e in zip(ev.sensors.items(), ev.sensor_error_per_sensor)
                    },
                    "length_unit": ev.length_unit,
                    "per_utterance": ev.per_utterance if args.per_utterance else None,
                },
                indent=2,
            )
        )
        return 0
    print(ev.table())
    if args.per_utterance:
        print()
        for row in ev.per_utterance:
            sensor = f"  sensor_error={row['sensor_error']:.4g}" if "sensor_error" in row else ""
            print(
                f"{row['utterance']}  frames={row['n_frames']}  rmse={row['rmse']:.4g}  "
                f"r={row['pearson_r']:.3f}{sensor}"
            )
    return 0
