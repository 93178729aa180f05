"""NNLS cross-mapping from captured motion to rig controls (Chen et al. 2012, Appendix A).

The paper's three steps, one pure function each:

1. :func:`find_key_shapes` -- the key shapes ``L_k`` are captured frames
   chosen by affinity propagation (the paper's unsupervised clustering [40]),
   unless the artist names them.
2. :func:`blend_weights` -- per frame ``i`` the non-negative blend weights
   ``alpha^i = argmin ||L^i - sum_k alpha_k^i L_k||^2, alpha >= 0`` (NNLS).
3. :func:`blend_vertices` -- the artist poses every key shape on the target
   character, giving ``V_k``; the frame's target vertices are
   ``V^i = sum_k alpha_k^i V_k``.
4. :func:`fit_controls` -- the controls ``C^i`` whose rig vertices best match
   ``V^i``, every control bounded in [0, 1]. The paper says "solved by the
   NNLS algorithm", but NNLS bounds only from below; the bound from above
   needs bounded least squares (``scipy.optimize.lsq_linear``, BVLS, exact)
   for a linear rig and ``scipy.optimize.least_squares`` with bounds
   (trust-region reflective, warm-started from the previous frame) for any
   other control-to-vertex function.

:class:`CrossMapper` strings them together in scikit-learn style::

    cm = CrossMapper().fit(captured)          # key shapes from the data
    cm.key_shapes_                            # show these to the artist
    cm.set_params(target_key_shapes=V, rig=rig)
    controls = cm.transform(captured)         # Corpus in, Corpus out

Notes
-----
The paper requires at least as many adjusted target vertices as controls
(``|V| >= |C|``); with fewer the fit is not unique and a warning says so.
When the target's controls *are* the key shapes (the paper's "well-defined
bases" case), leave ``target_key_shapes`` unset: the weights are the controls.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable

import numpy as np

from dam.base import Interval, Transformer
from dam.corpus.data import DataError
from dam.crossmap.rig import LinearRig, as_rig, check_bounds, check_fitted, check_frames, map_trajectories, stack_frames

__all__ = ["find_key_shapes", "blend_weights", "blend_vertices", "fit_controls", "CrossMapper"]


def find_key_shapes(
    frames,
    *,
    preference=None,
    damping: float = 0.9,
    max_frames: int = 2000,
    max_iter: int = 1000,
    random_state: int | None = 0,
):
    """Key shapes: exemplar frames found by affinity propagation.

    Parameters
    ----------
    frames : array-like, shape (n_frames, n_dims)
        Captured shapes, one flattened shape per row.
    preference : float, "min" or None, default None
        Affinity propagation's preference (similarity is the negative squared
        distance). ``None`` is the median similarity (scikit-learn's default;
        more key shapes), ``"min"`` the smallest similarity (few key shapes),
        a number is used as is.
    damping : float, default 0.9
        Affinity propagation damping in [0.5, 1).
    max_frames : int, default 2000
        Affinity propagation needs an n x n similarity matrix; above this many
        frames an evenly spaced subset is clustered (the exemplars are still
        captured frames).
    max_iter : int, default 1000
    random_state : int or None, default 0

    Returns
    -------
    key_shapes : ndarray, shape (n_key_shapes, n_dims)
        The exemplar frames.
    indices : ndarray of int, shape (n_key_shapes,)
        Their row numbers in ``frames``.

    Raises
    ------
    ValueError
        If affinity propagation does not converge (it then finds no
        exemplar); the message says what to change.
    """
    from sklearn.cluster import AffinityPropagation
    from sklearn.exceptions import ConvergenceWarning

    X = check_frames(frames, "frames")
    if int(max_frames) < 2:
        raise DataError(None, "max_frames", max_frames, "must be at least 2")
    rows = np.arange(len(X))
    if len(X) > max_frames:
        rows = np.unique(np.linspace(0, len(X) - 1, int(max_frames)).round().astype(int))
    Xs = X[rows]
    if len(Xs) == 1:
        return Xs.copy(), rows.copy()
    if isinstance(preference, str):
        if preference != "min":
            raise DataError(None, "preference", preference, 'must be a number, None or "min"')
        sq = np.sum(Xs**2, axis=1)
        sim = -(sq[:, None] + sq[None, :] - 2 * Xs @ Xs.T)
        preference = float(np.min(sim))
    ap = AffinityPropagation(damping=damping, preference=preference, max_iter=max_iter, random_state=random_state)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ConvergenceWarning)
        ap.fit(Xs)
    centers = np.asarray(ap.cluster_centers_indices_, dtype=int).ravel()
    if any(issubclass(w.category, ConvergenceWarning) for w in caught) or centers.size == 0:
        raise ValueError(
            f"affinity propagation did not converge on {len(Xs)} frames (damping={damping}, "
            f"preference={preference!r}, max_iter={max_iter}); raise damping or max_iter, "
            "lower the preference, or give the key shapes yourself"
        )
    idx = rows[np.sort(centers)]
    return X[idx].copy(), idx


def blend_weights(frames, key_shapes) -> np.ndarray:
    """Non-negative blend weights of every frame over the key shapes (NNLS).

    Solves ``min ||L^i - sum_k alpha_k^i L_k||^2`` with ``alpha >= 0`` for every
    frame ``i`` (Appendix A).

    Parameters
    ----------
    frames : array-like, shape (n_frames, n_dims)
    key_shapes : array-like, shape (n_key_shapes, n_dims)

    Returns
    -------
    weights : ndarray, shape (n_frames, n_key_shapes)
    """
    from scipy.optimize import nnls
    from threadpoolctl import threadpool_limits

    L = check_frames(key_shapes, "key_shapes")
    X = check_frames(frames, "frames", n_dims=L.shape[1], dims_name="the key shapes' n_dims")
    A = L.T
    out = np.empty((len(X), len(L)))
    with threadpool_limits(1, user_api="blas"):  # many tiny solves: BLAS threads only contend
        for i, x in enumerate(X):
            out[i] = nnls(A, x)[0]
    return out


def blend_vertices(weights, target_key_shapes) -> np.ndarray:
    """Target vertices of every frame: ``V^i = sum_k alpha_k^i V_k``.

    Parameters
    ----------
    weights : array-like, shape (n_frames, n_key_shapes)
    target_key_shapes : array-like, shape (n_key_shapes, n_target_dims)
        The key shapes as the artist posed them on the target character.

    Returns
    -------
    vertices : ndarray, shape (n_frames, n_target_dims)
    """
    V = check_frames(target_key_shapes, "target_key_shapes")
    W = check_frames(weights, "weights", n_dims=len(V), dims_name="the number of target key shapes")
    return W @ V


def fit_controls(
    vertices,
    rig,
    *,
    bounds=(0.0, 1.0),
    n_controls: int | None = None,
    x0=None,
    jacobian: Callable | None = None,
    max_nfev: int | None = None,
) -> np.ndarray:
    """Per-frame rig controls that reproduce the target vertices, within bounds.

    Solves ``min ||V^i - V(C^i)||^2`` subject to ``lower <= C^i <= upper`` for
    every frame ``i``.

    Parameters
    ----------
    vertices : array-like, shape (n_frames, n_dims)
        Target vertices, e.g. from :func:`blend_vertices`.
    rig : LinearRig, array-like of shape (n_controls, n_dims), or callable
        The control-to-vertex function. A :class:`~dam.rig.LinearRig` or a
        bare blendshape matrix (zero neutral) takes the fast path: exact
        bounded-variable least squares (``lsq_linear``, BVLS), with frames
        whose unbounded solution is already feasible solved in one batch.
        A callable ``f(c) -> (n_dims,)`` is fitted by bounded nonlinear least
        squares (``least_squares``, trust-region reflective), each frame
        warm-started from the previous frame's controls.
    bounds : (float or array, float or array), default (0, 1)
        Bounds of every control.
    n_controls : int, optional
        Number of controls; required when ``rig`` is a callable.
    x0 : array-like, shape (n_controls,), optional
        Start of the first frame for a callable rig; default the bounds' midpoint.
    jacobian : callable, optional
        ``J(c) -> (n_dims, n_controls)`` for a callable rig; default finite differences.
    max_nfev : int, optional
        Evaluation budget per frame for a callable rig.

    Returns
    -------
    controls : ndarray, shape (n_frames, n_controls)
        Every value within ``bounds``.
    """
    from threadpoolctl import threadpool_limits

    with threadpool_limits(1, user_api="blas"):  # many tiny solves: BLAS threads only contend
        return _fit_controls(vertices, rig, bounds, n_controls, x0, jacobian, max_nfev)


def _fit_controls(vertices, rig, bounds, n_controls, x0, jacobian, max_nfev):
    from scipy.optimize import least_squares, lsq_linear

    linear, func, n = as_rig(rig, n_controls)
    lo, hi = check_bounds(bounds, n)
    if linear is not None:
        V = check_frames(vertices, "vertices", n_dims=linear.n_dims, dims_name="the rig's n_dims")
        if linear.n_dims < n:
            warnings.warn(
                f"the rig has {n} controls but only {linear.n_dims} vertex coordinates; "
                "the controls are not unique (Appendix A asks for |V| >= |C|)",
                stacklevel=3,
            )
        A = linear.deltas.T
        B = V - linear.neutral
        # Frames whose unbounded least-squares solution is feasible need no BVLS.
        out, *_ = np.linalg.lstsq(A, B.T, rcond=None)
        out = out.T
        full_rank = np.linalg.matrix_rank(A) == n
        todo = np.arange(len(V)) if not full_rank else np.flatnonzero(((out < lo) | (out > hi)).any(axis=1))
        for i in todo:
            out[i] = lsq_linear(A, B[i], bounds=(lo, hi), method="bvls").x
        return np.clip(out, lo, hi)

    V = check_frames(vertices, "vertices")
    c = 0.5 * (lo + hi) if x0 is None else np.clip(check_frames(x0, "x0", n_dims=n)[0], lo, hi)
    first = np.asarray(func(c), dtype=float).ravel()
    if first.shape[0] != V.shape[1]:
        raise DataError(
            None, "rig", first.shape, f"returns {first.shape[0]} coordinates but the vertices have {V.shape[1]}"
        )
    jac = "2-point" if jacobian is None else (lambda c_: np.asarray(jacobian(c_), dtype=float))
    out = np.empty((len(V), n))
    for i, v in enumerate(V):
        # Keep the start strictly inside the box: trf needs an interior point.
        start = np.clip(c, lo + 1e-9 * (hi - lo), hi - 1e-9 * (hi - lo))
        res = least_squares(
            lambda c_, v=v: np.asarray(func(c_), dtype=float).ravel() - v,
            start,
            jac=jac,
            bounds=(lo, hi),
            method="trf",
            max_nfev=max_nfev,
            x_scale="jac",
        )
        if not np.all(np.isfinite(res.x)):
            raise DataError(
                None, f"vertices[{i}]", "non-finite controls", "the rig function returned non-finite values"
            )
        c = out[i] = np.clip(res.x, lo, hi)
    return out


class CrossMapper(Transformer):
    """Cross-map captured shapes to a target character's controls (Appendix A).

    Parameters
    ----------
    key_shapes : array-like, shape (n_key_shapes, n_dims), optional
        Key shapes chosen by the artist; if None, :meth:`fit` finds them by
        affinity propagation over the captured frames.
    target_key_shapes : array-like, shape (n_key_shapes, n_target_dims), optional
        The key shapes posed by the artist on the target character (``V_k``).
        If None, :meth:`transform` returns the blend weights (the paper's case
        where the key shapes are the target's bases).
    rig : LinearRig, array-like (n_controls, n_target_dims) or callable, optional
        The target's control-to-vertex function; needed to get controls from
        ``target_key_shapes``.
    n_controls : int, optional
        Number of controls of a callable rig.
    control_names : sequence of str, optional
        Channel names of the output; default the rig's names, ``key0..`` for
        weights, ``c0..`` otherwise.
    bounds : pair, default (0, 1)
        Bounds of every control.
    preference, damping, max_frames, max_iter, random_state
        Passed to :func:`find_key_shapes`.

    Attributes
    ----------
    key_shapes_ : ndarray, shape (n_key_shapes, n_dims)
    key_frame_indices_ : ndarray of int or None
        Rows of the stacked captured frames that became key shapes (None if given).
    n_dims_ : int
    """

    _parameter_constraints = {
        "n_controls": [None, Interval(int, 1, None, closed="left")],
        "damping": [Interval(float, 0.5, 1.0, closed="left")],
        "max_frames": [Interval(int, 1, None, closed="left")],
        "max_iter": [Interval(int, 1, None, closed="left")],
        "random_state": ["random_state"],
    }

    def __init__(
        self,
        *,
        key_shapes=None,
        target_key_shapes=None,
        rig=None,
        n_controls=None,
        control_names=None,
        bounds=(0.0, 1.0),
        preference=None,
        damping=0.9,
        max_frames=2000,
        max_iter=1000,
        random_state=0,
    ):
        self.key_shapes = key_shapes
        self.target_key_shapes = target_key_shapes
        self.rig = rig
        self.n_controls = n_controls
        self.control_names = control_names
        self.bounds = bounds
        self.preference = preference
        self.damping = damping
        self.max_frames = max_frames
        self.max_iter = max_iter
        self.random_state = random_state

    def fit(self, X, y=None) -> CrossMapper:
        """Find (or check) the key shapes on captured frames.

        Parameters
        ----------
        X : array (n_frames, n_dims), Utterance, Corpus, or a list of these
        """
        self._validate_params()
        frames = stack_frames(X, "X")
        if self.key_shapes is None:
            self.key_shapes_, self.key_frame_indices_ = find_key_shapes(
                frames,
                preference=self.preference,
                damping=self.damping,
                max_frames=self.max_frames,
                max_iter=self.max_iter,
                random_state=self.random_state,
            )
        else:
            self.key_shapes_ = check_frames(
                self.key_shapes, "key_shapes", n_dims=frames.shape[1], dims_name="the captured frames' n_dims"
            ).copy()
            self.key_frame_indices_ = None
        self.n_dims_ = frames.shape[1]
        return self

    def _check_fitted(self):
        check_fitted(self, "key_shapes_", "fit(captured)")

    def weights(self, X, *, names=None):
        """Blend weights per frame, shape (n_frames, n_key_shapes), container kept.

        ``names`` are the output channels, default ``key0, key1, ...``.
        """
        self._check_fitted()
        K = len(self.key_shapes_)
        names = [f"key{k}" for k in range(K)] if names is None else list(names)
        if len(names) != K:
            raise DataError(None, "control_names", len(names), f"expected {K} names, one per key shape")
        return map_trajectories(X, lambda F: blend_weights(F, self.key_shapes_), names)

    def _target_key_shapes(self) -> np.ndarray:
        """``target_key_shapes`` checked against the fitted key shapes, shape (n_key_shapes, n_target_dims)."""
        if self.target_key_shapes is None:
            raise DataError(None, "target_key_shapes", None, "not set; pose the key shapes on the target first")
        V = check_frames(self.target_key_shapes, "target_key_shapes")
        if len(V) != len(self.key_shapes_):
            raise DataError(
                None, "target_key_shapes", V.shape, f"needs one row per key shape ({len(self.key_shapes_)})"
            )
        return V

    def vertices(self, X):
        """Blended target vertices per frame, shape (n_frames, n_target_dims), container kept."""
        self._check_fitted()
        V = self._target_key_shapes()
        names = [f"v{k}" for k in range(V.shape[1])]
        return map_trajectories(X, lambda F: blend_vertices(blend_weights(F, self.key_shapes_), V), names)

    def _output_names(self, n: int) -> list[str]:
        if self.control_names is not None:
            if len(self.control_names) != n:
                raise DataError(None, "control_names", len(self.control_names), f"expected {n} names")
            return list(self.control_names)
        if isinstance(self.rig, LinearRig):
            return list(self.rig.control_names)
        return [f"c{k}" for k in range(n)]

    def transform(self, X):
        """Controls per frame: array, Utterance, Corpus (alignments kept) or list in, same out.

        Without ``target_key_shapes`` these are the blend weights; with them,
        the bounded fit of ``rig`` to the blended target vertices.
        """
        self._check_fitted()
        if self.target_key_shapes is None:
            return self.weights(X, names=self.control_names)
        if self.rig is None:
            raise DataError(
                None,
                "rig",
                None,
                "target_key_shapes are set but no rig to fit controls to; use vertices() for the blended vertices",
            )
        V = self._target_key_shapes()
        _, _, n = as_rig(self.rig, self.n_controls)

        def fn(F):
            verts = blend_vertices(blend_weights(F, self.key_shapes_), V)
            return fit_controls(verts, self.rig, bounds=self.bounds, n_controls=self.n_controls)

        return map_trajectories(X, fn, self._output_names(n), name_suffix="crossmap")
