"""What single-byte damage does to a model file: every byte of a fitted DAM file flipped.

Writes ``benchmarks/results/modelfile.json`` and ``modelfile.md``: for each byte of the
file, XOR 0xFF, then ``dam.load`` and predict one utterance. Each outcome is one of
``ModelFileError`` naming the path, identical predictions, different predictions (a silent
misread: must be 0) or another exception (must be 0). Also the time of one ``dam.load``
of the intact file (median), the reference being ``numpy.load`` of the same archive.

    python benchmarks/bench_modelfile.py
"""

from __future__ import annotations

import argparse
import collections
import json
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import machine, median_time  # noqa: E402

import dam  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"))
    args = ap.parse_args(argv)
    train = dam.datasets.load("tiny")[:3]
    alignment = dam.datasets.load("tiny")[0].alignment
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = dam.make("dam", max_iter=2, min_occurrences=1000).fit(train)
    expected = model.predict(alignment)
    outcomes: collections.Counter = collections.Counter()
    others = []
    with tempfile.TemporaryDirectory() as d:
        src, bad = Path(d) / "model.dam", Path(d) / "flipped.dam"
        model.save(src)
        raw = src.read_bytes()
        for i in range(len(raw)):
            b = bytearray(raw)
            b[i] ^= 0xFF
            bad.write_bytes(bytes(b))
            try:
                y = dam.load(bad).predict(alignment)
            except dam.ModelFileError as exc:
                named = str(bad) in str(exc)
                outcomes["ModelFileError naming the path" if named else "ModelFileError, path missing"] += 1
            except Exception as exc:  # must not happen
                outcomes[f"other: {type(exc).__name__}"] += 1
                others.append((i, repr(exc)[:200]))
            else:
                outcomes["identical predictions" if np.array_equal(y, expected) else "DIFFERENT predictions"] += 1
        t_load = median_time(lambda: dam.load(src), repeat=7)
        t_ref = median_time(lambda: dict(np.load(src, allow_pickle=False)), repeat=7)
    res = {
        "machine": machine(),
        "file_bytes": len(raw),
        "outcomes": dict(outcomes),
        "other_examples": others[:10],
        "load_seconds_median": t_load,
        "numpy_load_seconds_median": t_ref,
    }
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "modelfile.json").write_text(json.dumps(res, indent=2) + "\n")
    rows = "\n".join(f"| {k} | {v} |" for k, v in sorted(outcomes.items()))
    md = (
        f"Every byte of a {len(raw)}-byte DAM model file flipped (XOR 0xFF), then loaded and used:\n\n"
        f"| outcome | flips |\n|---|---|\n{rows}\n\n"
        f"`dam.load` of the intact file: {1e3 * t_load:.2f} ms (median); `numpy.load` of the same archive "
        f"{1e3 * t_ref:.2f} ms.\n\nMachine: {res['machine']['cpu']}, {res['machine']['cores']} cores, "
        f"{res['machine']['date']}\n"
    )
    (out / "modelfile.md").write_text(md)
    print(md)


if __name__ == "__main__":
    main()
