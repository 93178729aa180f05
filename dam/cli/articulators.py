"""The moving vocal tract on the command line: options of ``.gif``/``.mp4``/``.html`` outputs.

Shared by ``dam animate`` and ``dam predict`` through :func:`dam.cli.export.add_export_options`.
"""

from __future__ import annotations

import os

ARTICULATOR_EXTENSIONS = (".gif", ".mp4", ".html")  # dam.export.articulators.ARTICULATOR_FORMATS (import-free)


def add_articulator_options(p) -> None:
    g = p.add_argument_group(
        "moving vocal tract (.gif, .mp4 with ffmpeg, .html page with a player; needs "
        "VocalTractLab tract parameters, as the default model predicts)"
    )
    g.add_argument(
        "--fps", type=float, default=25.0, metavar="F", help="pictures per second of the animation (default 25)"
    )
    g.add_argument("--size", default="640x400", metavar="WxH", help="picture size in pixels (default 640x400)")
    g.add_argument(
        "--compare",
        metavar="MODEL_FILE",
        action="append",
        default=[],
        help="draw this model's prediction for the same phones beside it ('default' for the shipped model); repeatable",
    )
    g.add_argument(
        "--truth",
        metavar="TRAJECTORY",
        help="draw recorded controls beside it (.csv/.npy/EST track with the same channels), e.g. the "
        "utterance of the corpus whose alignment is animated",
    )


def _size(text: str):
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        return None
    return (w, h) if 64 <= w <= 4096 and 64 <= h <= 4096 else None


def check_articulator_options(parser, args, output: str) -> None:
    """Usage errors (exit 2) for articulator options that do not fit ``output``."""
    ext = os.path.splitext(output)[1].lower()
    used = args.fps != 25.0 or args.size != "640x400" or args.compare or args.truth
    if used and ext not in ARTICULATOR_EXTENSIONS:
        parser.error(f"--fps, --size, --compare and --truth are for .gif/.mp4/.html outputs, not {ext or output}")
    if not (0 < args.fps <= 120):
        parser.error(f"--fps must be in (0, 120], got {args.fps:g}")
    if _size(args.size) is None:
        parser.error(f"--size must be WIDTHxHEIGHT with each side 64 to 4096 pixels, got {args.size!r}")


def articulator_options(args, channels, frame_rate, n_frames, alignment) -> dict:
    """The options of :func:`dam.export.articulators.write_articulators` from the command line."""
    from dam.corpus import DataError

    compare = []
    for spec in args.compare:
        from dam.speech.animation import _resolve_model

        model, name = _resolve_model(spec)
        if list(model.channels_) != list(channels):
            raise DataError(
                spec,
                "channels",
                list(model.channels_),
                "the --compare model predicts other channels than the animated one",
            )
        compare.append(("default" if spec == "default" else os.path.basename(name), model.predict(alignment)))
    if args.truth:
        from dam.corpus.io import read_trajectory
        from dam.export.articulators import controls_at

        data, names, fr = read_trajectory(args.truth)
        if names is not None:
            missing = [c for c in channels if c not in names]
            if missing:
                raise DataError(args.truth, "channels", list(names), f"missing {', '.join(missing)}")
            data = data[:, [list(names).index(c) for c in channels]]
        elif data.shape[1] != len(channels):
            raise DataError(args.truth, "columns", data.shape[1], f"expected {len(channels)} channels")
        if fr is not None and abs(fr - frame_rate) > 1e-9:  # onto the animation's frames
            data = controls_at(data, fr, [i / float(frame_rate) for i in range(n_frames)])
        compare.append(("recorded", data[:n_frames]))
    return {"fps": args.fps, "size": _size(args.size), "compare": compare}
