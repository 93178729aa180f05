"""Fit and predict time and memory of every classical model against the length of ONE utterance.

A lab's recording is often one long take. This benchmark joins synthetic
phrases (:func:`bench_dam.corpus_of`, 40 phones, 2 channels at 100 frames/s)
into a single utterance of 1, 2, 5 and 10 minutes, fits each classical model
on it and predicts it back, and writes ``benchmarks/results/length.json`` and
``length.md``: seconds and peak memory of fit and of predict. Each fit runs in
a forked child process (imports already loaded) whose peak resident memory
is reset before the fit and read after it (``/proc/self/clear_refs``,
``VmHWM``), so memory is measured without slowing the run down. Linear cost
shows as time and memory doubling from 5 to 10 minutes (not quadrupling).

    python benchmarks/bench_length.py [--minutes 1 2 5 10] [--models dam cohen-massaro mmm phone-mean]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
import warnings
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _machine import machine  # noqa: E402
from bench_dam import corpus_of  # noqa: E402

import dam  # noqa: E402
from dam.corpus.data import Alignment, Corpus, Utterance  # noqa: E402

MODELS = ["dam", "dam-paper", "dam-m0", "cohen-massaro", "mmm", "phone-mean"]
N_CH = 2


def one_utterance(minutes: float) -> Corpus:
    """The phrases of ``corpus_of(minutes)`` joined end to end into one utterance."""
    phrases = corpus_of(minutes).select_channels(["c0", "c1"])
    labels, starts, ends, ys, t0 = [], [], [], [], 0
    for u in phrases:
        a = u.alignment
        keep = np.arange(len(a))
        labels += [a.labels[i] for i in keep]
        starts += list(a.starts + t0 / u.frame_rate)
        ends += list(a.ends + t0 / u.frame_rate)
        ys.append(u.trajectory)
        t0 += u.n_frames
    ends[-1] = (t0 - 1) / phrases.frame_rate
    y = np.concatenate(ys)
    a = Alignment(labels, starts, ends, source=f"one{minutes}")
    return Corpus([Utterance(a, y, phrases.frame_rate, ["c0", "c1"], name=f"one{minutes}")])


def _status_kib(field: str) -> int:
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith(field + ":"):
                return int(line.split()[1])
    raise RuntimeError(f"no {field} in /proc/self/status")


def measure(fn):
    """(result, seconds, peak MiB above the resident memory before the call)."""
    with open("/proc/self/clear_refs", "w") as f:  # resets the peak (VmHWM) to the current RSS
        f.write("5")
    base = _status_kib("VmRSS")
    t0 = time.perf_counter()
    out = fn()
    dt = time.perf_counter() - t0
    return out, dt, max(_status_kib("VmHWM") - base, 0) / 1024


def _fit_child(name, corpus, path, queue):
    model = dam.make(name)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        _, fit_s, fit_mb = measure(lambda: model.fit(corpus))
    model.save(path)
    queue.put((fit_s, fit_mb))


def _predict_child(path, corpus, queue):
    u = corpus[0]
    model = dam.load(path)
    pred, pred_s, pred_mb = measure(lambda: model.predict(u.alignment))
    queue.put((pred_s, pred_mb, float(np.sqrt(np.mean((pred - u.trajectory) ** 2)))))


def _in_child(target, *args):
    import multiprocessing as mp

    ctx = mp.get_context("fork")
    queue = ctx.Queue()
    proc = ctx.Process(target=target, args=(*args, queue))
    proc.start()
    out = queue.get()
    proc.join()
    return out


def run_isolated(name, corpus):
    """Fit ``name`` on ``corpus`` in one forked child and predict with the saved model in another
    (so neither reuses memory the other freed): (fit s, fit MiB, predict s, predict MiB, rmse)."""
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "model.dam")
        fit_s, fit_mb = _in_child(_fit_child, name, corpus, path)
        return (fit_s, fit_mb, *_in_child(_predict_child, path, corpus))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--minutes", type=float, nargs="+", default=[1, 2, 5, 10])
    ap.add_argument("--models", nargs="+", default=MODELS)
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"))
    args = ap.parse_args(argv)
    rows = []
    warm = corpus_of(0.3).select_channels(["c0", "c1"])
    with warnings.catch_warnings():  # imports (scipy, scikit-learn) out of the measured runs
        warnings.simplefilter("ignore")
        for name in args.models:
            dam.make(name).fit(warm).predict(warm[0].alignment)
    for minutes in args.minutes:
        corpus = one_utterance(minutes)
        u = corpus[0]
        for name in args.models:
            fit_s, fit_mb, pred_s, pred_mb, rmse = run_isolated(name, corpus)
            rows.append(
                {
                    "model": name,
                    "minutes": u.duration / 60,
                    "frames": u.n_frames,
                    "segments": len(u.alignment),
                    "fit_seconds": fit_s,
                    "fit_peak_mib": fit_mb,
                    "predict_seconds": pred_s,
                    "predict_peak_mib": pred_mb,
                    "training_rmse": rmse,
                }
            )
            print(
                f"{name:>14} {minutes:>4} min: fit {fit_s:.1f} s {fit_mb:.0f} MiB, predict {pred_s:.2f} s "
                f"{pred_mb:.0f} MiB",
                file=sys.stderr,
            )
    res = {"machine": machine(), "load_average": os.getloadavg(), "channels": N_CH, "rows": rows}
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "length.json").write_text(json.dumps(res, indent=2))
    m = res["machine"]
    lines = [
        "# Cost against the length of one utterance",
        "",
        f"{m['date']}, {m['cpu']}, {m['cores']} cores (shared; load average {res['load_average'][0]:.1f}). "
        f"Synthetic phrases joined into one utterance, {N_CH} channels at 100 frames/s; peak resident "
        "memory above the process's before the call (a forked child for the fit, another for predict with the saved model), time in the same run.",
        "",
        "| model | minutes | frames | segments | fit s | fit peak MiB | predict s | predict peak MiB |",
        "|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in sorted(rows, key=lambda r: (r["model"], r["minutes"])):
        lines.append(
            f"| {r['model']} | {r['minutes']:.1f} | {r['frames']} | {r['segments']} | "
            f"{r['fit_seconds']:.2f} | {r['fit_peak_mib']:.1f} | {r['predict_seconds']:.3f} | "
            f"{r['predict_peak_mib']:.1f} |"
        )
    (out / "length.md").write_text("\n".join(lines) + "\n")
    print(f"wrote {out / 'length.md'}", file=sys.stderr)


if __name__ == "__main__":
    main()
