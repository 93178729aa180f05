"""MOCHA-TIMIT and mngu0 directories: EST tracks + xwaves labels, written here from their documentation."""

import numpy as np
import pytest

from dam.corpus import DataError, load_corpus
from dam.corpus.formats.detect import detect_format
from dam.corpus.formats.est import write_est
from dam.corpus.formats.mocha import MOCHA_CHANNELS, load_mocha_corpus
from dam.corpus.io import read_alignment


def write_xlabel(path, ends_labels):
    """ESPS/xwaves label file: header up to '#', then 'end_time colour label' lines."""
    lines = ["signal fsew0_001", "type 0", "color 121", "comment created by hand", "font -misc-*", "#"]
    lines += [f"    {end:.4f}  121 {lab}" for end, lab in ends_labels]
    path.write_text("\n".join(lines) + "\n")


def mocha_dir(tmp_path, *, byte_orders=("01", "10"), n=250, breaks=()):
    rng = np.random.default_rng(7)
    raw = {}
    for k, order in enumerate(byte_orders):
        stem = f"fsew0_{k + 1:03d}"
        v = np.round(rng.normal(0, 2000, size=(n, 20))).astype(np.float32)  # 1/100 mm, as MOCHA stores
        present = np.ones(n, bool)
        present[list(breaks)] = False
        write_est(tmp_path / f"{stem}.ema", v, frame_rate=500.0, byte_order=order, present=present)
        write_xlabel(tmp_path / f"{stem}.lab", [(0.12, "breath"), (0.3, "dh"), (0.42, "@"), (n / 500 + 0.004, "sil")])
        (tmp_path / f"{stem}.lar").write_bytes(b"RIFF....laryngograph")
        raw[stem] = v
    return raw


def test_mocha_directory_reads_in_millimetres_with_the_20_channel_layout(tmp_path):
    raw = mocha_dir(tmp_path)
    assert detect_format(tmp_path) == "mocha"
    corpus = load_corpus(tmp_path)
    assert corpus.metadata["format"] == "mocha" and corpus.metadata["length_unit"] == "mm"
    assert corpus.frame_rate == 500.0
    assert corpus.channels == MOCHA_CHANNELS
    assert corpus.channels[:3] == ("ui_x", "li_x", "ul_x") and corpus.channels[5] == "ui_y"
    for u in corpus:
        np.testing.assert_allclose(u.trajectory, raw[u.name].astype(float) / 100.0)
        # labels past the EMA's end by 4 ms of silence are trimmed to its last frame time
        assert u.alignment.labels == ("breath", "dh", "@", "sil")
        assert u.alignment.duration == pytest.approx((250 - 1) / 500)
        assert u.mask is None
    assert set(corpus.sensors) >= {"tt", "ul", "ll", "td", "v"}
    assert corpus.sensors["tt"] == ("tt_x", "tt_y")


def test_mocha_break_frames_become_masked(tmp_path):
    mocha_dir(tmp_path, byte_orders=("01",), breaks=(10, 11, 12))
    u = load_corpus(tmp_path)[0]
    assert u.mask is not None and u.mask.shape == u.trajectory.shape
    assert not u.mask[10:13].any() and u.mask[:10].all() and u.mask[13:].all()
    assert np.isfinite(u.trajectory).all()


def test_mocha_labels_past_the_ema_that_cut_a_phone_are_refused(tmp_path):
    mocha_dir(tmp_path, byte_orders=("01",))
    write_xlabel(tmp_path / "fsew0_001.lab", [(0.3, "dh"), (0.6, "@")])
    with pytest.raises(DataError, match=r"fsew0_001.ema: field 'duration'.*'@'"):
        load_corpus(tmp_path)


def test_mocha_without_names_needs_20_channels(tmp_path):
    write_est(tmp_path / "msak0_001.ema", np.zeros((10, 19), np.float32), frame_rate=500.0)
    write_xlabel(tmp_path / "msak0_001.lab", [(0.02, "sil")])
    with pytest.raises(DataError, match=r"msak0_001.ema: field 'NumChannels'.*19"):
        load_mocha_corpus(tmp_path, read_alignment=read_alignment)


def test_mngu0_keeps_header_names_mm_and_masks_breaks(tmp_path):
    names = ["T1_px", "T1_py", "T1_pz", "T1_ox", "T3_py", "T3_pz", "upperlip_py", "upperlip_pz"]
    rng = np.random.default_rng(2)
    v = rng.normal(size=(120, len(names))).astype(np.float32)
    present = np.ones(120, bool)
    present[50] = False
    write_est(tmp_path / "mngu0_s1_0001.ema", v, frame_rate=200.0, channels=names, present=present)
    write_xlabel(tmp_path / "mngu0_s1_0001.lab", [(0.2, "#"), (0.5, "k"), (0.6, "#")])
    assert detect_format(tmp_path) == "mngu0"
    c = load_corpus(tmp_path)
    assert c.channels == tuple(names) and c.frame_rate == 200.0
    np.testing.assert_array_equal(c[0].trajectory[c[0].mask], v.astype(float)[c[0].mask])
    assert not c[0].mask[50].any() and c[0].mask[49].all()
    assert c.sensors == {
        "T1": ("T1_px", "T1_py", "T1_pz"),
        "T3": ("T3_py", "T3_pz"),
        "upperlip": ("upperlip_py", "upperlip_pz"),
    }
