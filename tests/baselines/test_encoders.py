"""The audio encoders of the neural synthesizers (issue 15): MFCC / log-mel against a hand
computation, frame alignment, refusal of corpora without audio, user-supplied features,
learning from audio, and audio-driven rows in ``compare``."""

import numpy as np
import pytest
from scipy.io import wavfile

import dam
from baselines.nn.acoustic import hz_to_mel, log_mel, mel_to_hz, mfcc
from baselines.nn.encoders import FEATURES_SUFFIX, encoder_from_state, make_encoder
from dam.datasets.tones import tiny_with_audio

SR = 16000


@pytest.fixture(scope="module")
def tones():
    """tiny with toy audio (every phone a chord), split 75/25."""
    return tiny_with_audio().train_test_split(0.25, random_state=0)


def _hand_mfcc(x, sr, t, *, window, n_mels, n_mfcc, preemphasis):
    """MFCC of the frame centred on sample round(t * sr), written out from the definitions:
    pre-emphasis, Hamming window, DFT as an explicit sum, HTK-mel triangles, log, DCT-II sum."""
    x = np.asarray(x, float)
    y = x.copy()
    y[1:] = x[1:] - preemphasis * x[:-1]
    N = int(round(window * sr))
    start = int(round(t * sr)) - N // 2
    frame = np.array([y[start + n] if 0 <= start + n < len(y) else 0.0 for n in range(N)])
    frame = frame * (0.54 - 0.46 * np.cos(2 * np.pi * np.arange(N) / (N - 1)))
    n_fft = 1
    while n_fft < N:
        n_fft *= 2
    k = np.arange(n_fft // 2 + 1)
    dft = np.exp(-2j * np.pi * np.outer(k, np.arange(N)) / n_fft) @ frame
    power = np.abs(dft) ** 2
    freqs = k * sr / n_fft
    m_lo, m_hi = 2595 * np.log10(1 + 0 / 700), 2595 * np.log10(1 + (sr / 2) / 700)
    edges = [700 * (10 ** ((m_lo + (m_hi - m_lo) * i / (n_mels + 1)) / 2595) - 1) for i in range(n_mels + 2)]
    energies = []
    for m in range(n_mels):
        lo, c, hi = edges[m], edges[m + 1], edges[m + 2]
        w = [(f - lo) / (c - lo) if lo <= f <= c else (hi - f) / (hi - c) if c < f <= hi else 0.0 for f in freqs]
        energies.append(np.dot(w, power))
    logE = np.log(np.maximum(energies, 1e-10))
    out = []
    for q in range(n_mfcc):
        s = sum(logE[m] * np.cos(np.pi * q * (m + 0.5) / n_mels) for m in range(n_mels))
        out.append(s * (np.sqrt(1 / n_mels) if q == 0 else np.sqrt(2 / n_mels)))
    return np.array(out), logE


@pytest.mark.parametrize(
    "f0,frame_rate,n_mfcc,window", [(1000.0, 100.0, 13, 0.025), (440.0, 50.0, 27, 0.02), (3100.0, 100.0, 20, 0.032)]
)
def test_mfcc_matches_hand_computation_on_a_pure_tone(f0, frame_rate, n_mfcc, window):
    """Agreement to 1e-8 (absolute, float64) with the definition computed term by term."""
    t = np.arange(SR) / SR
    x = 0.5 * np.sin(2 * np.pi * f0 * t + 0.3)
    got = mfcc(x, SR, frame_rate=frame_rate, n_mfcc=n_mfcc, n_mels=40, window=window)
    fb = log_mel(x, SR, frame_rate=frame_rate, n_mels=40, window=window)
    assert got.shape == (int(frame_rate) + 1, n_mfcc)
    for i in (0, int(frame_rate) // 2, int(frame_rate)):  # both edges (zero padding) and the middle
        want, want_log = _hand_mfcc(x, SR, i / frame_rate, window=window, n_mels=40, n_mfcc=n_mfcc, preemphasis=0.97)
        np.testing.assert_allclose(got[i], want, rtol=0, atol=1e-8)
        np.testing.assert_allclose(fb[i], want_log, rtol=0, atol=1e-8)
    # Physics, not code: the loudest mel band of a pure tone is the one centred nearest the tone.
    centres = mel_to_hz(np.linspace(hz_to_mel(0), hz_to_mel(SR / 2), 42))[1:-1]
    assert np.argmax(fb[int(frame_rate) // 2]) == np.argmin(np.abs(centres - f0))


@pytest.mark.parametrize("frame_rate,hop", [(100.0, None), (50.0, None), (50.0, 0.01)])
@pytest.mark.parametrize("t_click", [0.2, 0.503, 0.777, 0.4162])
def test_a_click_shows_in_the_frame_at_its_time(tmp_path, frame_rate, hop, t_click):
    """A single-sample click at t: the encoder frame with the most energy is round(t * frame_rate)
    (frame i is centred on i / frame_rate), read end to end from a WAV file of an utterance."""
    x = np.zeros(SR, np.int16)
    x[int(round(t_click * SR))] = 20000
    wavfile.write(tmp_path / "u.wav", SR, x)
    n = int(frame_rate) + 1
    a = dam.Alignment(["sil"], [0.0], [1.0])
    u = dam.Utterance(a, np.zeros((n, 1)), frame_rate, ["c"], audio=str(tmp_path / "u.wav"), name="u")
    corpus = dam.Corpus([u])
    enc = make_encoder("fbank" + ("" if hop is None else f":hop={hop}"), corpus)
    raw = enc.raw_frames(u, frame_rate, n)
    k = 1 if hop is None else int(round(1 / (frame_rate * hop)))
    assert raw.shape == (n, 40 * k)
    energy = np.exp(raw.reshape(n, k, 40)).sum(axis=(1, 2))
    assert np.argmax(energy) == int(round(t_click * frame_rate))
    if k > 1:  # the sub-frames are in time order: the click is in the one centred nearest it
        sub = np.exp(raw[int(round(t_click * frame_rate))].reshape(k, 40)).sum(axis=1)
        centres = int(round(t_click * frame_rate)) / frame_rate + (np.arange(k) - (k - 1) / 2) * hop
        dist = np.abs(centres - t_click)
        if np.sort(dist)[1] - dist.min() > 1e-3:  # not a tie
            assert np.argmax(sub) == np.argmin(dist)


def test_audio_encoders_refuse_a_corpus_without_audio_naming_the_utterance():
    tiny = dam.datasets.load("tiny")
    for spec in ("mfcc", "fbank", "mfcc-mfb-ssc"):
        with pytest.raises(dam.DataError, match="tiny000") as exc:
            make_encoder(spec, tiny)
        assert "audio" in str(exc.value) and "30 of 30" in str(exc.value)
    gru = dam.registry.make("gru", encoder="mfcc", max_epochs=1, verbose=0)
    with pytest.raises(dam.DataError, match="tiny000"):
        gru.fit(tiny)
    assert not gru.is_fitted()


def test_an_audio_model_refuses_an_alignment_and_a_phone_model_takes_an_utterance(tones):
    train, test = tones
    m = dam.registry.make("causal-mlp", encoder="mfcc", hidden_layer_sizes=(8,), max_epochs=1, verbose=0).fit(train)
    assert m.reads() == ("audio",)
    with pytest.raises(TypeError, match="reads audio"):
        m.predict(test[0].alignment)
    p = dam.registry.make("phone-mean").fit(train)
    np.testing.assert_array_equal(p.predict(test[0]), p.predict(test[0].alignment))


def test_encoder_options_are_parameters(tones):
    train, _ = tones
    enc = make_encoder("mfcc:n_mfcc=27,window=0.02", train)
    assert enc.n_features == 27
    back = encoder_from_state(enc.state())
    np.testing.assert_array_equal(
        back.frames(train[0], 100.0, train[0].n_frames), enc.frames(train[0], 100.0, train[0].n_frames)
    )
    with pytest.raises(dam.InvalidParameterError, match="encoder"):
        dam.registry.make("gru", encoder="mfcc:not_an_option=1", verbose=0).fit(train)
    with pytest.raises(dam.InvalidParameterError, match="encoder"):
        dam.registry.make("gru", encoder="phones:n_mfcc=3", verbose=0).fit(train)


def test_features_encoder_reads_user_features_beside_each_utterance(tmp_path):
    """``<stem>.features.npy`` at 50 Hz for a 100 Hz corpus: frame i reads row floor(i / 2)."""
    src = tiny_with_audio(tmp_path / "c")
    corpus = dam.load_corpus(tmp_path / "c")
    for u in corpus:
        rows = u.n_frames // 2 + 1
        np.save(tmp_path / "c" / f"{u.name}{FEATURES_SUFFIX}", np.arange(rows * 3, dtype=float).reshape(rows, 3))
    enc = make_encoder("features:features_rate=50", corpus)
    u = corpus[0]
    raw = enc.raw_frames(u, 100.0, u.n_frames)
    np.testing.assert_array_equal(raw[:, 0], 3 * (np.arange(u.n_frames) // 2))
    (tmp_path / "c" / f"{src[1].name}{FEATURES_SUFFIX}").unlink()
    with pytest.raises(dam.DataError, match=f"{src[1].name}{FEATURES_SUFFIX}"):
        make_encoder("features", dam.load_corpus(tmp_path / "c"))


@pytest.mark.parametrize(
    "name,params",
    [
        ("gru", {"n_layers": 1, "hidden_size": 32, "seq_len": 64, "learning_rate": 1e-2}),
        ("causal-mlp", {"hidden_layer_sizes": (64,), "learning_rate": 3e-3, "batch_size": 64}),
        (
            "transformer",
            {
                "window": 9,
                "n_layers": 1,
                "n_heads": 2,
                "d_model": 32,
                "d_ff": 64,
                "window_hop": 1,
                "learning_rate": 5e-3,
                "max_epochs": 150,
            },
        ),
    ],
)
def test_medina_decoders_learn_a_small_audio_corpus_from_mfcc(tones, name, params):
    """Training loss (standardized MSE) falls by 90% on 8 utterances of toy audio."""
    train, _ = tones
    small = train.subset(range(8))
    m = dam.registry.make(
        name,
        **{"encoder": "mfcc", "dropout": 0.0, "max_epochs": 80, "validation_fraction": 0.0, "verbose": 0, **params},
    ).fit(small)
    assert m.loss_curve_[-1] <= 0.1 * m.initial_loss_, (m.initial_loss_, m.loss_curve_[-1])


def test_mfcc_model_saves_loads_and_predicts_from_audio_alone(tones, tmp_path):
    train, test = tones
    m = dam.registry.make("gru", encoder="mfcc:n_mfcc=20", n_layers=1, hidden_size=8, max_epochs=2, verbose=0).fit(
        train
    )
    m.save(tmp_path / "m.dam")
    back = dam.load(tmp_path / "m.dam")
    u = test[0]
    np.testing.assert_allclose(back.predict(u), m.predict(u), rtol=1e-6, atol=1e-9)
    # no transcript: the audio file alone gives the same frames (the utterance's count)
    alone = back.predict_audio(u.audio)
    np.testing.assert_allclose(alone[: u.n_frames], m.predict(u), rtol=1e-5, atol=1e-6)
    assert abs(len(alone) - u.n_frames) <= 1


def test_compare_puts_audio_rows_beside_phone_rows(tones, capsys):
    """Phone-driven and audio-driven models in one table; every row on the utterances with audio."""
    from dam.evaluation.compare import compare

    train, test = tones
    no_audio = [u.replace(audio=None) for u in train[:3]]
    mixed = dam.Corpus(no_audio + list(train[3:]), name="mixed")
    res = compare(
        [
            "phone-mean",
            ("gru-mfcc", "gru", {"encoder": "mfcc", "n_layers": 1, "hidden_size": 8, "max_epochs": 3, "verbose": 0}),
        ],
        mixed,
        test,
    )
    assert {r.model for r in res.summary} == {"phone-mean", "gru-mfcc"}
    assert all(r.status == "ok" for r in res.summary), [(r.model, r.status, r.reason) for r in res.summary]
    assert res.row("gru-mfcc").rmse > 0 and "gru-mfcc" in res.table()
    err = capsys.readouterr().err
    assert f"{len(train) - 3} of {len(train)} utterances" in err


def test_dam_animate_audio_uses_an_audio_model_without_transcript(tones, tmp_path, capsys):
    """`dam animate --audio` with an audio-driven model: no alignment, no phone recognition; the CSV
    holds the model's prediction from the audio alone."""
    from dam.cli import main

    train, test = tones
    m = dam.registry.make("causal-mlp", encoder="mfcc", hidden_layer_sizes=(8,), max_epochs=2, verbose=0).fit(train)
    m.save(tmp_path / "m.dam")
    u = test[0]
    rc = main(["animate", "--audio", u.audio, "--model", str(tmp_path / "m.dam"), "-o", str(tmp_path / "out.csv")])
    assert rc == 0
    err = capsys.readouterr().err
    assert "LESS ACCURATE" not in err
    got = np.loadtxt(tmp_path / "out.csv", delimiter=",", skiprows=1)
    want = m.predict_audio(u.audio)
    np.testing.assert_allclose(got[:, 0], np.arange(len(want)) / 100.0, atol=1e-6)  # the time column
    np.testing.assert_allclose(got[:, 1:], want, rtol=1e-4, atol=1e-5)
