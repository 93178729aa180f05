"""Meshes of dam's own for glTF export: the VocalTractLab ribbon and a bank of bars.

The **VTL ribbon** is the midsagittal outline of VocalTractLab's JD3 speaker
(:func:`dam.crossmap.outlines.tract_outlines`: upper lip, palate and pharynx
wall; lower lip and jaw; tongue; epiglottis), each polyline drawn as a thin
flat strip in the x-y plane. Its morph targets are *linearised*: the outline
``O(x)`` of tract state ``x`` (19 parameters) is fitted by least squares as

    O(x) ~= a + J x

over the tract states of the bundled ``vtl`` corpus (every 6th frame of 40
utterances; a Jacobian at one state fits badly, R^2 0.08 on held-out frames,
because the outline points slide along the tongue as it stretches; the fit
gives R^2 0.97). With parameter ``k``'s VTL range ``[lo_k, hi_k]`` and
weight ``w_k = (x_k - lo_k) / (hi_k - lo_k)`` in [0, 1], the outline is
``base + sum_k w_k * target_k`` where ``target_k = J[:, k] (hi_k - lo_k)``
and ``base = a + J lo``. The toy rig controls
(:data:`dam.crossmap.outlines.TOY_CONTROLS`) get their exact outline
differences as targets, on the schwa outline.

The geometry is computed once with VocalTractLab (the ``vtl`` extra) and
bundled as ``data/vtl_ribbon.npz``, so exporting needs numpy only.
Regenerate it with ``python -m dam.export.meshes`` (about 30 s).

The **bars** mesh serves any other channels: one unit-wide bar per control
whose top rises by one unit at weight 1, a level meter a viewer can show.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

RIBBON_PATH = os.path.join(os.path.dirname(__file__), "data", "vtl_ribbon.npz")
#: Points per contour of the bundled ribbon.
RIBBON_POINTS = 40
#: Ribbon width (cm) and the scale from outline centimetres to glTF metres.
RIBBON_WIDTH_CM = 0.25
CM = 0.01

__all__ = ["MorphMesh", "vtl_ribbon_data", "vtl_ribbon", "toy_ribbon", "bars_mesh", "ribbon_strips", "RIBBON_PATH"]


@dataclass
class MorphMesh:
    """A triangle mesh with one morph target per control.

    Attributes
    ----------
    positions : ndarray, shape (n_vertices, 3)
        Base vertex positions (metres, y up).
    indices : ndarray of int, shape (n_triangles * 3,)
    targets : ndarray, shape (n_controls, n_vertices, 3)
        Displacement of every vertex at weight 1.
    names : tuple of str, length n_controls
    default_weights : ndarray, shape (n_controls,)
        Weights of the rest pose.
    to_weights : callable
        Maps control values (n_frames, n_controls) to morph weights.
    kind : str
        ``"vtl"``, ``"toy"`` or ``"bars"``.
    """

    positions: np.ndarray
    indices: np.ndarray
    targets: np.ndarray
    names: tuple
    default_weights: np.ndarray
    to_weights: object
    kind: str


def ribbon_strips(points, n_points: int, width: float = RIBBON_WIDTH_CM):
    """Turn flattened contour points into flat strips.

    Parameters
    ----------
    points : ndarray, shape (n_contours * n_points * 2,)
        ``x0, y0, x1, y1, ...`` per contour, as :func:`tract_outlines` returns.
    n_points : int
    width : float
        Strip width, in the units of ``points``.

    Returns
    -------
    vertices : ndarray, shape (n_contours * n_points * 2, 2)
        Two rim vertices per point, offset by half the width along the normal.
    owner : ndarray of int, shape (n_vertices,)
        Index of the contour point each vertex follows (for the targets).
    indices : ndarray of int, shape (n_contours * (n_points - 1) * 6,)
        Two triangles between consecutive point pairs.
    """
    P = np.asarray(points, dtype=float).reshape(-1, n_points, 2)
    verts, owner, tris = [], [], []
    for c, line in enumerate(P):
        tangent = np.gradient(line, axis=0)
        norm = np.linalg.norm(tangent, axis=1, keepdims=True)
        normal = np.stack([-tangent[:, 1], tangent[:, 0]], 1) / np.where(norm > 0, norm, 1.0)
        base = len(verts) and sum(len(v) for v in verts)
        verts.append(np.concatenate([line + 0.5 * width * normal, line - 0.5 * width * normal]))
        owner.append(np.concatenate([np.arange(n_points), np.arange(n_points)]) + c * n_points)
        i = np.arange(n_points - 1)
        a, b, c2, d = base + i, base + i + 1, base + n_points + i, base + n_points + i + 1
        tris.append(np.stack([a, c2, b, b, c2, d], 1).ravel())
    return np.concatenate(verts), np.concatenate(owner), np.concatenate(tris)


def vtl_ribbon_data(n_points: int = RIBBON_POINTS, *, every: int = 6, n_utterances: int = 40) -> dict:
    """Compute the ribbon's outline data with VocalTractLab (needs the ``vtl`` extra).

    Parameters
    ----------
    n_points : int, default 24
        Points per contour.
    every, n_utterances : int, default 6 and 40
        The linear fit uses every ``every``-th frame of the first
        ``n_utterances`` utterances of the bundled ``vtl`` corpus.

    Returns
    -------
    dict of ndarray
        ``intercept`` (n_dims,) and ``jacobian`` (19, n_dims) of the
        least-squares fit ``O(x) ~= intercept + x @ jacobian``; ``neutral``
        (n_dims,) the schwa outline; ``lo``, ``hi``, ``x0`` (19,);
        ``params`` (19,) names; ``toy_deltas`` (n_toy, n_dims) and
        ``toy_names``; ``n_points`` (). Outline units are centimetres.
    """
    import dam.datasets
    from dam.crossmap.outlines import TOY_CONTROLS, tract_outlines, vtl_shape
    from dam.datasets.vtl import VTL_CHANNELS, import_vtl

    vtl = import_vtl()
    info = {p["name"]: p for p in vtl.get_param_info("tract")}
    lo = np.array([float(info[n]["min"]) for n in VTL_CHANNELS])
    hi = np.array([float(info[n]["max"]) for n in VTL_CHANNELS])
    corpus = dam.datasets.load("vtl").select_channels(VTL_CHANNELS)
    X = np.concatenate([u.trajectory[::every] for u in corpus[:n_utterances]])
    outlines = tract_outlines(X, n_points=n_points)
    coef, *_ = np.linalg.lstsq(np.column_stack([np.ones(len(X)), X]), outlines, rcond=None)

    def outline(x):
        return tract_outlines(x, n_points=n_points)[0]

    x0 = vtl_shape("@")
    shapes = {n: outline(vtl_shape(n)) for n in sorted({s for pair in TOY_CONTROLS.values() for s in pair})}
    toy = np.stack([shapes[a] - shapes[b] for a, b in TOY_CONTROLS.values()])
    return {
        "intercept": coef[0],
        "jacobian": coef[1:],
        "neutral": outline(x0),
        "lo": lo,
        "hi": hi,
        "x0": x0,
        "params": np.array(VTL_CHANNELS),
        "toy_deltas": toy,
        "toy_names": np.array(list(TOY_CONTROLS)),
        "n_points": np.array(n_points),
    }


@lru_cache(maxsize=1)
def _bundled() -> dict:
    with np.load(RIBBON_PATH, allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


def _ribbon(outline_cm, targets_cm, n_points):
    """Strip geometry (metres, z = 0) with each rim vertex following its contour point."""
    verts, owner, indices = ribbon_strips(outline_cm, n_points)
    positions = np.column_stack([verts, np.zeros(len(verts))]) * CM
    d = np.asarray(targets_cm).reshape(len(targets_cm), -1, 2)[:, owner, :]
    targets = np.concatenate([d, np.zeros(d.shape[:2] + (1,))], axis=2) * CM
    return positions, indices, targets


def vtl_ribbon(channels) -> MorphMesh:
    """The ribbon driven by VTL tract parameters ``channels`` (a subset of the 19, any order).

    Weights are each parameter's position in its VTL range; parameters not
    among ``channels`` stay at the schwa.
    """
    data = _bundled()
    params = [str(p) for p in data["params"]]
    cols = [params.index(c) for c in channels]
    lo, hi, x0, J = data["lo"], data["hi"], data["x0"], data["jacobian"]
    span = hi - lo
    # Absent parameters stay at the schwa; present ones start from lo, moved by their weights.
    start = x0.copy()
    start[cols] = lo[cols]
    base = data["intercept"] + start @ J
    positions, indices, targets = _ribbon(base, J[cols] * span[cols, None], int(data["n_points"]))

    def to_weights(values):
        return (np.asarray(values, dtype=float) - lo[cols]) / span[cols]

    return MorphMesh(
        positions, indices, targets, tuple(channels), (x0[cols] - lo[cols]) / span[cols], to_weights, "vtl"
    )


def toy_ribbon(channels) -> MorphMesh:
    """The ribbon driven by toy-rig controls (``jaw_open``, ``lip_round``, ...); weights are the values."""
    data = _bundled()
    names = [str(p) for p in data["toy_names"]]
    cols = [names.index(c) for c in channels]
    positions, indices, targets = _ribbon(data["neutral"], data["toy_deltas"][cols], int(data["n_points"]))
    return MorphMesh(
        positions, indices, targets, tuple(channels), np.zeros(len(cols)), lambda v: np.asarray(v, dtype=float), "toy"
    )


def bars_mesh(channels, *, size: float = 0.01) -> MorphMesh:
    """A row of bars, one per control, each rising by ``10 * size`` metres at weight 1."""
    n = len(channels)
    k = np.arange(n, dtype=float)
    x0, x1 = k * 1.5 * size, (k * 1.5 + 1.0) * size
    y0, y1 = np.zeros(n), np.full(n, 0.5 * size)
    positions = np.stack(
        [
            np.column_stack([x0, y0, np.zeros(n)]),
            np.column_stack([x1, y0, np.zeros(n)]),
            np.column_stack([x0, y1, np.zeros(n)]),
            np.column_stack([x1, y1, np.zeros(n)]),
        ],
        axis=1,
    ).reshape(-1, 3)
    base = 4 * np.arange(n)[:, None]
    indices = (base + np.array([0, 1, 2, 2, 1, 3])).ravel()
    targets = np.zeros((n, 4 * n, 3))
    for j in range(n):
        targets[j, 4 * j + 2 : 4 * j + 4, 1] = 10 * size  # the top edge rises
    return MorphMesh(
        positions, indices, targets, tuple(channels), np.zeros(n), lambda v: np.asarray(v, dtype=float), "bars"
    )


def own_mesh(channels, kind: str = "auto", *, source=None) -> MorphMesh:
    """The mesh of dam's own for ``channels``: ``"vtl"``, ``"toy"``, ``"bars"`` or ``"auto"``.

    ``"auto"`` picks the VTL ribbon when every channel is a VTL tract
    parameter, the toy ribbon when every channel is a toy-rig control, else bars.
    """
    from dam.corpus import DataError

    data = _bundled()
    known = {"vtl": {str(p) for p in data["params"]}, "toy": {str(p) for p in data["toy_names"]}}
    if kind == "auto":
        kind = next((k for k in ("vtl", "toy") if set(channels) <= known[k]), "bars")
    if kind == "bars":
        return bars_mesh(channels)
    if kind not in known:
        raise DataError(source, "mesh", kind, "unknown mesh; use 'auto', 'vtl', 'toy' or 'bars'")
    missing = [c for c in channels if c not in known[kind]]
    if missing:
        raise DataError(
            source, "channels", missing, f"not controls of the {kind} ribbon", f"its controls are {sorted(known[kind])}"
        )
    return vtl_ribbon(channels) if kind == "vtl" else toy_ribbon(channels)


def _main() -> None:  # pragma: no cover - regenerates the bundled file
    data = vtl_ribbon_data()
    os.makedirs(os.path.dirname(RIBBON_PATH), exist_ok=True)
    from dam.corpus.atomic import atomic_write

    with atomic_write(RIBBON_PATH, "wb") as fh:
        np.savez_compressed(fh, **data)
    print(f"wrote {RIBBON_PATH}")


if __name__ == "__main__":  # pragma: no cover
    _main()
