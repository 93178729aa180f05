"""Misread data (issue 12): byte-order marks, other encodings, complex and ragged values,
absurd times, corpus.json of the wrong shape. Each is read correctly or refused with
dam's own error naming the file, the field and the value."""

import codecs
import json
import os

import numpy as np
import pytest

import dam
from dam.corpus.data import MAX_DURATION, TIME_TOL
from dam.corpus.formats.est import read_est, write_est
from dam.corpus.formats.htk import read_lab
from dam.corpus.formats.tables import write_csv
from dam.corpus.formats.textgrid import read_textgrid
from dam.corpus.io import load_corpus

BOM = codecs.BOM_UTF8


# -- byte-order marks: read as if absent --------------------------------------------------
def test_csv_with_a_bom_keeps_its_time_column(small_corpus_dir):
    plain = load_corpus(small_corpus_dir)
    for p in small_corpus_dir.glob("*.csv"):
        p.write_bytes(BOM + p.read_bytes())
    marked = load_corpus(small_corpus_dir)
    assert marked.channels == plain.channels and "time" not in " ".join(marked.channels)
    assert marked.frame_rate == plain.frame_rate
    for a, b in zip(marked, plain):
        np.testing.assert_array_equal(a.trajectory, b.trajectory)


def test_csv_with_a_bom_and_no_corpus_json_gets_its_rate_from_the_time_column(small_corpus_dir):
    (small_corpus_dir / "corpus.json").unlink()
    for p in small_corpus_dir.glob("*.csv"):
        p.write_bytes(BOM + p.read_bytes())
    c = load_corpus(small_corpus_dir)
    assert c.frame_rate == 100.0 and c.channels[0] == "lip_aperture"


@pytest.mark.parametrize(
    "encode",
    [
        lambda t: BOM + t.encode("utf-8"),
        lambda t: t.encode("utf-16"),
        lambda t: t.encode("utf-16-be") and codecs.BOM_UTF16_BE + t.encode("utf-16-be"),
    ],
    ids=["utf8-bom", "utf16", "utf16-be"],
)
def test_textgrid_in_any_marked_encoding_reads_the_same(small_corpus_dir, tmp_path, encode):
    src = small_corpus_dir / "tiny000.TextGrid"
    text = src.read_text(encoding="utf-8").replace('text = "p"', 'text = "é"')
    plain = tmp_path / "plain.TextGrid"
    plain.write_text(text, encoding="utf-8")
    marked = tmp_path / "marked.TextGrid"
    marked.write_bytes(encode(text))
    assert read_textgrid(marked) == read_textgrid(plain)


def test_lab_and_corpus_json_with_a_bom(small_corpus_dir, tmp_path):
    lab = tmp_path / "u.lab"
    lab.write_bytes(BOM + b"0 1000000 a\n1000000 2500000 b\n")
    a = read_lab(lab)
    assert a.labels == ("a", "b")
    meta = small_corpus_dir / "corpus.json"
    meta.write_bytes(BOM + meta.read_bytes())
    assert load_corpus(small_corpus_dir).name == "tiny"


# -- other encodings: refused with the file and the byte offset ---------------------------------
@pytest.mark.parametrize(
    "name, content",
    [
        ("u.lab", b"0 1000000 a\n1000000 2500000 caf\xe9\n"),
        ("u.csv", b"time,l\xe8vre\n0,1\n0.01,2\n"),
        ("corpus.json", b'{"name": "d\xe9j\xe0"}'),
    ],
)
def test_latin1_text_is_refused_naming_file_and_offset(tmp_path, name, content):
    path = tmp_path / name
    path.write_bytes(content)
    offset = content.index(next(bytes([b]) for b in content if b > 0x7F))
    reader = {
        "u.lab": read_lab,
        "u.csv": dam.corpus.formats.tables.read_csv,
        "corpus.json": dam.corpus.io.read_corpus_json,
    }[name]
    with pytest.raises(dam.DataError) as info:
        reader(path)
    msg = str(info.value)
    assert str(path) in msg and f"offset {offset}" in msg and f"0x{content[offset]:02x}" in msg


def test_latin1_textgrid_is_refused_naming_file_and_offset(small_corpus_dir):
    path = small_corpus_dir / "tiny000.TextGrid"
    raw = path.read_bytes().replace(b'text = "p"', b'text = "\xe9"', 1)
    path.write_bytes(raw)
    with pytest.raises(dam.DataError, match=f"offset {raw.index(0xE9)}") as info:
        read_textgrid(path)
    assert str(path) in str(info.value)


# -- values that are not real numbers ---------------------------------------------------------
def test_complex_trajectories_are_refused(small_corpus_dir):
    a = dam.Alignment(["a"], [0], [0.05])
    with pytest.raises(dam.DataError, match="complex"):
        dam.Utterance(a, np.ones((6, 1)) * (1 + 1j), 100, ["x"])
    for p in small_corpus_dir.glob("tiny00*.csv"):
        data, names, _ = dam.corpus.formats.tables.read_csv(p)
        p.unlink()
        np.save(p.with_suffix(".npy"), data * (1 + 0.5j))
    with pytest.raises(dam.DataError, match="complex") as info:
        load_corpus(small_corpus_dir)
    assert ".npy" in str(info.value)


@pytest.mark.parametrize(
    "trajectory",
    [
        [[1.0, 2.0], [3.0]],  # ragged
        [[1.0], [None], [2.0]],  # None inside
        np.array([[1.0], ["x"]], dtype=object),  # object with text
        "12345",  # text
        [[{"a": 1}]],  # nonsense
    ],
    ids=["ragged", "none", "object-text", "text", "dict"],
)
def test_ragged_and_object_trajectories_get_a_data_error(trajectory):
    a = dam.Alignment(["a"], [0], [0.02])
    with pytest.raises(dam.DataError, match="trajectory") as info:
        dam.Utterance(a, trajectory, 100, ["x"], source="u.csv")
    assert "u.csv" in str(info.value)


def test_channels_that_are_not_a_sequence_get_a_data_error():
    a = dam.Alignment(["a"], [0], [0.02])
    with pytest.raises(dam.DataError, match="channels"):
        dam.Utterance(a, np.ones((3, 1)), 100, 5)


# -- absurd times ---------------------------------------------------------------------------------------
def test_a_400_digit_htk_time_names_file_and_line(tmp_path):
    path = tmp_path / "u.lab"
    path.write_text(f"0 100000 a\n100000 {'9' * 400} b\n")
    with pytest.raises(dam.DataError, match="line 2") as info:
        read_lab(path)
    assert str(path) in str(info.value)


def test_infinite_xwaves_time_names_file(tmp_path):
    path = tmp_path / "u.lab"
    path.write_text("separator ;\n#\n0.1 125 a\ninf 125 b\n")
    with pytest.raises(dam.DataError, match="not finite") as info:
        read_lab(path)
    assert str(path) in str(info.value)


def test_a_1e10_second_segment_is_refused_before_any_allocation(tmp_path):
    path = tmp_path / "u.lab"
    path.write_text(f"0 1000000 a\n1000000 {10**17} b\n")  # 1e10 s
    with pytest.raises(dam.DataError, match="more than") as info:
        read_lab(path)
    assert str(path) in str(info.value) and "segment 1" in str(info.value)
    with pytest.raises(dam.DataError):
        dam.Alignment(["a"], [0.0], [MAX_DURATION * 2])


def test_a_sub_microsecond_segment_is_never_kept(tmp_path):
    """0.6 us: absorbed by its neighbour or refused, never kept as a segment of its own."""
    path = tmp_path / "u.lab"
    path.write_text("0 1000000 a\n1000000 1000006 b\n1000006 2000000 c\n")
    try:
        a = read_lab(path)
    except dam.DataError as exc:
        assert str(path) in str(exc)
    else:
        assert np.all(a.durations > TIME_TOL)


# -- corpus.json of the wrong shape ------------------------------------------------------------------------
@pytest.mark.parametrize(
    "meta, field",
    [
        ({"channels": 5}, "channels"),
        ({"channels": ["a", 3, "c", "d"]}, "channels"),
        ({"channels": ["a", "a", "b", "c"]}, "channels"),
        ({"frame_rate": "abc"}, "frame_rate"),
        ({"frame_rate": -100}, "frame_rate"),
        ({"frame_rate": True}, "frame_rate"),
        ({"frame_rate": float("inf")}, "frame_rate"),
        ({"name": ["x"]}, "name"),
        ([1, 2, 3], "json"),
    ],
)
def test_corpus_json_type_errors_name_file_field_and_value(small_corpus_dir, meta, field):
    path = small_corpus_dir / "corpus.json"
    path.write_text(json.dumps(meta))
    with pytest.raises(dam.DataError) as info:
        load_corpus(small_corpus_dir)
    assert info.value.field == field and info.value.source == str(path)


def test_deeply_nested_corpus_json(small_corpus_dir):
    path = small_corpus_dir / "corpus.json"
    path.write_text('{"x": ' + "[" * 100000 + "]" * 100000 + "}")
    with pytest.raises(dam.DataError, match="nested") as info:
        load_corpus(small_corpus_dir)
    assert str(path) in str(info.value)


# -- writers: a complete file or none, never NaN --------------------------------------------------------
def test_write_est_with_non_ascii_channel_names_round_trips(tmp_path):
    path = tmp_path / "u.ema"
    values = np.arange(6.0).reshape(3, 2)
    write_est(path, values, frame_rate=200, channels=["tongue_tip_ä", "lèvre"])
    track = read_est(path)
    assert track.channels == ["tongue_tip_ä", "lèvre"]
    np.testing.assert_array_equal(track.values, values)


def test_a_refused_write_leaves_no_file_and_keeps_the_old_one(tmp_path):
    est = tmp_path / "u.ema"
    with pytest.raises(dam.DataError, match="white space"):
        write_est(est, np.ones((3, 2)), frame_rate=200, channels=["a b", "c"])
    assert not est.exists()
    csv = tmp_path / "u.csv"
    write_csv(np.ones((3, 1)), ["x"], csv)
    before = csv.read_bytes()
    with pytest.raises(dam.DataError, match="not finite"):
        write_csv(np.array([[1.0], [np.nan]]), ["x"], csv)
    assert csv.read_bytes() == before
    assert sorted(os.listdir(tmp_path)) == ["u.csv"]


def test_a_prediction_too_large_to_hold_is_refused_before_allocation(tiny_train):
    """A day at the highest frame rate a model may have: refused, naming the duration."""
    from dam.base import MAX_PREDICTION_VALUES
    from dam.corpus.data import MAX_FRAME_RATE

    model = dam.make("phone-mean").fit(tiny_train)
    model.frame_rate_ = MAX_FRAME_RATE
    long = dam.Alignment(["aa"], [0.0], [MAX_DURATION], source="day.lab")
    assert long.n_frames(MAX_FRAME_RATE) * 4 > MAX_PREDICTION_VALUES
    with pytest.raises(dam.DataError, match="day.lab: field 'duration'"):
        model.predict(long)
