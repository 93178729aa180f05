"""Animation files on the command line: the export options shared by ``dam predict`` and
``dam animate``, ``--stream``, and ``dam export-runtime`` (the tiny runtime)."""

from __future__ import annotations

import os
import sys

import numpy as np

from dam.cli.common import info

FORMATS_HELP = ".csv, .json, .gltf, .glb, .TextGrid, .gif, .mp4 or .html"


def add_export_options(p) -> None:
    """The options of :func:`dam.export.export` that a command passes through."""
    g = p.add_argument_group("animation files (dam.export; the format follows the output's extension)")
    g.add_argument(
        "--map",
        metavar="MAP.json",
        help="first map the model's channels linearly onto rig targets: a dam-linear-map JSON file "
        "(sources, targets or preset 'arkit'/'oculus', matrix, offset); 'vtl:oculus' / 'vtl:arkit' "
        "for VTL tract parameters (the default model) fitted to the Oculus visemes of the bundled "
        "vtl corpus's phones (ARKit through a hand-made viseme table); or 'toy:arkit' / "
        "'toy:oculus' for the hand-made maps from the toy tract gestures",
    )
    g.add_argument(
        "--rig",
        metavar="MESH.glb",
        help="glTF only: animate this asset's morph targets (matched by name) instead of dam's own mesh",
    )
    g.add_argument(
        "--rig-names",
        metavar="NAMES.json",
        help='glTF with --rig: control -> morph target names that differ, e.g. {"JA": "jawOpen"}',
    )
    g.add_argument(
        "--weights",
        choices=("clip", "scale"),
        default="clip",
        help="glTF: bring weights outside [0, 1] into range by clipping (default) or by rescaling "
        "each control that leaves it; either is reported",
    )
    g.add_argument(
        "--mesh",
        choices=("auto", "vtl", "toy", "bars"),
        default="auto",
        help="glTF without --rig: dam's own mesh (auto: the VocalTractLab ribbon for VTL tract "
        "parameters or toy gestures, else a bar per control)",
    )
    from dam.cli.articulators import add_articulator_options

    add_articulator_options(p)


def check_export_options(parser, args, output: str) -> None:
    """Usage errors (exit 2) for options that do not fit the output format."""
    ext = os.path.splitext(output)[1].lower()
    gltf = ext in (".gltf", ".glb")
    if (args.rig or args.rig_names or args.weights != "clip" or args.mesh != "auto") and not gltf:
        parser.error(f"--rig, --rig-names, --weights and --mesh are for .gltf/.glb outputs, not {ext or output}")
    if args.rig_names and not args.rig:
        parser.error("--rig-names goes with --rig")
    if args.rig and args.mesh != "auto":
        parser.error("--mesh is dam's own mesh; with --rig the rig is the mesh")
    from dam.cli.articulators import check_articulator_options

    check_articulator_options(parser, args, output)


def _linear_map(spec):
    from dam.export.presets import LinearMap

    if spec in ("toy:arkit", "toy:oculus"):
        return LinearMap.hand_made(*spec.split(":"))
    if spec in ("vtl:arkit", "vtl:oculus"):
        return LinearMap.vtl(spec.split(":")[1])
    return LinearMap.load(spec)


def write_animation(args, values, channels, frame_rate, path, *, alignment=None, metadata=None, model=None):
    """Map (``--map``), export to ``path`` with the command's options, report clipping on stderr.

    The DAM's chosen modes go into ``.json`` and ``.TextGrid`` outputs.
    Returns the :class:`dam.export.ExportReport`.
    """
    from dam.export import export
    from dam.export.textgrid import chosen_modes

    if getattr(args, "map", None):
        m = _linear_map(args.map)
        values, channels = m.apply(values, channels), list(m.targets)
        info(args, f"mapped {len(m.sources)} channels onto {len(m.targets)} targets with {args.map}")
        moved = np.any(m.matrix != 0, axis=0) | (m.offset != 0)
        if getattr(args, "rig", None) and not moved.all():
            # a target the map never moves needs no morph target in the rig
            values, channels = values[:, moved], [c for c, k in zip(channels, moved) if k]
            info(args, f"animating the {len(channels)} targets the map moves")
    ext = os.path.splitext(path)[1].lower()
    opts = {}
    if ext in (".gltf", ".glb"):
        opts = {"rig": args.rig, "mapping": args.rig_names, "weights": args.weights, "mesh": args.mesh}
        if args.rig:
            opts.pop("mesh")
        else:
            opts.pop("rig"), opts.pop("mapping")
    elif ext in (".gif", ".mp4", ".html"):
        from dam.cli.articulators import articulator_options

        opts = articulator_options(args, channels, frame_rate, len(values), alignment)
    elif ext in (".json", ".textgrid") and model is not None and alignment is not None:
        modes = chosen_modes(model, alignment)
        if modes is not None:
            opts["modes"] = modes
    rep = export(values, path, channels=channels, frame_rate=frame_rate, alignment=alignment, metadata=metadata, **opts)
    for line in rep.messages():
        info(args, line)
    return rep


def stream_csv(model, alignment, out=None, *, max_duration=None) -> int:
    """Push ``alignment``'s phones one by one into a stream; print each final frame as a CSV line.

    The header is ``time`` and the channels. Returns the number of frames printed.
    """
    from dam.export.streaming import stream

    out = sys.stdout if out is None else out
    longest = float(alignment.durations.max())
    s = stream(model, max_duration=max(longest, max_duration or 0.0))
    out.write(",".join(["time", *s.channels]) + "\n")
    out.flush()
    n = 0

    def emit(frames):
        nonlocal n
        for row in frames:
            out.write(",".join([repr(n / s.frame_rate), *(repr(float(v)) for v in row)]) + "\n")
            n += 1
        out.flush()

    for lab, end in zip(alignment.labels, alignment.ends):
        emit(s.push(lab, end=float(end)))
    emit(s.finish())
    return n


# -- dam export-runtime --------------------------------------------------------------------------
def add_export_runtime(sub) -> None:
    p = sub.add_parser(
        "export-runtime",
        help="write a fitted model for the numpy-only tiny runtime",
        description="Write a fitted model (dam, dam-m0, cohen-massaro, phone-mean) to one small "
        ".json or .npz file that "
        "dam_runtime.py, a single numpy-only module copied beside it, loads and "
        "synthesizes from without this toolkit installed (same output to 1e-9).",
        epilog="example: dam export-runtime model.npz -o app/face.dam.json  "
        "(then in the app: import dam_runtime; dam_runtime.load('face.dam.json'))",
    )
    p.add_argument("model_file", metavar="MODEL_FILE", help="a fitted model (dam fit ... -o model.npz)")
    p.add_argument("-o", "--output", required=True, metavar="OUT.json|OUT.npz", help="the runtime model file")
    p.add_argument("--no-module", action="store_true", help="do not copy dam_runtime.py beside the output")
    p.set_defaults(func=cmd_export_runtime, _parser=p)


def cmd_export_runtime(args) -> int:
    from dam.corpus.atomic import check_output
    from dam.export.runtime import copy_runtime, export_runtime
    from dam.modelfile import load

    if os.path.splitext(args.output)[1].lower() not in (".json", ".npz"):
        args._parser.error(f"-o {args.output}: the runtime model is a .json or .npz file")
    check_output(args.output, inputs=[args.model_file])
    model = load(args.model_file)
    size = export_runtime(model, args.output)
    info(args, f"wrote {args.output} ({size / 1024:.1f} kB)")
    if not args.no_module:
        dest = copy_runtime(os.path.dirname(os.path.abspath(args.output)))
        info(args, f"wrote {dest} (numpy only)")
    return 0
