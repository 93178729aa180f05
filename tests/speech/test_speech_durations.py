"""The duration model recovers known context effects, beats the phone means, and round-trips its file."""

import numpy as np
import pytest

from dam import Alignment, ModelFileError
from dam.speech import DurationModel, context_features, phone_mean_baseline

PHONES = {"AA": 0.11, "IY": 0.09, "P": 0.07, "T": 0.06, "S": 0.09, "M": 0.06, "N": 0.05, "L": 0.06}
VOWELS = ("AA", "IY")
FINAL, STRESS, BEFORE_STOP = 1.5, 1.3, 0.8  # the generating effects


def _generate(n_utts, seed):
    """Phrases of CV(C) words; durations = base x effects x lognormal noise."""
    rng = np.random.default_rng(seed)
    out, word_ids = [], []
    cons = [p for p in PHONES if p not in VOWELS]
    for _ in range(n_utts):
        labels, wid, t = ["sil"], [-1], [0.2]
        for w in range(rng.integers(2, 6)):
            word = [rng.choice(cons), rng.choice(VOWELS) + str(rng.integers(0, 2))]
            if rng.random() < 0.6:
                word.append(rng.choice(cons))
            labels += word
            wid += [w] * len(word)
        labels.append("sil")
        wid.append(-1)
        n = len(labels)
        last_word = max(wid)
        for k in range(1, n - 1):
            lab = labels[k]
            base = PHONES[lab.rstrip("01")]
            d = base
            if wid[k] == last_word:
                d *= FINAL
            if lab.endswith("1"):
                d *= STRESS
            if labels[k + 1].rstrip("01") in ("P", "T"):
                d *= BEFORE_STOP
            t.append(d * np.exp(rng.normal(0, 0.05)))
        t.append(0.3)
        ends = np.cumsum(t)
        out.append(Alignment(labels, ends - np.array(t), ends))
        word_ids.append(wid)
    return out, word_ids


def _ratio(model, a, b):
    return model.effect(a) / model.effect(b)


def test_recovers_phrase_final_lengthening_stress_and_right_context():
    train, wid = _generate(400, 0)
    model = DurationModel(alpha=0.1).fit(train, wid)
    assert _ratio(model, "phrase=final_word", "phrase=initial_word") == pytest.approx(FINAL, rel=0.05)
    assert _ratio(model, "stress=1", "stress=0") == pytest.approx(STRESS, rel=0.05)
    # P and T are "bilabial" and "alveolar"; the nasals M/N share those classes without the effect
    assert _ratio(model, "right=bilabial", "right=silence") < 1.0


def test_beats_the_phone_mean_baseline_on_held_out_data():
    train, wid = _generate(300, 1)
    test, wid_test = _generate(100, 2)
    model = DurationModel().fit(train, wid)
    pred = np.concatenate([model.predict(list(a.labels), w) for a, w in zip(test, wid_test)])
    true = np.concatenate([a.ends - a.starts for a in test])
    base = phone_mean_baseline(train, test)
    rmse, rmse_base = np.sqrt(np.mean((pred - true) ** 2)), np.sqrt(np.mean((base - true) ** 2))
    assert rmse < 0.5 * rmse_base


def test_rate_factor_divides_durations_and_alignment_is_contiguous():
    train, wid = _generate(50, 3)
    model = DurationModel().fit(train, wid)
    labels = ["sil", "P", "AA1", "T", "sil"]
    d1 = model.predict(labels)
    assert np.allclose(model.predict(labels, rate=2.0), d1 / 2)
    al = model.predict_alignment(labels, rate=1.25)
    assert np.allclose(al.ends - al.starts, d1 / 1.25) and al.starts[0] == 0.0
    with pytest.raises(ValueError, match="rate"):
        model.predict(labels, rate=0)


def test_unknown_phones_fall_back_to_the_intercept():
    model = DurationModel().fit(*_generate(30, 4))
    d = model.predict(["sil", "ZH", "AA1", "sil"])
    assert np.all(np.isfinite(d)) and np.all(d > 0)


def test_features_without_words_and_with_words():
    f = context_features(["sil", "P", "AA1", "sil", "T", "IY0", "sil"])
    assert f[2][3] == "word=unknown" and "phrase=final_word" in f[2]
    f = context_features(["sil", "P", "AA1", "T", "IY0", "sil"], [-1, 0, 0, 1, 1, -1])
    assert f[1][3] == "word=initial" and f[2][3] == "word=final" and "phrase=initial_word" in f[1]
    assert "phrase=final_word" in f[3] and "stress=0" in f[4]


def test_save_load_round_trip(tmp_path):
    model = DurationModel().fit(*_generate(30, 5))
    path = tmp_path / "durations.npz"
    model.save(path)
    again = DurationModel.load(path)
    labels = ["sil", "M", "AA1", "N", "sil"]
    assert np.array_equal(again.predict(labels), model.predict(labels))
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".tmp")]


def test_load_refuses_other_files(tmp_path):
    bad = tmp_path / "x.npz"
    bad.write_bytes(b"not a model")
    with pytest.raises(ModelFileError, match="x.npz"):
        DurationModel.load(bad)
    from dam.datasets.default_model import DEFAULT_MODEL_PATH
    from dam.speech import load_default_model

    assert load_default_model() is not None
    with pytest.raises(ModelFileError, match="duration"):
        DurationModel.load(DEFAULT_MODEL_PATH)


def test_shipped_duration_model_loads_and_predicts_plausible_durations():
    from dam.speech import load_default_durations

    model = load_default_durations()
    d = model.predict(["sil", "d", "a:", "s", "sil"], [-1, 0, 0, 0, -1])
    assert np.all((d > 0.02) & (d < 1.0))


def test_vtl_word_boundaries_come_from_the_recorded_words():
    import json

    from dam.datasets import path
    from dam.datasets.default_model import vtl_word_ids

    corpus, word_ids = vtl_word_ids("test")
    meta = json.loads((path("vtl", "test") / "corpus.json").read_text())["utterances"]
    for utt, wid in zip(corpus, word_ids):
        assert wid is not None and len(wid) == len(utt.alignment.labels)
        assert sorted(set(wid) - {-1}) == list(range(len(meta[utt.name]["words"])))
        assert all((w == -1) == (lab == "sil") for w, lab in zip(wid, utt.alignment.labels))
