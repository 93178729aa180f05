"""Rig-space retargeting (Taylor et al. 2017, Section 6, Eqs. 2-3).

Motion in a reference space (AAM shape parameters in the paper; here any
trajectories: outline points, EMA sensors, another rig's controls) reaches a
character rig through a handful of poses the artist makes once:

1. :func:`principal_modes` -- the principal modes of the reference
   trajectories: mean ``s_0``, orthonormal modes ``s_k``, eigenvalues
   ``lambda_k`` (variances).
2. :func:`retargeting_poses` -- the reference shapes
   ``s_k^u = s_0 + s_k u sqrt(lambda_k)`` for ``u`` in ``{-3, +3}``
   and the first ``K`` modes, shown to the artist, who poses each on the rig:
   rig parameters ``r_k^u`` (and ``r_0`` for the mean shape).
3. :func:`retarget_weights` -- Eq. (2): ``w_k^u = max(p_k / (u sqrt(lambda_k)), 0)``
   where ``p_k = s_k . (s - s_0)`` is the frame's k-th mode coefficient.
4. :func:`rig_space_retarget` -- Eq. (3): ``R_t = (R - r_0) w + r_0``.

Reading of the paper's ambiguities (each a decision here):

* Sec. 6 writes ``sqrt(p_k)`` both in the pose definition and in Eq. (2),
  reusing the letter ``p`` of the shape parameters; it can only be the mode's
  variance (eigenvalue) ``lambda_k``, since the poses are "at +3 and -3
  standard deviations". With that reading ``w_k^u = 1`` exactly at the
  posed shape and the retargeted rig equals the artist's pose there.
* ``R`` is said to be "relative to the mean pose r_0", yet Eq. (3) subtracts
  ``r_0`` from it. We store the poses as the artist made them (absolute
  rig parameters) and apply Eq. (3) as written, so ``R - r_0`` are the
  offsets; pass ``relative=True`` if your poses are already offsets.
* Eq. (2) does not clip from above: beyond 3 standard deviations the weight
  exceeds 1 and the rig is extrapolated along the pose (as in the paper).
  ``bounds`` clips the final rig parameters if the rig needs it.
* Only the first ``K`` modes are retargeted; the rest of the motion (the
  paper's 9% of energy for K=4) is dropped by design.
* ``R`` is a matrix whose columns are poses ordered
  ``r_1^{-3}, r_1^{+3}, ..., r_K^{-3}, r_K^{+3}``; in files (and here) the
  poses are *rows*, in the same order.
"""

from __future__ import annotations

import numpy as np

from dam.base import Interval, Options, Transformer
from dam.corpus.data import DataError
from dam.crossmap.rig import check_bounds, check_fitted, check_frames, map_trajectories, stack_frames

__all__ = [
    "principal_modes",
    "project",
    "retargeting_poses",
    "retarget_weights",
    "rig_space_retarget",
    "RigSpaceRetargeter",
]


def principal_modes(frames, n_modes, *, source: str | None = None):
    """Mean, first ``n_modes`` principal modes and their eigenvalues.

    Parameters
    ----------
    frames : array-like, shape (n_frames, n_dims)
    n_modes : int
        ``K``; at most ``min(n_frames - 1, n_dims)``.

    Returns
    -------
    mean : ndarray, shape (n_dims,)
        ``s_0``.
    modes : ndarray, shape (n_modes, n_dims)
        Orthonormal modes ``s_k`` (rows), by decreasing variance.
    eigenvalues : ndarray, shape (n_modes,)
        ``lambda_k``: variance of the frames along each mode (ddof=1).
    """
    from sklearn.decomposition import PCA

    X = check_frames(frames, "frames", source=source)
    k_max = min(len(X) - 1, X.shape[1])
    if isinstance(n_modes, str) and n_modes == "auto":  # as many as fit, at most the paper's 4
        n_modes = max(1, min(4, k_max))
    if not (isinstance(n_modes, (int, np.integer)) and 1 <= n_modes <= k_max):
        raise DataError(
            source,
            "n_modes",
            n_modes,
            f"must be an integer in [1, {k_max}] for {len(X)} frames of {X.shape[1]} dims",
            "or 'auto'",
        )
    pca = PCA(n_components=int(n_modes), svd_solver="full").fit(X)
    lam = pca.explained_variance_
    if np.any(lam <= 1e-12 * max(lam[0], 1e-300)):
        k = int(np.flatnonzero(lam <= 1e-12 * max(lam[0], 1e-300))[0])
        raise DataError(
            source, "n_modes", n_modes, f"mode {k + 1} has no variance in the reference trajectories; use fewer modes"
        )
    return pca.mean_.copy(), pca.components_.copy(), lam.copy()


def project(frames, mean, modes) -> np.ndarray:
    """Mode coefficients ``p_k = s_k . (s - s_0)``, shape (n_frames, n_modes)."""
    modes = check_frames(modes, "modes")
    X = check_frames(frames, "frames", n_dims=modes.shape[1], dims_name="the modes' n_dims")
    return (X - np.asarray(mean, dtype=float)) @ modes.T


def _sigma_steps(u) -> np.ndarray:
    u = np.atleast_1d(np.asarray(u, dtype=float))
    if u.ndim != 1 or len(u) != 2 or not (u[0] < 0 < u[1]):
        raise DataError(None, "u", u.tolist(), "must be a pair (negative, positive), e.g. (-3, 3)")
    return u


def retargeting_poses(mean, modes, eigenvalues, u=(-3.0, 3.0)) -> np.ndarray:
    """The reference shapes to pose on the rig: ``s_k^u = s_0 + s_k u sqrt(lambda_k)``.

    Returns
    -------
    poses : ndarray, shape (2 n_modes, n_dims)
        Rows ordered ``s_1^{u-}, s_1^{u+}, s_2^{u-}, ...``.
    """
    u = _sigma_steps(u)
    modes = check_frames(modes, "modes")
    sd = np.sqrt(np.asarray(eigenvalues, dtype=float))
    step = (sd[:, None] * u[None, :]).ravel()  # (2K,)
    return np.asarray(mean, dtype=float) + step[:, None] * np.repeat(modes, 2, axis=0)


def retarget_weights(p, eigenvalues, u=(-3.0, 3.0)) -> np.ndarray:
    """Eq. (2): ``w_k^u = max(p_k / (u sqrt(lambda_k)), 0)``.

    Parameters
    ----------
    p : array-like, shape (n_frames, n_modes)
        Mode coefficients of the frames (:func:`project`).
    eigenvalues : array-like, shape (n_modes,)
    u : pair, default (-3, 3)

    Returns
    -------
    w : ndarray, shape (n_frames, 2 n_modes)
        Columns ordered ``w_1^{u-}, w_1^{u+}, w_2^{u-}, ...``; for each mode at
        most one of the pair is non-zero.
    """
    u = _sigma_steps(u)
    lam = np.asarray(eigenvalues, dtype=float).ravel()
    if np.any(~np.isfinite(lam)) or np.any(lam <= 0):
        raise DataError(None, "eigenvalues", lam.tolist(), "must be positive")
    P = check_frames(p, "p", n_dims=len(lam), dims_name="the number of eigenvalues")
    denom = (np.sqrt(lam)[:, None] * u[None, :]).ravel()  # (2K,)
    return np.maximum(np.repeat(P, 2, axis=1) / denom, 0.0)


def rig_space_retarget(w, rig_poses, rig_neutral, *, relative: bool = False) -> np.ndarray:
    """Eq. (3): ``R_t = (R - r_0) w + r_0``.

    Parameters
    ----------
    w : array-like, shape (n_frames, n_poses)
    rig_poses : array-like, shape (n_poses, n_rig)
        The artist's rig parameters for each pose (rows; the paper's columns
        of ``R``), absolute unless ``relative``.
    rig_neutral : array-like, shape (n_rig,)
        ``r_0``, the rig parameters of the mean shape.
    relative : bool, default False
        ``rig_poses`` already hold ``R - r_0``.

    Returns
    -------
    rig_params : ndarray, shape (n_frames, n_rig)
    """
    R = check_frames(rig_poses, "rig_poses")
    r0 = np.asarray(rig_neutral, dtype=float)
    if r0.ndim != 1 or len(r0) != R.shape[1]:
        raise DataError(None, "rig_neutral", r0.shape, f"must have shape ({R.shape[1]},), one value per rig parameter")
    if not np.all(np.isfinite(r0)):
        raise DataError(None, "rig_neutral", r0.tolist(), "values must be finite")
    W = check_frames(w, "w", n_dims=len(R), dims_name="the number of rig poses")
    D = R if relative else R - r0
    return W @ D + r0


class RigSpaceRetargeter(Transformer):
    """Rig-space retargeting of Taylor et al. (2017), Section 6.

    Parameters
    ----------
    n_modes : int or "auto", default 4
        ("auto": 4, or fewer when the reference has fewer dimensions)
        ``K``, the number of principal modes posed on the rig (the paper's 4).
    u : pair of float, default (-3, 3)
        The standard-deviation steps of the poses.
    rig_poses : array-like, shape (2 n_modes, n_rig), optional
        The artist's rig parameters for :meth:`reference_poses`, same row
        order. Needed by :meth:`transform`.
    rig_neutral : array-like, shape (n_rig,), optional
        ``r_0``, the rig parameters of the mean shape.
    relative : bool, default False
        ``rig_poses`` are offsets from ``r_0`` already.
    rig_names : sequence of str, optional
        Output channel names; default ``r0, r1, ...``.
    bounds : pair, optional
        Clip the rig parameters to these bounds (Eq. 3 does not).

    Attributes
    ----------
    mean_ : ndarray, shape (n_dims,)
    components_ : ndarray, shape (n_modes, n_dims)
    eigenvalues_ : ndarray, shape (n_modes,)
    explained_variance_ratio_ : ndarray, shape (n_modes,)
        Share of the reference variance in each mode (the paper's "91% energy").
    """

    _parameter_constraints = {
        "n_modes": [Interval(int, 1, None, closed="left"), Options({"auto"})],
        "relative": ["boolean"],
    }

    def __init__(
        self, *, n_modes=4, u=(-3.0, 3.0), rig_poses=None, rig_neutral=None, relative=False, rig_names=None, bounds=None
    ):
        self.n_modes = n_modes
        self.u = u
        self.rig_poses = rig_poses
        self.rig_neutral = rig_neutral
        self.relative = relative
        self.rig_names = rig_names
        self.bounds = bounds

    def fit(self, X, y=None) -> RigSpaceRetargeter:
        """Principal modes of the reference trajectories (array, Utterance, Corpus or list)."""
        self._validate_params()
        frames = stack_frames(X, "X")
        source = getattr(X, "source", None) or getattr(X, "name", None) or "reference trajectories"
        self.mean_, self.components_, self.eigenvalues_ = principal_modes(frames, self.n_modes, source=source)
        total = np.sum(np.var(frames, axis=0, ddof=1))
        self.explained_variance_ratio_ = self.eigenvalues_ / total
        self.n_dims_ = frames.shape[1]
        return self

    def _check_fitted(self):
        check_fitted(self, "components_", "fit(reference)")

    def reference_poses(self) -> np.ndarray:
        """The 2K reference shapes for the artist, shape (2 n_modes, n_dims)."""
        self._check_fitted()
        return retargeting_poses(self.mean_, self.components_, self.eigenvalues_, self.u)

    def weights(self, X):
        """Eq. (2) weights per frame, shape (n_frames, 2 n_modes), container kept."""
        self._check_fitted()
        names = [f"w{k // 2 + 1}{'-+'[k % 2]}" for k in range(2 * len(self.eigenvalues_))]
        return map_trajectories(X, self._weights, names)

    def _weights(self, F):
        return retarget_weights(project(F, self.mean_, self.components_), self.eigenvalues_, self.u)

    def transform(self, X):
        """Rig parameters per frame (Eq. 3): array, Utterance, Corpus (alignments kept) or list."""
        self._check_fitted()
        if self.rig_poses is None or self.rig_neutral is None:
            raise DataError(
                None,
                "rig_poses" if self.rig_poses is None else "rig_neutral",
                None,
                "not set; pose reference_poses() on the rig first",
            )
        R = check_frames(self.rig_poses, "rig_poses")
        if len(R) != 2 * len(self.eigenvalues_):
            raise DataError(
                None,
                "rig_poses",
                R.shape,
                f"needs {2 * len(self.eigenvalues_)} rows "
                f"(poses at u-, u+ for each of the {len(self.eigenvalues_)} modes)",
            )
        names = [f"r{k}" for k in range(R.shape[1])] if self.rig_names is None else list(self.rig_names)
        if len(names) != R.shape[1]:
            raise DataError(None, "rig_names", len(names), f"expected {R.shape[1]} names")
        lohi = None if self.bounds is None else check_bounds(self.bounds, R.shape[1])

        def fn(F):
            out = rig_space_retarget(self._weights(F), R, self.rig_neutral, relative=self.relative)
            return out if lohi is None else np.clip(out, *lohi)

        return map_trajectories(X, fn, names, name_suffix="retarget")
