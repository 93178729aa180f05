"""Modes of a phone (Chen et al. 2012, Section V-A).

Every occurrence of a phone is resampled with a cubic spline to ``K`` points
on its local time [0, 1], all channels stacked (each channel divided by its
standard deviation over the corpus so no channel dominates by its units);
affinity propagation (Frey & Dueck 2007, scikit-learn) clusters the
occurrences of each phone, the number of modes found automatically.

A phone gets exactly one mode, and the reason is recorded, when it has too
few occurrences, when affinity propagation does not converge, or when the
caller asks for single modes. Clusters smaller than ``min_mode_size`` are
merged into the nearest larger one (a mode needs data to be fitted).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np

__all__ = ["resample_occurrences", "cluster_modes", "ModeClustering"]


def resample_occurrences(trajectory: np.ndarray, frame_rate: float, starts, ends, n_points: int) -> np.ndarray:
    """Each segment's trajectory resampled to ``n_points`` on its local time [0, 1].

    One cubic spline through all frames of the utterance is evaluated at
    ``start + u * (end - start)``, ``u = linspace(0, 1, n_points)``, so short
    segments (fewer frames than points) are resampled from their neighbourhood;
    times beyond the last frame are clamped to it.

    Parameters
    ----------
    trajectory : ndarray, shape (n_frames, n_channels)
    frame_rate : float
    starts, ends : array-like, shape (n_segments,)
        Segment times in seconds.
    n_points : int
        K >= 2.

    Returns
    -------
    ndarray, shape (n_segments, n_points, n_channels)
    """
    from scipy.interpolate import CubicSpline

    traj = np.asarray(trajectory, dtype=float)
    starts = np.asarray(starts, dtype=float)
    ends = np.asarray(ends, dtype=float)
    u = np.linspace(0.0, 1.0, n_points)
    times = starts[:, None] + u[None, :] * (ends - starts)[:, None]
    frames = np.clip(times * frame_rate, 0.0, traj.shape[0] - 1)
    if traj.shape[0] == 1:
        return np.broadcast_to(traj[0], frames.shape + traj.shape[1:]).copy()
    if traj.shape[0] < 4:  # too few frames for a not-a-knot cubic: linear
        return np.stack(
            [np.interp(frames, np.arange(traj.shape[0]), traj[:, c]) for c in range(traj.shape[1])], axis=-1
        )
    spline = CubicSpline(np.arange(traj.shape[0]), traj, axis=0)
    return spline(frames)


@dataclass
class ModeClustering:
    """Result of :func:`cluster_modes` for one phone.

    Attributes
    ----------
    labels : ndarray of int, shape (n_occurrences,)
        Mode of each occurrence, 0 .. n_modes - 1.
    n_modes : int
    exemplars : ndarray of int, shape (n_modes,)
        Index of the occurrence that exemplifies each mode.
    reason : str
        Why there is a single mode ("" when clustering decided).
    """

    labels: np.ndarray
    n_modes: int
    exemplars: np.ndarray
    reason: str = ""
    details: dict = field(default_factory=dict)


def cluster_modes(
    features: np.ndarray,
    *,
    method: str = "affinity",
    min_occurrences: int = 6,
    min_mode_size: int = 3,
    preference="median",
    damping: float = 0.7,
    max_iter: int = 400,
    random_state=0,
) -> ModeClustering:
    """Cluster one phone's occurrences into modes by affinity propagation.

    Parameters
    ----------
    features : ndarray, shape (n_occurrences, n_features)
        Resampled, standardized occurrences, flattened.
    method : {"affinity", "single"}, default "affinity"
    min_occurrences : int, default 6
        Fewer occurrences than this: one mode.
    min_mode_size : int, default 3
        Modes with fewer occurrences are merged into the nearest other mode
        (by squared distance between exemplars).
    preference : "median", "min" or float, default "median"
        Affinity propagation's preference (self-similarity): the median or the
        minimum of the negative squared distances, or a given value. Lower
        preferences give fewer modes.
    damping, max_iter, random_state
        Passed to :class:`sklearn.cluster.AffinityPropagation`.

    Returns
    -------
    ModeClustering
    """
    X = np.asarray(features, dtype=float)
    n = X.shape[0]

    def single(reason: str) -> ModeClustering:
        return ModeClustering(np.zeros(n, dtype=int), 1, np.array([0]), reason)

    if method == "single":
        return single("modes='single'")
    if method != "affinity":
        raise ValueError(f"parameter 'modes' is {method!r}; use 'affinity' or 'single'")
    if n < max(min_occurrences, 2):
        return single(f"too few occurrences ({n} < {max(min_occurrences, 2)})")
    d2 = ((X[:, None, :] - X[None, :, :]) ** 2).sum(-1)
    S = -d2
    if np.allclose(d2, 0.0):
        return single("all occurrences identical")
    off = S[~np.eye(n, dtype=bool)]
    if isinstance(preference, str):
        if preference not in ("median", "min"):
            raise ValueError(f"parameter 'mode_preference' is {preference!r}; use 'median', 'min' or a number")
        pref = float(np.median(off) if preference == "median" else off.min())
    else:
        pref = float(preference)

    from sklearn.cluster import AffinityPropagation
    from sklearn.exceptions import ConvergenceWarning

    ap = AffinityPropagation(
        affinity="precomputed", preference=pref, damping=damping, max_iter=max_iter, random_state=random_state
    )
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ConvergenceWarning)
        ap.fit(S)
    if (
        any(issubclass(w.category, ConvergenceWarning) for w in caught)
        or np.any(ap.labels_ < 0)
        or len(ap.cluster_centers_indices_) == 0
    ):
        return single(f"affinity propagation did not converge in {max_iter} iterations")
    labels = np.asarray(ap.labels_, dtype=int)
    exemplars = np.asarray(ap.cluster_centers_indices_, dtype=int)
    labels, exemplars, merged = _merge_small(labels, exemplars, d2, min_mode_size)
    if len(exemplars) == 1:
        reason = (
            "affinity propagation found one mode"
            if merged == 0
            else f"all but one mode smaller than min_mode_size={min_mode_size}"
        )
        return ModeClustering(labels, 1, exemplars, reason, {"merged": merged})
    return ModeClustering(labels, len(exemplars), exemplars, "", {"merged": merged})


def _merge_small(labels, exemplars, d2, min_size):
    """Merge clusters below ``min_size`` into the nearest remaining exemplar; relabel 0..k-1."""
    merged = 0
    while len(exemplars) > 1:
        sizes = np.bincount(labels, minlength=len(exemplars))
        small = int(np.argmin(sizes))
        if sizes[small] >= min_size:
            break
        others = [k for k in range(len(exemplars)) if k != small]
        members = np.flatnonzero(labels == small)
        # each member joins the nearest other exemplar
        dist = d2[np.ix_(members, exemplars[others])]
        labels[members] = np.asarray(others)[np.argmin(dist, axis=1)]
        keep = np.array(others)
        remap = -np.ones(len(exemplars), dtype=int)
        remap[keep] = np.arange(len(keep))
        labels = remap[labels]
        exemplars = exemplars[keep]
        merged += 1
    # order modes by size (largest first) so mode 0 is the most common shape
    sizes = np.bincount(labels, minlength=len(exemplars))
    order = np.argsort(-sizes, kind="stable")
    remap = np.empty_like(order)
    remap[order] = np.arange(len(order))
    return remap[labels], exemplars[order], merged
