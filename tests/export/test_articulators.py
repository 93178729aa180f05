"""Articulators that move (issue 18): the VocalTractLab outline as .gif, .mp4 and .html.

The truth here is VocalTractLab itself (the outline of a tract state, computed independently with
dam.crossmap.outlines.tract_outlines), Pillow and ffmpeg decoding the files, and frame counts
from the duration.
"""

import json
import re

import numpy as np
import pytest
from PIL import Image

import dam
from dam.cli import main
from dam.corpus import Alignment, DataError
from dam.crossmap.outlines import CONTOURS, tract_outlines, vtl_shape
from dam.datasets.vtl import VTL_CHANNELS
from dam.export import articulators as art
from dam.export import export

FR = 100.0


@pytest.fixture(scope="module")
def ramp():
    """2.0 s of controls moving linearly from VTL's /a/ to its /i/ (200 frames at 100 Hz)."""
    a, i = vtl_shape("a"), vtl_shape("i")
    w = np.linspace(0.0, 1.0, 200)[:, None]
    return a, i, (1 - w) * a + w * i


def _alignment(duration):
    return Alignment(["sil", "a", "i", "sil"], [0.0, 0.3, 1.0, 1.7], [0.3, 1.0, 1.7, duration])


def _gif_frames(path):
    im = Image.open(path)
    out = []
    for k in range(im.n_frames):
        im.seek(k)
        out.append(np.asarray(im.convert("RGB")))
    return out


def test_gif_has_duration_times_fps_frames_and_moves(tmp_path, ramp):
    _, _, X = ramp
    out = tmp_path / "ramp.gif"
    rep = export(X, out, channels=VTL_CHANNELS, frame_rate=FR, alignment=_alignment(2.0), fps=10, size=(320, 240))
    frames = _gif_frames(out)
    assert len(frames) == rep.n_frames == 20  # 2.0 s x 10 frames/s
    assert frames[0].shape == (240, 320, 3)
    assert np.abs(frames[0].astype(int) - frames[-1].astype(int)).sum() > 0


def test_html_page_is_self_contained_with_every_frame(tmp_path, ramp):
    _, _, X = ramp
    out = tmp_path / "ramp.html"
    export(X[:150], out, channels=VTL_CHANNELS, frame_rate=FR, fps=8, size=(256, 192))
    page = out.read_text()
    frames = json.loads(re.search(r"const FRAMES = (\[.*?\]);", page, re.S).group(1))
    assert len(frames) == 12  # 1.5 s x 8 frames/s
    assert "http://" not in page and "https://" not in page and "<script src" not in page
    import base64
    import io

    first = Image.open(io.BytesIO(base64.b64decode(frames[0])))
    assert first.size == (256, 192)


def test_mp4_through_ffmpeg_has_the_frames(tmp_path, ramp):
    import imageio_ffmpeg

    _, _, X = ramp
    out = tmp_path / "ramp.mp4"
    export(X[:100], out, channels=VTL_CHANNELS, frame_rate=FR, fps=12, size=(320, 240))
    n, seconds = imageio_ffmpeg.count_frames_and_secs(str(out))
    assert n == 12 and seconds == pytest.approx(1.0, abs=0.01)


def test_mp4_without_ffmpeg_is_a_clear_error(tmp_path, ramp, monkeypatch):
    monkeypatch.setattr(art, "find_ffmpeg", lambda: None)
    with pytest.raises(DataError, match="ffmpeg"):
        export(ramp[2], tmp_path / "x.mp4", channels=VTL_CHANNELS, frame_rate=FR)
    assert not (tmp_path / "x.mp4").exists()


def test_outline_drawn_at_a_frame_is_vtls_outline_of_that_frames_controls(ramp):
    a, i, X = ramp
    fps, n_points = 10.0, 40
    times, outlines = art.articulator_outlines(X, VTL_CHANNELS, FR, fps=fps, n_points=n_points)
    r = art.ArticulatorRenderer([("ramp", outlines)], times, alignment=_alignment(2.0), n_points=n_points)
    try:
        for k in (0, 7, 19):
            r.draw(k)
            w = min(k / fps * FR / 199, 1.0)  # the ramp at time k / fps, by hand
            truth = tract_outlines((1 - w) * a + w * i, n_points=n_points)[0].reshape(len(CONTOURS), n_points, 2)
            for c, pts in zip(CONTOURS, truth):
                np.testing.assert_allclose(r.lines[0][c].get_xydata(), pts, atol=1e-9)
    finally:
        r.close()


def test_outline_panels_change_only_when_the_controls_do(ramp):
    a, _, X = ramp
    still = np.repeat(a[None], 200, axis=0)
    for controls, moves in ((X, True), (still, False)):
        times, outlines = art.articulator_outlines(controls, VTL_CHANNELS, FR, fps=5)
        r = art.ArticulatorRenderer([("v", outlines)], times, size=(320, 240))
        try:
            ax = r.figure.axes[0]
            x0, y0, x1, y1 = (int(round(v)) for v in ax.bbox.extents)
            crop = slice(240 - y1, 240 - y0), slice(x0, x1)
            first, last = r.image(0)[crop].astype(int), r.image(len(r) - 1)[crop].astype(int)
        finally:
            r.close()
        assert (np.abs(first - last).sum() > 0) == moves


def test_views_side_by_side_and_bad_input(tmp_path, ramp):
    a, i, X = ramp
    out = tmp_path / "two.gif"
    rep = export(
        X[:50],
        out,
        channels=VTL_CHANNELS,
        frame_rate=FR,
        fps=10,
        size=(480, 240),
        compare=[("reversed", X[:50][::-1])],
        metadata={"model": "dam"},
    )
    assert rep.n_frames == 5 and "2 views" in rep.notes[0]
    with pytest.raises(DataError, match="19 tract parameters"):
        export(np.zeros((10, 2)), tmp_path / "x.gif", channels=["JA", "LP"], frame_rate=FR)
    with pytest.raises(DataError, match="fps"):
        export(X, tmp_path / "x.gif", channels=VTL_CHANNELS, frame_rate=FR, fps=0)
    with pytest.raises(DataError, match="different number of frames"):
        export(X, tmp_path / "x.gif", channels=VTL_CHANNELS, frame_rate=FR, compare=[("short", X[:10])])
    assert not list(tmp_path.glob("x.*"))


def test_cli_animate_prediction_beside_the_recording(tmp_path, capsys):
    corpus = dam.datasets.load("vtl", split="test")
    u = corpus[1]
    src = dam.datasets.path("vtl") / "test"
    tg = str(src / f"{u.name}.TextGrid")
    out = tmp_path / "cmp.html"
    code = main(
        [
            "animate",
            "--alignment",
            tg,
            "--truth",
            str(src / f"{u.name}.npy"),
            "-o",
            str(out),
            "--fps",
            "5",
            "--size",
            "320x200",
        ]
    )
    assert code == 0
    page = out.read_text()
    frames = json.loads(re.search(r"const FRAMES = (\[.*?\]);", page, re.S).group(1))
    assert len(frames) == round(u.n_frames / corpus.frame_rate * 5)
    assert "recorded" in page
    with pytest.raises(SystemExit) as exc:
        main(["animate", "--alignment", tg, "-o", str(tmp_path / "x.csv"), "--fps", "10"])
    assert exc.value.code == 2
