"""Fill the README's generated blocks from the benchmark results: README numbers are never typed.

A block in README.md looks like::

    <!-- generated:NAME (benchmarks/update_readme.py; do not edit by hand) -->
    ...
    <!-- /generated:NAME -->

and :data:`BLOCKS` says how NAME is rendered from ``benchmarks/results/*.json``. Run after a
benchmark::

    python benchmarks/update_readme.py            # rewrite the blocks
    python benchmarks/update_readme.py --check    # exit 1 naming every block that differs

``tests/test_readme.py`` runs the check, so a README that disagrees with its results files fails.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
README = ROOT / "README.md"
BLOCK = re.compile(r"(<!-- generated:(?P<name>[\w-]+)[^>]*-->\n)(?P<body>.*?)(<!-- /generated:(?P=name) -->)", re.S)


def _load(name: str) -> dict:
    return json.loads((RESULTS / name).read_text(encoding="utf-8"))


def _g(x, digits: int = 4) -> str:
    return f"{x:.{digits}g}"


def _p(p) -> str:
    return "" if p in ("", None) else (f"{p:.2g}" if p >= 1e-4 else f"{p:.1e}")


def _compare_table(rows, best) -> list[str]:
    out = [
        "| model | RMSE | 95% CI | Pearson r | fit s | µs/phone | frames/s | p vs best (Holm) |",
        "|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        if r["status"] != "ok":
            out.append(f"| {r['model']} | {r['status']}: {r['reason']} | | | | | | |")
            continue
        p = "best" if r["model"] == best else _p(r["wilcoxon_p_holm"])
        out.append(
            f"| {r['model']} | {_g(r['rmse'])} | {_g(r['rmse_ci_low'])}–{_g(r['rmse_ci_high'])} | "
            f"{r['pearson_r']:.3f} | {r['fit_seconds']:.2f} | {r['predict_us_per_phone']:.1f} | "
            f"{r['frames_per_second']:.3g} | {p} |"
        )
    return out


def render_demo() -> str:
    """`dam demo`'s table, from results/compare_demo.json (benchmarks/bench_compare.py demo)."""
    d = _load("compare_demo.json")
    m = d["machine"]
    n_test = max(r["n_utterances"] or 0 for r in d["summary"] if r["status"] == "ok")
    lines = [
        f"What it prints (`benchmarks/results/compare_demo.md`, `python benchmarks/bench_compare.py demo`: "
        f"{m['date']}, {m['cpu']}, {d['train_utterances']} training utterances ({d['train_minutes']} min), "
        f"channels {', '.join(d['channels'])}). The run took {d['cpu_seconds']:.0f} CPU seconds, so about "
        f"{d['two_idle_cores_seconds']:.0f} s on two idle cores (the tasks as joblib's two workers would "
        f"share them); it was measured on a machine shared with other jobs (load average "
        f"{d['load_average_start'][0]:.1f}), which is why the fit seconds below are longer:",
        "",
    ]
    lines += _compare_table(d["summary"], d["best"])
    ok = [r for r in d["summary"] if r["status"] == "ok"]
    rank = {r["model"]: k for k, r in enumerate(ok, start=1)}
    said = f"Held out: the {n_test} test utterances of `vtl` (words never seen in training). Best: `{d['best']}`"
    if "dam" in rank and d["best"] != "dam":
        dam_row = next(r for r in ok if r["model"] == "dam")
        said += (
            f"; the DAM ranks {rank['dam']} of {len(ok)} (Holm-corrected p = {_p(dam_row['wilcoxon_p_holm'])} "
            "against the best)"
        )
    lines += ["", said + "."]
    return "\n".join(lines) + "\n"


#: nn.json row -> how the README names it (the settings that differ from the defaults are said)
NN_LABELS = {
    "lstm": "lstm (bidirectional)",
    "bi-gru-5L": "gru, 5 layers, bidirectional, hidden 32, ≤ 20 epochs",
    "transformer": "transformer",
    "sliding-dnn": "sliding-dnn",
    "causal-mlp": "causal-mlp",
    "gru": "gru (causal, 2 layers)",
    "gru-1L": "gru (causal, 1 layer)",
    "sliding-dnn-linguistic": "sliding-dnn, linguistic features",
}


def render_all_models() -> str:
    """Every model on all 19 channels of vtl: networks from results/nn.json, classical models from
    results/compare_vtl_all.json when it exists, else the DAM rows of results/dam_accuracy_vtl.json."""
    nn = _load("nn.json")
    rows = []
    for r in nn["rows"]:
        if r["model"] == "phone-mean":
            continue
        rows.append(
            (
                NN_LABELS.get(r["model"], r["model"]),
                r["rmse"],
                f"{r['pearson_r']:.3f}",
                f"{r['fit_seconds']:.0f}",
                f"{r['frames_per_second']:,.0f} frames/s",
                "nn.json",
            )
        )
    classical = RESULTS / "compare_vtl_all.json"
    if classical.exists():
        c = _load("compare_vtl_all.json")
        for r in c["summary"]:
            if r["status"] == "ok":
                rows.append(
                    (
                        r["model"],
                        r["rmse"],
                        f"{r['pearson_r']:.3f}",
                        f"{r['fit_seconds']:.0f}",
                        f"{r['predict_us_per_phone']:.0f} µs/phone",
                        "compare_vtl_all.json",
                    )
                )
    else:
        acc = _load("dam_accuracy_vtl.json")["models"]
        for key in ("phone-mean", "dam", "dam-m0"):
            r = acc[key]
            rows.append(
                (key, r["rmse"], f"{r['pearson_r']:.3f}", f"{r['fit_seconds']:.0f}", "", "dam_accuracy_vtl.json")
            )
    hmm_dv = RESULTS / "hmm_dv.json"  # benchmarks/bench_hmm_dv.py: the HMM and dynamic-viseme rows
    if hmm_dv.exists():
        seen = {r[0] for r in rows}
        for r in _load("hmm_dv.json")["rows"]:
            if r["model"] in ("hmm", "dynamic-visemes") and r["model"] not in seen:
                rows.append(
                    (
                        r["model"],
                        r["rmse"],
                        f"{r['pearson_r']:.3f}",
                        f"{r['fit_seconds']:.0f}",
                        f"{r['us_per_phone']:.0f} µs/phone",
                        "hmm_dv.json",
                    )
                )
    rows.sort(key=lambda r: r[1])
    best = rows[0][1]
    lines = ["| model | RMSE | Pearson r | fit s | synthesis | source |", "|---|---:|---:|---:|---:|---|"]
    for label, rmse, r, fit, synth, src in rows:
        val = f"**{rmse:.3f}**" if rmse == best else f"{rmse:.3f}"
        lines.append(f"| {label} | {val} | {r} | {fit} | {synth} | `{src}` |")
    return "\n".join(lines) + "\n"


def render_crossmap() -> str:
    """The crossmap showcase's figures, from results/crossmap_pipeline.json (benchmarks/bench_crossmap.py)."""
    d = _load("crossmap_pipeline.json")
    runs = d["runs"]
    main = runs[-1]
    lines = [
        f"`python examples/crossmap_pipeline.py` goes the whole way (outlines → "
        f"{main['key_shapes']} key shapes → NNLS weights (outline RMSE {main['blend_rmse_cm']:.3f} cm "
        f"against a {main['captured']['outline_sd_cm']:.2f} cm spread) → controls bounded in [0, 1] "
        f"(vertex fit {main['controls']['vertex_fit_rmse']:.3f}) → DAM → held-out synthesis → retargeting "
        f"to a second character; {main['seconds']:.0f} s on this shared machine). Held-out RMSE of the "
        f"synthesized controls (clipped to the rig's "
        f"[0, 1]) on {main['held_out']['utterances']} test phrases, by minutes of training phrases "
        f"(`benchmarks/results/crossmap_pipeline.md`, {d['machine']['date']}):",
        "",
        "| training | phrases | "
        + " | ".join(main["held_out"]["scores"])
        + f" | {main['model']} values outside [0, 1] before clipping |",
        "|---:|---:|" + "---:|" * (len(main["held_out"]["scores"]) + 1),
    ]
    for run in runs:
        sc = run["held_out"]["scores"]
        lines.append(
            f"| {run['minutes']:g} min | {run['captured']['train_utterances']} | "
            + " | ".join(f"{sc[m]['rmse']:.3f}" for m in main["held_out"]["scores"])
            + f" | {100 * sc[run['model']]['outside_0_1_share']:.0f}% |"
        )
    return "\n".join(lines) + "\n"


def render_hmm_dv() -> str:
    """HMM, dynamic visemes and the tree at both window spans, from results/hmm_dv.json
    (benchmarks/bench_hmm_dv.py)."""
    d = _load("hmm_dv.json")
    m = d["machine"]
    lines = [
        f"Held-out `vtl:test`, all {len(d['channels'])} channels (`benchmarks/results/hmm_dv.md`, {m['date']}, "
        f"{m['cpu']}, shared with other jobs: fit and synthesis times are upper bounds):",
        "",
        "| model | input span (s) | fit (s) | synthesis (µs/phone) | RMSE | r |",
        "|---|---:|---:|---:|---:|---:|",
    ]
    rows = sorted(d["rows"], key=lambda r: r["rmse"])
    for r in rows:
        span = f"{r['input_span_seconds']:.2f}" if "input_span_seconds" in r else ""
        rmse = f"**{r['rmse']:.3f}**" if r is rows[0] else f"{r['rmse']:.3f}"
        lines.append(
            f"| {r['model']} | {span} | {r['fit_seconds']:.1f} | {r['us_per_phone']:.0f} | {rmse} | "
            f"{r['pearson_r']:.3f} |"
        )
    return "\n".join(lines) + "\n"


def render_taylor() -> str:
    """Taylor et al. (2017)'s comparison, from results/compare_taylor.json (benchmarks/bench_compare.py taylor)."""
    d = _load("compare_taylor.json")
    m = d["machine"]
    lines = [
        f"`benchmarks/results/compare_taylor.md` ({m['date']}, {m['cpu']}, channels {', '.join(d['channels'])}, "
        f"{d['train_utterances']} training utterances; load average {d['load_average_start'][0]:.1f} at the "
        f"start, so times are upper bounds):",
        "",
    ]
    lines += _compare_table(d["summary"], d["best"])
    return "\n".join(lines) + "\n"


def _bench_module(name: str):
    """``benchmarks/<name>.py`` as a module (its renderer is the one its .md is written with)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(name, ROOT / "benchmarks" / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    sys.path.insert(0, str(ROOT / "benchmarks"))  # for its _machine import
    try:
        spec.loader.exec_module(mod)
    finally:
        sys.path.remove(str(ROOT / "benchmarks"))
    return mod


def render_audio_models() -> str:
    """Audio- beside phone-driven rows on vtl, from results/audio_models.json (bench_audio_models.py)."""
    return _bench_module("bench_audio_models").markdown(_load("audio_models.json"))


def render_short_segments() -> str:
    """Very short phones in every context, from results/short_segments.json (bench_short_segments.py)."""
    return _bench_module("bench_short_segments").summary(_load("short_segments.json"))


BLOCKS = {
    "demo": render_demo,
    "all-models": render_all_models,
    "crossmap": render_crossmap,
    "hmm-dv": render_hmm_dv,
    "taylor": render_taylor,
    "audio-models": render_audio_models,
    "short-segments": render_short_segments,
}


def render(name: str) -> str:
    if name not in BLOCKS:
        raise KeyError(f"README block {name!r} has no renderer; known: {', '.join(BLOCKS)}")
    return BLOCKS[name]()


def update(text: str) -> tuple[str, list[str]]:
    """``text`` with every generated block re-rendered, and the names of the blocks that changed
    (or cannot be rendered: their results file is missing; those keep their text)."""
    changed = []

    def sub(m):
        try:
            body = render(m.group("name"))
        except FileNotFoundError as exc:  # its results file is not there: the block cannot be right
            print(f"README.md: block {m.group('name')!r}: {exc.filename} missing; run its benchmark", file=sys.stderr)
            changed.append(m.group("name"))
            return m.group(0)
        if body != m.group("body"):
            changed.append(m.group("name"))
        return m.group(1) + body + m.group(4)

    return BLOCK.sub(sub, text), changed


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="change nothing; exit 1 if a block is stale")
    args = ap.parse_args(argv)
    text = README.read_text(encoding="utf-8")
    new, changed = update(text)
    if args.check:
        if changed:
            print(
                f"README.md: stale generated blocks: {', '.join(changed)} (run benchmarks/update_readme.py)",
                file=sys.stderr,
            )
            return 1
        return 0
    if new != text:
        from dam.corpus.atomic import atomic_write

        with atomic_write(README) as fh:
            fh.write(new)
    _, left = update(new)  # what is still not right: blocks whose results file is missing
    done = [n for n in changed if n not in left]
    print(f"README.md: {len(done)} block(s) updated{': ' + ', '.join(done) if done else ''}")
    return 1 if left else 0


if __name__ == "__main__":
    raise SystemExit(main())
