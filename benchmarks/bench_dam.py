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
  are medians of several runs, in wall time and in the process's CPU time (the
  machine is shared: wall time also counts waiting for a core);
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
REPEAT = 9  # runs per synthesis figure (the median is reported)


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
        # Cohen-Massaro on the same corpus (issue 11: its fit no slower than the DAM's)
        cm_times = []
        for _ in range(reps):
            t0 = time.perf_counter()
            cm = CohenMassaro().fit(corpus)
            cm_times.append(time.perf_counter() - t0)
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
            "cohen_massaro_fit_seconds_per_channel": float(np.median(cm_times)) / N_CH,
            "cohen_massaro_evaluations_per_channel": cm.n_fev_.tolist(),
        }
        res["training"].append(row)
        print(
            f"{minutes:>5} min: {row['fit_seconds_per_channel']:.2f} s per channel "
            f"({row['modes']} modes, EM iterations {row['em_iterations_per_channel']}); Cohen-Massaro "
            f"{row['cohen_massaro_fit_seconds_per_channel']:.2f} s per channel",
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


def _synthesis(dam_model) -> dict:
    """Per-utterance, batch and one-phone-per-call microseconds per phone, four models, one run.

    Medians of ``REPEAT`` runs (each run calls ``predict`` on all 60 utterances, the
    2000-phone alignment once, or all 200 one-phone alignments), in wall time and in
    this process's CPU time. For the DAM also ``synthesize`` alone (mode selection
    plus Eq. 2, the issue's measure: ``predict`` adds the input checks every model
    shares) and selection alone.
    """
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
    cpu = time.process_time

    def figures(per_utt, batch, one) -> dict:
        """Wall and CPU medians of the three workloads, µs per phone (per call for one phone)."""
        out = {}
        for clock, prefix in ((time.perf_counter, ""), (cpu, "cpu_")):
            out[prefix + "per_utterance_us_per_phone"] = (
                median_time(lambda: [per_utt(a) for a in utts], REPEAT, clock=clock) / n_utt_phones * 1e6
            )
            if batch is not None:
                out[prefix + "batch_us_per_phone"] = (
                    median_time(lambda: batch(long), REPEAT, clock=clock) / len(long) * 1e6
                )
            out[prefix + "one_phone_us_per_call"] = (
                median_time(lambda: [one(a) for a in singles], REPEAT, clock=clock) / len(singles) * 1e6
            )
        return out

    rows = {}
    for name, m in models.items():
        rows[name] = figures(m.predict, m.predict, m.predict)
        print(
            f"{name:>14}: {rows[name]['per_utterance_us_per_phone']:.1f} us/phone per utterance, "
            f"{rows[name]['batch_us_per_phone']:.1f} batch, {rows[name]['one_phone_us_per_call']:.0f} us "
            "per one-phone call",
            file=sys.stderr,
        )
    # the DAM's mode selection plus Eq. (2) without predict's input checks, and selection alone
    synth = figures(dam_model.synthesize, dam_model.synthesize, dam_model.synthesize)
    select = figures(dam_model.select_modes, None, dam_model.select_modes)
    # the machine's state: one small numpy call (a few tenths of a microsecond when idle)
    x = np.zeros(8)
    t_call = median_time(lambda: [np.add(x, x) for _ in range(1000)], REPEAT) / 1000
    return {
        "model": repr(dam_model),
        "model_modes": len(dam_model.mode_phone_),
        "utterances": len(utts),
        "utterance_phones": [20, 60],
        "segments_per_utterance_mean": n_utt_phones / len(utts),
        "batch_phones": len(long),
        "one_phone_calls": len(singles),
        "repeats": REPEAT,
        "dam_synthesize": synth,
        "dam_selection": select,
        "dam_selection_us_per_phone": select["per_utterance_us_per_phone"],
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
    if "repeats" not in s:  # results of an older run (best of 5)
        raise SystemExit("dam.json predates median synthesis figures: re-run benchmarks/bench_dam.py")
    lines = [
        f"Synthesis, {m['date']} ({m['cpu']}, {m['cores']} cores, shared; median of {s['repeats']} runs; "
        f"model `{s['model']}` with {s['model_modes']} modes; the paper: 800 µs per phone). "
        f"Per utterance: one `predict` call for each of {s['utterances']} utterances of 20-60 phones; "
        f"batch: one call on {s['batch_phones']} phones; one phone: one call for each of "
        f"{s['one_phone_calls']} one-phone alignments.",
        "",
        "Wall time, and in parentheses the CPU time of the process (on a shared machine the wall time "
        "also counts waiting for a core):",
        "",
        "| model | per utterance (20-60 phones), µs/phone | batch of 2000, µs/phone | one-phone call, µs |",
        "|---|---:|---:|---:|",
    ]

    def row(name, f) -> str:
        cells = []
        for k, fmt in (
            ("per_utterance_us_per_phone", ".1f"),
            ("batch_us_per_phone", ".1f"),
            ("one_phone_us_per_call", ".0f"),
        ):
            cells.append(f"{f[k]:{fmt}} ({f['cpu_' + k]:{fmt}})" if k in f else "")
        return f"| {name} | " + " | ".join(cells) + " |"

    for name, f in s["models"].items():
        lines.append(row(name, f))
    lines.append(row("dam: selection + Eq. (2) (`synthesize`)", s["dam_synthesize"]))
    lines.append(row("dam: selection alone (`select_modes`)", s["dam_selection"]))
    lines += [
        "",
        f"Targets (issue 11): selection plus Eq. (2) at most {s['target_per_utterance_us_per_phone']:.0f} µs "
        f"per phone per utterance and {s['target_one_phone_us']:.0f} µs for a one-phone call. "
        "`predict` adds what every model's `predict` checks (the input's type, the output's size, shape and finiteness).",
        "",
        f"State of the machine during this run: load average {s['load_average'][0]:.1f} on "
        f"{m['cores']} cores; one small numpy call took {s['numpy_small_call_us']:.2f} µs "
        "(0.3-0.5 µs on an idle machine), the reference matmul "
        f"{r['reference_matmul_seconds'] * 1e3:.1f} ms.",
    ]
    return lines


def _training_lines(r) -> list:
    lines = [
        f"Training, {r.get('training_from', r['machine']['date'])} (synthetic corpora, 4 channels, median "
        "seconds per channel; the paper: 50-60 min per control for 10 min; Cohen-Massaro in the same run):",
        "",
        "| minutes of speech | DAM s per channel | Cohen-Massaro s per channel |",
        "|---:|---:|---:|",
    ]
    for t in r["training"]:
        cm = t.get("cohen_massaro_fit_seconds_per_channel")
        lines.append(
            f"| {t['minutes']:.1f} | {t['fit_seconds_per_channel']:.2f} | {'' if cm is None else f'{cm:.2f}'} |"
        )
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
        "| minutes | frames | modes | DAM s per channel (median) | EM iterations per channel | runs | "
        "Cohen-Massaro s per channel | CM / DAM | phone-mean fit s | DAM per channel / matmul |",
        "|---:|---:|---:|---:|---|---:|---:|---:|---:|---:|",
    ]
    for t in r["training"]:
        cm = t.get("cohen_massaro_fit_seconds_per_channel")
        lines.append(
            f"| {t['minutes']:.1f} | {t['frames']} | {t['modes']} | {t['fit_seconds_per_channel']:.2f} | "
            f"{t['em_iterations_per_channel']} | {t['runs']} | "
            + (f"{cm:.2f} | {cm / t['fit_seconds_per_channel']:.2f} | " if cm is not None else "| | ")
            + f"{t['phone_mean_fit_seconds']:.3f} | {t['ratio_per_channel_to_matmul']:.0f} |"
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
