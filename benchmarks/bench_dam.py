"""DAM training and synthesis speed, and training memory, against corpus length.

Writes ``benchmarks/results/dam.json`` and ``dam.md``. The corpora are
synthetic (:mod:`dam.datasets.synthetic`): 40 phones, 4 channels at 100
frames/s, rendered from a known DAM with noise, so the figures do not depend on
a bundled corpus. Reported, with medians and the machine:

* training seconds per channel (the fit on all channels divided by their
  number: mode clustering is shared, the EM runs per channel) for 1, 2, 5, 10
  minutes of speech; the paper needed 50-60 minutes per control for ~10 minutes;
* peak traced memory (tracemalloc) of training on the longest corpus;
* synthesis microseconds per phone for the DAM, Cohen-Massaro, MMM and
  phone-mean in the same run: per utterance (one ``predict`` call per
  utterance of 20-60 phones, what a user does), in one batch (one long
  alignment) and one phone per call; the paper: 0.8 ms per phone. Timings
  are the best of several repeats (as ``timeit`` reports them: the machine is
  shared, and the minimum is the run least disturbed by other work);
* the E-step's normal equations built utterance by utterance (what the DAM
  uses) against a scipy sparse ``X.T @ X``;
* references measured in the same run: a 200x2000 by 2000x200 numpy matmul,
  and the ``phone-mean`` baseline's fit and prediction.

    python benchmarks/bench_dam.py [--minutes 1 2 5 10] [--repeat 3] [--synthesis-only] [--readme]

``--synthesis-only`` fits one model (2 minutes) for the synthesis figures and
keeps the training figures of the previous full run from ``dam.json`` (the
.md says so, with that run's date). ``--readme`` only rewrites the block
between ``<!-- bench_dam:start -->`` and ``<!-- bench_dam:end -->`` in
README.md from ``dam.json`` (so the README quotes the results file, never
numbers typed by hand).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
import tracemalloc
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # small problems; see DAM._fit

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _machine import machine, median_time  # noqa: E402

from baselines.cohen_massaro import CohenMassaro  # noqa: E402
from baselines.mmm import MMM  # noqa: E402
from baselines.reference import PhoneMean  # noqa: E402
from dam.datasets.synthetic import dam_parameters, make_corpus, random_alignment  # noqa: E402
from dam.model.estimator import DAM  # noqa: E402

PHONES = [f"p{i:02d}" for i in range(40)]
N_CH = 4


def corpus_of(minutes: float, seed: int = 0):
    """About ``minutes`` of speech: utterances of 8-16 phones of 60-180 ms."""
    par = dam_parameters(PHONES, N_CH, degree=4, random_state=seed, sigma_range=(0.2, 0.6), scale=0.5)
    true = DAM.from_parameters(
        par, frame_rate=100.0, channels=[f"c{i}" for i in range(N_CH)], basis="legendre", extrapolate="hold"
    )
    n_utt = int(round(minutes * 60 / 1.44))  # 12 phones x 120 ms on average
    return make_corpus(true, n_utterances=n_utt, noise=0.02, random_state=seed, name=f"bench{minutes}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--minutes", type=float, nargs="+", default=[1, 2, 5, 10])
    ap.add_argument("--repeat", type=int, default=3, help="runs per size (the longest gets one)")
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"))
    ap.add_argument(
        "--synthesis-only",
        action="store_true",
        help="measure synthesis only; keep the training figures of the previous run's dam.json",
    )
    ap.add_argument(
        "--readme", action="store_true", help="only rewrite the README's bench_dam block from results/dam.json"
    )
    args = ap.parse_args(argv)
    if args.readme:
        return write_readme_block(Path(args.out) / "dam.json", Path(__file__).resolve().parents[1] / "README.md")
    previous = None
    if args.synthesis_only:
        prev_path = Path(args.out) / "dam.json"
        if not prev_path.exists():
            ap.error(f"--synthesis-only keeps the training figures of {prev_path}, which does not exist")
        previous = json.loads(prev_path.read_text())

    ref_a, ref_b = np.random.default_rng(0).random((2, 2000, 200))
    t_matmul = median_time(lambda: ref_a.T @ ref_b, repeat=7)
    res = {
        "machine": machine(),
        "load_average": os.getloadavg(),
        "phones": len(PHONES),
        "channels": N_CH,
        "frame_rate": 100.0,
        "reference_matmul_seconds": t_matmul,
        "training": [],
        "notes": "seconds are medians; ratios divide by the matmul measured in the same run",
    }
    print(f"reference matmul (2000x200)^T (2000x200): {t_matmul * 1e3:.2f} ms", file=sys.stderr)

    fitted = None
    if previous is not None:
        for k in ("training", "training_peak_memory_mb", "training_peak_memory_minutes", "estep_normal_equations"):
            if k in previous:
                res[k] = previous[k]
        res["training_from"] = previous.get("training_from", previous["machine"]["date"])
        fitted = DAM().fit(corpus_of(2))
    for minutes in [] if previous is not None else args.minutes:
        corpus = corpus_of(minutes)
        reps = 1 if minutes == max(args.minutes) else args.repeat
        times, models = [], []
        for _ in range(reps):
            t0 = time.perf_counter()
            models.append(DAM().fit(corpus))
            times.append(time.perf_counter() - t0)
        m = models[-1]
        t_pm = median_time(lambda: PhoneMean().fit(corpus), repeat=3)
        row = {
            "minutes": corpus.duration / 60,
            "frames": corpus.n_frames,
            "segments": corpus.n_segments,
            "modes": len(m.mode_phone_),
            "fit_seconds_median": float(np.median(times)),
            "fit_seconds_per_channel": float(np.median(times)) / N_CH,
            "em_iterations_per_channel": m.n_iter_.tolist(),
            "runs": reps,
            "phone_mean_fit_seconds": t_pm,
            "ratio_per_channel_to_matmul": float(np.median(times)) / N_CH / t_matmul,
        }
        res["training"].append(row)
        print(
            f"{minutes:>5} min: {row['fit_seconds_per_channel']:.2f} s per channel "
            f"({row['modes']} modes, EM iterations {row['em_iterations_per_channel']})",
            file=sys.stderr,
        )
        if fitted is None or minutes == 2:
            fitted = m
        if minutes == max(args.minutes):
            # peak memory of training (a separate run: tracing slows it down)
            tracemalloc.start()
            DAM().fit(corpus)
            _, peak = tracemalloc.get_traced_memory()
            tracemalloc.stop()
            res["training_peak_memory_mb"] = peak / 2**20
            res["training_peak_memory_minutes"] = corpus.duration / 60
            res["estep_normal_equations"] = _estep_compare(m, corpus)

    res["synthesis"] = _synthesis(fitted)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "dam.json").write_text(json.dumps(res, indent=2))
    (out / "dam.md").write_text(_markdown(res))
    print(f"wrote {out / 'dam.json'} and {out / 'dam.md'}", file=sys.stderr)


def best_time(fn, repeat: int = 7, clock=time.perf_counter) -> float:
    """The best of ``repeat`` runs, in seconds (``timeit``'s convention on a shared machine).

    ``clock=time.process_time`` counts the CPU time of this process only: on a
    machine shared with other jobs, wall time also counts the time the process
    waited for a core."""
    times = []
    for _ in range(repeat):
        t0 = clock()
        fn()
        times.append(clock() - t0)
    return min(times)


def _synthesis(dam_model) -> dict:
    """Per-utterance, batch and one-phone-per-call microseconds per phone, four models, one run."""
    import warnings

    train = corpus_of(1, seed=3)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        models = {
            "dam": dam_model,
            "cohen-massaro": CohenMassaro().fit(train),
            "mmm": MMM().fit(train),
            "phone-mean": PhoneMean().fit(train),
        }
    rng = np.random.default_rng(1)
    utts = [random_alignment(rng, PHONES, n_segments=int(rng.integers(20, 61))) for _ in range(60)]
    n_utt_phones = sum(len(a) for a in utts)
    long = random_alignment(rng, PHONES, n_segments=2000)
    singles = [random_alignment(rng, PHONES, n_segments=1) for _ in range(200)]
    n_single = sum(len(a) for a in singles)
    rows = {}
    for name, m in models.items():
        t_utt = best_time(lambda: [m.predict(a) for a in utts], repeat=5)
        t_batch = best_time(lambda: m.predict(long), repeat=5)
        t_one = best_time(lambda: [m.predict(a) for a in singles], repeat=5)
        cpu = time.process_time
        rows[name] = {
            "per_utterance_us_per_phone": t_utt / n_utt_phones * 1e6,
            "batch_us_per_phone": t_batch / len(long) * 1e6,
            "one_phone_us_per_call": t_one / len(singles) * 1e6,
            "cpu_per_utterance_us_per_phone": best_time(lambda: [m.predict(a) for a in utts], 5, cpu)
            / n_utt_phones
            * 1e6,
            "cpu_batch_us_per_phone": best_time(lambda: m.predict(long), 5, cpu) / len(long) * 1e6,
            "cpu_one_phone_us_per_call": best_time(lambda: [m.predict(a) for a in singles], 5, cpu)
            / len(singles)
            * 1e6,
        }
        print(
            f"{name:>14}: {rows[name]['per_utterance_us_per_phone']:.1f} us/phone per utterance, "
            f"{rows[name]['batch_us_per_phone']:.1f} batch, {rows[name]['one_phone_us_per_call']:.0f} us "
            "per one-phone call",
            file=sys.stderr,
        )
    # what the DAM spends per utterance on mode selection alone (the rest is Eq. 2)
    t_sel = best_time(lambda: [dam_model.select_modes(a) for a in utts], repeat=5)
    # the machine's state: one small numpy call (a few tenths of a microsecond when idle)
    x = np.zeros(8)
    t_call = best_time(lambda: [np.add(x, x) for _ in range(1000)], repeat=5) / 1000
    return {
        "model": repr(dam_model),
        "model_modes": len(dam_model.mode_phone_),
        "utterances": len(utts),
        "utterance_phones": [20, 60],
        "segments_per_utterance_mean": n_utt_phones / len(utts),
        "batch_phones": len(long),
        "one_phone_segments_per_call_mean": n_single / len(singles),
        "dam_selection_us_per_phone": t_sel / n_utt_phones * 1e6,
        "numpy_small_call_us": t_call * 1e6,
        "load_average": os.getloadavg(),
        "models": rows,
        "paper_us_per_phone": 800.0,
        "target_per_utterance_us_per_phone": 20.0,
        "target_one_phone_us": 50.0,
    }


def write_readme_block(results: Path, readme: Path) -> None:
    """Replace the README block between the bench_dam markers with figures from ``results``."""
    r = json.loads(results.read_text())
    start, end = "<!-- bench_dam:start -->", "<!-- bench_dam:end -->"
    text = readme.read_text()
    if start not in text or end not in text:
        raise SystemExit(f"{readme}: no {start} ... {end} block to fill")
    block = "\n".join([start, "", *_synthesis_lines(r), "", *_training_lines(r), "", end])
    head, rest = text.split(start, 1)
    readme.write_text(head + block + rest.split(end, 1)[1])
    print(f"updated {readme}", file=sys.stderr)


def _synthesis_lines(r) -> list:
    s, m = r["synthesis"], r["machine"]
    lines = [
        f"Synthesis, {m['date']} ({m['cpu']}, {m['cores']} cores, shared; best of 5; model `{s['model']}` "
        f"with {s['model_modes']} modes; the paper: 800 µs per phone):",
        "",
        "Wall time, and in parentheses the CPU time of the process (on a shared machine the wall time "
        "also counts waiting for a core):",
        "",
        "| model | per utterance (20-60 phones), µs/phone | batch of 2000, µs/phone | one-phone call, µs |",
        "|---|---:|---:|---:|",
    ]
    for name, row in s["models"].items():
        cpu = lambda k, f: f" ({row[k]:{f}})" if k in row else ""
        lines.append(
            f"| {name} | {row['per_utterance_us_per_phone']:.1f}{cpu('cpu_per_utterance_us_per_phone', '.1f')} | "
            f"{row['batch_us_per_phone']:.1f}{cpu('cpu_batch_us_per_phone', '.1f')} | "
            f"{row['one_phone_us_per_call']:.0f}{cpu('cpu_one_phone_us_per_call', '.0f')} |"
        )
    lines += ["", f"DAM mode selection alone: {s['dam_selection_us_per_phone']:.1f} µs per phone per utterance."]
    if "numpy_small_call_us" in s:
        lines += [
            "",
            f"State of the machine during this run: load average {s['load_average'][0]:.1f} on "
            f"{m['cores']} cores; one small numpy call took {s['numpy_small_call_us']:.2f} µs "
            "(0.3-0.5 µs on an idle machine), the reference matmul "
            f"{r['reference_matmul_seconds'] * 1e3:.1f} ms (5.7 ms idle).",
        ]
    return lines


def _training_lines(r) -> list:
    lines = [
        "DAM training (synthetic corpora, 4 channels; the paper: 50-60 min per control for 10 min):",
        "",
        "| minutes of speech | s per channel |",
        "|---:|---:|",
    ]
    for t in r["training"]:
        lines.append(f"| {t['minutes']:.1f} | {t['fit_seconds_per_channel']:.2f} |")
    return lines


def _estep_compare(model, corpus) -> dict:
    """Normal equations utterance by utterance (used) vs scipy sparse X^T X, one channel's sigmas."""
    from threadpoolctl import threadpool_limits

    from dam.model.estep import Occurrences, design_matrix, normal_equations, pairs

    labels = [u.alignment.labels for u in corpus]
    glob = [np.array([model.phone_modes_[p][0] for p in lab]) for lab in labels]  # first mode of each phone
    occ = Occurrences.from_corpus(corpus, glob, len(model.mode_phone_), degree=model.degree)
    sigma = model.sigma_[:, 0]
    Y = np.concatenate(corpus.trajectories)
    pr = pairs(occ, sigma)
    with threadpool_limits(1):
        t_gram = median_time(lambda: normal_equations(occ, sigma, Y, pr), repeat=3)

        def sparse():
            X = design_matrix(occ, sigma, pr)
            return (X.T @ X).toarray(), X.T @ Y

        t_sparse = median_time(sparse, repeat=3)
    return {
        "pairs": int(len(pr[0])),
        "unknowns": occ.n_coef,
        "per_utterance_seconds": t_gram,
        "scipy_sparse_seconds": t_sparse,
        "speedup": t_sparse / t_gram,
    }


def _markdown(r) -> str:
    m = r["machine"]
    lines = [
        "# DAM benchmark",
        "",
        f"Machine: {m['cpu']}, {m['cores']} cores, Python {m['python']}, numpy {m['numpy']}, "
        f"{m['date']}; load average {r['load_average'][0]:.1f} (shared machine). "
        f"Synthetic corpora: {r['phones']} phones, {r['channels']} channels at 100 frames/s. "
        f"Reference in the same run: a (2000x200)^T(2000x200) matmul took "
        f"{r['reference_matmul_seconds'] * 1e3:.2f} ms.",
        "",
        "## Training (paper: 50-60 min per control for ~10 min of speech; target < 10 s)",
        "",
        *(
            [
                f"Training figures kept from the full run of {r['training_from']} (this run measured "
                "synthesis only: `--synthesis-only`).",
                "",
            ]
            if "training_from" in r
            else []
        ),
        "| minutes | frames | modes | s per channel (median) | EM iterations per channel | runs | phone-mean fit s | per channel / matmul |",
        "|---:|---:|---:|---:|---|---:|---:|---:|",
    ]
    for t in r["training"]:
        lines.append(
            f"| {t['minutes']:.1f} | {t['frames']} | {t['modes']} | {t['fit_seconds_per_channel']:.2f} | "
            f"{t['em_iterations_per_channel']} | {t['runs']} | {t['phone_mean_fit_seconds']:.3f} | "
            f"{t['ratio_per_channel_to_matmul']:.0f} |"
        )
    if "training_peak_memory_mb" in r:
        lines += [
            "",
            f"Peak traced memory of training on {r['training_peak_memory_minutes']:.1f} minutes: "
            f"{r['training_peak_memory_mb']:.0f} MB (tracemalloc).",
        ]
        e = r["estep_normal_equations"]
        lines += [
            "",
            f"E-step normal equations ({e['pairs']} frame/phone pairs, {e['unknowns']} unknowns): "
            f"utterance by utterance {e['per_utterance_seconds'] * 1e3:.0f} ms vs scipy sparse "
            f"X.T @ X {e['scipy_sparse_seconds'] * 1e3:.0f} ms ({e['speedup']:.1f}x).",
        ]
    lines += ["", "## Synthesis", "", *_synthesis_lines(r)]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    main()
