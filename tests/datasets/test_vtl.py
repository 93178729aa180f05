"""The VocalTractLab corpus generator and the bundled ``vtl`` corpus."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("vocaltractlab_cython")

import dam.datasets  # noqa: E402
from dam.corpus.data import SILENCE, Alignment, DataError, fit_to_frames  # noqa: E402
from dam.corpus.io import load_corpus  # noqa: E402
from dam.datasets import vtl  # noqa: E402

# Words without plosives and nasals: VTL times every oral closure by search
# (about 0.5 s of CPU each), these synthesize in milliseconds.
FAST = [
    vtl.Word("Allee", ("a", "l", "e:"), (0.08, 0.07, 0.15)),
    vtl.Word("Hose", ("h", "o:", "z", "@"), (0.07, 0.14, 0.09, 0.06)),
    vtl.Word("Eier", ("aI", "6"), (0.15, 0.1)),
    vtl.Word("Reise", ("r", "aI", "z", "@"), (0.07, 0.15, 0.09, 0.06)),
    vtl.Word("Schal", ("S", "a:", "l"), (0.1, 0.15, 0.08)),
    vtl.Word("viel", ("f", "i:", "l"), (0.1, 0.12, 0.08)),
]


def _plan(labels, durations, audio=False):
    return vtl.PhrasePlan("p", ("w",), tuple(labels), tuple(durations), (1,), 1.0, audio)


def _mid(alignment, k, traj, channel):
    """Value of ``channel`` at the middle of segment k (100 Hz frames)."""
    t = 0.5 * (alignment.starts[k] + alignment.ends[k])
    return traj[int(round(t * 100)), vtl.VTL_CHANNELS.index(channel)]


# -- symbols ----------------------------------------------------------------
@pytest.mark.parametrize(
    "symbol",
    [
        "a:",
        "I",
        "E",
        "O",
        "U",
        "Y",
        "9",
        "@",
        "6",
        "aI",
        "aU",
        "OY",
        "I6",
        "f",
        "v",
        "s",
        "z",
        "S",
        "C",
        "j",
        "x",
        "R",
        "h",
        "l",
        "?",
        "m",
        "t",
    ],
)
def test_symbols_vtl_knows_make_gestures(symbol):
    assert symbol in vtl.VTL_PHONEMES
    assert vtl.probe_vtl_symbol(symbol)


@pytest.mark.parametrize("symbol", ["w", "eI", "oU", "Q", "aj", "n=", "sil"])
def test_symbols_vtl_drops_are_not_in_the_table(symbol):
    assert symbol not in vtl.VTL_PHONEMES
    assert not vtl.probe_vtl_symbol(symbol)


def test_map_phones_maps_lax_vowels_and_rejects_unknown():
    assert vtl.map_phones(["S", "i", "e", "o", "u", "r", "i:"]) == ("S", "I", "E", "O", "U", "R", "i:")
    with pytest.raises(DataError, match=r"word 'we'.*phone 0.*'w'"):
        vtl.map_phones(["w", "E"], source="word 'we'")


def test_unknown_symbol_stops_generation_before_synthesis(tmp_path):
    lexicon = FAST + [vtl.Word("Wetter", ("w", "e", "t", "6"), (0.08, 0.1, 0.08, 0.1))]
    with pytest.raises(DataError, match=r"Wetter.*phone 0.*drop it silently.*got 'w'"):
        vtl.generate_vtl_corpus(tmp_path, lexicon=lexicon, n_train_minutes=0.01, n_test_minutes=0.01, verbose=0)
    assert not (tmp_path / "train").exists()


def test_shipped_lexicon_maps_onto_vtl_symbols():
    words = vtl.load_lexicon()
    assert len(words) == 4313
    assert len({w.word for w in words}) == len(words)
    for w in words:
        assert len(w.phones) == len(w.durations)
        vtl.map_phones(w.phones, source=w.word)  # raises on any unknown symbol
    durs = np.concatenate([w.durations for w in words])
    assert durs.min() > 0.0 and durs.max() < 2.0


# -- tract sequences ----------------------------------------------------------
def test_read_tract_sequence(tmp_path):
    glottis = " ".join(["1"] * 11)
    rows = [" ".join(str(k * 100 + j) for j in range(19)) for k in range(3)]
    body = "\n".join(f"{glottis}\n{r}" for r in rows)
    p = tmp_path / "t.txt"
    p.write_text(f"# comment\n# more\nGeometric glottis\n3\n{body}\n")
    states = vtl.read_tract_sequence(p)
    assert states.shape == (3, 19)
    assert states[2, 5] == 205
    p.write_text(f"# c\nGeometric glottis\n4\n{body}\n")
    with pytest.raises(DataError, match="4 states"):
        vtl.read_tract_sequence(p)


def test_resample_puts_frame_i_at_i_over_rate():
    t_state = np.arange(802) / vtl.VTL_STATE_RATE  # 2 s of VTL states
    slow = np.column_stack([np.sin(2 * np.pi * 1.5 * t_state), np.cos(2 * np.pi * 3.0 * t_state)])
    out = vtl.resample_tract(slow, 100.0)
    t = np.arange(len(out)) / 100.0
    truth = np.column_stack([np.sin(2 * np.pi * 1.5 * t), np.cos(2 * np.pi * 3.0 * t)])
    inner = slice(10, len(out) - 10)  # away from the filter's edge effects
    np.testing.assert_allclose(out[inner], truth[inner], atol=2e-3)
    assert len(out) >= 200


# -- synthesis --------------------------------------------------------------------
def test_lips_close_during_m_and_tongue_tip_rises_for_l():
    res = vtl.synthesize_phrase(_plan(["", "a", "m", "a", "l", "a", ""], [0.2, 0.15, 0.1, 0.15, 0.1, 0.15, 0.2]))
    a, y = res["alignment"], res["trajectory"]
    assert y.shape == (a.n_frames(100.0), 19) and np.isfinite(y).all()
    assert a.labels == (SILENCE, "a", "m", "a", "l", "a", SILENCE)
    # LD is VTL's vertical lip distance: negative means the lips are pressed together.
    assert _mid(a, 2, y, "LD") < 0.0 < _mid(a, 1, y, "LD") - 0.5
    # The tongue tip rises towards the alveolar ridge for /l/.
    assert _mid(a, 4, y, "TTY") > _mid(a, 5, y, "TTY") + 0.3


@pytest.mark.slow  # VTL's acoustic simulation: seconds of CPU per second of speech
def test_audio_is_16khz_and_as_long_as_the_alignment():
    res = vtl.synthesize_phrase(_plan(["", "a:", ""], [0.05, 0.2, 0.05], audio=True))
    wav, a = res["audio"], res["alignment"]
    assert wav.dtype == np.int16 and len(wav) == int(np.ceil(a.duration * 16000))
    vowel = wav[int(0.1 * 16000) : int(0.2 * 16000)].astype(float)
    assert np.sqrt(np.mean(vowel**2)) > 300  # voiced, not silence


# -- generation ---------------------------------------------------------------------
def _generate(out, seed, n_jobs):
    return vtl.generate_vtl_corpus(
        out,
        seed=seed,
        lexicon=FAST,
        n_train_minutes=0.04,
        n_test_minutes=0.02,
        test_word_fraction=0.34,
        audio_fraction=0.0,
        n_jobs=n_jobs,
        verbose=0,
        words_per_phrase=(2, 3),
    )


def _files(root):
    return {p.relative_to(root).as_posix(): p.read_bytes() for p in sorted(Path(root).rglob("*")) if p.is_file()}


def test_generation_is_deterministic_and_reloads(tmp_path):
    a = _generate(tmp_path / "a", seed=5, n_jobs=1)
    _generate(tmp_path / "b", seed=5, n_jobs=1)
    assert _files(tmp_path / "a") == _files(tmp_path / "b")  # same seed, same bytes
    loaded = load_corpus(tmp_path / "a" / "train")
    assert loaded.channels == vtl.VTL_CHANNELS and loaded.frame_rate == 100.0
    for u, v in zip(loaded, a["train"]):
        np.testing.assert_array_equal(u.trajectory, v.trajectory)
        assert u.alignment == v.alignment
    meta = json.loads((tmp_path / "a" / "train" / "corpus.json").read_text())
    assert meta["seed"] == 5 and meta["generator"] == "dam.datasets.vtl" and "GPL" in meta["licence"]
    train_words = {w for u in meta["utterances"].values() for w in u["words"]}
    test_meta = json.loads((tmp_path / "a" / "test" / "corpus.json").read_text())
    test_words = {w for u in test_meta["utterances"].values() for w in u["words"]}
    assert train_words and test_words and not train_words & test_words
    with pytest.raises(DataError, match="not empty"):
        _generate(tmp_path / "a", seed=5, n_jobs=1)


def test_phrases_do_not_depend_on_what_the_process_synthesized_before():
    # What makes the corpus independent of n_jobs: all randomness is in the plan, and VTL
    # (global state in its C library) gives a phrase the same trajectory whatever ran before it.
    plans, _ = vtl.plan_corpus(
        seed=3,
        lexicon=FAST,
        n_train_minutes=0.04,
        n_test_minutes=0.01,
        test_word_fraction=0.34,
        audio_fraction=0.0,
        words_per_phrase=(2, 3),
    )
    phrases = plans["train"] + plans["test"]
    assert len(phrases) >= 3
    forward = [vtl.synthesize_phrase(p)["trajectory"] for p in phrases]
    backward = [vtl.synthesize_phrase(p)["trajectory"] for p in reversed(phrases)][::-1]
    for f, b in zip(forward, backward):
        np.testing.assert_array_equal(f, b)


@pytest.mark.slow  # starting two worker processes costs ~10 s on a loaded machine
def test_generation_gives_the_same_bytes_whatever_n_jobs(tmp_path):
    _generate(tmp_path / "a", seed=5, n_jobs=1)
    _generate(tmp_path / "b", seed=5, n_jobs=2)
    assert _files(tmp_path / "a") == _files(tmp_path / "b")


def test_failed_plan_leaves_an_existing_corpus_alone(tmp_path):
    _generate(tmp_path, seed=1, n_jobs=1)
    before = _files(tmp_path)
    bad = FAST + [vtl.Word("Wetter", ("w", "e", "t", "6"), (0.08, 0.1, 0.08, 0.1))]
    with pytest.raises(DataError, match="Wetter"):
        vtl.generate_vtl_corpus(
            tmp_path, lexicon=bad, overwrite=True, n_train_minutes=0.01, n_test_minutes=0.01, verbose=0
        )
    assert _files(tmp_path) == before


def test_generate_errors_are_one_line(capsys):
    from dam.cli import main

    assert main(["generate-vtl", "unused", "--frame-rate", "500"]) == 1
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "frame_rate" in err and "500" in err


def test_audio_goes_to_an_exact_spread_share_of_phrases():
    plans = vtl.plan_phrases(FAST, minutes=0.5, rng=np.random.default_rng(0), audio_fraction=0.25)
    assert sum(p.audio for p in plans) == round(0.25 * len(plans)) >= 2
    assert plans[0].audio and plans[-1].audio
    few = vtl.plan_phrases(FAST, minutes=0.05, rng=np.random.default_rng(0), audio_fraction=0.01)
    assert sum(p.audio for p in few) == 1  # asked for audio: at least one phrase gets it


def test_another_seed_draws_other_phrases():
    def plans(seed):
        rng = np.random.default_rng(seed)
        return vtl.plan_phrases(FAST, minutes=0.1, rng=rng)

    assert plans(5) == plans(5) and plans(5) != plans(6)


def test_generate_help_runs():
    out = subprocess.run(
        [sys.executable, "-m", "dam.cli", "generate-vtl", "--help"], capture_output=True, text=True, check=True
    )
    assert "--seed" in out.stdout and "--train-minutes" in out.stdout


# -- the bundled corpus ------------------------------------------------------------------
@pytest.fixture(scope="module")
def bundled():
    return dam.datasets.load("vtl", "train"), dam.datasets.load("vtl", "test")


def test_bundled_corpus_size_and_format(bundled):
    train, test = bundled
    assert train.frame_rate == test.frame_rate == 100.0
    assert train.channels == test.channels == vtl.VTL_CHANNELS
    assert 9.5 <= train.duration / 60 <= 11.0
    assert 2.0 <= test.duration / 60 <= 3.5
    known = vtl.VTL_PHONEMES | {SILENCE}
    assert train.phones <= known and test.phones <= known
    assert test.phones <= train.phones  # every test phone is seen in training
    assert all(np.isfinite(u.trajectory).all() for u in train)


def test_bundled_corpus_splits_words_and_has_some_audio(bundled):
    import soundfile

    train, test = bundled
    words = [{w for u in c.metadata["utterances"].values() for w in u["words"]} for c in (train, test)]
    assert words[0] and words[1] and not words[0] & words[1]
    assert sum(bool(u.audio) for u in train) >= 10 and sum(bool(u.audio) for u in test) >= 2
    with_audio = [u for c in (train, test) for u in c if u.audio]
    for u in with_audio[:3]:
        wav, rate = soundfile.read(u.audio, dtype="int16")
        assert rate == 16000  # the audio spans the frames: to the last frame time, at most one frame more
        assert u.alignment.duration * 16000 <= len(wav) <= u.n_frames / u.frame_rate * 16000 + 1
        # Speech where the alignment has phones, near-silence in the leading pause.
        lead = wav[: int(0.8 * u.alignment.ends[0] * 16000)].astype(float)
        speech = wav[int(u.alignment.ends[0] * 16000) : int(u.alignment.starts[-1] * 16000)].astype(float)
        assert np.sqrt(np.mean(speech**2)) > 10 * np.sqrt(np.mean(lead**2)) + 100


def test_bundled_corpus_is_what_the_regenerate_command_plans(bundled):
    plans, _ = vtl.plan_corpus(seed=0)  # the defaults are the bundled corpus's
    for split, corpus in zip(("train", "test"), bundled):
        assert [p.name for p in plans[split]] == [u.name for u in corpus]
        for p, u in zip(plans[split], corpus):
            ends = np.round(np.cumsum(p.durations), 3)
            assert u.alignment == fit_to_frames(
                Alignment(p.labels, ends - np.asarray(p.durations), ends), u.n_frames, u.frame_rate
            )
            assert corpus.metadata["utterances"][u.name]["words"] == list(p.words)
            if p.audio:  # the generator's share; `dam vtl-audio` adds more phrases, never fewer
                assert u.audio


def test_bundled_trajectory_resynthesizes_identically(bundled):
    # The phrase with the fewest oral closures (VTL's slow step), synthesized again.
    plans, _ = vtl.plan_corpus(seed=0)
    closures = {"p", "b", "t", "d", "k", "g", "m", "n", "N", "ts", "pf", "tS", "dZ"}
    plan = min(plans["test"], key=lambda p: (sum(lab in closures for lab in p.labels), sum(p.durations)))
    res = vtl.synthesize_phrase(plan)
    np.testing.assert_array_equal(res["trajectory"].astype(np.float32), bundled[1][plan.name].trajectory)
