"""Landmark-to-rig solve (Medina et al. 2022, Section 7, Eqs. 2-4).

Per frame ``t`` the rig parameters ``theta_t`` minimise (Eqs. 2-4)::

    e(theta) = sum_l ||C(theta)_l - y_l||^2  +  alpha * sum_p |theta_p|

where ``C(theta)_l`` is the ``l``-th landmark of the posed rig and ``y_l`` its
target, ``C(theta_N)_l + delta_l`` with ``delta_l = A(v_l - v_N,l)`` the
captured landmark's offset from the captured neutral pose mapped into the
rig's frame by the similarity transform ``A`` fitted on the neutral pose.
Each frame starts from the previous frame's solution; no temporal prior.

Decisions (the paper leaves them open):

* **Optimiser.** The paper uses L-BFGS. We use SciPy's L-BFGS-B rather than
  jaxopt: the parameters of a rig have bounds (FACS controls in [0, 1]),
  which L-BFGS-B handles natively, and on the non-negative orthant
  ``|theta| = theta`` so the L1 prior is smooth there and the solve is exact,
  not a smoothed approximation. A parameter whose bounds straddle zero is
  split as ``theta = a - b`` with ``a, b >= 0`` and prior ``a + b`` (the
  standard exact reformulation of L1). The frames are solved one after the
  other (warm start), so jax's batching would not help, and jaxopt is
  unmaintained.
* **Eq. (3)** sums ``|theta_l|`` over ``l = 1..L``, the landmarks' index; it
  can only mean all ``P`` parameters, which is what we sum.
* **Symmetry.** "We enforce symmetry on both sides of the face on our
  parameter vector": ``symmetric_pairs`` lists ``(left, right)`` parameter
  indices that are tied equal (one free variable each pair; the prior still
  counts both). Pairs may chain.
* **``A`` on offsets.** ``delta_l = A(v - v_N)`` applies the similarity
  transform to a difference, where its translation cancels; we apply its
  scale and rotation only (:func:`similarity_transform`, Umeyama's method).
* **Gradient.** Exact for a :class:`~dam.rig.LinearRig` or when a Jacobian is
  given; otherwise L-BFGS-B's finite differences.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from dam.base import Interval, Transformer
from dam.corpus.data import DataError
from dam.crossmap.rig import LinearRig, as_rig, check_bounds, check_fitted, check_frames, map_trajectories, stack_frames

__all__ = ["similarity_transform", "landmark_targets", "tied_parameters", "solve_landmarks", "LandmarkSolver"]


def similarity_transform(src, dst):
    """Least-squares similarity ``dst ~ s R src + t`` (Umeyama 1991).

    Parameters
    ----------
    src, dst : array-like, shape (n_points, d)

    Returns
    -------
    scale : float
    rotation : ndarray, shape (d, d)
        A proper rotation (det +1).
    translation : ndarray, shape (d,)
    """
    P = check_frames(src, "src")
    Q = check_frames(dst, "dst", n_dims=P.shape[1], dims_name="src's dimension")
    if len(Q) != len(P):
        raise DataError(None, "dst", Q.shape, f"needs as many points as src ({len(P)})")
    mp, mq = P.mean(0), Q.mean(0)
    Pc, Qc = P - mp, Q - mq
    var = np.sum(Pc**2) / len(P)
    if var <= 0:
        raise DataError(None, "src", P.shape, "all points coincide; no transform is defined")
    U, S, Vt = np.linalg.svd(Qc.T @ Pc / len(P))
    E = np.eye(P.shape[1])
    if np.linalg.det(U) * np.linalg.det(Vt) < 0:
        E[-1, -1] = -1.0
    Rot = U @ E @ Vt
    s = float(np.trace(np.diag(S) @ E) / var)
    return s, Rot, mq - s * Rot @ mp


def landmark_targets(captured, captured_neutral, rig_neutral, *, landmark_dim: int = 2) -> np.ndarray:
    """Targets ``C(theta_N)_l + A(v_l - v_N,l)`` of Eq. (2) for every frame.

    Parameters
    ----------
    captured : array-like, shape (n_frames, n_landmarks * landmark_dim)
        Captured (or predicted) landmarks, flattened ``x0, y0, x1, y1, ...``.
    captured_neutral : array-like, shape (n_landmarks * landmark_dim,)
        The same landmarks in the neutral pose, ``v_N``.
    rig_neutral : array-like, shape (n_landmarks * landmark_dim,)
        The rig's landmarks in the neutral pose, ``C(theta_N)``.
    landmark_dim : int, default 2

    Returns
    -------
    targets : ndarray, shape (n_frames, n_landmarks * landmark_dim)
    """
    vN = np.asarray(captured_neutral, dtype=float).ravel()
    cN = np.asarray(rig_neutral, dtype=float).ravel()
    X = check_frames(captured, "captured", n_dims=len(vN), dims_name="captured_neutral's length")
    if len(cN) != len(vN):
        raise DataError(None, "rig_neutral", cN.shape, f"must have {len(vN)} coordinates like captured_neutral")
    if len(vN) % landmark_dim:
        raise DataError(None, "landmark_dim", landmark_dim, f"does not divide the {len(vN)} coordinates")
    s, Rot, _ = similarity_transform(vN.reshape(-1, landmark_dim), cN.reshape(-1, landmark_dim))
    off = (X - vN).reshape(len(X), -1, landmark_dim) @ (s * Rot).T
    return cN + off.reshape(len(X), -1)


def tied_parameters(n_params: int, bounds, symmetric_pairs: Sequence[tuple[int, int]] | None = None):
    """The free variables ``z`` behind the parameters: ``theta = M z``.

    Tied parameters share one variable; a variable whose bounds straddle zero
    is split into a non-negative and a non-positive part so that the L1 prior
    is the linear ``cost . z`` on the feasible box.

    Returns
    -------
    M : ndarray, shape (n_params, n_vars)
    lower, upper : ndarray, shape (n_vars,)
    cost : ndarray, shape (n_vars,)
        ``sum_p |theta_p| = cost . z`` at any optimum.
    """
    lo, hi = check_bounds(bounds, n_params)
    parent = list(range(n_params))

    def root(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for k, pair in enumerate(symmetric_pairs or ()):
        try:
            i, j = (int(v) for v in pair)
        except (TypeError, ValueError):
            raise DataError(None, f"symmetric_pairs[{k}]", pair, "must be a pair of parameter indices") from None
        for v in (i, j):
            if not 0 <= v < n_params:
                raise DataError(None, f"symmetric_pairs[{k}]", pair, f"index out of range for {n_params} parameters")
        parent[root(i)] = root(j)
    groups: dict[int, list[int]] = {}
    for p in range(n_params):
        groups.setdefault(root(p), []).append(p)
    cols, lows, highs, cost = [], [], [], []
    for members in sorted(groups.values()):
        g_lo, g_hi = lo[members].max(), hi[members].min()
        if g_lo > g_hi:
            raise DataError(
                None, "bounds", (members, float(g_lo), float(g_hi)), "tied parameters have bounds that do not overlap"
            )
        col = np.zeros(n_params)
        col[members] = 1.0
        m = float(len(members))
        if g_lo >= 0 or g_hi <= 0:  # one sign: |theta| = +theta or -theta, linear on the box
            cols.append(col)
            lows.append(g_lo)
            highs.append(g_hi)
            cost.append(m if g_lo >= 0 else -m)
        else:  # both signs: theta = a - b with a, b >= 0 and |theta| = a + b at the optimum
            cols += [col, -col]
            lows += [0.0, 0.0]
            highs += [g_hi, -g_lo]
            cost += [m, m]
    return np.stack(cols, axis=1), np.array(lows), np.array(highs), np.array(cost)


def _to_vars(theta, M, lower, upper):
    """A start ``z`` for parameters ``theta``: each variable's mean signed member, clipped."""
    return np.clip((M.T @ theta) / np.abs(M).sum(0), lower, upper)


def solve_landmarks(
    targets,
    rig,
    *,
    alpha: float = 0.01,
    bounds=(0.0, 1.0),
    n_params: int | None = None,
    jacobian: Callable | None = None,
    symmetric_pairs=None,
    x0=None,
    max_iter: int = 500,
    tol: float = 1e-12,
    n_restarts: int = 5,
    return_info: bool = False,
):
    """Rig parameters of every frame from landmark targets (Eqs. 2-4), L-BFGS-B, warm-started.

    Parameters
    ----------
    targets : array-like, shape (n_frames, n_coords)
        Target landmark coordinates ``y`` in the rig's frame (see
        :func:`landmark_targets`), flattened.
    rig : LinearRig, array-like (n_params, n_coords), or callable
        ``C(theta)``: parameters to landmark coordinates. A callable returns
        ``(n_coords,)``.
    alpha : float, default 0.01
        Weight of the L1 prior (the paper's 0.01).
    bounds : pair, default (0, 1)
        Bounds of every parameter (scalars or arrays).
    n_params : int, optional
        Required for a callable rig.
    jacobian : callable, optional
        ``J(theta) -> (n_coords, n_params)`` for a callable rig.
    symmetric_pairs : sequence of (int, int), optional
        Parameters tied equal (left/right).
    x0 : array-like, shape (n_params,), optional
        Start of the first frame; default zero clipped to the bounds.
    max_iter : int, default 500
        L-BFGS-B iterations per frame.
    tol : float, default 1e-12
        L-BFGS-B ``ftol`` (relative reduction); ``gtol`` is ``100 * tol``.
    n_restarts : int, default 5
        With an exact gradient, restart L-BFGS-B (at most this often) while the
        projected gradient is not yet zero: on a degenerate problem (more
        parameters than landmark coordinates) it can stall on ``ftol``.
    return_info : bool, default False
        Also return a dict with per-frame ``energy``, ``pose_error``
        (Eq. 2) and ``n_iter``.

    Returns
    -------
    theta : ndarray, shape (n_frames, n_params)
    info : dict, only if ``return_info``
    """
    from scipy.optimize import minimize
    from threadpoolctl import threadpool_limits

    if not (np.isfinite(alpha) and alpha >= 0):
        raise DataError(None, "alpha", alpha, "must be a non-negative number")
    lin, func, n = as_rig(rig, n_params, count_name="n_params")
    jac_fn = None if (lin is not None or jacobian is None) else (lambda th: np.asarray(jacobian(th), dtype=float))
    M, zlo, zhi, cost = tied_parameters(n, bounds, symmetric_pairs)
    plo, phi = check_bounds(bounds, n)
    theta = np.clip(np.zeros(n) if x0 is None else check_frames(x0, "x0", n_dims=n)[0], plo, phi)
    first = np.asarray(func(theta), dtype=float).ravel()
    Y = check_frames(targets, "targets", n_dims=len(first), dims_name="the rig's landmark coordinates")
    if lin is not None:  # linear landmarks: C(M z) = neutral + A z
        A = lin.deltas.T @ M

    def energy(z, y):
        th = M @ z
        if lin is not None:
            r = lin.neutral + A @ z - y
            return r @ r + alpha * cost @ z, 2 * A.T @ r + alpha * cost
        r = np.asarray(func(th), dtype=float).ravel() - y
        e = r @ r + alpha * cost @ z
        if jac_fn is None:
            return e
        return e, 2 * M.T @ (jac_fn(th).T @ r) + alpha * cost

    use_jac = lin is not None or jac_fn is not None
    box = list(zip(zlo, zhi))
    opts = {"maxiter": max_iter, "ftol": tol, "gtol": tol * 1e2, "maxcor": 20}

    def _solve_frame(z, y):
        nit = 0
        for _ in range(1 + max(int(n_restarts), 0)):
            res = minimize(energy, z, args=(y,), jac=use_jac, method="L-BFGS-B", bounds=box, options=opts)
            z, nit = np.clip(res.x, zlo, zhi), nit + res.nit
            # L-BFGS-B can stop on "relative reduction" far from the optimum of a degenerate
            # problem (more parameters than landmarks); a restart drops its stale curvature pairs.
            if not use_jac or res.nit == 0:
                break
            g = energy(z, y)[1]
            if np.max(np.abs(z - np.clip(z - g, zlo, zhi))) <= 1e-8 * max(1.0, np.max(np.abs(g))):
                break
        return z, M @ z, nit

    out = np.empty((len(Y), n))
    info = {"energy": np.empty(len(Y)), "pose_error": np.empty(len(Y)), "n_iter": np.empty(len(Y), int)}
    z = _to_vars(theta, M, zlo, zhi)
    # Thousands of tiny solves: OpenBLAS threads only add contention (20x slower on a busy machine).
    with threadpool_limits(1, user_api="blas"):
        for t, y in enumerate(Y):
            z, out[t], nit = _solve_frame(z, y)
            if return_info:
                r = np.asarray(func(out[t]), dtype=float).ravel() - y
                info["pose_error"][t] = r @ r
                info["energy"][t] = r @ r + alpha * np.abs(out[t]).sum()
                info["n_iter"][t] = nit
    if not np.all(np.isfinite(out)):
        raise DataError(None, "targets", "non-finite parameters", "the rig function returned non-finite values")
    out = np.clip(out, plo, phi)
    return (out, info) if return_info else out


class LandmarkSolver(Transformer):
    """Landmark-to-rig solve of Medina et al. (2022), Section 7.

    ``fit`` learns the similarity transform from the captured neutral pose to
    the rig's neutral landmarks; ``transform`` turns captured landmark
    trajectories into rig parameters, frame by frame (Eqs. 2-4).

    Parameters
    ----------
    rig : LinearRig, array-like (n_params, n_coords) or callable
        ``C(theta)``.
    n_params : int, optional
        Required for a callable rig.
    alpha : float, default 0.01
    bounds : pair, default (0, 1)
    symmetric_pairs : sequence of (int, int), optional
    jacobian : callable, optional
    neutral_params : array-like (n_params,), optional
        ``theta_N``; default zeros.
    landmark_dim : int, default 2
    param_names : sequence of str, optional
        Output channels; default the rig's control names or ``p0, p1, ...``.
    max_iter, tol
        Per-frame L-BFGS-B settings.

    Attributes
    ----------
    scale_, rotation_ : float, ndarray (d, d)
        The similarity transform's scale and rotation (1 and identity when
        fitted without a neutral pose: targets are in rig coordinates).
    captured_neutral_, rig_neutral_ : ndarray (n_coords,) or None
    """

    _parameter_constraints = {
        "n_params": [None, Interval(int, 1, None, closed="left")],
        "alpha": [Interval(float, 0, None, closed="left")],
        "landmark_dim": [Interval(int, 1, 3, closed="both")],
        "max_iter": [Interval(int, 1, None, closed="left")],
        "tol": [Interval(float, 0, None, closed="left")],
    }

    def __init__(
        self,
        *,
        rig=None,
        n_params=None,
        alpha=0.01,
        bounds=(0.0, 1.0),
        symmetric_pairs=None,
        jacobian=None,
        neutral_params=None,
        landmark_dim=2,
        param_names=None,
        max_iter=500,
        tol=1e-12,
    ):
        self.rig = rig
        self.n_params = n_params
        self.alpha = alpha
        self.bounds = bounds
        self.symmetric_pairs = symmetric_pairs
        self.jacobian = jacobian
        self.neutral_params = neutral_params
        self.landmark_dim = landmark_dim
        self.param_names = param_names
        self.max_iter = max_iter
        self.tol = tol

    def _n(self):
        return as_rig(self.rig, self.n_params, count_name="n_params")[2]

    def _rig_fn(self):
        return as_rig(self.rig, self.n_params, count_name="n_params")[1]

    def fit(self, X=None, y=None) -> LandmarkSolver:
        """Fit the neutral alignment on captured neutral-pose frames (their mean), or none if X is None."""
        self._validate_params()
        n = self._n()
        thN = (
            np.zeros(n)
            if self.neutral_params is None
            else check_frames(self.neutral_params, "neutral_params", n_dims=n)[0]
        )
        d = int(self.landmark_dim)
        if X is None:
            self.scale_, self.rotation_ = 1.0, np.eye(d)
            self.captured_neutral_ = self.rig_neutral_ = None
            return self
        frames = stack_frames(X, "X")
        self.captured_neutral_ = frames.mean(0)
        self.rig_neutral_ = np.asarray(self._rig_fn()(thN), dtype=float).ravel()
        if len(self.rig_neutral_) != len(self.captured_neutral_):
            raise DataError(
                None,
                "X",
                frames.shape,
                f"has {frames.shape[1]} coordinates but the rig has {len(self.rig_neutral_)} landmark coordinates",
            )
        self.scale_, self.rotation_, _ = similarity_transform(
            self.captured_neutral_.reshape(-1, d), self.rig_neutral_.reshape(-1, d)
        )
        return self

    def _solve(self, F):
        if self.captured_neutral_ is not None:
            F = landmark_targets(F, self.captured_neutral_, self.rig_neutral_, landmark_dim=self.landmark_dim)
        x0 = self.neutral_params
        return solve_landmarks(
            F,
            self._rig_fn(),
            alpha=self.alpha,
            bounds=self.bounds,
            n_params=self.n_params,
            jacobian=self.jacobian,
            symmetric_pairs=self.symmetric_pairs,
            x0=x0,
            max_iter=self.max_iter,
            tol=self.tol,
        )

    def transform(self, X):
        """Rig parameters per frame: array, Utterance, Corpus (alignments kept) or list in, same out."""
        check_fitted(self, "scale_", "fit(neutral_frames) or fit(None)")
        n = self._n()
        if self.param_names is not None:
            names = list(self.param_names)
        elif isinstance(self.rig, LinearRig):
            names = list(self.rig.control_names)
        else:
            names = [f"p{k}" for k in range(n)]
        if len(names) != n:
            raise DataError(None, "param_names", len(names), f"expected {n} names")
        return map_trajectories(X, self._solve, names, name_suffix="landmarks")
