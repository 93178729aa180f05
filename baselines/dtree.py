"""Sliding-window decision-tree regression (Kim et al. 2015), the strongest baseline of Taylor et al. (2017).

Every frame's input window of ``kx = 11`` frames of phone labels
(:func:`dam.features.window_features`, raw one-hot or Taylor et al.'s
linguistic indicator features) predicts the output window of ``ky = 5``
frames of every channel with one multi-output scikit-learn regression tree
(minimum leaf size 10); the overlapping output windows are averaged frame by
frame (:func:`dam.features.overlap_average`).

Window spacing. Taylor et al. worked at 29.97 video frames per second, where
11 frames span 0.37 s of context. Articulatory data come at 100-400 Hz, so the
window frames here are ``dilation = round(frame_rate / window_rate)`` frames
apart (``window_rate = 30`` Hz by default): the same number of frames and the
same span of context as the paper, at every frame of the data. Every frame
up to 100 Hz is a training example (``example_stride``).

The fitted tree is stored as arrays (children, feature, threshold, value) and
predicted by walking them in numpy: a saved model needs neither
scikit-learn nor pickle.
"""

from __future__ import annotations

import numpy as np

from dam import Alignment, Corpus, Interval, Options, StateNames, Synthesizer
from dam.corpus import (
    fit_transition_clusters,
    overlap_average,
    phone_vocabulary,
    window_dilation,
    window_features,
    window_targets,
)

__all__ = ["DecisionTree", "tree_to_arrays", "predict_tree_arrays"]

_TREE_KEYS = ("children_left", "children_right", "feature", "threshold", "value")


def tree_to_arrays(tree) -> dict[str, np.ndarray]:
    """The arrays of a fitted scikit-learn tree (``estimator.tree_``).

    Returns
    -------
    dict with ``children_left``, ``children_right`` (int, -1 at leaves),
    ``feature`` (int), ``threshold`` (float), all of shape (n_nodes,), and
    ``value`` (float, shape (n_nodes, n_outputs)).
    """
    return {
        "children_left": np.asarray(tree.children_left, dtype=np.int64),
        "children_right": np.asarray(tree.children_right, dtype=np.int64),
        "feature": np.asarray(tree.feature, dtype=np.int64),
        "threshold": np.asarray(tree.threshold, dtype=np.float64),
        "value": np.asarray(tree.value, dtype=np.float64).reshape(tree.node_count, -1),
    }


def predict_tree_arrays(arrays: dict, X: np.ndarray) -> np.ndarray:
    """Predict with a tree given as arrays (scikit-learn's rule: ``x[feature] <= threshold`` goes left).

    Parameters
    ----------
    arrays : dict from :func:`tree_to_arrays`
    X : ndarray, shape (n_samples, n_features)
        Compared in float32, as scikit-learn does.

    Returns
    -------
    ndarray, shape (n_samples, n_outputs)
    """
    X = np.asarray(X, dtype=np.float32)
    left, right = arrays["children_left"], arrays["children_right"]
    feature, threshold = arrays["feature"], arrays["threshold"]
    node = np.zeros(len(X), dtype=np.int64)
    rows = np.arange(len(X))
    active = left[node] >= 0
    while active.any():  # one level of the tree per pass
        r, nd = rows[active], node[active]
        go_left = X[r, feature[nd]] <= threshold[nd]
        node[r] = np.where(go_left, left[nd], right[nd])
        active[r] = left[node[r]] >= 0
    return arrays["value"][node]


class DecisionTree(Synthesizer):
    """Kim et al. (2015) sliding-window regression tree, as benchmarked by Taylor et al. (2017).

    Parameters
    ----------
    kx : int, default 11
        Input window length in frames.
    ky : int, default 5
        Output window length in frames.
    features : {"raw", "linguistic"}, default "raw"
        One-hot phones, or Taylor et al.'s linguistic indicator features.
    transitions : {"data", "phonetic"}, default "data"
        For ``features="linguistic"``: phone-pair transition clusters fitted
        on the training corpus as the paper did
        (:func:`dam.features.fit_transition_clusters`), or the phonetic
        approximation.
    window_rate : float or None, default 30.0
        Rate (Hz) of the window frames; None uses every data frame (dilation 1).
    example_stride : int or None, default None
        Train on every ``example_stride``-th frame; None: every frame up to
        100 Hz, about 100 examples per second above (``ceil(frame_rate / 100)``).
        The feature matrix holds ``n_frames / example_stride`` rows of float32
        (2341 columns for 40 phones with linguistic features).
    min_samples_leaf : int, default 10
    max_depth : int or None, default None
    random_state : int, default 0
    unknown_phone : {"error", "fallback"}, default "error"

    Attributes
    ----------
    vocabulary_ : list of str
        Phones of the one-hot features (training phones and silence).
    dilation_ : int
    tree_ : dict of ndarray
        The fitted tree (:func:`tree_to_arrays`); outputs ordered window
        frame major, channel minor.
    transition_clusters_ : dict of ndarray or None
    n_leaves_ : int
    """

    name = "dtree"
    _tags = {"deterministic": True, "numpy_runtime": True}
    _parameter_constraints = {
        **dict.fromkeys(["kx", "ky", "min_samples_leaf"], [Interval(int, 1, None, closed="left")]),
        "example_stride": [Interval(int, 1, None, closed="left"), None],
        "max_depth": [Interval(int, 1, None, closed="left"), None],
        "features": [Options({"raw", "linguistic"})],
        "transitions": [Options({"data", "phonetic"})],
        "window_rate": [Interval(float, 0, None, closed="neither"), None],
    }
    _state_schema = {  # checked at save and load (dam.modelfile.check_state)
        "vocabulary_": StateNames(),
        "dilation_": Interval(int, 1, None),
        "transition_clusters_": None,
        "tree_": None,
        "n_leaves_": Interval(int, 1, None),
    }

    def __init__(
        self,
        *,
        kx: int = 11,
        ky: int = 5,
        features: str = "raw",
        transitions: str = "data",
        window_rate: float | None = 30.0,
        example_stride: int | None = None,
        min_samples_leaf: int = 10,
        max_depth: int | None = None,
        random_state: int = 0,
        unknown_phone: str = "error",
    ):
        self.kx = kx
        self.ky = ky
        self.features = features
        self.transitions = transitions
        self.window_rate = window_rate
        self.example_stride = example_stride
        self.min_samples_leaf = min_samples_leaf
        self.max_depth = max_depth
        self.random_state = random_state
        self.unknown_phone = unknown_phone

    @classmethod
    def get_test_params(cls) -> list[dict]:
        return [
            {"max_depth": 12},
            {"features": "linguistic", "kx": 7, "ky": 3, "max_depth": 8, "unknown_phone": "fallback"},
        ]

    def _features(self, alignment: Alignment, n_frames: int) -> np.ndarray:
        return window_features(
            alignment,
            self.frame_rate_,
            n_frames,
            self.vocabulary_,
            kx=self.kx,
            features=self.features,
            transition_clusters=self.transition_clusters_,
            dilation=self.dilation_,
        )

    def _fit(self, corpus: Corpus) -> None:
        from sklearn.tree import DecisionTreeRegressor

        self.vocabulary_ = phone_vocabulary(corpus, silence=corpus.alignments[0].silence)
        self.dilation_ = window_dilation(corpus.frame_rate, self.window_rate)
        self.transition_clusters_ = None
        if self.features == "linguistic" and self.transitions == "data":
            self.transition_clusters_ = fit_transition_clusters(
                corpus, self.vocabulary_, random_state=self.random_state
            )
        stride = (
            int(np.ceil(corpus.frame_rate / 100.0 - 1e-9)) if self.example_stride is None else int(self.example_stride)
        )
        X, Y = [], []
        for u in corpus:
            # Every stride-th frame, the phase varying over utterances.
            take = np.arange(len(X) % stride, u.n_frames, stride)
            X.append(self._features(u.alignment, u.n_frames)[take])
            Y.append(window_targets(u.trajectory, ky=self.ky, dilation=self.dilation_)[take])
        est = DecisionTreeRegressor(
            min_samples_leaf=self.min_samples_leaf, max_depth=self.max_depth, random_state=self.random_state
        )
        est.fit(np.concatenate(X), np.concatenate(Y))
        self._sklearn_tree = est  # kept for inspection and tests; never saved
        self.tree_ = tree_to_arrays(est.tree_)
        self.n_leaves_ = int(est.get_n_leaves())

    def _predict(self, alignment: Alignment, n_frames: int) -> np.ndarray:
        labels = self._known_labels(alignment, self.unknown_phone)
        if tuple(labels) != alignment.labels:
            alignment = Alignment(
                labels, alignment.starts, alignment.ends, source=alignment.source, silence=alignment.silence
            )
        windows = predict_tree_arrays(self.tree_, self._features(alignment, n_frames))
        return overlap_average(windows, self.ky, len(self.channels_), dilation=self.dilation_)
