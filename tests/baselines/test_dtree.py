"""Sliding-window decision tree (Kim et al. 2015): window averaging, array round trip, features."""

import numpy as np
import pytest

from baselines.dtree import DecisionTree, predict_tree_arrays, tree_to_arrays
from dam.base import load
from dam.corpus.data import Alignment, Corpus, Utterance
from dam.corpus.features import overlap_average, window_features


def _one_utterance():
    # 10 frames/s: frames 0,1 silence (y = 0), frames 2,3 /a/ (y = 4)
    a = Alignment(["sil", "a"], [0.0, 0.2], [0.2, 0.4])
    return Corpus([Utterance(a, [[0.0], [0.0], [4.0], [4.0]], 10.0, ["y"], name="u")])


def test_window_averaging_equals_hand_computation():
    corpus = _one_utterance()
    # kx = 1: the tree sees only the frame's phone and predicts the mean target window of that phone.
    model = DecisionTree(kx=1, ky=3, window_rate=None, min_samples_leaf=1).fit(corpus)
    # target windows (frames i-1, i, i+1, edges repeated): sil rows [0,0,0], [0,0,4] -> mean [0, 0, 2];
    # a rows [0,4,4], [4,4,4] -> mean [2, 4, 4]
    windows = predict_tree_arrays(model.tree_, window_features(corpus[0].alignment, 10.0, 4, model.vocabulary_, kx=1))
    np.testing.assert_allclose(windows, [[0, 0, 2], [0, 0, 2], [2, 4, 4], [2, 4, 4]])
    # frame 0: (0 + 0)/2; frame 1: (2 + 0 + 2)/3; frame 2: (2 + 4 + 2)/3; frame 3: (4 + 4)/2
    np.testing.assert_allclose(model.predict(corpus[0].alignment)[:, 0], [0.0, 4 / 3, 8 / 3, 4.0])


@pytest.mark.parametrize("features", ["raw", "linguistic"])
def test_tree_arrays_predict_like_sklearn_after_save_load(features, tmp_path):
    from dam.testing import default_corpora

    train, test = default_corpora()
    model = DecisionTree(features=features, kx=7, ky=3, max_depth=10).fit(train)
    path = tmp_path / "dtree.dam"
    model.save(path)
    back = load(path)
    for a in test.alignments[:3]:
        X = model._features(a, a.n_frames(model.frame_rate_))
        sk = model._sklearn_tree.predict(X)
        np.testing.assert_array_equal(predict_tree_arrays(back.tree_, X), sk)
        np.testing.assert_array_equal(
            back.predict(a), overlap_average(sk, 3, train.n_channels, dilation=model.dilation_)
        )


def test_tree_to_arrays_on_a_hand_made_split():
    from sklearn.tree import DecisionTreeRegressor

    X = np.array([[0.0], [1.0], [2.0], [3.0]])
    y = np.array([[1.0, 10.0], [1.0, 10.0], [5.0, 50.0], [5.0, 50.0]])
    arr = tree_to_arrays(DecisionTreeRegressor(max_depth=1).fit(X, y).tree_)
    assert arr["threshold"][0] == pytest.approx(1.5) and arr["value"].shape == (3, 2)
    np.testing.assert_allclose(predict_tree_arrays(arr, [[1.4], [1.6], [-9.0]]), [[1, 10], [5, 50], [1, 10]])


def test_window_rate_sets_dilation():
    corpus = _one_utterance()
    assert DecisionTree(window_rate=None).fit(corpus).dilation_ == 1
    assert DecisionTree(window_rate=3.0, kx=3, ky=1).fit(corpus).dilation_ == 3  # 10 Hz / 3 Hz


def test_bad_params_are_refused():
    with pytest.raises(ValueError, match="features"):
        DecisionTree(features="mfcc").fit(_one_utterance())
    with pytest.raises(ValueError, match="kx"):
        DecisionTree(kx=0).fit(_one_utterance())
