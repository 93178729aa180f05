"""DAM training and synthesis speed, and training memory, against corpus length.

Writes ``benchmarks/results/dam.json`` and ``dam.md``. The corpora are
synthetic (:mod:`dam.datasets.synthetic`): 40 phones, 4 channels at 100
frames/s, rendered from a known DAM with noise, so the figures do not depend on
a bundled corpus. Reported, with medians and the machine:

* training seconds per channel (the fit on all channels divided by their
  number: mode clustering is shared, the EM runs per channel) for 1, 2, 5, 10
  minutes of speech; the paper needed 50-60 minutes per control for ~10 minutes;
* peak traced memory (tracemalloc) of training on the longest corpus;
* synthesis microseconds per phone, in one batch (one long alignment) and one
  phone at a time (a one-phone alignment per call); the paper: 0.8 ms per phone;
* the E-step's normal equations built utterance by utterance (what the DAM
  uses) against a scipy sparse ``X.T @ X``;
* references measured in the same run: a 200x2000 by 2000x200 numpy matmul,
  and the ``phone-mean`` baseline's fit and prediction.

    python benchmarks/bench_dam.py [--minutes 1 2 5 10] [--repeat 3] [--synthesis-only]

``--synthesis-only`` fits one model (2 minutes) for the synthesis figures and
keeps the training figures of the previous full run from ``dam.json`` (the
.md says so, with that run's date).
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time
import tracemalloc
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")   # small problems; see DAM._fit

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _machine import machine, median_time  # noqa: E402

from baselines.reference import PhoneMean  # noqa: E402
from dam.corpus.data import Alignment  # noqa: E402
from dam.datasets.synthetic import dam_parameters, make_corpus, random_alignment  # noqa: E402
from dam.model.estimator import DAM  # noqa: E402

PHONES = [f"p{i:02d}" for i in range(40)]
N_CH = 4


def corpus_of(minutes: float, seed: int = 0):
    """About ``minutes`` of speech: utterances of 8-16 phones of 60-180 ms."""
    par = dam_parameters(PHONES, N_CH, degree=4, random_state=seed, sigma_range=(0.2, 0.6), scale=0.5)
    true = DAM.from_parameters(par, frame_rate=100.0, channels=[f"c{i}" for i in range(N_CH)],
                               basis="legendre", extrapolate="hold")
    n_utt = int(round(minutes * 60 / 1.44))       # 12 phones x 120 ms on average
    return make_corpus(true, n_utterances=n_utt, noise=0.02, random_state=seed, name=f"bench{minutes}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--minutes", type=float, nargs="+", default=[1, 2, 5, 10])
    ap.add_argument("--repeat", type=int, default=3, help="runs per size (the longest gets one)")
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"))
    ap.add_argument("--synthesis-only", action="store_true",
                    help="measure synthesis only; keep the training figures of the previous run's dam.json")
    args = ap.parse_args(argv)
    previous = None
    if args.synthesis_only:
        prev_path = Path(args.out) / "dam.json"
        if not prev_path.exists():
            ap.error(f"--synthesis-only keeps the training figures of {prev_path}, which does not exist")
        previous = json.loads(prev_path.read_text())

    ref_a, ref_b = np.random.default_rng(0).random((2, 2000, 200))
    t_matmul = median_time(lambda: ref_a.T @ ref_b, repeat=7)
    res = {"machine": machine(), "load_average": os.getloadavg(), "phones": len(PHONES),
           "channels": N_CH, "frame_rate": 100.0, "reference_matmul_seconds": t_matmul,
           "training": [], "notes": "seconds are medians; ratios divide by the matmul measured in the same run"}
    print(f"reference matmul (2000x200)^T (2000x200): {t_matmul * 1e3:.2f} ms", file=sys.stderr)

    fitted = None
    if previous is not None:
        for k in ("training", "training_peak_memory_mb", "training_peak_memory_minutes", "estep_normal_equations"):
            if k in previous:
                res[k] = previous[k]
        res["training_from"] = previous.get("training_from", previous["machine"]["date"])
        res["synthesis_previous"] = {**previous["synthesis"], "date": previous["machine"]["date"],
                                     "load_average": previous["load_average"]}
        fitted = DAM().fit(corpus_of(2))
    for minutes in ([] if previous is not None else args.minutes):
        corpus = corpus_of(minutes)
        reps = 1 if minutes == max(args.minutes) else args.repeat
        times, models = [], []
        for _ in range(reps):
            t0 = time.perf_counter()
            models.append(DAM().fit(corpus))
            times.append(time.perf_counter() - t0)
        m = models[-1]
        t_pm = median_time(lambda: PhoneMean().fit(corpus), repeat=3)
        row = {"minutes": corpus.duration / 60, "frames": corpus.n_frames, "segments": corpus.n_segments,
               "modes": len(m.mode_phone_), "fit_seconds_median": float(np.median(times)),
               "fit_seconds_per_channel": float(np.median(times)) / N_CH,
               "em_iterations_per_channel": m.n_iter_.tolist(), "runs": reps,
               "phone_mean_fit_seconds": t_pm,
               "ratio_per_channel_to_matmul": float(np.median(times)) / N_CH / t_matmul}
        res["training"].append(row)
        print(f"{minutes:>5} min: {row['fit_seconds_per_channel']:.2f} s per channel "
              f"({row['modes']} modes, EM iterations {row['em_iterations_per_channel']})", file=sys.stderr)
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

    # synthesis: one long alignment (batch) and one phone at a time
    rng = np.random.default_rng(1)
    long = random_alignment(rng, PHONES, n_segments=2000)
    t_batch = median_time(lambda: fitted.predict(long), repeat=7)
    singles = [random_alignment(rng, PHONES, n_segments=1) for _ in range(200)]
    t_single = median_time(lambda: [fitted.predict(a) for a in singles], repeat=5) / len(singles)
    pm = PhoneMean().fit(corpus_of(1))
    t_pm_batch = median_time(lambda: pm.predict(long), repeat=7)
    res["synthesis"] = {
        "model": repr(fitted),
        "batch_phones": len(long), "batch_us_per_phone": t_batch / len(long) * 1e6,
        "one_phone_at_a_time_us_per_call": t_single * 1e6,
        "phone_mean_batch_us_per_phone": t_pm_batch / len(long) * 1e6,
        "ratio_batch_to_phone_mean": t_batch / t_pm_batch,
        "paper_us_per_phone": 800.0, "target_batch_us_per_phone": 20.0,
        "model_modes": len(fitted.mode_phone_)}
    print(f"synthesis: {res['synthesis']['batch_us_per_phone']:.1f} us/phone batch, "
          f"{res['synthesis']['one_phone_at_a_time_us_per_call']:.0f} us per one-phone call", file=sys.stderr)

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "dam.json").write_text(json.dumps(res, indent=2))
    (out / "dam.md").write_text(_markdown(res))
    print(f"wrote {out / 'dam.json'} and {out / 'dam.md'}", file=sys.stderr)


def _estep_compare(model, corpus) -> dict:
    """Normal equations utterance by utterance (used) vs scipy sparse X^T X, one channel's sigmas."""
    from threadpoolctl import threadpool_limits

    from dam.model.estep import Occurrences, design_matrix, normal_equations, pairs

    labels = [u.alignment.labels for u in corpus]
    glob = [np.array([model.phone_modes_[p][0] for p in lab]) for lab in labels]   # first mode of each phone
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
    return {"pairs": int(len(pr[0])), "unknowns": occ.n_coef, "per_utterance_seconds": t_gram,
            "scipy_sparse_seconds": t_sparse, "speedup": t_sparse / t_gram}


def _markdown(r) -> str:
    m = r["machine"]
    lines = ["# DAM benchmark", "",
             f"Machine: {m['cpu']}, {m['cores']} cores, Python {m['python']}, numpy {m['numpy']}, "
             f"{m['date']}; load average {r['load_average'][0]:.1f} (shared machine). "
             f"Synthetic corpora: {r['phones']} phones, {r['channels']} channels at 100 frames/s. "
             f"Reference in the same run: a (2000x200)^T(2000x200) matmul took "
             f"{r['reference_matmul_seconds'] * 1e3:.2f} ms.", "",
             "## Training (paper: 50-60 min per control for ~10 min of speech; target < 10 s)", "",
             *([f"Training figures kept from the full run of {r['training_from']} (this run measured "
                "synthesis only: `--synthesis-only`).", ""] if "training_from" in r else []),
             "| minutes | frames | modes | s per channel (median) | EM iterations per channel | runs | phone-mean fit s | per channel / matmul |",
             "|---:|---:|---:|---:|---|---:|---:|---:|"]
    for t in r["training"]:
        lines.append(f"| {t['minutes']:.1f} | {t['frames']} | {t['modes']} | {t['fit_seconds_per_channel']:.2f} | "
                     f"{t['em_iterations_per_channel']} | {t['runs']} | {t['phone_mean_fit_seconds']:.3f} | "
                     f"{t['ratio_per_channel_to_matmul']:.0f} |")
    if "training_peak_memory_mb" in r:
        lines += ["", f"Peak traced memory of training on {r['training_peak_memory_minutes']:.1f} minutes: "
                      f"{r['training_peak_memory_mb']:.0f} MB (tracemalloc)."]
        e = r["estep_normal_equations"]
        lines += ["", f"E-step normal equations ({e['pairs']} frame/phone pairs, {e['unknowns']} unknowns): "
                      f"utterance by utterance {e['per_utterance_seconds'] * 1e3:.0f} ms vs scipy sparse "
                      f"X.T @ X {e['scipy_sparse_seconds'] * 1e3:.0f} ms ({e['speedup']:.1f}x)."]
    s = r["synthesis"]
    lines += ["", "## Synthesis (paper: 800 us per phone; target < 20 us per phone in batch)", "",
              "| | us per phone |", "|---|---:|",
              f"| DAM, batch of {s['batch_phones']} phones (A* + Eq. 2) | {s['batch_us_per_phone']:.1f} |",
              f"| DAM, one phone per call | {s['one_phone_at_a_time_us_per_call']:.0f} |",
              f"| phone-mean, same batch | {s['phone_mean_batch_us_per_phone']:.1f} |",
              "", f"DAM batch / phone-mean batch: {s['ratio_batch_to_phone_mean']:.1f}x "
                  f"(model `{s.get('model', 'DAM()')}` with {s['model_modes']} modes, fitted on 2 minutes)."]
    if "synthesis_previous" in r:
        p = r["synthesis_previous"]
        lines += ["", f"Previous run ({p['date']}, load average {p['load_average'][0]:.1f}, model "
                      f"`{p.get('model', 'DAM(normalize=False)')}`): {p['batch_us_per_phone']:.1f} us per phone in batch, "
                      f"{p['one_phone_at_a_time_us_per_call']:.0f} us per one-phone call, "
                      f"{p['ratio_batch_to_phone_mean']:.1f}x phone-mean."]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    main()
