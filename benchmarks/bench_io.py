"""How long loading a corpus directory of a few hundred utterances takes.

Writes ``benchmarks/results/io.json`` and ``io.md``. The reference measured in
the same run is reading the same CSV files with ``numpy.loadtxt`` alone, so
the ratio says what the TextGrid parsing and validation cost on top.

    python benchmarks/bench_io.py [--utterances 300]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import machine, median_time  # noqa: E402

import dam  # noqa: E402
from dam.corpus.io import load_corpus, save_corpus  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--utterances", type=int, default=300)
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"))
    args = ap.parse_args(argv)
    tiny = dam.datasets.load("tiny")
    utts = [tiny[k % len(tiny)].replace(name=f"u{k:04d}") for k in range(args.utterances)]
    with tempfile.TemporaryDirectory() as d:
        save_corpus(dam.Corpus(utts), d)
        csvs = sorted(Path(d).glob("*.csv"))
        t_load = median_time(lambda: load_corpus(d), repeat=5)
        t_ref = median_time(lambda: [np.loadtxt(p, delimiter=",", skiprows=1) for p in csvs], repeat=5)
        corpus = load_corpus(d)
    res = {
        "machine": machine(),
        "utterances": len(corpus),
        "minutes": corpus.duration / 60,
        "load_corpus_seconds_median": t_load,
        "numpy_loadtxt_seconds_median": t_ref,
        "ratio_to_loadtxt": t_load / t_ref,
    }
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "io.json").write_text(json.dumps(res, indent=2) + "\n")
    md = (
        f"| utterances | minutes | load_corpus (median s) | numpy.loadtxt of the CSVs (s) | ratio |\n"
        f"|---|---|---|---|---|\n| {len(corpus)} | {corpus.duration / 60:.1f} | {t_load:.3f} | {t_ref:.3f} "
        f"| {t_load / t_ref:.2f} |\n\nMachine: {res['machine']['cpu']}, {res['machine']['cores']} cores, "
        f"{res['machine']['date']}\n"
    )
    (out / "io.md").write_text(md)
    print(md)


if __name__ == "__main__":
    main()
