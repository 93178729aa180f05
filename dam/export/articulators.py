"""Articulators that move: the VocalTractLab midsagittal outline as ``.gif``, ``.mp4`` or ``.html``.

Controls that are VocalTractLab's 19 tract parameters (the bundled ``vtl``
corpus, the default model of ``dam animate``) are drawn as the outline of
the vocal tract that VocalTractLab computes for them
(:func:`dam.crossmap.outlines.tract_outlines`: upper lip, teeth, palate,
velum and pharynx wall; lower lip, teeth and jaw; tongue; epiglottis), one
picture per output frame, with the phones scrolling underneath. Several
views (two models, or a prediction and the recorded truth) are drawn side
by side on shared axes.

Output frame ``k`` shows time ``k / fps``; an utterance of ``n`` control
frames at ``frame_rate`` lasts ``n / frame_rate`` seconds and becomes
``round(duration * fps)`` pictures (at least one). The controls at an output
time are interpolated linearly between the two nearest control frames, and
the outline is VocalTractLab's exact outline of those controls (a few ms of
CPU per picture and view; a 3-second utterance at 25 pictures/s takes a few
CPU seconds in all: ``benchmarks/bench_articulators.py`` measures it).

Files:

* ``.gif``: an animated GIF written with Pillow (GIF delays are whole
  centiseconds: 25 fps is exact, 30 fps plays at 1/0.03 s);
* ``.mp4``: H.264 through ffmpeg (``ffmpeg`` on the PATH, or the binary of
  ``imageio-ffmpeg``: ``pip install "dam[video]"``);
* ``.html``: one self-contained page (PNG frames embedded, no external
  resource) with a play/pause button, a frame slider and a speed choice.

Needs VocalTractLab (``pip install "dam[vtl]"``).
"""

from __future__ import annotations

import base64
import html as _html
import io
import json
import os
import shutil
import subprocess

import numpy as np

from dam import plotting
from dam.corpus import Alignment, DataError
from dam.corpus.atomic import atomic_path, atomic_write

__all__ = [
    "ARTICULATOR_FORMATS",
    "frame_count",
    "controls_at",
    "articulator_outlines",
    "ArticulatorRenderer",
    "write_articulators",
    "find_ffmpeg",
]

#: Extensions :func:`write_articulators` writes (registered in :data:`dam.export.FORMATS`).
ARTICULATOR_FORMATS = (".gif", ".mp4", ".html")
#: Contour colours: the fixed walls grey, the moving parts in the palette.
_CONTOUR_STYLE = {
    "upper": ("0.35", "upper lip, palate,\nvelum, pharynx"),
    "lower": (plotting.PALETTE[0], "lower lip, jaw"),
    "tongue": (plotting.PALETTE[1], "tongue"),
    "epiglottis": (plotting.PALETTE[2], "epiglottis"),
}


def frame_count(duration: float, fps: float) -> int:
    """Pictures of an animation of ``duration`` seconds at ``fps``: ``round(duration * fps)``, at least 1.

    Examples
    --------
    >>> frame_count(3.0, 25)
    75
    """
    return max(1, int(round(float(duration) * float(fps))))


def controls_at(values, frame_rate: float, times) -> np.ndarray:
    """Controls at ``times`` (s), linearly interpolated between frames (frame ``i`` at ``i / frame_rate``).

    Parameters
    ----------
    values : ndarray, shape (n_frames, n_channels)
    frame_rate : float
    times : array-like, shape (n_times,)
        Outside the frames, the first or last frame is held.

    Returns
    -------
    ndarray, shape (n_times, n_channels)

    Examples
    --------
    >>> controls_at(np.array([[0.0], [1.0]]), 10.0, [0.05])
    array([[0.5]])
    """
    values = np.asarray(values, dtype=float)
    pos = np.asarray(times, dtype=float) * float(frame_rate)
    grid = np.arange(len(values))
    return np.stack([np.interp(pos, grid, values[:, j]) for j in range(values.shape[1])], axis=1)


def _vtl_order(channels, source) -> list[int]:
    from dam.datasets.vtl import VTL_CHANNELS

    missing = [c for c in VTL_CHANNELS if c not in channels]
    if missing:
        raise DataError(
            source,
            "channels",
            list(channels),
            f"the articulator drawing needs VocalTractLab's 19 tract parameters "
            f"({' '.join(VTL_CHANNELS)}); missing {', '.join(missing)}",
            "animate with a model trained on them (the default model of `dam animate`), "
            "or write .csv/.json/.gltf instead",
        )
    return [list(channels).index(c) for c in VTL_CHANNELS]


def articulator_outlines(
    values,
    channels,
    frame_rate: float,
    *,
    fps: float = 25.0,
    n_points: int = 40,
    n_frames: int | None = None,
    source=None,
):
    """The vocal-tract outline at every output frame.

    Parameters
    ----------
    values : array-like, shape (n_control_frames, n_channels)
        Controls including VocalTractLab's 19 tract parameters (any order, other channels ignored).
    channels : sequence of str, length n_channels
    frame_rate : float
        Control frames per second.
    fps : float, default 25
        Output frames per second.
    n_points : int, default 40
        Points per contour (equally spaced along it).
    n_frames : int, optional
        Output frames; default :func:`frame_count` of the controls' duration.
    source : str, optional
        Named in errors.

    Returns
    -------
    times : ndarray, shape (n_frames,)
        ``k / fps``.
    outlines : ndarray, shape (n_frames, 4 * n_points * 2)
        Flattened points (cm) of the contours :data:`dam.crossmap.outlines.CONTOURS`, as
        :func:`dam.crossmap.outlines.tract_outlines` returns them.
    """
    from dam.crossmap.outlines import tract_outlines

    values = np.asarray(values, dtype=float)
    order = _vtl_order(channels, source)
    if not (np.isfinite(fps) and fps > 0):
        raise DataError(source, "fps", fps, "must be a positive number of frames per second")
    n = frame_count(len(values) / float(frame_rate), fps) if n_frames is None else int(n_frames)
    times = np.arange(n) / float(fps)
    states = controls_at(values[:, order], frame_rate, times)
    return times, tract_outlines(states, n_points=n_points)


class ArticulatorRenderer:
    """Draws outline frames of one or more views side by side, phones scrolling underneath.

    Parameters
    ----------
    views : list of (str, ndarray of shape (n_frames, 4 * n_points * 2))
        Title and outline frames of each view (:func:`articulator_outlines`), all the same length.
    times : ndarray, shape (n_frames,)
        Time of every frame (s).
    alignment : Alignment, optional
        The phones drawn in the scrolling strip (a window of ``window`` seconds around the current time).
    title : str, default "Midsagittal vocal tract (VocalTractLab)"
    size : (int, int), default (640, 400)
        Width and height in pixels (rounded up to even numbers, as H.264 needs).
    n_points : int, default 40
    window : float, default 1.2
        Seconds of phones shown in the strip.

    Attributes
    ----------
    figure : matplotlib Figure
    lines : list of dict str -> Line2D
        Per view, the line of every contour (its data is the outline of the last drawn frame).
    size : (int, int)
    """

    def __init__(
        self,
        views,
        times,
        *,
        alignment: Alignment | None = None,
        title: str = "Midsagittal vocal tract (VocalTractLab)",
        size=(640, 400),
        n_points: int = 40,
        window: float = 1.2,
        dpi: int = 100,
    ):
        from dam.crossmap.outlines import CONTOURS

        plt = plotting.pyplot()
        self.views = [(str(t), np.asarray(o, dtype=float)) for t, o in views]
        self.times = np.asarray(times, dtype=float)
        self.n_points, self.window, self.alignment = int(n_points), float(window), alignment
        w, h = (int(v) + int(v) % 2 for v in size)
        self.size = (w, h)
        self.figure = fig = plt.figure(figsize=(w / dpi, h / dpi), dpi=dpi, layout="constrained")
        nv = len(self.views)
        gs = fig.add_gridspec(
            2 if alignment is not None else 1, nv, height_ratios=[1.0, 0.16] if alignment is not None else [1.0]
        )
        allpts = np.concatenate([o.reshape(-1, 2) for _, o in self.views])
        lo, hi = allpts.min(axis=0), allpts.max(axis=0)
        pad = 0.05 * (hi - lo).max()
        self.lines = []
        for v, (name, _) in enumerate(self.views):
            ax = fig.add_subplot(gs[0, v])
            ax.set_xlim(lo[0] - pad, hi[0] + pad)
            ax.set_ylim(lo[1] - pad, hi[1] + pad)
            ax.set_aspect("equal", adjustable="box")
            ax.set_title(name, fontsize=9)
            ax.set_xlabel("x (cm)")
            ax.set_ylabel("y (cm)" if v == 0 else "")
            self.lines.append(
                {
                    c: ax.plot([], [], color=_CONTOUR_STYLE[c][0], lw=1.8, label=_CONTOUR_STYLE[c][1])[0]
                    for c in CONTOURS
                }
            )
        self.clock = fig.text(0.005, 0.995, "", ha="left", va="top", fontsize=8)
        self.tier = self.cursor = None
        if alignment is not None:
            self.tier = fig.add_subplot(gs[1, :])
            plotting.phone_tier(self.tier, alignment)
            self.cursor = self.tier.axvline(0.0, color=plotting.TRUTH, lw=1.5)
            self._labels = [(t, t.get_position()[0]) for t in self.tier.texts]
            from matplotlib.ticker import MultipleLocator

            self.tier.xaxis.set_major_locator(MultipleLocator(0.5))
        fig.suptitle(title, fontsize=10)
        first = self.lines[0]
        plotting.legend_outside(fig, list(first.values()), [ln.get_label() for ln in first.values()], title="contour")
        self.draw(0)
        fig.canvas.draw()  # constrained layout once; then frozen (one layout per frame is slow)
        fig.set_layout_engine("none")
        # Blitting: the still parts are drawn once; a frame redraws only what moves.
        self._moving = [ln for lines in self.lines for ln in lines.values()] + [self.clock]
        if self.tier is not None:
            self._moving.append(self.tier)
        for a in self._moving:
            a.set_animated(True)
        fig.canvas.draw()
        self._background = fig.canvas.copy_from_bbox(fig.bbox)

    def __len__(self) -> int:
        return len(self.times)

    def draw(self, k: int):
        """Put frame ``k`` on the figure; returns the figure."""
        from dam.crossmap.outlines import CONTOURS

        for lines, (_, outlines) in zip(self.lines, self.views):
            pts = outlines[k].reshape(len(CONTOURS), self.n_points, 2)
            for c, p in zip(CONTOURS, pts):
                lines[c].set_data(p[:, 0], p[:, 1])
        t = float(self.times[k])
        self.clock.set_text(f"t = {t:.2f} s")
        if self.tier is not None:
            self.tier.set_xlim(t - self.window / 2, t + self.window / 2)
            for text, x in self._labels:  # laying out hidden labels is most of a frame's cost
                text.set_visible(abs(x - t) < self.window)
            self.cursor.set_xdata([t, t])
        return self.figure

    def image(self, k: int) -> np.ndarray:
        """Frame ``k`` as pixels, shape (height, width, 3), uint8."""
        self.draw(k)
        canvas = self.figure.canvas
        canvas.restore_region(self._background)
        for a in self._moving:
            self.figure.draw_artist(a)
        rgba = np.asarray(canvas.buffer_rgba())
        return np.array(rgba[: self.size[1], : self.size[0], :3])

    def close(self) -> None:
        plotting.pyplot().close(self.figure)


def find_ffmpeg() -> str | None:
    """The ffmpeg program: on the PATH, else the one ``imageio-ffmpeg`` ships; None when there is neither."""
    exe = shutil.which("ffmpeg")
    if exe:
        return exe
    try:
        import imageio_ffmpeg

        return imageio_ffmpeg.get_ffmpeg_exe()
    except (ImportError, RuntimeError):
        return None


def _paletted(frames):
    """Frames as 64-colour images with one palette (from the first frame): the same colours move."""
    from PIL import Image

    pal = Image.fromarray(frames[0]).quantize(colors=64, method=Image.Quantize.MEDIANCUT)
    return [Image.fromarray(f).quantize(palette=pal, dither=Image.Dither.NONE) for f in frames]


def _write_gif(frames, path, fps):
    images = _paletted(frames)
    with atomic_path(path) as tmp:
        images[0].save(
            tmp,
            format="GIF",
            save_all=True,
            append_images=images[1:],
            loop=0,
            duration=1000.0 / fps,
            disposal=1,
            optimize=False,
        )


def _write_mp4(frames, path, fps, exe):
    h, w = frames[0].shape[:2]
    with atomic_path(path) as tmp:
        cmd = [
            exe,
            "-y",
            "-loglevel",
            "error",
            "-f",
            "rawvideo",
            "-pix_fmt",
            "rgb24",
            "-s",
            f"{w}x{h}",
            "-r",
            repr(float(fps)),
            "-i",
            "-",
            "-an",
            "-c:v",
            "libx264",
            "-pix_fmt",
            "yuv420p",
            "-movflags",
            "+faststart",
            "-f",
            "mp4",
            tmp,
        ]
        proc = subprocess.run(cmd, input=b"".join(f.tobytes() for f in frames), capture_output=True)
        if proc.returncode:
            raise DataError(path, "mp4", exe, f"ffmpeg failed: {proc.stderr.decode(errors='replace')[-400:]}")


_PLAYER = """<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{title}</title>
<style>body{{font-family:sans-serif;margin:1em}} #ctl{{margin-top:.4em}} img{{border:1px solid #ddd}}</style>
</head><body>
<h3>{title}</h3>
<img id="frame" width="{w}" height="{h}" alt="vocal tract outline">
<div id="ctl"><button id="play">pause</button>
<input id="pos" type="range" min="0" max="{last}" value="0" style="width:{slider}px">
<span id="lab"></span>
<select id="speed"><option value="0.25">0.25x</option><option value="0.5">0.5x</option>
<option value="1" selected>1x</option></select></div>
<p style="font-size:small">made by dam (dam animate); {n} frames at {fps:g} frames/s</p>
<script>
const FRAMES = {frames};
const FPS = {fps!r};
let k = 0, playing = true, speed = 1, last = performance.now();
const img = document.getElementById("frame"), pos = document.getElementById("pos"),
      lab = document.getElementById("lab"), btn = document.getElementById("play");
function show(i) {{ k = i; img.src = "data:image/png;base64," + FRAMES[k]; pos.value = k;
  lab.textContent = "frame " + (k + 1) + " / " + FRAMES.length + ", t = " + (k / FPS).toFixed(2) + " s"; }}
btn.onclick = () => {{ playing = !playing; btn.textContent = playing ? "pause" : "play"; last = performance.now(); }};
pos.oninput = () => {{ playing = false; btn.textContent = "play"; show(parseInt(pos.value)); }};
document.getElementById("speed").onchange = (e) => {{ speed = parseFloat(e.target.value); }};
function tick(now) {{
  if (playing && now - last >= 1000 / (FPS * speed)) {{ last = now; show((k + 1) % FRAMES.length); }}
  requestAnimationFrame(tick); }}
show(0); requestAnimationFrame(tick);
</script></body></html>
"""


def _write_html(frames, path, fps, title):
    encoded = []
    for f in _paletted(frames):
        buf = io.BytesIO()
        f.save(buf, format="PNG", optimize=True)
        encoded.append(base64.b64encode(buf.getvalue()).decode("ascii"))
    h, w = frames[0].shape[:2]
    page = _PLAYER.format(
        title=_html.escape(title),
        w=w,
        h=h,
        last=len(frames) - 1,
        slider=max(w - 200, 100),
        n=len(frames),
        fps=float(fps),
        frames=json.dumps(encoded),
    )
    with atomic_write(path, "w") as fh:
        fh.write(page)


def write_articulators(
    values,
    path,
    *,
    channels,
    frame_rate,
    alignment=None,
    metadata=None,
    fps: float = 25.0,
    size=(640, 400),
    compare=None,
    label: str | None = None,
    n_points: int = 40,
):
    """Write the moving vocal-tract outline of controls to ``.gif``, ``.mp4`` or ``.html``.

    The writer of :func:`dam.export.export` for those extensions.

    Parameters
    ----------
    values : ndarray, shape (n_frames, n_channels)
        VocalTractLab tract parameters (checked by :func:`dam.export.export`).
    path : str
        Output; the extension picks the file type.
    channels : sequence of str
    frame_rate : float
        Control frames per second.
    alignment : Alignment, optional
        Phones scrolled underneath.
    metadata : dict, optional
        ``metadata["model"]`` names the first view (unless ``label`` does).
    fps : float, default 25
        Output frames per second.
    size : (int, int), default (640, 400)
        Picture width and height in pixels.
    compare : list of (str, ndarray), optional
        More views drawn beside the first: a title and controls with the same ``channels`` and
        ``frame_rate`` (e.g. ``[("recorded", truth)]`` or another model's prediction).
    label : str, optional
        Title of the first view (default the model's name, or "controls").
    n_points : int, default 40
        Points per contour.

    Returns
    -------
    ExportReport
        ``n_frames`` is the number of pictures written, ``frame_rate`` their rate.

    Raises
    ------
    dam.DataError
        Not VocalTractLab tract parameters, a ``compare`` view of another shape,
        a bad ``fps`` or ``size``, or ``.mp4`` without ffmpeg.
    """
    from .tables import ExportReport, check_animation

    ext = os.path.splitext(path)[1].lower()
    try:
        size = tuple(int(v) for v in size)
    except (TypeError, ValueError):
        raise DataError(path, "size", size, "must be (width, height) in pixels") from None
    if len(size) != 2 or min(size) < 64 or max(size) > 4096:
        raise DataError(path, "size", size, "must be (width, height), each 64 to 4096 pixels")
    try:
        fps = float(fps)
    except (TypeError, ValueError):
        raise DataError(path, "fps", fps, "not a number") from None
    if not (np.isfinite(fps) and 0 < fps <= 120):
        raise DataError(path, "fps", fps, "must be a number of frames per second in (0, 120]")
    exe = None
    if ext == ".mp4":
        exe = find_ffmpeg()
        if exe is None:
            raise DataError(
                path,
                "extension",
                ".mp4",
                "writing .mp4 needs ffmpeg, which was not found",
                'install ffmpeg or pip install "dam[video]", or write .gif or .html',
            )
    model = (metadata or {}).get("model")
    first = label or (model if isinstance(model, str) else "controls")
    n = frame_count(len(values) / frame_rate, fps)
    times, main = articulator_outlines(
        values, channels, frame_rate, fps=fps, n_points=n_points, n_frames=n, source=path
    )
    views = [(first, main)]
    for k, (name, other) in enumerate(compare or []):
        other, _, _ = check_animation(other, channels, frame_rate, f"{path} (view {name!r})")
        if abs(len(other) - len(values)) > 1:
            raise DataError(
                path,
                f"compare[{k}] ({name})",
                len(other),
                f"has a different number of frames than the animation ({len(values)})",
            )
        views.append(
            (
                str(name),
                articulator_outlines(other, channels, frame_rate, fps=fps, n_points=n_points, n_frames=n, source=path)[
                    1
                ],
            )
        )
    title = "Midsagittal vocal tract (VocalTractLab)" + (
        ": " + " | ".join(v[0] for v in views) if len(views) > 1 else f", {first}"
    )
    r = ArticulatorRenderer(views, times, alignment=alignment, title=title, size=size, n_points=n_points)
    try:
        frames = [r.image(k) for k in range(n)]
    finally:
        r.close()
    if ext == ".gif":
        _write_gif(frames, path, fps)
    elif ext == ".mp4":
        _write_mp4(frames, path, fps, exe)
    else:
        _write_html(frames, path, fps, title)
    notes = [
        f"{n} pictures of {r.size[0]}x{r.size[1]} at {fps:g} frames/s"
        + (f", {len(views)} views side by side" if len(views) > 1 else "")
    ]
    if ext == ".gif" and abs(round(100 / fps) - 100 / fps) > 1e-9:
        notes.append(
            f"GIF delays are whole centiseconds: {fps:g} frames/s plays at {100 / round(100 / fps):.3g} frames/s"
        )
    return ExportReport(
        path=path, format=ext.lstrip("."), n_frames=n, n_channels=len(channels), frame_rate=fps, notes=notes
    )
