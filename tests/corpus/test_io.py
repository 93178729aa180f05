"""Corpus I/O: TextGrid (long and short), HTK .lab, CSV with time column, NPY; writers; bad input."""

import json

import numpy as np
import pytest

import dam
from dam import Alignment, DataError
from dam.corpus.io import (
    load_corpus,
    read_alignment,
    read_lab,
    read_textgrid,
    save_corpus,
    write_csv,
    write_lab,
    write_textgrid,
)

LONG_TG = """File type = "ooTextFile"
Object class = "TextGrid"

xmin = 0
xmax = 0.5
tiers? <exists>
size = 2
item []:
    item [1]:
        class = "IntervalTier"
        name = "words"
        xmin = 0
        xmax = 0.5
        intervals: size = 1
        intervals [1]:
            xmin = 0
            xmax = 0.5
            text = "pa"
    item [2]:
        class = "IntervalTier"
        name = "phones"
        xmin = 0
        xmax = 0.5
        intervals: size = 4
        intervals [1]:
            xmin = 0
            xmax = 0.1
            text = ""
        intervals [2]:
            xmin = 0.1
            xmax = 0.2
            text = "p"
        intervals [3]:
            xmin = 0.2
            xmax = 0.4
            text = "aa"
        intervals [4]:
            xmin = 0.4
            xmax = 0.5
            text = "sp"
"""

SHORT_TG = """File type = "ooTextFile"
Object class = "TextGrid"

0
0.5
<exists>
1
"IntervalTier"
"segments"
0
0.5
3
0
0.1
""
0.1
0.3
"m"
0.3
0.5
"iy"
"""


def test_long_textgrid_phones_tier_and_empty_pauses(tmp_path):
    p = tmp_path / "u.TextGrid"
    p.write_text(LONG_TG)
    a = read_textgrid(p)
    assert a.labels == ("sil", "p", "aa", "sil")
    np.testing.assert_allclose(a.ends, [0.1, 0.2, 0.4, 0.5])
    assert read_textgrid(p, tier="words").labels == ("pa",)
    with pytest.raises(DataError, match=r"u.TextGrid: field 'tier'.*'nope'"):
        read_textgrid(p, tier="nope")


def test_short_textgrid_first_interval_tier(tmp_path):
    p = tmp_path / "u.TextGrid"
    p.write_text(SHORT_TG)
    assert read_alignment(p).labels == ("sil", "m", "iy")


def test_htk_lab_units(tmp_path):
    p = tmp_path / "u.lab"
    p.write_text("0 1000000 sil\n1000000 2500000 p\n2500000 4000000 aa\n")
    a = read_lab(p)
    np.testing.assert_allclose(a.ends, [0.1, 0.25, 0.4])
    p.write_text("hello world\n")
    with pytest.raises(DataError, match="line 1"):
        read_lab(p)
    p.write_text("0.0 0.1 sil\n0.1 0.2 p\n")  # seconds in an HTK file: refused, not guessed
    with pytest.raises(DataError, match="line 1 times.*integers in 100 ns"):
        read_lab(p)


def test_xwaves_lab_in_seconds(tmp_path):
    p = tmp_path / "mocha.lab"
    p.write_text(
        "signal msak0_001\nnfields 1\n#\n    0.0000 125 h#\n    0.1175 125 breath\n"
        "    0.2350 125 sil\n    0.3100 125 dh\n"
    )
    a = read_lab(p)
    assert a.labels == ("breath", "sil", "dh")
    np.testing.assert_allclose(a.starts, [0, 0.1175, 0.235])
    np.testing.assert_allclose(a.ends, [0.1175, 0.235, 0.31])


def test_writers_round_trip(tmp_path):
    a = Alignment(["sil", "p", "aa", "sil"], [0, 0.1, 0.23, 0.4], [0.1, 0.23, 0.4, 0.5])
    write_textgrid(a, tmp_path / "a.TextGrid")
    write_lab(a, tmp_path / "a.lab")
    assert read_alignment(tmp_path / "a.TextGrid") == a
    assert read_alignment(tmp_path / "a.lab") == a


def _corpus_dir(tmp_path, n=3, rate=100.0):
    rng = np.random.default_rng(0)
    tmp_path.mkdir(parents=True, exist_ok=True)
    for k in range(n):
        (tmp_path / f"u{k}.TextGrid").write_text(LONG_TG)
        write_csv(rng.normal(size=(int(0.5 * rate), 3)), ["x", "y", "z"], tmp_path / f"u{k}.csv", frame_rate=rate)
    return tmp_path


def test_load_corpus_with_time_column_and_pauses(tmp_path):
    c = load_corpus(_corpus_dir(tmp_path, rate=200.0))
    assert len(c) == 3 and c.channels == ("x", "y", "z") and c.frame_rate == 200.0
    assert c[0].alignment.labels == ("sil", "p", "aa", "sil") and c[0].n_frames == 100
    assert c.phones == {"sil", "p", "aa"}


def test_save_corpus_round_trip(tmp_path):
    c = dam.datasets.load("tiny")
    save_corpus(c, tmp_path / "out", alignment_format="lab", trajectory_format="npy")
    back = load_corpus(tmp_path / "out")
    assert len(back) == len(c) and back.frame_rate == c.frame_rate and back.channels == c.channels
    for u, v in zip(c, back):
        np.testing.assert_array_equal(u.trajectory, v.trajectory)
        assert u.alignment == v.alignment


def test_bundled_tiny_corpus_counts():
    c = dam.datasets.load("tiny")
    assert len(c) == 30 and c.frame_rate == 100.0 and len(c.channels) == 4
    assert "sil" in c.phones and "" not in c.phones


def test_bad_corpus_directories(tmp_path):
    with pytest.raises(DataError, match="no .TextGrid or .lab"):
        load_corpus(tmp_path)
    d = _corpus_dir(tmp_path / "c")
    (d / "u1.csv").unlink()
    with pytest.raises(DataError, match=r"u1.TextGrid: field 'trajectory'"):
        load_corpus(d)
    d = _corpus_dir(tmp_path / "d")
    write_csv(np.zeros((50, 2)), ["x", "y"], d / "u2.csv", frame_rate=100)
    with pytest.raises(DataError, match="channel count differs"):
        load_corpus(d)
    d = _corpus_dir(tmp_path / "e")
    (d / "corpus.json").write_text(json.dumps({"frame_rate": 50}))
    with pytest.raises(DataError, match=r"u0.csv: field 'time'.*disagrees"):
        load_corpus(d)
    d = _corpus_dir(tmp_path / "f")
    text = (d / "u0.csv").read_text().splitlines()
    text[5] = text[5].split(",")[0] + ",nan,1,2"
    (d / "u0.csv").write_text("\n".join(text) + "\n")
    with pytest.raises(DataError, match=r"u0.csv: field \"trajectory\[4, 'x'\] \(frame 4.*not finite \(got nan\)"):
        load_corpus(d)
    d = _corpus_dir(tmp_path / "g")
    (d / "u0.TextGrid").write_text(LONG_TG.replace("xmin = 0.2\n", "xmin = 0.15\n"))
    with pytest.raises(DataError, match=r"u0.TextGrid.*overlap.*0.15"):
        load_corpus(d)


def test_npy_without_channel_names_uses_corpus_json(tmp_path):
    (tmp_path / "u.TextGrid").write_text(LONG_TG)
    np.save(tmp_path / "u.npy", np.ones((50, 2)))
    with pytest.raises(DataError, match="frame rate is unknown"):
        load_corpus(tmp_path)
    (tmp_path / "corpus.json").write_text(json.dumps({"frame_rate": 100, "channels": ["jaw", "lip"], "speaker": "m01"}))
    c = load_corpus(tmp_path)
    assert c.channels == ("jaw", "lip") and c.metadata == {"speaker": "m01"}
