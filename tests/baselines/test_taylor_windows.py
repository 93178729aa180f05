"""Taylor et al.'s windows at the corpus frame rate: window_rate gives the paper's span of context."""

import numpy as np
import pytest

import dam
from dam.corpus import overlap_average, window_dilation, window_features, window_offsets


@pytest.mark.parametrize("frame_rate,expected", [(100.0, 3), (29.97, 1), (400.9, 13), (60.0, 2)])
def test_window_dilation_keeps_the_papers_span(frame_rate, expected):
    d = window_dilation(frame_rate, 30.0)
    assert d == expected
    # 11 window frames at this dilation span the paper's 11 / 29.97 s to within half a data frame per step
    assert abs(11 * d / frame_rate - 11 / 29.97) <= 11 * 0.5 / frame_rate + 1e-9
    assert window_dilation(frame_rate, None) == 1


def test_window_dilation_refuses_a_bad_rate():
    with pytest.raises(ValueError, match="window_rate"):
        window_dilation(100.0, 0.0)


def test_sliding_dnn_reads_and_writes_dilated_windows():
    train, test = dam.testing.default_corpora()
    model = dam.make("sliding-dnn", hidden_layer_sizes=(8,), max_epochs=1, verbose=0, kx=5, ky=3, window_rate=30.0).fit(
        train
    )
    a = test[0].alignment
    n = a.n_frames(model.frame_rate_)
    assert model._dilation() == 3
    X = model._inputs(model._input_encoder(), a, n)
    np.testing.assert_array_equal(
        X, window_features(a, model.frame_rate_, n, model._input_encoder().vocabulary, kx=5, dilation=3)
    )
    # the phones of the window of frame 20 are those of frames 14, 17, 20, 23, 26
    assert list(window_offsets(5, dilation=3) + 20) == [14, 17, 20, 23, 26]
    from baselines.nn.train import predict_padded

    windows = predict_padded(model._network(), X)
    want = overlap_average(windows, 3, train.n_channels, dilation=3) * model.y_scale_ + model.y_mean_
    np.testing.assert_allclose(model.predict(a), want, rtol=1e-6, atol=1e-9)
    # the default (every data frame) still reads neighbouring frames
    assert dam.make("sliding-dnn").get_params()["window_rate"] is None
