"""Vocal-tract outlines from VocalTractLab as captured motion, and the toy outline rig."""

import numpy as np
import pytest

from dam import Alignment, Corpus, DataError, Utterance
from dam.crossmap.outlines import (
    CONTOURS,
    outline_channels,
    outline_corpus,
    resample_contour,
    toy_tract_rig,
    tract_outlines,
    vtl_shape,
)

pytest.importorskip("vocaltractlab_cython")
TCY, JA = 9, 3  # indices in VTL's 19 tract parameters


def test_resample_contour_spaces_points_evenly_and_keeps_ends():
    P = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 0.0], [1.0, 3.0]])  # length 4, a repeated point
    Q = resample_contour(P, 5)
    np.testing.assert_allclose(Q, [[0, 0], [1, 0], [1, 1], [1, 2], [1, 3]], atol=1e-12)
    np.testing.assert_allclose(resample_contour(np.ones((3, 2)), 4), np.ones((4, 2)))


def test_outlines_have_the_expected_shape_and_names():
    states = np.stack([vtl_shape(s) for s in ("a", "i", "u")])
    out = tract_outlines(states, n_points=12)
    assert out.shape == (3, len(CONTOURS) * 12 * 2) and np.isfinite(out).all()
    names = outline_channels(n_points=12)
    assert len(names) == out.shape[1] and names[:3] == ["upper00_x", "upper00_y", "upper01_x"]
    tongue = tract_outlines(states, contours=["tongue"], n_points=12)
    np.testing.assert_allclose(tongue, out[:, 2 * 24 : 3 * 24])


def test_outlines_move_when_the_tract_moves():
    base = vtl_shape("@")
    up = base.copy()
    up[TCY] += 1.0  # tongue body up by 1 cm
    o = tract_outlines(np.stack([base, base, up]), n_points=16).reshape(3, 4, 16, 2)
    np.testing.assert_array_equal(o[0], o[1])  # same state, same outline
    moved = np.abs(o[2] - o[0]).max(axis=(1, 2))
    assert moved[CONTOURS.index("tongue")] > 0.3
    assert moved[CONTOURS.index("lower")] == 0 and moved[CONTOURS.index("upper")] == 0
    # the tongue goes up (y grows) on average
    assert (o[2, 2, :, 1] - o[0, 2, :, 1]).mean() > 0.1
    jaw = base.copy()
    jaw[JA] -= 2.0  # open the jaw
    o2 = tract_outlines(np.stack([base, jaw]), contours=["lower"]).reshape(2, 16, 2)
    assert (o2[1, :, 1] - o2[0, :, 1]).min() <= -0.2  # part of the lower outline drops


def test_outline_step_interpolation_is_close_to_exact():
    a, i = vtl_shape("a"), vtl_shape("i")
    s = 0.5 - 0.5 * np.cos(np.linspace(0, np.pi, 21))[:, None]
    states = (1 - s) * a + s * i  # a smooth a -> i glide
    exact = tract_outlines(states, contours=["tongue"], n_points=8)
    approx = tract_outlines(states, contours=["tongue"], n_points=8, step=2)
    np.testing.assert_allclose(approx[::2], exact[::2], atol=1e-12)  # knots are exact
    assert np.abs(approx - exact).max() < 0.05  # cm


def test_outline_corpus_keeps_alignments_and_reorders_channels():
    from dam.datasets.vtl import VTL_CHANNELS

    states = np.stack([vtl_shape("a"), vtl_shape("i"), vtl_shape("i"), vtl_shape("a")])
    perm = np.arange(19)[::-1]
    al = Alignment(["a", "i"], [0, 0.02], [0.02, 0.04])
    corpus = Corpus([Utterance(al, states[:, perm], 100.0, [VTL_CHANNELS[k] for k in perm], name="ai")])
    out = outline_corpus(corpus, contours=["tongue", "lower"], n_points=6)
    assert out[0].alignment == corpus[0].alignment and out.channels == tuple(outline_channels(["tongue", "lower"], 6))
    np.testing.assert_allclose(out[0].trajectory, tract_outlines(states, contours=["tongue", "lower"], n_points=6))
    bad = Corpus([Utterance(al, states[:, :3], 100.0, ["a", "b", "c"], name="x")])
    with pytest.raises(DataError, match="missing HX"):
        outline_corpus(bad)


def test_toy_rig_reproduces_the_vtl_shapes_it_was_built_from():
    rig = toy_tract_rig(contours=["tongue", "lower"], n_points=8)
    assert rig.n_controls == 7 and rig.control_names[0] == "jaw_open"
    at = lambda name: tract_outlines(vtl_shape(name), contours=["tongue", "lower"], n_points=8)[0]
    np.testing.assert_allclose(rig(np.zeros(7)), at("@"), atol=1e-12)
    c = np.zeros(7)
    c[0] = 1.0
    np.testing.assert_allclose(rig(c), at("a"), atol=1e-12)


def test_bad_outline_input():
    with pytest.raises(DataError, match="states"):
        tract_outlines(np.zeros((2, 18)))
    with pytest.raises(DataError, match="contours"):
        tract_outlines(vtl_shape("a"), contours=["lips"])
    with pytest.raises(DataError, match="shape"):
        vtl_shape("no-such-shape")
