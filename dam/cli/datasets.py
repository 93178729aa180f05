"""``dam generate-vtl``, ``dam vtl-lexicon`` and ``dam generate-tiny``: make the bundled corpora again."""

from __future__ import annotations

import argparse

from dam.datasets.vtl import LEXICON_PATH, extract_articubench_lexicon, generate_vtl_corpus


def add_generate_arguments(p: argparse.ArgumentParser, *, quiet: bool = True) -> None:
    """The options of ``generate`` (shared with ``dam generate-vtl``, which has its own ``-q``)."""
    p.add_argument("out_dir", help="directory that receives train/ and test/")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument(
        "--train-minutes",
        type=float,
        default=10.0,
        dest="n_train_minutes",
        metavar="MIN",
        help="speech in train/, pauses included (default 10)",
    )
    p.add_argument(
        "--test-minutes",
        type=float,
        default=2.5,
        dest="n_test_minutes",
        metavar="MIN",
        help="speech in test/ (default 2.5)",
    )
    p.add_argument(
        "--test-word-fraction",
        type=float,
        default=0.2,
        metavar="F",
        help="share of the words kept for test/ only (default 0.2)",
    )
    p.add_argument(
        "--frame-rate", type=float, default=100.0, metavar="HZ", help="output frame rate, at most 400.9 (default 100)"
    )
    p.add_argument(
        "--audio-fraction",
        type=float,
        default=0.05,
        metavar="F",
        help="share of phrases that also get 16 kHz audio (default 0.05; audio costs ~4 s of CPU per second of speech)",
    )
    p.add_argument(
        "--format",
        choices=("npy", "csv"),
        default="npy",
        dest="trajectory_format",
        help="trajectory files: float32 .npy (default) or .csv",
    )
    p.add_argument(
        "-j", "--n-jobs", type=int, default=1, metavar="N", help="worker processes, -1 for all cores (default 1)"
    )
    p.add_argument("--overwrite", action="store_true", help="replace existing train/ and test/")
    if quiet:
        p.add_argument("-q", "--quiet", action="store_true", help="no progress bars")


_DESCRIPTION = (
    "Generate an articulatory corpus with VocalTractLab: phrases of German words (phones and "
    "durations measured in real speech), varied speaking rate and pauses, synthesized into VTL's "
    "19 tract parameters at --frame-rate, some with 16 kHz audio; train/ and test/ use disjoint "
    "words. Same seed, same files."
)
_EPILOG = "the bundled corpus: dam generate-vtl dam/datasets/data/vtl --seed 0 --overwrite -j 2"


def add_generate_vtl(sub) -> None:
    p = sub.add_parser(
        "generate-vtl",
        help="generate a VocalTractLab articulatory corpus (needs dam[vtl])",
        description=_DESCRIPTION,
        epilog=_EPILOG,
    )
    add_generate_arguments(p, quiet=False)
    p.set_defaults(func=_cmd_generate_vtl)


def _cmd_generate_vtl(args) -> int:
    run_generate(args)
    return 0


def run_generate(args) -> dict:
    corpora = generate_vtl_corpus(
        args.out_dir,
        seed=args.seed,
        n_train_minutes=args.n_train_minutes,
        n_test_minutes=args.n_test_minutes,
        test_word_fraction=args.test_word_fraction,
        frame_rate=args.frame_rate,
        audio_fraction=args.audio_fraction,
        trajectory_format=args.trajectory_format,
        n_jobs=args.n_jobs,
        verbose=0 if getattr(args, "quiet", False) else 1,
        overwrite=args.overwrite,
    )
    for split, c in corpora.items():
        print(f"{split}: {c!r} -> {c.source}")
    return corpora


def add_vtl_audio(sub) -> None:
    p = sub.add_parser(
        "vtl-audio",
        help="synthesize the audio of (more of) the vtl corpus (needs dam[vtl,audio])",
        description="Give a generated vtl corpus its audio, in place: VocalTractLab synthesizes each phrase again "
        "from its gestural score (same seed, same phrases; every stored trajectory must come out bit "
        "for bit), and 16 kHz 16-bit FLAC goes beside it as <stem>.flac. Phrases that have their FLAC "
        "are skipped (the cache): stop it any time and run it again. Audio costs about 3 s of CPU "
        "per second of speech (about 35 CPU-minutes for the whole bundled corpus).",
        epilog="the whole bundled corpus: dam vtl-audio --fraction 1   (run it with nice on a shared machine)",
    )
    p.add_argument(
        "root", nargs="?", default=None, help="directory with train/ and test/ (default: the bundled vtl corpus)"
    )
    p.add_argument(
        "--fraction",
        type=float,
        default=1.0,
        metavar="F",
        help="share of the phrases of each split that should have audio (default 1)",
    )
    p.add_argument(
        "--max-cpu-minutes",
        type=float,
        default=None,
        metavar="MIN",
        help="stop starting phrases after this much CPU time (default: no limit)",
    )
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_vtl_audio)


def _cmd_vtl_audio(args) -> int:
    from dam.corpus.data import DataError
    from dam.datasets import path as dataset_path
    from dam.datasets.vtl import add_vtl_audio

    if not 0 <= args.fraction <= 1:
        raise DataError(None, "--fraction", args.fraction, "must be between 0 and 1")
    root = args.root or str(dataset_path("vtl"))
    report = add_vtl_audio(
        root,
        fraction=args.fraction,
        verbose=0 if args.quiet else 1,
        max_cpu_seconds=None if args.max_cpu_minutes is None else 60 * args.max_cpu_minutes,
    )
    for split, r in report.items():
        print(
            f"{split}: {r['audio']} of {r['n']} phrases have audio ({r['added']} new), "
            f"{r['seconds'] / 60:.1f} min of speech, {r['bytes'] / 1e6:.1f} MB of FLAC"
        )
    return 0


def add_vtl_lexicon(sub) -> None:
    p = sub.add_parser(
        "vtl-lexicon",
        help="extract the VTL word list from articubench (maintainers)",
        description="Extract the word list of the vtl corpus generator from articubench's "
        "data/lexical_embedding_vectors.pkl (needs pandas).",
    )
    p.add_argument("pkl", help="path to articubench/data/lexical_embedding_vectors.pkl")
    p.add_argument("--out", default=None, help="output path (default: the bundled word list)")
    p.set_defaults(func=_cmd_vtl_lexicon)


def _cmd_vtl_lexicon(args) -> int:
    out = args.out or str(LEXICON_PATH)
    n = extract_articubench_lexicon(args.pkl, out)
    print(f"wrote {n} words to {out}")
    return 0


def add_generate_tiny(sub) -> None:
    p = sub.add_parser(
        "generate-tiny",
        help="write the tiny toy corpus (what the tests use)",
        description="Write the tiny corpus (30 utterances of a toy articulatory model, 4 channels, "
        "100 Hz) to OUT_DIR. OUT_DIR is written as a whole: it must not exist or be "
        "empty, unless --overwrite replaces it.",
        epilog="the bundled corpus: dam generate-tiny dam/datasets/data/tiny --overwrite",
    )
    p.add_argument("out_dir", metavar="OUT_DIR", help="directory to create (or replace, with --overwrite)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--overwrite", action="store_true", help="replace OUT_DIR if it exists and holds files")
    p.set_defaults(func=_cmd_generate_tiny)


def _cmd_generate_tiny(args) -> int:
    from dam.corpus.atomic import check_output
    from dam.datasets.tiny import write

    check_output(args.out_dir, directory=True, overwrite=args.overwrite, option="OUT_DIR")
    corpus = write(args.out_dir, overwrite=args.overwrite, seed=args.seed)
    print(f"wrote {corpus!r} to {args.out_dir}")
    return 0
