"""``dam align`` and ``dam animate``: speech and text in (needs ``dam[audio]``)."""

from __future__ import annotations

import os
import sys
import time
import warnings

from dam.cli.common import info


def _transcript(args):
    """The transcript from --text or --transcript FILE (None if neither)."""
    if getattr(args, "transcript", None):
        from dam.corpus import DataError

        try:
            with open(args.transcript, encoding="utf-8") as fh:
                text = fh.read()
        except OSError as exc:
            raise DataError(args.transcript, "transcript", args.transcript, f"cannot read ({exc.strerror})") from None
        except UnicodeDecodeError:
            raise DataError(args.transcript, "transcript", args.transcript, "not UTF-8 text") from None
        return text
    return args.text


def _add_text_options(p, what: str) -> None:
    g = p.add_mutually_exclusive_group()
    g.add_argument("--text", metavar="T", help=f"{what} (quote it)")
    g.add_argument("--transcript", metavar="FILE", help=f"a UTF-8 text file holding {what}")


_ALIGN_DESCRIPTION = (
    "Align English speech to its transcript with pocketsphinx 5 (its bundled en-us acoustic model, "
    "offline) and write a Praat TextGrid with interval tiers 'words' and 'phones' (ARPAbet without "
    "stress digits, pauses 'sil'). Any sample rate, bit depth or channel count libsndfile reads "
    "(WAV, FLAC, OGG ...) is mixed down and resampled to 16 kHz. Numbers and punctuation in the "
    "transcript are read as a reader would say them. Without a transcript, pocketsphinx recognizes "
    "phones instead (LESS ACCURATE; no word tier). If the audio cannot be aligned, nothing is written."
)


def add_align(sub) -> None:
    p = sub.add_parser(
        "align",
        help="align speech audio to its transcript (TextGrid with words and phones)",
        description=_ALIGN_DESCRIPTION,
        epilog='example: dam align speech.wav --text "The birch canoe slid on the smooth planks." -o speech.TextGrid',
    )
    p.add_argument("audio", metavar="AUDIO", help="a sound file (WAV, FLAC ...)")
    _add_text_options(p, "the transcript")
    p.add_argument(
        "-o",
        "--output",
        metavar="OUT.TextGrid",
        help="the TextGrid to write (default: print the phones as start, end, label on stdout)",
    )
    p.set_defaults(func=_cmd_align, _parser=p)


def _cmd_align(args) -> int:
    from dam.speech import align, write_speech_textgrid

    if args.output and not args.output.lower().endswith(".textgrid"):
        args._parser.error(f"-o {args.output}: the output must be a .TextGrid file")
    if args.output:
        from dam.corpus.atomic import check_output  # before any work: never over an input

        check_output(args.output, inputs=[args.audio, args.transcript])
    text = _transcript(args)
    t0 = time.perf_counter()
    result = align(args.audio, text)
    seconds = time.perf_counter() - t0
    if result.less_accurate:
        print(
            "dam: warning: no transcript given: phones come from phone recognition, which is LESS "
            "ACCURATE than forced alignment (give --text or --transcript)",
            file=sys.stderr,
        )
    n_words = 0 if result.words is None else sum(w != result.words.silence for w in result.words.labels)
    info(
        args,
        f"{result.method}: {n_words} words, "
        f"{sum(p != result.phones.silence for p in result.phones.labels)} phones in "
        f"{result.duration:.2f} s of audio; took {seconds:.2f} s "
        f"(real-time factor {seconds / result.duration:.3f})",
    )
    if result.guessed:
        info(args, "not in the CMU dictionary, pronounced by rule: " + " ".join(result.guessed))
    if args.output:
        write_speech_textgrid(args.output, result.phones, result.words)
        info(args, f"wrote {args.output}")
    else:
        for s, e, lab in zip(result.phones.starts, result.phones.ends, result.phones.labels):
            print(f"{s:.3f}\t{e:.3f}\t{lab}")
    return 0


_ANIMATE_DESCRIPTION = (
    "Animate English text, speech audio (with or without its transcript) or a phone alignment with a "
    "model, and write the predicted controls to -o in the format its extension names (.csv with a time "
    "column; .json, .gltf/.glb, .TextGrid through dam's exporters; .gif, .mp4, .html: the moving vocal tract "
    "outline of VocalTractLab). Without --model, the default model "
    "shipped in the package is used: a DAM fitted on the bundled vtl corpus (German SAMPA; 19 "
    "VocalTractLab tract parameters at 100 Hz). Phones the model does not know are replaced by the "
    "nearest ones it knows (through IPA), and every replacement is reported."
)


def add_animate(sub) -> None:
    p = sub.add_parser(
        "animate",
        help="animate text, speech audio or an alignment with a model",
        description=_ANIMATE_DESCRIPTION,
        epilog='example: dam animate --text "The birch canoe slid on the smooth planks." '
        "-o out.csv   (or -o tongue.gif to watch the tongue move)",
    )
    src = p.add_argument_group(
        "input (exactly one of --audio, --text, --alignment; --text or --transcript with --audio is its transcript)"
    )
    src.add_argument("--audio", metavar="WAV", help="speech audio")
    src.add_argument("--text", metavar="T", help="English text (or the transcript of --audio)")
    src.add_argument("--transcript", metavar="FILE", help="the transcript of --audio, in a text file")
    src.add_argument("--alignment", metavar="FILE", help="phones with times (TextGrid, .lab ...)")
    p.add_argument(
        "--alphabet",
        choices=("arpabet", "ipa", "xsampa", "sampa", "german-sampa"),
        help="phone set of --alignment (default: guessed)",
    )
    p.add_argument(
        "--model",
        metavar="MODEL_FILE_OR_NAME",
        default="default",
        help="a model file (dam fit ... -o model.npz) or 'default' (the shipped DAM)",
    )
    p.add_argument("--durations", metavar="FILE", help="duration model file for --text (default: the shipped one)")
    p.add_argument(
        "--rate", type=float, default=1.0, help="speaking-rate factor for --text: 1.2 speaks 20%% faster (default 1.0)"
    )
    p.add_argument(
        "-o",
        "--output",
        metavar="OUT",
        help="output file; its extension picks the format (.csv, .json, .gltf, .glb, .TextGrid, "
        ".gif/.mp4/.html: the moving vocal tract); "
        "required unless --stream",
    )
    p.add_argument(
        "--overwrite", action="store_true", help="replace OUT even if it is a file of a corpus (never an input)"
    )
    p.add_argument(
        "--stream",
        action="store_true",
        help="print the frames to standard output as CSV lines (time, channels) as they become final, "
        "phone by phone (dam.export.streaming; the same values as the batch output)",
    )
    from dam.cli.export import add_export_options

    add_export_options(p)
    p.set_defaults(func=_cmd_animate, _parser=p)


def _cmd_animate(args) -> int:
    from dam.speech import PhoneApproximationWarning, animate

    p = args._parser
    given = [
        n
        for n, v in (
            ("--audio", args.audio),
            ("--text", args.text if not args.audio else None),
            ("--alignment", args.alignment),
        )
        if v
    ]
    if len(given) != 1:
        p.error(
            "give exactly one of --audio WAV [--text T | --transcript FILE], --text T, --alignment FILE"
            f" (got {', '.join(given) or 'none'})"
        )
    if args.transcript and not args.audio:
        p.error("--transcript goes with --audio (for text alone use --text)")
    if args.transcript and args.text:
        p.error("give the transcript once: --text or --transcript")
    if args.alphabet and not args.alignment:
        p.error("--alphabet goes with --alignment")
    if not (args.rate > 0):
        p.error(f"--rate must be positive, got {args.rate}")
    if not args.output and not args.stream:
        p.error("give -o OUT (.csv, .json, .gltf, .glb, .TextGrid) or --stream")
    if args.output and not os.path.splitext(args.output)[1]:
        p.error(f"-o {args.output}: give the output an extension (.csv, .json, .gltf, .glb, .TextGrid)")
    from dam.cli.export import check_export_options

    check_export_options(p, args, args.output or ".csv")
    from dam.corpus.atomic import check_output  # before any work: never over an input

    if args.output:
        check_output(
            args.output,
            inputs=[
                args.audio,
                args.transcript,
                args.alignment,
                args.durations,
                None if args.model == "default" else args.model,
            ],
            overwrite=args.overwrite,
        )
    text = _transcript(args)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PhoneApproximationWarning)  # printed below, once
        result = animate(
            text=text,
            audio=args.audio,
            alignment=args.alignment,
            model=args.model,
            durations=args.durations,
            rate=args.rate,
            alphabet=args.alphabet,
        )
    meta = result.metadata
    t0 = time.perf_counter()
    if args.stream:
        from dam.cli.export import stream_csv
        from dam.speech.animation import _resolve_model

        stream_csv(_resolve_model(args.model)[0], result.alignment)
    if args.output:
        _write(result, args.output, args)
    write_seconds = time.perf_counter() - t0
    if "LESS ACCURATE" in meta["method"]:
        print(
            "dam: warning: no transcript given: phones come from phone recognition, which is LESS "
            "ACCURATE than forced alignment (give --text or --transcript)",
            file=sys.stderr,
        )
    info(args, f"phones used: {' '.join(meta['phones'])}")
    if meta["model_phones"] != meta["phones"]:
        info(args, f"as the model's phones ({meta['model_alphabet']}): {' '.join(meta['model_phones'])}")
    for a in meta["approximations"]:
        info(
            args,
            f"approximated: {a['phone']} /{a['ipa']}/ -> {a['replacement']}"
            + (f" /{a['replacement_ipa']}/" if a["replacement_ipa"] else "")
            + f" ({a['reason']}; for {a['used_for']})",
        )
    if not meta["approximations"]:
        info(args, "approximated: none")
    if meta["guessed_words"]:
        info(args, "not in the CMU dictionary, pronounced by rule: " + " ".join(meta["guessed_words"]))
    n = result.trajectories.shape[0]
    info(
        args,
        f"{n} frames x {len(result.channels)} channels at {result.frame_rate:g} Hz "
        f"({meta['duration']:.2f} s) from {meta['source']} with {meta['model']}; "
        f"took {meta['seconds']:.3f} s (+{write_seconds:.3f} s to write) -> {args.output or 'stdout'}",
    )
    return 0


def _write(result, path, args) -> None:
    """Write through dam.export (the format from the extension), with the export options of ``args``."""
    from dam.cli.export import write_animation

    model = None
    if os.path.splitext(path)[1].lower() in (".json", ".textgrid"):  # they record the DAM's chosen modes
        from dam.speech.animation import _resolve_model

        model = _resolve_model(args.model)[0]
    write_animation(
        args,
        result.trajectories,
        result.channels,
        result.frame_rate,
        path,
        alignment=result.alignment,
        metadata=dict(result.metadata),
        model=model,
    )
