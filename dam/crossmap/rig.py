"""A linear blendshape rig, and what the rig-space methods share.

The three ways from captured motion to a character's controls
(:mod:`dam.crossmap`, :mod:`dam.retarget`, :mod:`dam.landmarks`) all talk
about a *rig*: a function from a control vector ``c`` (``n_controls``) to
vertex (or landmark) coordinates (``n_dims``, flattened ``x0, y0, x1, y1,
...``). The fast, exact path is a linear blendshape rig,

    V(c) = neutral + c @ deltas,

with ``deltas`` of shape ``(n_controls, n_dims)``; every method also accepts
any callable ``f(c) -> V`` instead.

This module also holds the small input helpers the three modules share:
frame matrices checked once (shape, NaN) and trajectories of a
``Utterance``/``Corpus`` mapped frame-wise with their alignments kept.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from dam.corpus.data import Corpus, DataError, Utterance

__all__ = [
    "LinearRig",
    "as_rig",
    "check_frames",
    "check_bounds",
    "map_trajectories",
    "stack_frames",
    "check_fitted",
    "load_matrix",
    "name_source",
]


def check_frames(
    X, field: str, *, n_dims: int | None = None, source: str | None = None, dims_name: str = "n_dims"
) -> np.ndarray:
    """``X`` as a finite float array of shape (n_frames, n_dims).

    A 1-D input is one frame. Raises :class:`DataError` naming ``field`` and
    the offending shape or value.
    """
    arr = np.asarray(X, dtype=float)
    if arr.ndim == 1:
        arr = arr[None, :]
    if arr.ndim != 2:
        raise DataError(source, field, arr.shape, "must be 2-D (n_frames, n_dims)")
    if arr.shape[0] == 0 or arr.shape[1] == 0:
        raise DataError(source, field, arr.shape, "is empty")
    if n_dims is not None and arr.shape[1] != n_dims:
        raise DataError(source, field, arr.shape, f"has {arr.shape[1]} columns but {dims_name} is {n_dims}")
    bad = np.argwhere(~np.isfinite(arr))
    if bad.size:
        i, j = (int(v) for v in bad[0])
        raise DataError(
            source,
            f"{field}[{i}, {j}]",
            float(arr[i, j]),
            "value is not finite",
            f"{len(bad)} non-finite value(s) in all",
        )
    return arr


def check_bounds(bounds, n: int, field: str = "bounds") -> tuple[np.ndarray, np.ndarray]:
    """``(lower, upper)`` arrays of length ``n`` from a pair of scalars or arrays."""
    try:
        lo, hi = bounds
    except (TypeError, ValueError):
        raise DataError(None, field, bounds, "must be a pair (lower, upper)") from None
    lo = np.broadcast_to(np.asarray(lo, dtype=float), (n,)).copy()
    hi = np.broadcast_to(np.asarray(hi, dtype=float), (n,)).copy()
    if np.isnan(lo).any() or np.isnan(hi).any():
        raise DataError(None, field, bounds, "bounds must not be NaN")
    bad = np.flatnonzero(lo >= hi)
    if bad.size:
        i = int(bad[0])
        raise DataError(
            None, f"{field}[{i}]", (float(lo[i]), float(hi[i])), "lower bound must be below the upper bound"
        )
    return lo, hi


def stack_frames(X, field: str = "X") -> np.ndarray:
    """All frames of an array, an Utterance, a Corpus or a list of these, stacked."""
    if isinstance(X, Corpus):
        return np.concatenate(X.trajectories, axis=0)
    if isinstance(X, Utterance):
        return X.trajectory
    # np.ndim of an Utterance is 0: test the containers by type first.
    if isinstance(X, (list, tuple)) and X and all(isinstance(x, (Utterance, Corpus)) or np.ndim(x) == 2 for x in X):
        return np.concatenate([stack_frames(x, f"{field}[{k}]") for k, x in enumerate(X)], axis=0)
    return check_frames(X, field)


def map_trajectories(
    X, fn: Callable[[np.ndarray], np.ndarray], channels: Sequence[str], *, name_suffix: str | None = None
):
    """Apply ``fn`` (frames -> frames) to ``X``, keeping its container.

    An array gives an array; an Utterance an Utterance and a Corpus a Corpus
    with the same alignments, frame rate and names and the new ``channels``;
    a list gives a list.
    """
    if isinstance(X, Corpus):
        utts = [map_trajectories(u, fn, channels) for u in X]
        # The source's channel list describes the old channels, not these.
        meta = {k: v for k, v in X.metadata.items() if k not in ("channels", "frame_rate")}
        if name_suffix:
            meta["derived_by"] = name_suffix
        return Corpus(utts, name=X.name, metadata=meta, source=X.source)
    if isinstance(X, Utterance):
        return Utterance(X.alignment, fn(X.trajectory), X.frame_rate, channels, audio=X.audio, name=X.name)
    if isinstance(X, list):
        return [map_trajectories(x, fn, channels) for x in X]
    return fn(X)


def _names(names, n: int, prefix: str, field: str) -> tuple[str, ...]:
    if names is None:
        return tuple(f"{prefix}{k}" for k in range(n))
    names = tuple(str(s) for s in names)
    if len(names) != n:
        raise DataError(None, field, len(names), f"expected {n} names")
    return names


class LinearRig:
    """A linear blendshape rig: ``V(c) = neutral + c @ deltas``.

    Parameters
    ----------
    neutral : array-like, shape (n_dims,)
        Vertex (or landmark) coordinates at ``c = 0``, flattened.
    deltas : array-like, shape (n_controls, n_dims)
        Displacement of every coordinate per unit of each control.
    control_names : sequence of str, optional
        Defaults to ``c0, c1, ...``.
    bounds : (float or array, float or array), default (0, 1)
        Range of every control (a character's controls usually lie in [0, 1]).

    Notes
    -----
    Load one from files with :meth:`from_files` (``.npy`` or ``.csv``): the
    deltas file is ``(n_controls, n_dims)``, the neutral ``(n_dims,)``.
    """

    def __init__(self, neutral, deltas, *, control_names=None, bounds=(0.0, 1.0)):
        deltas = check_frames(deltas, "deltas")
        self.deltas = deltas
        neutral = np.asarray(neutral, dtype=float)
        if neutral.ndim != 1:
            raise DataError(None, "neutral", neutral.shape, "must be 1-D (n_dims,)")
        self.neutral = check_frames(
            neutral, "neutral", n_dims=deltas.shape[1], dims_name="the number of columns of deltas"
        )[0]
        self.control_names = _names(control_names, deltas.shape[0], "c", "control_names")
        self.bounds = check_bounds(bounds, deltas.shape[0])

    @property
    def n_controls(self) -> int:
        return self.deltas.shape[0]

    @property
    def n_dims(self) -> int:
        return self.deltas.shape[1]

    def __repr__(self) -> str:
        return f"LinearRig({self.n_controls} controls -> {self.n_dims} coordinates)"

    def __call__(self, controls) -> np.ndarray:
        """Vertices of one control vector (n_controls,) -> (n_dims,), or of many (T, n_controls) -> (T, n_dims)."""
        c = np.asarray(controls, dtype=float)
        if c.shape[-1] != self.n_controls:
            raise DataError(None, "controls", c.shape, f"last axis must have the rig's {self.n_controls} controls")
        return self.neutral + c @ self.deltas

    def jacobian(self, controls=None) -> np.ndarray:
        """d V / d c, shape (n_dims, n_controls); constant for a linear rig."""
        return self.deltas.T

    @classmethod
    def from_files(cls, deltas_path: str, neutral_path: str | None = None, **kw) -> LinearRig:
        """A rig from ``.npy``/``.csv`` files; no neutral file means a zero neutral."""
        deltas = load_matrix(deltas_path, "deltas")
        neutral = np.zeros(deltas.shape[1]) if neutral_path is None else load_matrix(neutral_path, "neutral").ravel()
        try:
            return cls(neutral, deltas, **kw)
        except DataError as exc:
            raise name_source(exc, f"{deltas_path}" + (f", {neutral_path}" if neutral_path else "")) from None


def as_rig(rig, n_controls: int | None = None, *, count_name: str = "n_controls"):
    """A rig argument as ``(linear, function, n_controls)``.

    ``rig`` is a :class:`LinearRig`, a bare blendshape matrix
    ``(n_controls, n_dims)`` (zero neutral, the paper's ``sum_k V(C_k)``) or a
    callable, which then needs ``n_controls``. ``linear`` is the LinearRig or
    None for a callable; ``function`` maps controls to coordinates.
    """
    if isinstance(rig, LinearRig):
        return rig, rig, rig.n_controls
    if callable(rig):
        if n_controls is None:
            raise DataError(None, count_name, None, f"a rig given as a function needs {count_name}")
        return None, rig, int(n_controls)
    if rig is None:
        raise DataError(None, "rig", None, "no rig given")
    deltas = check_frames(rig, "rig")
    lin = LinearRig(np.zeros(deltas.shape[1]), deltas)
    return lin, lin, lin.n_controls


def check_fitted(estimator, attribute: str, how: str) -> None:
    """Raise :class:`~dam.NotFittedError` unless ``estimator`` has ``attribute`` (``how``: the call that sets it)."""
    if not hasattr(estimator, attribute):
        from dam.base import NotFittedError

        raise NotFittedError(f"this {type(estimator).__name__} is not fitted yet; call {how} first")


def name_source(exc: DataError, source) -> DataError:
    """Name ``source`` (a file) in a DataError raised before the file was known; returns ``exc``."""
    if exc.source is None and source:
        exc.source = str(source)
        exc.args = (str(exc).replace("<input>", str(source), 1),)
    return exc


def load_matrix(path: str, field: str) -> np.ndarray:
    """A numeric matrix from ``.npy`` (never unpickled) or ``.csv`` (comma-separated, no header)."""
    import os

    if not os.path.exists(path):
        raise DataError(path, field, path, "file not found")
    try:
        if str(path).endswith(".npy"):
            arr = np.load(path, allow_pickle=False)
        else:
            arr = np.loadtxt(path, delimiter=",", ndmin=2)
    except ValueError as exc:
        raise DataError(path, field, os.path.basename(path), f"not a numeric .npy/.csv matrix ({exc})") from None
    arr = np.asarray(arr, dtype=float)
    bad = np.argwhere(~np.isfinite(arr))
    if bad.size:
        raise DataError(path, f"{field}{list(map(int, bad[0]))}", float(arr[tuple(bad[0])]), "value is not finite")
    return arr
