"""Forced alignment of shipped speech whose phone timing is known (espeak-ng's own phoneme events).

The files in tests/data/speech were made once by make_speech_data.py: four Harvard
sentences and one of words in no dictionary, in three voices, at 16, 22.05 and 44.1 kHz, 16- and 24-bit, mono and
stereo, WAV and FLAC, with 0.3 s of silence around them. The truth is the sample
at which espeak-ng started each phoneme and word.

Stated tolerance (pocketsphinx's frames are 10 ms; espeak-ng folds a stop's
closure into the phone before it, so onsets are the comparable boundaries):
median phone-onset error at most 25 ms, 80% of onsets within 60 ms; word
onsets: median at most 25 ms. Measured when written: 13 ms median phone onset
error, 9 ms median word onset error.
"""

import json
from pathlib import Path

import numpy as np
import pytest
import soundfile as sf

from dam import DataError
from dam.speech import AlignmentError, align, normalize_text
from dam.speech.aligner import FORCED, PHONE_RECOGNITION, onset_errors

DATA = Path(__file__).parent.parent / "data" / "speech"
NAMES = ["birch", "glue", "well", "chicken", "blicket"]
CMU_PHONES = set(
    "AA AE AH AO AW AY B CH D DH EH ER EY F G HH IH IY JH K L M N NG OW OY P R S SH T TH UH UW V W Y Z ZH".split()
)


def _truth(name):
    return json.loads((DATA / f"{name}.json").read_text())


@pytest.fixture(scope="module")
def aligned():
    return {n: align(DATA / _truth(n)["audio"], _truth(n)["text"]) for n in NAMES}


def _onset_errors(result, truth):
    return onset_errors(result, truth["words"], truth["phones"])


def test_words_come_out_in_transcript_order(aligned):
    for n in NAMES:
        words = [w for w in aligned[n].words.labels if w != "sil"]
        assert words == [w for w in normalize_text(_truth(n)["text"]) if w != "<pause>"]
        assert aligned[n].method == FORCED and not aligned[n].less_accurate


def test_phone_and_word_onsets_within_tolerance(aligned):
    w_err, p_err = [], []
    for n in NAMES:
        w, p = _onset_errors(aligned[n], _truth(n))
        w_err += w
        p_err += p
    p_err, w_err = np.array(p_err), np.array(w_err)
    assert len(p_err) >= 60  # most words are comparable phone by phone
    assert np.median(p_err) <= 0.025
    assert np.mean(p_err <= 0.060) >= 0.80
    assert np.median(w_err) <= 0.025


def test_alignment_covers_the_audio_and_uses_arpabet_without_stress(aligned):
    for n in NAMES:
        r = aligned[n]
        info = sf.info(str(DATA / _truth(n)["audio"]))
        assert r.duration == pytest.approx(info.frames / info.samplerate, abs=1e-3)
        assert r.phones.starts[0] == 0.0 and r.phones.ends[-1] == pytest.approx(r.duration)
        assert set(r.phones.labels) <= CMU_PHONES | {"sil"}
        assert r.phones.labels[0] == "sil" and r.phones.labels[-1] == "sil"


def test_array_input_at_another_rate_gives_the_same_alignment(aligned):
    x, sr = sf.read(str(DATA / "birch.wav"), dtype="int16")
    r = align(x, _truth("birch")["text"], sample_rate=sr)
    assert r.phones.labels == aligned["birch"].phones.labels
    assert np.allclose(r.phones.starts, aligned["birch"].phones.starts, atol=0.011)


def test_textgrid_has_words_and_phones_and_praat_reads_it(aligned, tmp_path):
    from praatio import textgrid

    path = tmp_path / "speech.TextGrid"
    aligned["glue"].write_textgrid(path)
    tg = textgrid.openTextgrid(str(path), includeEmptyIntervals=True)
    assert tg.tierNames == ("words", "phones") or list(tg.tierNames) == ["words", "phones"]
    words = [e.label for e in tg.getTier("words").entries if e.label]
    assert words == "glue the sheet to the dark blue background".split()
    phones = tg.getTier("phones").entries
    assert phones[0].label == "sil" and all(not any(c.isdigit() for c in e.label) for e in phones)
    assert tg.maxTimestamp == pytest.approx(aligned["glue"].duration)


def test_wrong_transcript_is_an_alignment_error_naming_the_file():
    with pytest.raises(AlignmentError) as err:
        align(
            DATA / "birch.wav",
            "The birch canoe slid on the smooth planks and then sank to the bottom of the lake under the ice.",
        )
    assert "birch.wav" in str(err.value)


def test_silence_and_too_short_audio_are_refused():
    with pytest.raises(AlignmentError, match="silent"):
        align(np.zeros(16000), "hello", sample_rate=16000)
    with pytest.raises(AlignmentError, match="too short"):
        align(np.random.default_rng(0).normal(0, 0.1, 800), "hello", sample_rate=16000)
    with pytest.raises(DataError, match="sample_rate"):
        align(np.zeros(100), "hello")


def test_unreadable_audio_file_is_a_data_error(tmp_path):
    bad = tmp_path / "bad.wav"
    bad.write_bytes(b"RIFF0000WAVEjunk")
    with pytest.raises(DataError, match="bad.wav"):
        align(bad, "hello")


def test_audio_only_falls_back_to_phone_recognition_labelled_less_accurate():
    r = align(DATA / "chicken.wav")
    assert r.method == PHONE_RECOGNITION and r.less_accurate and "LESS ACCURATE" in r.method
    assert r.words is None
    assert set(r.phones.labels) <= CMU_PHONES | {"sil"}
    assert sum(p != "sil" for p in r.phones.labels) >= 10


def test_words_missing_from_the_dictionary_are_aligned_with_rule_pronunciations(aligned):
    r = aligned["blicket"]
    assert r.guessed == ["glorp", "snarfed", "blicket"]
    words = [(w, s) for w, s in zip(r.words.labels, r.words.starts) if w != "sil"]
    truth = {g["words"]: g for g in _truth("blicket")["words"]}
    for w, s in words:
        assert abs(s - truth[w]["start"]) <= 0.05, w
    assert aligned["birch"].guessed == []
