"""What generating a VocalTractLab corpus costs, step by step.

VTL's segment-to-gesture step times every oral closure (plosives, nasals,
affricates) by searching the gesture boundaries that put the closure exactly
on the segment, and its audio is a time-domain acoustic simulation; both
dominate the cost of ``dam.datasets.vtl``. This measures, on one CPU:

* the gestural score of a phrase without closures (the reference),
* the extra cost of each closure,
* the tract sequence (19 parameters at 400.9 Hz) per second of speech,
* audio synthesis per second of speech (x real time),

as CPU seconds (``time.process_time``: the machine is shared, wall time is
not the cost) with medians over repeats, and writes
``benchmarks/results/vtl.json`` and ``vtl.md``.

    python benchmarks/bench_vtl.py [--repeat 3]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _machine import machine  # noqa: E402

from dam.datasets.vtl import PhrasePlan, import_vtl, segment_file_text  # noqa: E402


def cpu_median(fn, repeat: int) -> float:
    """Median CPU seconds of one call of ``fn``."""
    out = []
    for _ in range(repeat):
        t0 = time.process_time()
        fn()
        out.append(time.process_time() - t0)
    return statistics.median(out)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"))
    args = ap.parse_args(argv)
    vtl = import_vtl()

    # Two phrases of the same length: vowels, fricatives and /l/ only, and the
    # same with four of the segments turned into closures (m, t, k, b).
    plain = [
        ("", 0.15),
        ("a", 0.12),
        ("l", 0.08),
        ("a:", 0.15),
        ("z", 0.09),
        ("@", 0.08),
        ("f", 0.1),
        ("i:", 0.14),
        ("l", 0.08),
        ("E", 0.1),
        ("S", 0.1),
        ("a", 0.14),
        ("", 0.15),
    ]
    closed = list(plain)
    for k, sym in zip((2, 4, 6, 10), ("m", "t", "k", "b")):
        closed[k] = (sym, closed[k][1])
    n_closures = 4
    seconds = sum(d for _, d in plain)
    with tempfile.TemporaryDirectory() as tmp:

        def files(name, segs):
            seg, ges = os.path.join(tmp, f"{name}.seg"), os.path.join(tmp, f"{name}.ges")
            labels, durations = zip(*segs)
            with open(seg, "w", encoding="utf-8") as fh:
                fh.write(segment_file_text(PhrasePlan(name, (), labels, durations, (), 1.0, False)))
            return seg, ges

        seg_p, ges_p = files("plain", plain)
        seg_c, ges_c = files("closed", closed)
        t_plain = cpu_median(lambda: vtl.phoneme_file_to_gesture_file(seg_p, ges_p), args.repeat)
        t_closed = cpu_median(lambda: vtl.phoneme_file_to_gesture_file(seg_c, ges_c), args.repeat)
        trk = os.path.join(tmp, "c.tract")
        t_tract = cpu_median(lambda: vtl.gesture_file_to_motor_file(ges_c, trk), args.repeat)
        t_audio = cpu_median(lambda: vtl.gesture_file_to_audio(ges_c), max(1, args.repeat - 1))
    per_closure = (t_closed - t_plain) / n_closures
    res = {
        "machine": machine(),
        "vtl": vtl.get_version(),
        "phrase_seconds": seconds,
        "gestural_score_without_closures_cpu_s": t_plain,
        "gestural_score_with_4_closures_cpu_s": t_closed,
        "cpu_s_per_closure": per_closure,
        "closure_cost_ratio_to_plain_score": per_closure / t_plain if t_plain > 0 else None,
        "tract_sequence_cpu_s_per_speech_s": t_tract / seconds,
        "audio_cpu_s_per_speech_s": t_audio / seconds,
    }
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "vtl.json").write_text(json.dumps(res, indent=2) + "\n")
    m = res["machine"]
    md = (
        "| step | CPU seconds (median) | ratio to the plain gestural score |\n|---|---|---|\n"
        f"| gestural score, {seconds:.2f} s phrase without closures | {t_plain:.4f} | 1 |\n"
        f"| each oral closure (p b t d k g m n N ts pf tS dZ) | {per_closure:.3f} | "
        f"{res['closure_cost_ratio_to_plain_score'] or float('nan'):.0f} |\n"
        f"| tract sequence, per second of speech | {t_tract / seconds:.4f} | "
        f"{t_tract / seconds / t_plain if t_plain else float('nan'):.1f} |\n"
        f"| audio, per second of speech | {t_audio / seconds:.2f} | "
        f"{t_audio / seconds / t_plain if t_plain else float('nan'):.0f} |\n\n"
        f"VTL {res['vtl']}. Machine: {m['cpu']}, {m['cores']} cores, {m['date']}.\n"
    )
    (out / "vtl.md").write_text(md)
    print(md)


if __name__ == "__main__":
    main()
