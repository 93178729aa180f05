"""Vocal-tract outlines from VocalTractLab: real geometry as "captured motion".

VocalTractLab (``vocaltractlab-cython``, the ``vtl`` extra) computes, for any
of its tract states (19 parameters, :data:`dam.datasets.vtl.VTL_CHANNELS`),
the midsagittal outline of the vocal tract as four polylines: ``upper``
(upper lip, teeth, palate, velum, pharynx wall), ``lower`` (lower lip,
teeth, jaw), ``tongue`` and ``epiglottis``. :func:`tract_outlines` resamples
each polyline to a fixed number of points equally spaced along its length,
so a trajectory of tract states becomes a trajectory of 2-D points, one
flattened ``x0, y0, x1, y1, ...`` row per frame (centimetres) -- motion
nobody on this project designed, to cross-map and retarget.

:func:`toy_tract_rig` builds a small linear blendshape rig on the same points
whose controls in [0, 1] are named articulatory gestures (jaw opening,
tongue fronting, lip rounding, ...), each the outline difference between two
of VTL's stock shapes.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence

import numpy as np

from dam.corpus.data import Corpus, DataError
from dam.crossmap.rig import LinearRig, check_frames, map_trajectories
from dam.datasets.vtl import VTL_CHANNELS, import_vtl

__all__ = [
    "CONTOURS",
    "TOY_CONTROLS",
    "resample_contour",
    "outline_channels",
    "tract_outlines",
    "outline_corpus",
    "vtl_shape",
    "toy_tract_rig",
    "plot_outline",
]

#: The polylines VTL's ``vtlGetOutlines`` returns, in its order.
CONTOURS = ("upper", "lower", "tongue", "epiglottis")

#: Toy rig controls: name -> (VTL shape at 1, VTL shape at 0). Each control
#: moves the outline from the second shape towards the first.
TOY_CONTROLS = {
    "jaw_open": ("a", "@"),
    "tongue_front": ("i", "@"),
    "lip_round": ("y", "i"),
    "tongue_back": ("u", "y"),
    "lip_close": ("ll-labial-closure(a)", "a"),
    "tip_up": ("tt-alveolar-closure(a)", "a"),
    "dorsum_up": ("tb-velar-closure(a)", "a"),
}


def resample_contour(points, n_points: int) -> np.ndarray:
    """``n_points`` points equally spaced along a polyline, ends kept.

    Parameters
    ----------
    points : array-like, shape (n, 2)
    n_points : int, at least 2

    Returns
    -------
    ndarray, shape (n_points, 2)
    """
    P = np.asarray(points, dtype=float)
    if P.ndim != 2 or P.shape[0] < 1:
        raise DataError(None, "points", P.shape, "must be (n, d) with at least one point")
    if int(n_points) < 2:
        raise DataError(None, "n_points", n_points, "must be at least 2")
    seg = np.linalg.norm(np.diff(P, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    if s[-1] <= 0:
        return np.repeat(P[:1], n_points, axis=0)
    keep = np.concatenate([[True], seg > 0])  # repeated points would break interpolation
    s, P = s[keep], P[keep]
    t = np.linspace(0.0, s[-1], int(n_points))
    return np.stack([np.interp(t, s, P[:, d]) for d in range(P.shape[1])], axis=1)


def _check_contours(contours) -> tuple[str, ...]:
    contours = (contours,) if isinstance(contours, str) else tuple(contours)
    for c in contours:
        if c not in CONTOURS:
            raise DataError(None, "contours", c, f"unknown contour; VTL has {', '.join(CONTOURS)}")
    if not contours:
        raise DataError(None, "contours", contours, "name at least one contour")
    return contours


def outline_channels(contours: Sequence[str] = CONTOURS, n_points: int = 16) -> list[str]:
    """Channel names of :func:`tract_outlines`: ``tongue03_x``, ``tongue03_y``, ..."""
    return [f"{c}{i:02d}_{ax}" for c in _check_contours(contours) for i in range(n_points) for ax in "xy"]


def _outline(vtl, state, contours, n_points) -> np.ndarray:
    lines = vtl.get_outlines(np.ascontiguousarray(state, dtype=float))
    return np.concatenate([resample_contour(lines[c], n_points).ravel() for c in contours])


def tract_outlines(
    states, *, contours: Sequence[str] = CONTOURS, n_points: int = 16, step: int = 1, verbose: int = 0
) -> np.ndarray:
    """Outline point trajectories of tract-parameter trajectories.

    Parameters
    ----------
    states : array-like, shape (n_frames, 19) or (19,)
        VTL tract states (``HX HY JX JA LP LD VS VO TCX TCY TTX TTY TBX TBY
        TRX TRY TS1 TS2 TS3``), one per frame.
    contours : sequence of str, default all of :data:`CONTOURS`
    n_points : int, default 16
        Points per contour, equally spaced along it.
    step : int, default 1
        Compute every ``step``-th frame (and the last) and interpolate the
        others with a cubic spline. VTL takes about 10-40 ms per outline;
        ``step=2`` halves that at 100 frames/s at a small cost in accuracy
        (measure it with ``step=1`` on a phrase).
    verbose : int, default 0
        1 shows a progress bar on a terminal.

    Returns
    -------
    ndarray, shape (n_frames, len(contours) * n_points * 2)
        Columns as in :func:`outline_channels` (centimetres).
    """
    vtl = import_vtl()
    contours = _check_contours(contours)
    n_params = vtl.get_constants()["n_tract_params"]
    X = check_frames(states, "states", n_dims=n_params, dims_name="VTL's number of tract parameters")
    step = int(step)
    if step < 1:
        raise DataError(None, "step", step, "must be a positive integer")
    rows = np.arange(0, len(X), step)
    if rows[-1] != len(X) - 1:
        rows = np.append(rows, len(X) - 1)
    from tqdm.auto import tqdm

    show = verbose > 0 and sys.stderr.isatty()
    out = np.stack(
        [
            _outline(vtl, X[i], contours, n_points)
            for i in tqdm(rows, desc="outlines", disable=not show, file=sys.stderr)
        ]
    )
    if len(rows) == len(X):
        return out
    if len(rows) < 4:
        return np.stack([np.interp(np.arange(len(X)), rows, out[:, j]) for j in range(out.shape[1])], 1)
    from scipy.interpolate import CubicSpline

    return CubicSpline(rows, out, axis=0)(np.arange(len(X)))


def outline_corpus(
    corpus: Corpus, *, contours: Sequence[str] = CONTOURS, n_points: int = 16, step: int = 1, verbose: int = 0
) -> Corpus:
    """A corpus of tract parameters (e.g. ``dam.datasets.load("vtl")``) as outline trajectories.

    The alignments, frame rate and names are kept; the channels become
    :func:`outline_channels`. The corpus's channels must be VTL's 19 tract
    parameters (in any order).
    """
    missing = [c for c in VTL_CHANNELS if c not in corpus.channels]
    if missing:
        raise DataError(
            corpus.source, "channels", list(corpus.channels), f"not VTL tract parameters: missing {', '.join(missing)}"
        )
    order = [corpus.channels.index(c) for c in VTL_CHANNELS]
    names = outline_channels(contours, n_points)
    out = map_trajectories(
        corpus,
        lambda F: tract_outlines(F[:, order], contours=contours, n_points=n_points, step=step, verbose=verbose),
        names,
        name_suffix="outlines",
    )
    out.metadata.update({"outline_contours": list(_check_contours(contours)), "outline_points": int(n_points)})
    return out


def vtl_shape(name: str) -> np.ndarray:
    """The tract state (19,) of one of the speaker's stock shapes (``"a"``, ``"i"``,
    ``"tt-alveolar-closure(a)"``...)."""
    vtl = import_vtl()
    try:
        return np.asarray(vtl.get_shape(name, "tract"), dtype=float)
    except Exception as exc:
        raise DataError(None, "shape", name, f"not a shape of the VTL speaker ({exc})") from None


def toy_tract_rig(
    *, contours: Sequence[str] = CONTOURS, n_points: int = 16, controls: dict | None = None, neutral: str = "@"
) -> LinearRig:
    """A linear blendshape rig on outline points with named controls in [0, 1].

    Parameters
    ----------
    contours, n_points
        The point layout, as in :func:`tract_outlines`.
    controls : dict, default :data:`TOY_CONTROLS`
        Control name -> (VTL shape at 1, VTL shape at 0); the control's delta
        is the outline of the first minus the outline of the second.
    neutral : str, default "@"
        VTL shape of the rig at all controls 0 (schwa).

    Returns
    -------
    LinearRig
        ``len(controls)`` controls, bounds [0, 1].
    """
    controls = TOY_CONTROLS if controls is None else controls
    shapes = {n for pair in controls.values() for n in pair} | {neutral}
    lines = {n: tract_outlines(vtl_shape(n), contours=contours, n_points=n_points)[0] for n in sorted(shapes)}
    deltas = np.stack([lines[a] - lines[b] for a, b in controls.values()])
    return LinearRig(lines[neutral], deltas, control_names=list(controls), bounds=(0.0, 1.0))


def plot_outline(frame, *, contours: Sequence[str] = CONTOURS, n_points: int = 16, ax=None, **style):
    """Draw one outline frame (flattened points) as polylines; returns the axes."""
    import matplotlib.pyplot as plt

    contours = _check_contours(contours)
    F = np.asarray(frame, dtype=float).reshape(len(contours), n_points, 2)
    ax = ax or plt.gca()
    label = style.pop("label", None)
    for k, pts in enumerate(F):
        ax.plot(pts[:, 0], pts[:, 1], label=label if k == 0 else None, **style)
    ax.set_aspect("equal")
    return ax
