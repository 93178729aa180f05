"""Wisconsin X-ray microbeam .txy files, written here by hand from the handbook's layout (as wrassp reads it)."""

import numpy as np
import pytest

from dam.corpus import Alignment, DataError, load_corpus
from dam.corpus.formats.htk import write_lab
from dam.corpus.formats.xrmb import XRMB_MISSING, read_txy, write_txy

M = XRMB_MISSING


def txy_lines(n, *, lost=(), period=6866, seed=0):
    """n frames after the all-missing first line at time 0; ``lost``: (frame, pellet index) pairs."""
    rng = np.random.default_rng(seed)
    um = rng.integers(-60000, 20000, size=(n, 16))
    for f, p in lost:
        um[f, 2 * p : 2 * p + 2] = M
    um[0] = M  # the first frame of every file is the marker
    lines = ["\t".join(str(v) for v in (i * period, *um[i])) for i in range(n)]
    return lines, um


def test_txy_values_in_mm_times_in_microseconds_and_the_marker(tmp_path):
    lines, um = txy_lines(40, lost=[(5, 2), (6, 2), (7, 2), (20, 7)])
    p = tmp_path / "tp001.txy"
    p.write_text("\n".join(lines) + "\n")
    tr = read_txy(p)
    assert tr.frame_rate == pytest.approx(1e6 / 6866)
    assert tr.channels[:4] == ["UL_x", "UL_y", "LL_x", "LL_y"] and tr.channels[-2:] == ["MNM_x", "MNM_y"]
    missing = um == M
    assert np.array_equal(np.isnan(tr.values), missing)
    np.testing.assert_allclose(tr.values[~missing], um[~missing] / 1000.0)


def test_xrmb_directory_masks_the_lost_pellets(tmp_path):
    lines, um = txy_lines(146, lost=[(30, 3), (31, 3), (100, 0)])
    (tmp_path / "tp001.txy").write_text("\n".join(lines) + "\n")
    dur = 146 * 0.006866
    write_lab(Alignment(["sil", "b", "a", "sil"], [0, 0.2, 0.5, 0.9], [0.2, 0.5, 0.9, dur]), tmp_path / "tp001.lab")
    corpus = load_corpus(tmp_path)
    assert corpus.metadata["format"] == "xrmb" and corpus.metadata["length_unit"] == "mm"
    u = corpus[0]
    assert corpus.frame_rate == pytest.approx(145.645, abs=1e-3)
    assert np.array_equal(~u.mask, um == M)
    assert np.isfinite(u.trajectory).all()
    np.testing.assert_allclose(u.trajectory[u.mask], um[um != M] / 1000.0)
    # the filled value of a lost pellet lies on the line between its observed neighbours (T2_x, frame 30-31)
    j = corpus.channels.index("T2_x")
    np.testing.assert_allclose(u.trajectory[30:32, j], np.interp([30, 31], [29, 32], um[[29, 32], j] / 1000.0))
    assert corpus.sensors["T2"] == ("T2_x", "T2_y") and len(corpus.sensors) == 8


def test_write_txy_round_trip(tmp_path):
    rng = np.random.default_rng(4)
    v = np.round(rng.normal(0, 20, size=(12, 16)), 3)
    v[3, 4:6] = np.nan
    mask = np.ones_like(v, bool)
    mask[7, 0] = False
    p = tmp_path / "w.txy"
    write_txy(p, v, mask=mask)
    tr = read_txy(p)
    expect = v.copy()
    expect[7, 0] = np.nan
    np.testing.assert_array_equal(np.isnan(tr.values), np.isnan(expect))
    np.testing.assert_allclose(tr.values[~np.isnan(expect)], expect[~np.isnan(expect)])
    assert p.read_text().splitlines()[1].split("\t")[0] == "6866"


@pytest.mark.parametrize(
    "edit, field, value",
    [
        (lambda ls: ls.__setitem__(3, ls[3].rsplit("\t", 2)[0]), "line 4", "15"),
        (lambda ls: ls.__setitem__(2, ls[2].replace("\t", "\t12.5x", 1)), "line 3", "12.5x"),
        (lambda ls: ls.__setitem__(4, "100\t" + ls[4].split("\t", 1)[1]), "line 5 time", "100"),
    ],
)
def test_malformed_txy_is_refused(tmp_path, edit, field, value):
    lines, _ = txy_lines(8)
    edit(lines)
    p = tmp_path / "bad.txy"
    p.write_text("\n".join(lines) + "\n")
    with pytest.raises(DataError) as err:
        read_txy(p)
    msg = str(err.value)
    assert "bad.txy" in msg and f"field {field!r}" in msg and value in msg


def test_txy_without_labels_is_named(tmp_path):
    lines, _ = txy_lines(8)
    (tmp_path / "tp009.txy").write_text("\n".join(lines) + "\n")
    with pytest.raises(DataError, match=r"tp009.txy: field 'alignment'"):
        load_corpus(tmp_path)


def linear_txy(path, n, *, period=6866, slope=0.25, lost=()):
    """Pellet positions that are linear in time (µm), so linear resampling is exact."""
    t_us = np.arange(n) * period
    um = np.rint(np.outer(t_us * 1e-3 * slope, np.arange(1, 17)) + np.arange(16) * 1000).astype(np.int64)
    for f, p in lost:
        um[f, 2 * p : 2 * p + 2] = M
    path.write_text("\n".join("\t".join(str(v) for v in (t_us[i], *um[i])) for i in range(n)) + "\n")
    return t_us * 1e-6, um


def test_frame_rate_resamples_by_linear_interpolation_and_carries_the_mask(tmp_path):
    t, um = linear_txy(tmp_path / "a.txy", 150, lost=[(70, 1)])
    dur = 150 * 0.006866
    write_lab(Alignment(["sil", "a", "sil"], [0, 0.3, 0.7], [0.3, 0.7, dur]), tmp_path / "a.lab")
    c = load_corpus(tmp_path, frame_rate=100.0)
    u = c[0]
    assert c.frame_rate == 100.0 and u.n_frames == int(np.ceil(dur * 100 - 1e-6))
    tj = np.arange(u.n_frames) / 100.0
    inside = tj <= t[-1]
    for j in (0, 5, 15):
        expect = np.interp(tj, t, um[:, j] / 1000.0)
        np.testing.assert_allclose(u.trajectory[inside & u.mask[:, j], j], expect[inside & u.mask[:, j]], atol=1e-9)
    # the LL pellet (channels 2, 3) was lost at source frame 70 (t = 0.4806 s): of the output frames only
    # 48 (0.48 s, between source frames 69 and 70) has it as a neighbour; 49 (0.49 s) lies between 71 and 72
    lost_out = np.flatnonzero(~u.mask[:, 2])
    assert list(lost_out) == [48] and u.mask[:, [0, 1, 4]].all()


def test_files_at_different_rates_need_frame_rate(tmp_path):
    linear_txy(tmp_path / "a.txy", 100)
    linear_txy(tmp_path / "b.txy", 100, period=5000)
    for stem, dur in (("a", 100 * 0.006866), ("b", 0.5)):
        write_lab(Alignment(["sil", "a"], [0, 0.2], [0.2, dur]), tmp_path / f"{stem}.lab")
    with pytest.raises(DataError, match=r"b.txy: field 'frame_rate'.*200 frames/s.*frame_rate="):
        load_corpus(tmp_path)
    c = load_corpus(tmp_path, frame_rate=200.0)
    assert c.frame_rate == 200.0 and len(c) == 2


def test_a_jittered_frame_keeps_the_nominal_rate(tmp_path):
    lines, um = txy_lines(30)
    parts = lines[12].split("\t")
    parts[0] = str(12 * 6866 + 900)  # one frame 0.9 ms late
    lines[12] = "\t".join(parts)
    (tmp_path / "j.txy").write_text("\n".join(lines) + "\n")
    tr = read_txy(tmp_path / "j.txy")
    assert tr.frame_rate == pytest.approx(1e6 / 6866)
    assert tr.times is not None and tr.times[12] == pytest.approx((12 * 6866 + 900) * 1e-6)
