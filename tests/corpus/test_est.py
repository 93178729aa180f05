"""EST track files (mngu0 / MOCHA-TIMIT EMA): reader, writer, corpus loading."""

import struct

import numpy as np
import pytest

from dam.corpus.data import Alignment, DataError
from dam.corpus.formats.est import read_est, read_est_trajectory, stored_frame_rate, write_est
from dam.corpus.io import load_corpus, write_lab

HEADER = (
    "EST_File Track\n"
    "DataType binary\n"
    "NumFrames 3\n"
    "ByteOrder {order}\n"
    "NumChannels 2\n"
    "EqualSpace 1\n"
    "BreaksPresent true\n"
    "CommentChar ;\n"
    "\n"
    "Channel_0 T1_py\n"
    "Channel_1 T1_pz\n"
    "EST_Header_End\n"
)
FRAMES = [(0.0, 1.0, 1.5, -2.25), (0.005, 1.0, 1.75, -2.5), (0.01, 0.0, 2.0, -2.75)]


@pytest.mark.parametrize("order,fmt", [("01", "<"), ("10", ">")])
def test_hand_written_binary_layout(tmp_path, order, fmt):
    # The layout as mngu0 ships it: header text, then per frame float32 time,
    # float32 value flag and the channel values, in the declared byte order.
    body = b"".join(struct.pack(fmt + "4f", *f) for f in FRAMES)
    path = tmp_path / "x.ema"
    path.write_bytes(HEADER.format(order=order).encode() + body)
    tr = read_est(path)
    assert tr.channels == ["T1_py", "T1_pz"]
    assert tr.header["DataType"] == "binary" and tr.header["NumFrames"] == 3
    np.testing.assert_array_equal(tr.times, np.float32([0.0, 0.005, 0.01]))
    np.testing.assert_array_equal(tr.values, [[1.5, -2.25], [1.75, -2.5], [2.0, -2.75]])
    np.testing.assert_array_equal(tr.present, [True, True, False])


def test_hand_written_ascii(tmp_path):
    text = (
        "EST_File Track\nDataType ascii\nNumFrames 2\nNumChannels 3\nBreaksPresent true\n"
        "EST_Header_End\n0.000000 1 1 2 3\n0.010000 1 4 5 6.5\n"
    )
    path = tmp_path / "x.est"
    path.write_text(text)
    tr = read_est(path)
    assert tr.channels is None
    np.testing.assert_allclose(tr.values, [[1, 2, 3], [4, 5, 6.5]])
    assert tr.frame_rate == pytest.approx(100.0)


@pytest.mark.parametrize("binary", [True, False])
@pytest.mark.parametrize("order", ["01", "10"])
def test_write_read_round_trip(tmp_path, binary, order):
    rng = np.random.default_rng(0)
    vals = rng.normal(size=(7, 4)).astype(np.float32).astype(float)
    path = tmp_path / "r.ema"
    write_est(path, vals, frame_rate=200.0, channels=["a", "b", "c", "d"], binary=binary, byte_order=order)
    tr = read_est(path)
    np.testing.assert_allclose(tr.values, vals, rtol=1e-6)
    np.testing.assert_allclose(tr.times, np.arange(7) / 200.0, atol=1e-7)
    assert tr.channels == ["a", "b", "c", "d"] and tr.present.all()


def test_writer_byte_layout(tmp_path):
    path = tmp_path / "w.ema"
    write_est(path, [[1.0, 2.0], [3.0, 4.0]], times=[0.0, 0.5], channels=["x", "y"], byte_order="10")
    raw = path.read_bytes()
    head, _, body = raw.partition(b"EST_Header_End\n")
    assert head.startswith(b"EST_File Track\nDataType binary\nByteOrder 10\n")
    assert b"Channel_1 y\n" in head
    assert len(body) == 2 * (2 + 2) * 4
    assert struct.unpack(">8f", body) == (0.0, 1.0, 1.0, 2.0, 0.5, 1.0, 3.0, 4.0)


def test_errors_name_file_and_field(tmp_path):
    bad = tmp_path / "bad.ema"
    bad.write_text("EST_File Wave\n")
    with pytest.raises(DataError, match="bad.ema.*header"):
        read_est(bad)
    order = tmp_path / "order.ema"
    order.write_bytes(HEADER.format(order="11").encode() + bytes(48))
    with pytest.raises(DataError, match="order.ema.*ByteOrder.*'11'"):
        read_est(order)
    short = tmp_path / "short.ema"
    short.write_bytes(HEADER.format(order="01").encode() + bytes(40))
    with pytest.raises(DataError, match="short.ema.*data size.*40 bytes"):
        read_est(short)
    nohead = tmp_path / "nohead.ema"
    nohead.write_bytes(HEADER.format(order="01").encode().replace(b"NumChannels 2\n", b"") + bytes(48))
    with pytest.raises(DataError, match="NumChannels"):
        read_est(nohead)


def test_trajectory_reader_refuses_breaks_and_uneven_times(tmp_path):
    p = tmp_path / "b.ema"
    write_est(p, np.zeros((4, 1)), frame_rate=100, present=[1, 1, 0, 1])
    with pytest.raises(DataError, match="frame 2 .*break"):
        read_est_trajectory(p)
    q = tmp_path / "u.ema"
    write_est(q, np.zeros((4, 1)), times=[0, 0.01, 0.02, 0.05])
    with pytest.raises(DataError, match="evenly spaced"):
        read_est_trajectory(q)


def test_ema_corpus_with_htk_labels_loads(tmp_path):
    # A speech scientist's EMA corpus: binary EST tracks at 200 Hz + HTK labels, no corpus.json.
    rng = np.random.default_rng(1)
    truth = {}
    # Lengths as in mngu0: float32 times put 1 / median(diff) at 200.00004 for one file and 199.9978
    # for the other; the reader must still give both the 200 Hz they were written at.
    for stem, n in (("u1", 60), ("u2", 1500)):
        vals = rng.normal(size=(n, 3)).astype(np.float32)
        write_est(tmp_path / f"{stem}.ema", vals, frame_rate=200.0, channels=["tt_x", "tt_y", "li_y"])
        dur = n / 200.0
        write_lab(
            Alignment(["sil", "a", "sil"], [0, 0.05, dur - 0.05], [0.05, dur - 0.05, dur]), tmp_path / f"{stem}.lab"
        )
        truth[stem] = vals
    corpus = load_corpus(tmp_path)
    assert corpus.frame_rate == 200.0
    assert corpus.channels == ("tt_x", "tt_y", "li_y")
    for u in corpus:
        np.testing.assert_array_equal(u.trajectory, truth[u.name])
        assert u.alignment.labels == ("sil", "a", "sil")


@pytest.mark.parametrize("rate", [200.0, 500.0, 100.0, 250.0])
@pytest.mark.parametrize("n", [3, 700, 20000])
def test_frame_rate_survives_float32_times(rate, n):
    t32 = (np.arange(n) / rate).astype(np.float32)
    assert stored_frame_rate(t32) == rate
    # an odd rate comes back within the precision the times carry
    odd = 44100 / 110
    assert stored_frame_rate((np.arange(n) / odd).astype(np.float32)) == pytest.approx(
        odd, rel=2e-3 if n == 3 else 1e-5
    )
