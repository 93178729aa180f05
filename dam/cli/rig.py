"""``dam crossmap``, ``dam retarget`` and ``dam rigsolve``: captured motion to rig controls.

Registered in :data:`dam.cli._EXTERNAL`; the heavy modules are imported by
the handlers only. Matrices (key shapes, rigs, poses) are ``.npy`` files or
comma-separated ``.csv`` files without a header, one row per shape/pose/
control, coordinates flattened ``x0, y0, x1, y1, ...``.
"""

from __future__ import annotations

import argparse

from dam.cli.common import info

_MATRIX_NOTE = (
    "Matrix files: .npy, or .csv with comma-separated numbers and no header; one row\n"
    "per shape, pose or control, coordinates flattened x0,y0,x1,y1,..."
)


def _save_matrix(arr, path) -> None:
    import numpy as np

    from dam.corpus.atomic import atomic_write

    if str(path).endswith(".npy"):
        with atomic_write(path, "wb") as fh:
            np.save(fh, np.asarray(arr, dtype=float))
    else:
        with atomic_write(path, "w") as fh:
            np.savetxt(fh, np.atleast_2d(arr), delimiter=",", fmt="%.10g")


def _check_outputs(args, corpora=(), matrices=(), files=()) -> None:
    """Before any work: -o OUT_DIR and the matrix files written (``files``: option names)
    are not inputs (the corpora and ``matrices`` options), not inside an input corpus,
    and their directories exist; an OUT_DIR holding files needs --overwrite."""
    from dam.corpus.atomic import check_output

    inputs = list(corpora) + [getattr(args, m, None) for m in matrices]
    if getattr(args, "output", None):
        check_output(args.output, inputs=inputs, directory=True, overwrite=args.overwrite)
    for opt in files:
        if getattr(args, opt, None):
            check_output(getattr(args, opt), inputs=inputs, option="--" + opt.replace("_", "-"))


def _name_file(args, exc, fields: dict) -> None:
    """Put the file a bad matrix came from into a DataError raised without a source."""
    from dam.corpus.data import DataError
    from dam.crossmap.rig import name_source

    if isinstance(exc, DataError):
        name_source(exc, getattr(args, fields.get(str(exc.field).split("[")[0], ""), None))


def _with_files(**fields):
    """Decorator: errors about a matrix name the file it was read from (field -> argument)."""

    def wrap(cmd):
        def run(args):
            try:
                return cmd(args)
            except Exception as exc:
                _name_file(args, exc, fields)
                raise

        run.__name__, run.__doc__ = cmd.__name__, cmd.__doc__
        return run

    return wrap


def _names(text):
    return None if text is None else [s.strip() for s in text.split(",") if s.strip()]


def _rig(args):
    from dam.crossmap.rig import LinearRig

    if args.rig_deltas is None:
        return None
    kw = {"control_names": _names(args.control_names)} if args.control_names else {}
    return LinearRig.from_files(args.rig_deltas, args.rig_neutral, bounds=tuple(args.bounds), **kw)


def _add_io(p, what: str) -> None:
    p.add_argument("-o", "--output", metavar="OUT_DIR", help=f"corpus directory to write the {what} to")
    p.add_argument("--format", choices=("csv", "npy"), default="csv", help="trajectory files (default: csv)")
    p.add_argument("--overwrite", action="store_true", help="replace OUT_DIR if it exists and holds files")


def _add_outline_options(p) -> None:
    g = p.add_argument_group("VocalTractLab outlines (captured motion from tract parameters)")
    g.add_argument(
        "--outlines",
        action="store_true",
        help="the corpus holds VTL's 19 tract parameters: turn every frame into outline points first",
    )
    g.add_argument(
        "--contours",
        default="upper,lower,tongue,epiglottis",
        help="outline contours, comma-separated (default: all four)",
    )
    g.add_argument("--n-points", type=int, default=16, help="points per contour (default: 16)")
    g.add_argument(
        "--step", type=int, default=1, help="compute every STEP-th frame and spline the rest (default: 1, exact)"
    )


def _load(args, spec):
    from dam.datasets import resolve

    corpus = resolve(spec)
    if getattr(args, "outlines", False):
        from dam.crossmap.outlines import outline_corpus

        info(args, f"computing outlines of {corpus!r}")
        corpus = outline_corpus(
            corpus,
            contours=_names(args.contours),
            n_points=args.n_points,
            step=args.step,
            verbose=0 if args.quiet else 1,
        )
    return corpus


def _write(args, corpus, what: str) -> None:
    from dam.corpus.atomic import atomic_directory
    from dam.corpus.io import save_corpus

    if args.output:
        with atomic_directory(args.output, overwrite=args.overwrite) as tmp:  # whole or not at all
            save_corpus(corpus, tmp, trajectory_format=args.format)
        info(args, f"wrote {what} {corpus!r} to {args.output}")
    else:
        info(args, f"{what} computed but not written: give -o OUT_DIR")


# -- crossmap ---------------------------------------------------------------
def add_crossmap(sub) -> None:
    p = sub.add_parser(
        "crossmap",
        help="cross-map captured shapes to rig controls (NNLS, Chen et al. 2012 App. A)",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description=(
            "Cross-map the captured motion in CAPTURED (a corpus directory or bundled name; each frame a\n"
            "flattened shape) to a character's controls, keeping the alignments:\n"
            "  1. key shapes: --key-shapes, or found by affinity propagation (--save-key-shapes writes them);\n"
            "  2. per-frame non-negative blend weights over the key shapes (NNLS);\n"
            "  3. with --target-key-shapes (the key shapes posed on the character, same row order) and a\n"
            "     linear rig (--rig-deltas, --rig-neutral): controls fitted to the blended vertices, each\n"
            "     within --bounds (bounded least squares). Without a target the weights are the output.\n\n"
            + _MATRIX_NOTE
            + "\n"
            "  --key-shapes          (n_key_shapes, n_dims)   n_dims = channels of CAPTURED\n"
            "  --target-key-shapes   (n_key_shapes, n_target_dims)\n"
            "  --rig-deltas          (n_controls, n_target_dims)   V(c) = neutral + c @ deltas\n"
            "  --rig-neutral         (n_target_dims,) or one row; default zeros"
        ),
        epilog=(
            "examples:\n"
            "  dam crossmap vtl:train --outlines --save-key-shapes keys.npy -o weights/\n"
            "  dam crossmap captured/ --key-shapes keys.npy --target-key-shapes posed.npy \\\n"
            "      --rig-deltas deltas.npy --rig-neutral neutral.npy --control-names jaw,lips -o controls/"
        ),
    )
    p.add_argument("captured", metavar="CAPTURED", help="corpus directory or bundled corpus name")
    _add_io(p, "controls")
    p.add_argument(
        "--key-shapes", metavar="FILE", help="key shapes chosen by the artist (default: affinity propagation)"
    )
    p.add_argument("--save-key-shapes", metavar="FILE", help="write the key shapes (.npy/.csv) for the artist to pose")
    p.add_argument("--target-key-shapes", metavar="FILE", help="the key shapes posed on the target character")
    p.add_argument("--rig-deltas", metavar="FILE", help="linear rig blendshapes, one row per control")
    p.add_argument("--rig-neutral", metavar="FILE", help="linear rig neutral vertices (default: zeros)")
    p.add_argument("--control-names", metavar="A,B,...", help="output channel names")
    p.add_argument(
        "--bounds",
        nargs=2,
        type=float,
        default=(0.0, 1.0),
        metavar=("LO", "HI"),
        help="bounds of every control (default: 0 1)",
    )
    p.add_argument(
        "--preference",
        default=None,
        help="affinity propagation preference: a number, 'min' (few key shapes) or unset (median)",
    )
    p.add_argument("--damping", type=float, default=0.9, help="affinity propagation damping (default: 0.9)")
    p.add_argument(
        "--max-frames", type=int, default=2000, help="cluster at most this many evenly spaced frames (default: 2000)"
    )
    _add_outline_options(p)
    p.set_defaults(func=cmd_crossmap)


@_with_files(
    key_shapes="key_shapes",
    target_key_shapes="target_key_shapes",
    deltas="rig_deltas",
    neutral="rig_neutral",
    vertices="target_key_shapes",
)
def cmd_crossmap(args) -> int:
    from dam.corpus.data import DataError
    from dam.crossmap.crossmapping import CrossMapper
    from dam.crossmap.rig import load_matrix

    if args.target_key_shapes is not None and args.rig_deltas is None:  # before the slow part
        raise DataError(None, "--rig-deltas", None, "--target-key-shapes needs the target's rig (--rig-deltas)")
    _check_outputs(
        args,
        [args.captured],
        ("key_shapes", "target_key_shapes", "rig_deltas", "rig_neutral"),
        files=("save_key_shapes",),
    )
    pref = args.preference
    if pref is not None and pref != "min":
        try:
            pref = float(pref)
        except ValueError:
            raise DataError(None, "--preference", pref, "must be a number or 'min'") from None
    captured = _load(args, args.captured)
    cm = CrossMapper(
        key_shapes=None if args.key_shapes is None else load_matrix(args.key_shapes, "key_shapes"),
        target_key_shapes=None
        if args.target_key_shapes is None
        else load_matrix(args.target_key_shapes, "target_key_shapes"),
        rig=_rig(args),
        bounds=tuple(args.bounds),
        preference=pref,
        damping=args.damping,
        max_frames=args.max_frames,
        control_names=_names(args.control_names) if args.rig_deltas is None else None,
    )
    cm.fit(captured)
    info(
        args,
        f"{len(cm.key_shapes_)} key shapes"
        + ("" if cm.key_frame_indices_ is None else f" (frames {cm.key_frame_indices_.tolist()})"),
    )
    if args.save_key_shapes:
        _save_matrix(cm.key_shapes_, args.save_key_shapes)
        info(args, f"wrote key shapes {cm.key_shapes_.shape} to {args.save_key_shapes}")
    if args.output:
        _write(args, cm.transform(captured), "controls" if args.target_key_shapes else "blend weights")
    elif not args.save_key_shapes:
        info(args, "nothing written: give -o OUT_DIR and/or --save-key-shapes FILE")
    return 0


# -- retarget -----------------------------------------------------------------
def add_retarget(sub) -> None:
    p = sub.add_parser(
        "retarget",
        help="rig-space retargeting (Taylor et al. 2017, Sec. 6)",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description=(
            "Rig-space retargeting. The principal modes of REFERENCE (a corpus directory or bundled name)\n"
            "give 2K reference poses, the mean +/- 3 standard deviations along each of the first K modes\n"
            "(--save-poses writes them, rows ordered 1-, 1+, 2-, 2+, ...). An artist poses each on the rig;\n"
            "with those rig parameters (--rig-poses, same order) and the rig's parameters for the mean\n"
            "shape (--rig-neutral), every frame of INPUT (default: REFERENCE) becomes rig parameters:\n"
            "  w_k^u = max(p_k / (u sqrt(lambda_k)), 0)      (Eq. 2)\n"
            "  r = (R - r0) w + r0                          (Eq. 3)\n\n" + _MATRIX_NOTE + "\n"
            "  --rig-poses    (2K, n_rig) absolute rig parameters, rows ordered 1-, 1+, 2-, 2+, ...\n"
            "  --rig-neutral  (n_rig,) or one row"
        ),
        epilog=(
            "examples:\n"
            "  dam retarget reference/ --n-modes 4 --save-poses poses.csv\n"
            "  dam retarget reference/ --rig-poses rig_poses.csv --rig-neutral r0.csv "
            "--input predicted/ -o rig/"
        ),
    )
    p.add_argument("reference", metavar="REFERENCE", help="corpus whose principal modes define the poses")
    _add_io(p, "rig parameters")
    p.add_argument("--input", metavar="CORPUS", help="corpus to retarget (default: REFERENCE)")
    p.add_argument(
        "--n-modes",
        type=_n_modes,
        default="auto",
        help="K, principal modes posed on the rig (default: auto, 4 or as many as the reference has "
        "dimensions if fewer)",
    )
    p.add_argument("--sigma", type=float, default=3.0, help="poses at +/- this many standard deviations (default: 3)")
    p.add_argument("--save-poses", metavar="FILE", help="write the 2K reference poses for the artist")
    p.add_argument("--rig-poses", metavar="FILE", help="the artist's rig parameters for the 2K poses")
    p.add_argument("--rig-neutral", metavar="FILE", help="the rig parameters of the mean shape, r0")
    p.add_argument("--rig-names", metavar="A,B,...", help="output channel names")
    p.add_argument(
        "--bounds",
        nargs=2,
        type=float,
        default=None,
        metavar=("LO", "HI"),
        help="clip the rig parameters (Eq. 3 does not; default: no clipping)",
    )
    _add_outline_options(p)
    p.set_defaults(func=cmd_retarget)


def _n_modes(text: str):
    if text == "auto":
        return text
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--n-modes expects an integer or 'auto', got {text!r}") from None


@_with_files(rig_poses="rig_poses", rig_neutral="rig_neutral", rig_names="rig_names")
def cmd_retarget(args) -> int:
    from dam.corpus.data import DataError
    from dam.crossmap.retarget import RigSpaceRetargeter
    from dam.crossmap.rig import load_matrix

    if not args.sigma > 0:
        raise DataError(None, "--sigma", args.sigma, "must be a positive number of standard deviations")
    _check_outputs(args, [args.reference, args.input], ("rig_poses", "rig_neutral"), files=("save_poses",))
    reference = _load(args, args.reference)
    if (args.rig_poses is None) != (args.rig_neutral is None):
        raise DataError(
            None,
            "--rig-poses" if args.rig_poses is None else "--rig-neutral",
            None,
            "--rig-poses and --rig-neutral go together",
        )
    rt = RigSpaceRetargeter(
        n_modes=args.n_modes,
        u=(-args.sigma, args.sigma),
        rig_poses=None if args.rig_poses is None else load_matrix(args.rig_poses, "rig_poses"),
        rig_neutral=None if args.rig_neutral is None else load_matrix(args.rig_neutral, "rig_neutral").ravel(),
        rig_names=_names(args.rig_names),
        bounds=None if args.bounds is None else tuple(args.bounds),
    )
    rt.fit(reference)
    share = ", ".join(f"{100 * v:.1f}%" for v in rt.explained_variance_ratio_)
    n_modes = rt.components_.shape[0]
    info(args, f"{n_modes} modes explain {100 * rt.explained_variance_ratio_.sum():.1f}% of the variance ({share})")
    if args.save_poses:
        _save_matrix(rt.reference_poses(), args.save_poses)
        info(args, f"wrote {2 * n_modes} reference poses to {args.save_poses}")
    if args.rig_poses is not None:
        data = reference if args.input is None else _load(args, args.input)
        _write(args, rt.transform(data), "rig parameters")
    elif args.output:
        raise DataError(None, "--rig-poses", None, "-o needs the artist's rig poses (--rig-poses, --rig-neutral)")
    return 0


# -- rigsolve -------------------------------------------------------------------
def add_rigsolve(sub) -> None:
    p = sub.add_parser(
        "rigsolve",
        help="landmarks to rig parameters (L-BFGS + L1 prior, Medina et al. 2022, Sec. 7)",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description=(
            "Solve, frame by frame, the rig parameters whose landmarks best match LANDMARKS (a corpus\n"
            "directory or bundled name; each frame flattened x0,y0,x1,y1,...):\n"
            "  min ||C(theta) - y||^2 + alpha * sum |theta|     within --bounds, warm-started (Eqs. 2-4)\n"
            "C is a linear rig (--rig-deltas, --rig-neutral). With --neutral the captured neutral pose is\n"
            "aligned to the rig's neutral landmarks by a similarity transform first.\n\n" + _MATRIX_NOTE
        ),
        epilog="example: dam rigsolve ema/ --rig-deltas rig.npy --rig-neutral n.npy --symmetric 0:1,2:3 -o rig/",
    )
    p.add_argument("landmarks", metavar="LANDMARKS", help="corpus of landmark trajectories")
    _add_io(p, "rig parameters")
    p.add_argument("--rig-deltas", metavar="FILE", required=True, help="(n_params, n_coords) rig landmark deltas")
    p.add_argument("--rig-neutral", metavar="FILE", help="(n_coords,) rig landmarks at theta = 0")
    p.add_argument("--control-names", metavar="A,B,...", help="output channel names")
    p.add_argument("--alpha", type=float, default=0.01, help="weight of the L1 prior (default: 0.01, the paper's)")
    p.add_argument(
        "--bounds",
        nargs=2,
        type=float,
        default=(0.0, 1.0),
        metavar=("LO", "HI"),
        help="bounds of every parameter (default: 0 1)",
    )
    p.add_argument("--symmetric", metavar="I:J,...", help="tie parameters I and J (left/right), comma-separated")
    p.add_argument("--neutral", metavar="FILE", help="captured landmarks of the neutral pose (n_coords,)")
    p.add_argument("--landmark-dim", type=int, default=2, help="coordinates per landmark (default: 2)")
    p.set_defaults(func=cmd_rigsolve)


@_with_files(deltas="rig_deltas", neutral="rig_neutral", X="neutral")
def cmd_rigsolve(args) -> int:
    from dam.corpus.data import DataError
    from dam.crossmap.landmarks import LandmarkSolver
    from dam.crossmap.rig import load_matrix

    _check_outputs(args, [args.landmarks], ("rig_deltas", "rig_neutral", "neutral"))
    pairs = None
    if args.symmetric:
        try:
            pairs = [tuple(int(v) for v in item.split(":")) for item in args.symmetric.split(",")]
        except ValueError:
            raise DataError(None, "--symmetric", args.symmetric, "expected I:J pairs, e.g. 0:1,2:3") from None
    solver = LandmarkSolver(
        rig=_rig(args),
        alpha=args.alpha,
        bounds=tuple(args.bounds),
        symmetric_pairs=pairs,
        landmark_dim=args.landmark_dim,
    )
    solver.fit(None if args.neutral is None else load_matrix(args.neutral, "neutral").reshape(1, -1))
    out = solver.transform(_load(args, args.landmarks))
    _write(args, out, "rig parameters")
    return 0
