"""The neural predictors (baselines/nn): learning, causality, averaging, persistence, compilation.

Every network is fitted once per module on a four-utterance corpus, with
settings that share compiled code between the tests (refits reuse it).
"""

import subprocess
import sys

# jax, equinox and optax are required for the test run (dam[test]; tests/conftest.py checks): no skipping here.
import equinox  # noqa: E402, F401
import jax  # noqa: E402, F401
import numpy as np
import optax  # noqa: E402, F401
import pytest

import dam  # noqa: E402
from dam.corpus.data import Alignment, Corpus, Utterance  # noqa: E402
from dam.testing import clone  # noqa: E402

# Tiny networks, no dropout, no validation: each must drive its training loss down.
OVERFIT = {
    "sliding-dnn": {"hidden_layer_sizes": (48, 48), "dropout": 0.0, "learning_rate": 3e-3, "batch_size": 32},
    "causal-mlp": {"hidden_layer_sizes": (48,), "dropout": 0.0, "learning_rate": 3e-3, "batch_size": 32},
    "gru": {"n_layers": 1, "hidden_size": 24, "seq_len": 32, "dropout": 0.0, "learning_rate": 1e-2, "batch_size": 8},
    "lstm": {
        "hidden_size": 16,
        "dense_size": 16,
        "seq_len": 32,
        "dropout": 0.0,
        "learning_rate": 1e-2,
        "batch_size": 8,
    },
    "transformer": {
        "window": 9,
        "n_layers": 1,
        "n_heads": 2,
        "d_model": 16,
        "d_ff": 32,
        "window_hop": 1,
        "dropout": 0.0,
        "learning_rate": 3e-3,
        "batch_size": 32,
    },
}
COMMON = {"max_epochs": 60, "validation_fraction": 0.0, "verbose": 0, "random_state": 0}
CAUSAL = ["causal-mlp", "gru"]
LOOKS_AHEAD = ["sliding-dnn", "lstm", "transformer"]  # centred windows or bidirectional


PHONE_TARGETS = {
    "sil": (0.0, 0.0),
    "aa": (1.0, -0.5),
    "iy": (0.3, 1.0),
    "s": (-0.8, 0.6),
    "m": (-1.0, -1.0),
    "t": (0.5, 0.2),
}


def learnable_corpus(n_utterances=6, seed=0):
    """Phone sequences whose trajectory is a causal 3-frame moving average of per-phone
    targets: a function of the current and two previous frames' phones, so every
    network here (causal or not) can fit it exactly."""
    rng = np.random.default_rng(seed)
    phones = list(PHONE_TARGETS)[1:]
    utts = []
    for i in range(n_utterances):
        labels = ["sil"] + list(rng.choice(phones, size=10)) + ["sil"]
        frames = rng.integers(3, 12, size=len(labels))
        ends = np.cumsum(frames) / 100.0
        starts = np.concatenate([[0.0], ends[:-1]])
        per_frame = np.concatenate([np.tile(PHONE_TARGETS[p], (f, 1)) for p, f in zip(labels, frames)])
        padded = np.concatenate([per_frame[:1], per_frame[:1], per_frame])
        traj = (padded[2:] + padded[1:-1] + padded[:-2]) / 3.0
        utts.append(Utterance(Alignment(labels, starts, ends), traj, 100.0, ("x", "y"), name=f"u{i}"))
    return Corpus(utts, name="learnable")


@pytest.fixture(scope="module")
def small():
    return learnable_corpus()


_FITTED = {}


def fitted(name, corpus):
    if name not in _FITTED:
        _FITTED[name] = dam.make(name, **OVERFIT[name], **COMMON).fit(corpus)
    return _FITTED[name]


def _standardized_mse(model, corpus):
    err = [((model.predict(u.alignment) - u.trajectory) / model.y_scale_) ** 2 for u in corpus]
    return float(np.mean(np.concatenate(err)))


@pytest.mark.parametrize("name", list(OVERFIT))
def test_network_overfits_tiny_corpus(name, small):
    model = fitted(name, small)
    assert model.n_epochs_ == COMMON["max_epochs"] and len(model.loss_curve_) == model.n_epochs_
    assert model.validation_curve_ == []
    # Training loss (standardized units) falls by at least 90% from the untrained network's.
    assert model.loss_curve_[-1] <= 0.1 * model.initial_loss_, (model.initial_loss_, model.loss_curve_[-5:])
    # ... and so does the error of the synthesized trajectories themselves.
    assert _standardized_mse(model, small) <= 0.1 * model.initial_loss_


@pytest.mark.parametrize("name", list(OVERFIT))
def test_save_load_gives_identical_predictions(name, small, tmp_path):
    model = fitted(name, small)
    path = tmp_path / f"{name}.dam"
    model.save(path)
    back = dam.load(path)
    assert type(back) is type(model) and back.get_params() == model.get_params()
    for u in small:
        np.testing.assert_array_equal(back.predict(u.alignment), model.predict(u.alignment))


@pytest.mark.parametrize("name", ["sliding-dnn", "gru"])
def test_same_seed_same_weights_other_seed_other_weights(name, small):
    model = fitted(name, small)
    again = clone(model).fit(small)
    assert len(again.weights_) == len(model.weights_)
    for a, b in zip(again.weights_, model.weights_):
        np.testing.assert_array_equal(a, b)
    # Only the seed differs between these two (same epochs), so the seed is what changes the weights.
    one = clone(model).set_params(max_epochs=1).fit(small)
    other = clone(model).set_params(random_state=1, max_epochs=1).fit(small)
    assert not any(np.array_equal(a, b) for a, b in zip(other.weights_, one.weights_))


def _future_changed(alignment, t0, fallback_phones):
    """The same segments, with every segment starting at or after ``t0`` relabelled."""
    labels = list(alignment.labels)
    for k, s in enumerate(alignment.starts):
        if s >= t0:
            labels[k] = next(p for p in fallback_phones if p != labels[k])
    assert labels != list(alignment.labels)
    return Alignment(labels, alignment.starts, alignment.ends)


def _before_and_after(model, corpus):
    a = max(corpus.alignments, key=len)
    t0 = a.starts[len(a) // 2]
    n0 = int(np.ceil(t0 * model.frame_rate_ - 1e-9))  # frames before n0 see only unchanged phones
    changed = _future_changed(a, t0, ["aa", "iy", "s"])
    return model.predict(a), model.predict(changed), n0


@pytest.mark.parametrize("name", CAUSAL)
def test_causal_outputs_ignore_future_inputs(name, small):
    model = fitted(name, small)
    base, changed, n0 = _before_and_after(model, small)
    np.testing.assert_allclose(changed[:n0], base[:n0], rtol=0, atol=1e-6)
    assert np.abs(changed[n0:] - base[n0:]).max() > 1e-3  # the change itself is seen


@pytest.mark.parametrize("name", LOOKS_AHEAD)
def test_lookahead_outputs_see_future_inputs(name, small):
    model = fitted(name, small)
    base, changed, n0 = _before_and_after(model, small)
    assert np.abs(changed[:n0] - base[:n0]).max() > 1e-4


def test_bidirectional_state_ignores_padding(small):
    import equinox as eqx
    import jax.numpy as jnp

    model = fitted("lstm", small)
    net, enc = model._network(), model._input_encoder()
    a = small[0].alignment
    x = enc.frames(a, model.frame_rate_, small[0].n_frames)
    outs = []
    for length in (len(x) + 3, len(x) + 40):
        xp = np.zeros((length, x.shape[1]), np.float32)
        xp[: len(x)] = x
        m = (np.arange(length) < len(x)).astype(np.float32)
        outs.append(np.asarray(eqx.filter_jit(net)(jnp.asarray(xp), jnp.asarray(m)))[: len(x)])
    np.testing.assert_allclose(outs[0], outs[1], rtol=0, atol=1e-5)


@pytest.mark.parametrize("cell", ["gru", "lstm"])
def test_recurrent_layer_equals_equinox_cell_step_by_step(cell):
    import equinox as eqx

    from baselines.nn.rnn import run_recurrent_layer

    make = eqx.nn.GRUCell if cell == "gru" else eqx.nn.LSTMCell
    c = make(3, 5, key=jax.random.key(1))
    xs = np.random.default_rng(0).standard_normal((7, 3)).astype(np.float32)
    mask = np.array([1, 1, 1, 1, 1, 0, 0], bool)
    for reverse in (False, True):
        state = np.zeros(5, np.float32) if cell == "gru" else (np.zeros(5, np.float32),) * 2
        expected = np.zeros((7, 5))
        order = range(6, -1, -1) if reverse else range(7)
        for t in order:  # the library's own cell, one frame at a time; padding leaves the state alone
            if mask[t]:
                state = c(xs[t], state)
            expected[t] = state if cell == "gru" else state[0]
        got = np.asarray(run_recurrent_layer(c, xs, mask, reverse=reverse))
        np.testing.assert_allclose(got, expected, rtol=1e-5, atol=1e-6)


@pytest.mark.parametrize("name", ["sliding-dnn", "transformer"])
def test_prediction_is_the_hand_average_of_overlapping_windows(name, small):
    from baselines.nn.train import predict_padded

    model = fitted(name, small)
    u = small[1]
    n, C = u.n_frames, small.n_channels
    k = model.ky if name == "sliding-dnn" else model.window
    windows = predict_padded(model._network(), model._inputs(model._input_encoder(), u.alignment, n))
    windows = windows.reshape(n, k, C)
    expected = np.zeros((n, C))
    for t in range(n):  # frame t collects entry j of the window centred at t - (j - k // 2)
        hits = [windows[t - (j - k // 2), j] for j in range(k) if 0 <= t - (j - k // 2) < n]
        expected[t] = np.mean(hits, axis=0)
    got = (model.predict(u.alignment) - model.y_mean_) / model.y_scale_
    np.testing.assert_allclose(got, expected, rtol=1e-6, atol=1e-9)


def test_causal_mlp_synthesizes_the_last_frame_of_each_window(small):
    from baselines.nn.train import predict_padded

    model = fitted("causal-mlp", small)
    u = small[1]
    windows = predict_padded(model._network(), model._inputs(model._input_encoder(), u.alignment, u.n_frames))
    got = (model.predict(u.alignment) - model.y_mean_) / model.y_scale_
    np.testing.assert_allclose(got, windows.reshape(u.n_frames, model.ky, -1)[:, -1], rtol=1e-6, atol=1e-9)


@pytest.mark.parametrize("name", ["sliding-dnn", "gru"])
def test_second_prediction_does_not_recompile(name, small):
    from baselines.nn import train

    model = fitted(name, small)
    fr = model.frame_rate_
    a = small[0].alignment
    model.predict(a)
    count = train.TRACE_COUNT["predict"]
    model.predict(a)
    # a different length in the same bucket reuses the compiled function
    model.predict(a.with_end(a.duration + 3 / fr))
    assert train.bucket_length(a.n_frames(fr)) == train.bucket_length(a.n_frames(fr) + 3)
    assert train.TRACE_COUNT["predict"] == count
    # the counter does count: a new bucket compiles once
    long = a.with_end(a.duration + 2 * train.bucket_length(a.n_frames(fr)) / fr)
    model.predict(long)
    model.predict(long)
    assert train.TRACE_COUNT["predict"] == count + 1


def test_early_stopping_keeps_the_best_epoch(small):
    corpus = learnable_corpus(8, seed=1)
    params = dict(OVERFIT["sliding-dnn"], **COMMON)
    params.update(validation_fraction=0.25, patience=2, max_epochs=40, learning_rate=3e-2)
    model = dam.make("sliding-dnn", **params).fit(corpus)
    val = np.asarray(model.validation_curve_)
    assert len(val) == model.n_epochs_ == len(model.loss_curve_)
    assert model.best_epoch_ == int(np.argmin(val)) + 1
    assert model.n_epochs_ < 40, "validation loss kept improving: raise the learning rate of this test"
    assert model.n_epochs_ - model.best_epoch_ == 2


def test_bad_parameters_are_named(small):
    with pytest.raises(ValueError, match="dropout"):
        dam.make("sliding-dnn", dropout=1.5).fit(small)
    with pytest.raises(ValueError, match="cell"):
        dam.make("gru", cell="rnn").fit(small)
    with pytest.raises(ValueError, match="d_model"):
        dam.make("transformer", d_model=10, n_heads=4).fit(small)
    with pytest.raises(ValueError, match="encoder"):
        dam.make("causal-mlp", encoder="wav2vec").fit(small)


def test_verbose_zero_is_silent(small, capfd):
    dam.make("sliding-dnn", **{**OVERFIT["sliding-dnn"], **COMMON, "max_epochs": 2}).fit(small)
    out, err = capfd.readouterr()
    assert out == "" and err == ""


def test_import_dam_and_listing_models_do_not_import_jax():
    code = (
        "import sys, dam; from dam import registry; registry.names(); dam.make; "
        "assert 'jax' not in sys.modules, 'jax imported'"
    )
    subprocess.run([sys.executable, "-c", code], check=True, cwd=str(__import__("pathlib").Path(__file__).parents[1]))
