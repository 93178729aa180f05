"""VisemeNet (Zhou et al. 2018), adapted: three stages from audio, activations and their thresholds."""

import numpy as np
import pytest

import dam
from baselines.nn.visemenet import VisemeNet, joint_loss
from dam.corpus import AudioClip, frame_labels
from dam.datasets.tones import tiny_with_audio

SMALL = dict(
    n_past=3,
    n_future=3,
    hidden_size=32,
    n_layers=1,
    fc_size=32,
    seq_len=64,
    dropout=0.0,
    pretrain_epochs=5,
    learning_rate=1e-2,
    batch_size=16,
    verbose=0,
)


@pytest.fixture(scope="module")
def tones():
    return tiny_with_audio().train_test_split(0.25, random_state=0)


@pytest.fixture(scope="module")
def fitted(tones):
    train, _ = tones
    return VisemeNet(**SMALL, max_epochs=60).fit(train)


def test_learns_a_small_audio_corpus(tones):
    """The joint multi-task loss on 8 utterances falls by 90% from the untrained network's."""
    import jax.numpy as jnp

    train, _ = tones
    small = train.subset(range(8))
    m = VisemeNet(**SMALL, max_epochs=120, validation_fraction=0.0).fit(small)
    X, Y, W = m._stack(m._encoder, list(small))
    untrained = m._make_network(m.n_inputs_, m.n_outputs_, 0)
    before = float(joint_loss(untrained, jnp.asarray(X), jnp.asarray(Y), jnp.asarray(W), None))
    after = float(joint_loss(m._network(), jnp.asarray(X), jnp.asarray(Y), jnp.asarray(W), None))
    assert after <= 0.1 * before, (before, after)


def test_phone_groups_are_recognised_from_audio(fitted, tones):
    """Stage 1 reads no transcript; its argmax agrees with the articulatory class of the
    aligned phone on most held-out frames (chance: the largest class, silence)."""
    _, test = tones
    scores = fitted.activation_scores(test)
    labels = [lab for u in test for lab in frame_labels(u.alignment, u.frame_rate, u.n_frames)]
    chance = max(labels.count(x) for x in set(labels)) / len(labels)
    assert scores["phone_group_accuracy"] > max(0.7, chance + 0.2), (scores["phone_group_accuracy"], chance)
    st = fitted.predict_stages(test[0])
    np.testing.assert_allclose(st["phone_group_probabilities"].sum(axis=1), 1.0, rtol=1e-6)


def test_gate_keeps_values_where_active_and_rest_elsewhere(fitted, tones):
    _, test = tones
    u = test[0]
    st = fitted.predict_stages(u)
    y = fitted.predict(u)
    on = st["activation_probabilities"] > fitted.thresholds_
    np.testing.assert_array_equal(on, st["active"])
    np.testing.assert_allclose(y[on], st["values"][on], rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(y[~on], np.broadcast_to(fitted.rest_, y.shape)[~on], rtol=1e-6, atol=1e-9)
    assert on.any() and (~on).any()


def test_activation_precision_recall_by_counting(fitted, tones):
    """activation_scores equals a count written here from the definition (active: more than
    activation_threshold standard deviations from the rest, the mean over silence frames)."""
    train, test = tones
    Y = np.concatenate(train.trajectories)
    std = np.where(Y.std(axis=0) > 1e-12, Y.std(axis=0), 1.0)
    sil = np.concatenate(
        [u.trajectory[np.array(frame_labels(u.alignment, u.frame_rate, u.n_frames)) == "sil"] for u in train]
    )
    rest = sil.mean(axis=0)
    tp = n_pred = n_true = 0
    for u in test:
        truth = np.abs(u.trajectory - rest) / std > fitted.activation_threshold
        pred = fitted.predict_stages(u)["active"]
        tp += np.sum(truth & pred)
        n_pred += pred.sum()
        n_true += truth.sum()
    s = fitted.activation_scores(test)
    assert s["precision"] == pytest.approx(tp / n_pred, rel=1e-12)
    assert s["recall"] == pytest.approx(tp / n_true, rel=1e-12)
    assert 0.5 < s["precision"] <= 1 and 0.5 < s["recall"] <= 1  # it learned something


def test_thresholds_maximise_f1_on_held_out_utterances(tones):
    """Exhaustive search over the grid on the validation utterances gives the same thresholds."""
    train, _ = tones
    m = VisemeNet(**SMALL, max_epochs=10, validation_fraction=0.25).fit(train)
    _, val = m._validation_split(train, 0)
    grid = np.round(np.arange(0.05, 0.96, 0.05), 2)
    P = np.concatenate([m.predict_stages(u)["activation_probabilities"] for u in val])
    A = np.concatenate([m._active((u.trajectory - m.y_mean_) / m.y_scale_) for u in val]) > 0
    for c in range(P.shape[1]):
        f1 = []
        for t in grid:
            pred = P[:, c] > t
            tp = np.sum(pred & A[:, c])
            f1.append(2 * tp / max(pred.sum() + A[:, c].sum(), 1e-12))
        assert f1[list(grid).index(m.thresholds_[c])] == pytest.approx(max(f1))


def test_look_ahead_is_bounded_by_n_future(fitted, tones):
    """Changing the audio from 0.5 s on changes no output frame before the analysis window
    (25 ms) and the n_future frames of look-ahead reach it; later frames do change."""
    _, test = tones
    u = max(test, key=lambda v: v.n_frames)
    from scipy.io import wavfile

    sr, x = wavfile.read(u.audio)
    x = x.astype(float) / 32768
    changed = x.copy()
    changed[int(0.5 * sr) :] = np.random.default_rng(0).uniform(-0.5, 0.5, len(x) - int(0.5 * sr))
    a = fitted.predict(AudioClip(x, sr))
    b = fitted.predict(AudioClip(changed, sr))
    first_touched = 49  # frame 49's window, centred at 0.49 s, reaches 0.5025 s
    safe = first_touched - fitted.n_future
    np.testing.assert_allclose(a[:safe], b[:safe], rtol=1e-6, atol=1e-9)
    assert not np.allclose(a[first_touched + 5 :], b[first_touched + 5 :])


def test_needs_an_audio_encoder_and_audio():
    tiny = dam.datasets.load("tiny")
    with pytest.raises(dam.InvalidParameterError, match="encoder"):
        VisemeNet(encoder="phones").fit(tiny)
    with pytest.raises(dam.DataError, match="tiny000"):
        VisemeNet(**SMALL, max_epochs=1).fit(tiny)
