"""Haskins IEEE rate comparison / mview .mat files, written here with scipy from the documented struct layout."""

import numpy as np
import pytest
from scipy.io import savemat

from dam.corpus import DataError, load_corpus
from dam.corpus.formats.mview import read_mview

FIELDS = [
    ("NAME", "O"),
    ("SRATE", "O"),
    ("SIGNAL", "O"),
    ("SOURCE", "O"),
    ("SENTENCE", "O"),
    ("WORDS", "O"),
    ("PHONES", "O"),
    ("LABELS", "O"),
]
SENSORS = ["TR", "TB", "TT", "UL", "LL", "ML", "JAW", "JAWL"]
EMPTY = np.zeros((0, 0))


def segs(items):
    a = np.zeros((1, len(items)), dtype=[("LABEL", "O"), ("OFFS", "O")])
    for k, (lab, s, e) in enumerate(items):
        a[0, k] = (lab, np.array([[s, e]]))
    return a


def write_mview(path, signals, phones, *, rate=100.0, words=(("the", 0.1, 0.3),), sentence="the birch canoe"):
    rec = np.zeros((1, 1 + len(signals)), dtype=FIELDS)
    rec[0, 0] = ("AUDIO", 44100.0, np.zeros(4410), "mic", sentence, segs(words), segs(phones), EMPTY)
    for k, (name, sig) in enumerate(signals.items(), 1):
        rec[0, k] = (name, rate, sig, "wave", "", EMPTY, EMPTY, EMPTY)
    savemat(str(path), {path.stem: rec})


PHONES = [("sil", 0.0, 0.1), ("DH", 0.1, 0.16), ("AH0", 0.16, 0.3), ("sil", 0.3, 0.5)]


def test_mview_reads_all_sensors_six_columns_and_phones(tmp_path):
    rng = np.random.default_rng(0)
    sig = {s: rng.normal(size=(50, 6)) for s in SENSORS}
    sig["TT"][10:13, :] = np.nan  # a dropout of the tongue tip sensor
    write_mview(tmp_path / "F01_B01_S01_R01_N.mat", sig, PHONES)
    write_mview(tmp_path / "F01_B01_S02_R01_N.mat", {s: rng.normal(size=(50, 6)) for s in SENSORS}, PHONES)
    palate = np.zeros((1, 1), dtype=FIELDS)
    palate[0, 0] = ("PALATE", 100.0, np.ones((30, 3)), "", "", EMPTY, EMPTY, EMPTY)
    savemat(str(tmp_path / "F01_palate.mat"), {"F01_palate": palate})  # no PHONES: skipped
    corpus = load_corpus(tmp_path)
    assert corpus.metadata["format"] == "mview" and corpus.metadata["length_unit"] == "mm"
    assert [u.name for u in corpus] == ["F01_B01_S01_R01_N", "F01_B01_S02_R01_N"]
    assert corpus.frame_rate == 100.0
    assert corpus.channels[:6] == ("TR_px", "TR_py", "TR_pz", "TR_ox", "TR_oy", "TR_oz")
    assert len(corpus.channels) == 48
    u = corpus[0]
    truth = np.hstack([sig[s] for s in SENSORS])
    ok = np.isfinite(truth)
    assert np.array_equal(u.mask, ok)
    np.testing.assert_array_equal(u.trajectory[ok], truth[ok])
    assert u.alignment.labels == ("sil", "DH", "AH0", "sil")
    np.testing.assert_allclose(u.alignment.ends, [0.1, 0.16, 0.3, 0.49])  # ends at the last frame time
    assert corpus.sensors["TT"] == ("TT_px", "TT_py", "TT_pz")
    assert corpus.metadata["sentences"]["F01_B01_S01_R01_N"] == "the birch canoe"
    _, _, info = read_mview(tmp_path / "F01_B01_S01_R01_N.mat")
    assert info["words"][0][0] == "the" and info["words"][0][1:] == pytest.approx((0.1, 0.3))
    assert load_corpus(tmp_path, sensors=["TT", "UL"]).channels == tuple(
        f"{s}_{c}" for s in ("TT", "UL") for c in ("px", "py", "pz", "ox", "oy", "oz")
    )


@pytest.mark.parametrize(
    "change, field, value",
    [
        (lambda sig, ph: ph.__setitem__(1, ("DH", 0.1, 0.05)), "segment 1 ('DH')", "0.1"),
        (lambda sig, ph: sig.__setitem__("TB", np.zeros((40, 6))), "F.TB", "40 frames"),
        (
            lambda sig, ph: sig.__setitem__("TB", np.array([["a", "b"], ["c", "d"]], dtype=object)),
            "F.TB.SIGNAL",
            "ndarray",
        ),
    ],
)
def test_malformed_mview_is_refused(tmp_path, change, field, value):
    sig = {s: np.zeros((50, 6)) for s in ("TT", "TB")}
    ph = list(PHONES)
    change(sig, ph)
    write_mview(tmp_path / "F.mat", sig, ph)
    with pytest.raises(DataError) as err:
        read_mview(tmp_path / "F.mat")
    msg = str(err.value)
    assert "F.mat" in msg and field in msg and value in msg


def test_not_a_mat_file_is_refused(tmp_path):
    (tmp_path / "x.mat").write_text("hello")
    with pytest.raises(DataError, match=r"x.mat: field 'mat'"):
        load_corpus(tmp_path)


def test_corpus_json_beside_a_distributed_corpus_sets_rate_and_sensors(tmp_path):
    import json

    write_mview(tmp_path / "F.mat", {s: np.zeros((50, 6)) for s in ("TT", "TB")}, PHONES)
    (tmp_path / "corpus.json").write_text(json.dumps({"frame_rate": 200, "sensors": {"tip": ["TT_px", "TT_pz"]}}))
    c = load_corpus(tmp_path)
    assert c.frame_rate == 200.0 and c[0].n_frames == 100
    assert c.sensors == {"tip": ("TT_px", "TT_pz")}
    (tmp_path / "corpus.json").write_text(json.dumps({"sensors": {"tip": ["TT_qx", "TT_pz"]}}))
    with pytest.raises(DataError, match=r"corpus.json: field \"sensors\['tip'\]\".*'TT_qx'"):
        load_corpus(tmp_path)
