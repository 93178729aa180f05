"""Articulators that move: how long ``dam animate -o out.gif`` takes to draw a 3-second utterance.

Writes ``benchmarks/results/articulators.json`` and ``articulators.md``, and the README's picture
``benchmarks/results/articulators_frame.png`` (one frame: the default DAM beside the recording).

For the held-out vtl utterances closest to 3.0 s (the default DAM's prediction, 19 VocalTractLab
tract parameters at 100 Hz), at 25 pictures/s and 640x400 pixels, one view and two views
(prediction beside the recording): seconds of wall and CPU time for

* the outlines (VocalTractLab's ``vtlGetOutlines`` per picture and view),
* drawing the pictures (matplotlib, blitting only what moves),
* writing ``.gif``, ``.html`` and ``.mp4`` (whole call of :func:`dam.export.export`).

    python benchmarks/bench_articulators.py [--repeat 3]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import machine  # noqa: E402

import dam  # noqa: E402
from dam.export import export  # noqa: E402
from dam.export.articulators import ArticulatorRenderer, articulator_outlines  # noqa: E402
from dam.speech import load_default_model  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results"
FPS, SIZE, SECONDS = 25.0, (640, 400), 3.0


def timed(fn, *args, **kw):
    w, c = time.perf_counter(), time.process_time()
    out = fn(*args, **kw)
    return out, time.perf_counter() - w, time.process_time() - c


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3, help="utterances to time (default 3)")
    args = ap.parse_args(argv)
    test = dam.datasets.load("vtl", "test")
    model = load_default_model()
    # whole utterances of about 3 s (an alignment cannot be cut without cutting a phone)
    utts = sorted(test, key=lambda u: abs(u.duration - SECONDS))[: args.repeat]
    rows = []
    with tempfile.TemporaryDirectory() as d:
        for u in utts:
            pred = model.predict(u.alignment)
            truth = u.trajectory[: len(pred)]
            (times, outl), w_out, c_out = timed(articulator_outlines, pred, model.channels_, 100.0, fps=FPS)
            r = ArticulatorRenderer([("dam", outl)], times, alignment=u.alignment, size=SIZE)
            _, w_draw, c_draw = timed(list, map(r.image, range(len(r))))
            r.close()
            row = {
                "utterance": u.name,
                "duration_s": len(pred) / 100.0,
                "pictures": len(times),
                "outlines_s": w_out,
                "outlines_cpu_s": c_out,
                "draw_s": w_draw,
                "draw_cpu_s": c_draw,
            }
            for ext in ("gif", "html", "mp4"):
                _, w, c = timed(
                    export,
                    pred,
                    f"{d}/a.{ext}",
                    channels=model.channels_,
                    frame_rate=100.0,
                    alignment=u.alignment,
                    fps=FPS,
                    size=SIZE,
                )
                row[f"{ext}_s"], row[f"{ext}_cpu_s"] = w, c
            _, w, c = timed(
                export,
                pred,
                f"{d}/b.gif",
                channels=model.channels_,
                frame_rate=100.0,
                alignment=u.alignment,
                fps=FPS,
                size=SIZE,
                compare=[("recorded", truth)],
                metadata={"model": "default DAM"},
            )
            row["gif_two_views_s"], row["gif_two_views_cpu_s"] = w, c
            rows.append(row)
            print(json.dumps(row), flush=True)
    # the README's frame: prediction beside the recording, half-way through the first utterance
    u = utts[0]
    pred = model.predict(u.alignment)
    times, a = articulator_outlines(pred, model.channels_, 100.0, fps=FPS)
    _, b = articulator_outlines(u.trajectory[: len(pred)], model.channels_, 100.0, fps=FPS, n_frames=len(times))
    r = ArticulatorRenderer(
        [("default DAM (predicted)", a), ("VocalTractLab (recorded)", b)],
        times,
        alignment=u.alignment,
        size=(640, 330),
        title=f"dam animate: held-out vtl utterance {u.name}",
    )
    from PIL import Image

    frame = Image.fromarray(r.image(len(r) // 2)).quantize(colors=64)
    frame.save(RESULTS / "articulators_frame.png", optimize=True)
    r.close()
    med = {k: float(np.median([r_[k] for r_ in rows])) for k in rows[0] if k not in ("utterance",)}
    out = {
        "machine": machine(),
        "load": os.getloadavg()[0],
        "fps": FPS,
        "size": SIZE,
        "seconds": SECONDS,
        "rows": rows,
        "median": med,
    }
    (RESULTS / "articulators.json").write_text(json.dumps(out, indent=1))
    md = [
        f"# Articulators that move: a {SECONDS:g}-second utterance at {FPS:g} pictures/s, {SIZE[0]}x{SIZE[1]}",
        "",
        f"Machine: {out['machine']['cpu']}, {out['machine']['cores']} cores, "
        f"{out['machine']['date']}, load average {out['load']:.1f} (wall time grows with it, CPU time "
        f"hardly). Median of {len(rows)} held-out vtl utterances "
        "(wall seconds; CPU seconds of this process in brackets; ffmpeg's own CPU not counted).",
        "",
        "| step | seconds |",
        "| --- | --- |",
    ]
    for label, key in [
        ("outlines (VocalTractLab), one view", "outlines_s"),
        ("drawing, one view", "draw_s"),
        (".gif, one view (whole export)", "gif_s"),
        (".html, one view", "html_s"),
        (".mp4, one view", "mp4_s"),
        (".gif, prediction beside the recording", "gif_two_views_s"),
    ]:
        md.append(f"| {label} | {med[key]:.2f} ({med[key.replace('_s', '_cpu_s')]:.2f}) |")
    (RESULTS / "articulators.md").write_text("\n".join(md) + "\n")
    print("\n".join(md))
    return 0


if __name__ == "__main__":
    sys.exit(main())
