"""Audio in corpora (issue 15): FLAC/WAV beside the trajectories, sample rates checked, and the
bundled vtl corpus's audio: present where corpus.json says, and reproduced bit for bit by VTL."""

import json
import shutil

import numpy as np
import pytest
import soundfile
from scipy.io import wavfile

import dam
from dam.corpus import audio_header
from dam.datasets.vtl import AUDIO_SUFFIX, add_vtl_audio, audio_priority

VTL = dam.datasets.path("vtl")


@pytest.mark.parametrize("n", [1, 2, 7, 54, 213])
def test_audio_priority_is_a_nested_evenly_spread_order(n):
    order = audio_priority(n)
    assert sorted(order) == list(range(n))
    for k in range(1, n + 1):  # every prefix leaves no gap much wider than n / k
        chosen = sorted(order[:k])
        gaps = np.diff([*chosen, chosen[0] + n])
        assert gaps.max() <= 2 * np.ceil(n / k), (k, chosen)
    first = [5 % n, 3 % n]
    assert audio_priority(n, first)[: len(set(first))] == list(dict.fromkeys(first))


def test_flac_and_wav_headers_agree_with_libsndfile(tmp_path):
    x = (np.sin(np.arange(12345) / 7) * 1e4).astype(np.int16)
    for rate, suffix, channels in [(16000, ".flac", 1), (44100, ".flac", 2), (8000, ".wav", 1), (22050, ".wav", 2)]:
        path = tmp_path / f"a{rate}{suffix}"
        data = x if channels == 1 else np.stack([x, x], axis=1)
        soundfile.write(path, data, rate, subtype="PCM_16")
        info = soundfile.info(path)
        assert audio_header(path) == (info.samplerate, info.frames, info.channels)
    (tmp_path / "bad.flac").write_bytes(b"RIFF....")
    with pytest.raises(dam.DataError, match="bad.flac"):
        audio_header(tmp_path / "bad.flac")


def _corpus_dir(tmp_path, audio_rate=None):
    tiny = dam.datasets.load("tiny")
    d = tmp_path / "c"
    dam.save_corpus(tiny.subset(range(3)), d, metadata={} if audio_rate is None else {"audio_rate": audio_rate})
    return d, tiny


def test_load_corpus_reads_audio_beside_trajectories_and_checks_the_rate(tmp_path):
    d, tiny = _corpus_dir(tmp_path, audio_rate=16000)
    soundfile.write(d / "tiny000.flac", np.zeros(1600, np.int16), 16000)
    wavfile.write(d / "tiny001.wav", 16000, np.zeros(1600, np.int16))
    c = dam.load_corpus(d)
    assert [u.audio and u.audio.rsplit("/", 1)[-1] for u in c] == ["tiny000.flac", "tiny001.wav", None]
    wavfile.write(d / "tiny002.wav", 8000, np.zeros(800, np.int16))
    with pytest.raises(dam.DataError, match="tiny002.wav") as exc:
        dam.load_corpus(d)
    assert "sample rate" in str(exc.value) and "8000" in str(exc.value)
    (d / "tiny002.wav").unlink()
    wavfile.write(d / "tiny000.wav", 16000, np.zeros(1600, np.int16))
    with pytest.raises(dam.DataError, match="more than one audio file"):
        dam.load_corpus(d)


def _flagged(split):
    meta = json.loads((VTL / split / "corpus.json").read_text(encoding="utf-8"))
    return meta, [name for name, e in meta["utterances"].items() if e["audio"]]


@pytest.mark.parametrize("split", ["train", "test"])
def test_bundled_vtl_audio_is_where_corpus_json_says(split):
    meta, flagged = _flagged(split)
    assert meta["audio_rate"] == 16000 and meta["audio_format"] == "flac"
    on_disk = sorted(p.stem for p in (VTL / split).glob(f"*{AUDIO_SUFFIX}"))
    assert on_disk == sorted(flagged) and not list((VTL / split).glob("*.wav"))
    assert len(flagged) >= 0.1 * len(meta["utterances"])  # more than the 5% of the first release
    corpus = dam.datasets.load("vtl", split=split)
    for u in corpus:
        assert (u.audio is not None) == (u.name in flagged)
        if u.audio:
            info = soundfile.info(u.audio)
            assert (info.samplerate, info.channels, info.subtype) == (16000, 1, "PCM_16")
            textgrid = dam.read_alignment(VTL / split / f"{u.name}.TextGrid")  # the phrase, not trimmed to frames
            assert info.frames == int(np.ceil(textgrid.duration * 16000 - 1e-6))


def test_vtl_regenerates_a_bundled_flac_bit_for_bit(tmp_path):
    """Delete the shortest bundled FLAC in a copy; add_vtl_audio synthesizes exactly that one
    again, with the same samples, and leaves every trajectory file untouched."""
    root = tmp_path / "vtl"
    shutil.copytree(VTL, root)
    _, flagged = _flagged("test")
    name = min(flagged, key=lambda n: (VTL / "test" / f"{n}{AUDIO_SUFFIX}").stat().st_size)
    (root / "test" / f"{name}{AUDIO_SUFFIX}").unlink()
    npy_before = {p.name: p.read_bytes() for p in (root / "test").glob("*.npy")}
    share = len(flagged) / len(_flagged("test")[0]["utterances"])
    report = add_vtl_audio(root, fraction=share, splits=("test",), verbose=0)
    assert list(report) == ["test"] and report["test"]["added"] == 1
    new, sr = soundfile.read(root / "test" / f"{name}{AUDIO_SUFFIX}", dtype="int16")
    old, sr_old = soundfile.read(VTL / "test" / f"{name}{AUDIO_SUFFIX}", dtype="int16")
    assert sr == sr_old == 16000
    np.testing.assert_array_equal(new, old)
    assert {p.name: p.read_bytes() for p in (root / "test").glob("*.npy")} == npy_before
