"""BAS Partitur (.par) files as WebMAUS writes them, written here by hand from the BPF description."""

import wave

import numpy as np
import pytest

from dam.corpus import Alignment, DataError, load_corpus
from dam.corpus.formats.bas import read_par, write_par
from dam.corpus.formats.tables import write_csv

PAR = """LHD: Partitur 1.3
REP: Muenchen
SNB: 2
SAM: 16000
SBF: 01
SSB: 16
NCH: 1
SPN: S01
LBD:
ORT: 0 guten
ORT: 1 Tag
KAN: 0 gu:t@n
KAN: 1 ta:k
MAU: 0 799 -1 <p:>
MAU: 800 1199 0 g
MAU: 2000 1599 0 u:
MAU: 3600 799 0 t
MAU: 4400 1599 0 @n
MAU: 6000 2399 1 t
MAU: 8400 2399 1 a:k
MAU: 10800 1599 -1 <p:>
"""


def test_par_mau_tier_times_in_samples(tmp_path):
    p = tmp_path / "g.par"
    p.write_text(PAR)
    a = read_par(p)
    assert a.labels == ("sil", "g", "u:", "t", "@n", "t", "a:k", "sil")
    begins = np.array([0, 800, 2000, 3600, 4400, 6000, 8400, 10800])
    durs = np.array([799, 1199, 1599, 799, 1599, 2399, 2399, 1599])
    np.testing.assert_allclose(a.starts, begins / 16000)
    np.testing.assert_allclose(a.ends, (begins + durs + 1) / 16000)  # inclusive sample ranges
    assert a.duration == pytest.approx(0.775)


def test_mau_only_file_takes_the_rate_of_its_wav(tmp_path):
    body = "".join(line + "\n" for line in PAR.splitlines() if line.startswith("MAU:"))
    p = tmp_path / "m.par"
    p.write_text(body)
    with pytest.raises(DataError, match=r"m.par: field 'SAM'.*m.wav"):
        read_par(p)
    with wave.open(str(tmp_path / "m.wav"), "wb") as w:
        w.setnchannels(1)
        w.setsampwidth(2)
        w.setframerate(8000)
        w.writeframes(b"\0\0" * 100)
    a = read_par(p)
    assert a.ends[-1] == pytest.approx(12400 / 8000)
    assert read_par(p, sample_rate=32000).ends[-1] == pytest.approx(12400 / 32000)


@pytest.mark.parametrize(
    "old, new, field, value",
    [
        ("SAM: 16000", "SAM: fast", "SAM", "fast"),
        ("MAU: 800 1199 0 g", "MAU: 800.5 1199 0 g", "line 15 (MAU) begin/duration/word", "800.5"),
        ("MAU: 800 1199 0 g", "MAU: 800 1199", "line 15 (MAU)", "800 1199"),
        ("MAU: 800 1199 0 g", "MAU 800 1199 0 g", "line 15", "MAU 800 1199 0 g"),
    ],
)
def test_malformed_par_is_refused(tmp_path, old, new, field, value):
    p = tmp_path / "bad.par"
    p.write_text(PAR.replace(old, new))
    with pytest.raises(DataError) as err:
        read_par(p)
    msg = str(err.value)
    assert "bad.par" in msg and f"field {field!r}" in msg and value in msg


def test_missing_tier_and_overlap(tmp_path):
    p = tmp_path / "t.par"
    p.write_text(PAR)
    with pytest.raises(DataError, match=r"t.par: field 'tier'.*'SAP'"):
        read_par(p, tier="SAP")
    p.write_text(PAR.replace("MAU: 2000 1599 0 u:", "MAU: 1000 1599 0 u:"))
    with pytest.raises(DataError, match=r"t.par: field \"segment 2 \('u:'\) start\": overlaps"):
        read_par(p)


def test_write_par_round_trip(tmp_path):
    rate = 22050
    rng = np.random.default_rng(3)
    bounds = np.cumsum(rng.integers(50, 3000, size=9))
    labels = ["sil", "h", "E", "l", "o:", "sil", "v", "E6", "sil"]
    a = Alignment(labels, np.r_[0, bounds[:-1]] / rate, bounds / rate)
    p = tmp_path / "w.par"
    write_par(a, p, rate, words=[("hallo", [1, 2, 3, 4]), ("wer", [6, 7])])
    back = read_par(p)
    assert back == a
    text = p.read_text()
    assert "SAM: 22050\n" in text and "ORT: 1 wer" in text and "MAU: 0 " in text and " -1 <p:>" in text


def test_bas_directory_loads_with_trajectories(tmp_path):
    (tmp_path / "g.par").write_text(PAR)
    y = np.random.default_rng(0).normal(size=(78, 2))
    write_csv(y, ["tt_x", "tt_y"], tmp_path / "g.csv", frame_rate=100.0)
    corpus = load_corpus(tmp_path)
    assert corpus[0].alignment.labels[1] == "g"
    np.testing.assert_allclose(corpus[0].trajectory, y, atol=1e-5)
    assert corpus.sensors == {"tt": ("tt_x", "tt_y")}
