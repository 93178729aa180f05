"""Animation out: streaming latency, the tiny runtime's speed, exported model size, glTF export time.

Writes ``benchmarks/results/export.json`` and ``export.md``.

* Streaming (:class:`dam.export.streaming.StreamingSynthesizer`) of the
  shipped default DAM (vtl, 100 Hz) over held-out vtl utterances, phone by
  phone: the stated lookahead (seconds and frames), the measured lag
  (seconds between the last pushed phone's end and the first frame not yet
  final, after every push: median, 95th percentile, max) and the wall time
  per pushed phone.
* The tiny runtime (``dam_runtime.py``, numpy only): microseconds per phone
  of ``synthesize`` against the toolkit's ``predict`` on the same
  alignments, and the largest difference between the two.
* Size of the exported runtime model (``.json``, ``.npz``) for the default
  DAM and a DAM fitted on ``tiny``, beside the toolkit's own model file.
* glTF export of a one-minute utterance (19 VTL controls at 100 Hz, the
  VocalTractLab ribbon): seconds to write ``.glb`` and ``.gltf``, file sizes,
  and the Khronos validator's verdict when node is present.

    python benchmarks/bench_export.py
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
from _machine import machine, median_time  # noqa: E402

import dam  # noqa: E402
import dam.datasets  # noqa: E402
from dam.corpus import Alignment  # noqa: E402
from dam.export import export  # noqa: E402
from dam.export.runtime import export_runtime, runtime_source  # noqa: E402
from dam.export.streaming import StreamingSynthesizer  # noqa: E402
from dam.speech import load_default_model  # noqa: E402


def held_out(model, n):
    vtl = dam.datasets.load("vtl")
    known = set(model.phone_modes_)
    return [u.alignment for u in vtl[150:] if u.alignment.phones <= known][:n]


def bench_streaming(model, aligns):
    longest = max(float(a.durations.max()) for a in aligns)
    lags, push_s, worst = [], [], 0.0
    s = None
    for a in aligns:
        s = StreamingSynthesizer(model, max_duration=longest)
        chunks = []
        for lab, end in zip(a.labels, a.ends):
            t0 = time.perf_counter()
            chunks.append(s.push(lab, end=float(end)))
            push_s.append(time.perf_counter() - t0)
            lags.append(float(end) - s.n_emitted / s.frame_rate)
        chunks.append(s.finish())
        worst = max(worst, float(np.abs(np.concatenate(chunks) - model.predict(a)).max()))
    lags = np.array(lags)
    return {
        "max_duration_s": longest,
        "reach_durations": s.reach,
        "lookahead_s": s.lookahead,
        "lookahead_frames": s.lookahead_frames,
        "lag_median_s": float(np.median(lags)),
        "lag_p95_s": float(np.percentile(lags, 95)),
        "lag_max_s": float(lags.max()),
        "push_us_median": 1e6 * float(np.median(push_s)),
        "push_us_p95": 1e6 * float(np.percentile(push_s, 95)),
        "max_abs_diff_vs_batch": worst,
        "n_utterances": len(aligns),
        "n_phones": len(lags),
    }


def load_runtime():
    import importlib.util

    spec = importlib.util.spec_from_file_location("dam_runtime", runtime_source())
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def bench_runtime(model, aligns, tmp):
    rt_mod = load_runtime()
    path = os.path.join(tmp, "m.npz")
    export_runtime(model, path)
    rt = rt_mod.load(path)
    n_phones = sum(len(a) for a in aligns)
    t_rt = median_time(lambda: [rt.synthesize(a.labels, a.ends, a.starts) for a in aligns], repeat=5)
    t_tk = median_time(lambda: [model.predict(a) for a in aligns], repeat=5)
    diff = max(float(np.abs(rt.synthesize(a.labels, a.ends, a.starts) - model.predict(a)).max()) for a in aligns)
    return {
        "runtime_us_per_phone": 1e6 * t_rt / n_phones,
        "toolkit_us_per_phone": 1e6 * t_tk / n_phones,
        "max_abs_diff": diff,
        "n_phones": n_phones,
        "runtime_module_lines": len(open(runtime_source(), encoding="utf-8").read().splitlines()),
    }


def bench_sizes(models, tmp):
    out = {}
    for name, m in models.items():
        row = {}
        for ext in (".json", ".npz"):
            row[f"runtime{ext}_bytes"] = export_runtime(m, os.path.join(tmp, f"{name}{ext}"))
        m.save(os.path.join(tmp, f"{name}.model.npz"))
        row["toolkit_model_bytes"] = os.path.getsize(os.path.join(tmp, f"{name}.model.npz"))
        row["n_modes"] = int(m.coef_.shape[0])
        row["n_channels"] = int(m.coef_.shape[2])
        out[name] = row
    return out


def one_minute(model):
    vtl = dam.datasets.load("vtl")
    labels, ends, t = [], [], 0.0
    known = set(model.phone_modes_)
    for u in vtl:
        if not u.alignment.phones <= known:
            continue
        for lab, d in zip(u.alignment.labels, u.alignment.durations):
            t += float(d)
            labels.append(lab)
            ends.append(t)
        if t >= 60.0:
            break
    ends = np.array(ends)
    return Alignment(labels, np.concatenate([[0.0], ends[:-1]]), ends)


def bench_gltf(model, tmp):
    a = one_minute(model)
    y = model.predict(a)
    out = {"duration_s": a.duration, "n_frames": int(len(y)), "n_controls": int(y.shape[1])}
    paths = []
    for ext in ("glb", "gltf"):
        p = os.path.join(tmp, f"minute.{ext}")
        out[f"{ext}_seconds"] = median_time(
            lambda p=p: export(y, p, channels=model.channels_, frame_rate=model.frame_rate_, alignment=a), repeat=3
        )
        out[f"{ext}_bytes"] = os.path.getsize(p)
        paths.append(p)
    try:
        sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests" / "export"))
        import export_tools

        validate = export_tools.gltf_validator()
        reports = validate(paths)
        out["validator_errors"] = int(sum(r["issues"]["numErrors"] for r in reports.values()))
        out["validator_warnings"] = int(sum(r["issues"]["numWarnings"] for r in reports.values()))
        out["validator"] = next(iter(reports.values()))["validatorVersion"]
    except Exception as exc:  # node missing: say so, do not guess
        out["validator"] = f"not run: {exc}"
    return out


def markdown(res) -> str:
    s, r, g, t = res["streaming"], res["runtime"], res["gltf"], res["streaming_multimode_tiny"]
    lines = [
        "# Animation out (benchmarks/bench_export.py)",
        "",
        f"Machine: {res['machine']['cpu']}, {res['machine']['cores']} cores, Python {res['machine']['python']}, "
        f"numpy {res['machine']['numpy']}; {res['machine']['date']}.",
        "",
        "## Streaming (default DAM, held-out vtl utterances)",
        "",
        "| stated lookahead | frames | lag median | lag p95 | lag max | per push (median / p95) | max diff vs batch |",
        "|---|---|---|---|---|---|---|",
        f"| {s['lookahead_s']:.3f} s (reach {s['reach_durations']:.2f} x longest phone {s['max_duration_s']:.3f} s) "
        f"| {s['lookahead_frames']} | {s['lag_median_s']:.3f} s | {s['lag_p95_s']:.3f} s | {s['lag_max_s']:.3f} s "
        f"| {s['push_us_median']:.0f} / {s['push_us_p95']:.0f} us | {s['max_abs_diff_vs_batch']:.1e} |",
        "",
        f"{s['n_phones']} phones in {s['n_utterances']} utterances. Lag: seconds from the end of the last phone "
        "pushed back to the first frame not yet final. The default DAM has one mode per phone; the DAM fitted "
        f"on tiny has several for most phones, so frames also wait until the modes are decided: on tiny's "
        f"{t['n_utterances']} utterances, stated lookahead {t['lookahead_s']:.3f} s, lag median "
        f"{t['lag_median_s']:.3f} s, p95 {t['lag_p95_s']:.3f} s, max {t['lag_max_s']:.3f} s, "
        f"{t['push_us_median']:.0f} us per push, max diff vs batch {t['max_abs_diff_vs_batch']:.1e}.",
        "",
        "## Tiny runtime (numpy only)",
        "",
        "| runtime us/phone | toolkit predict us/phone | max abs diff | module lines |",
        "|---|---|---|---|",
        f"| {r['runtime_us_per_phone']:.1f} | {r['toolkit_us_per_phone']:.1f} | {r['max_abs_diff']:.1e} "
        f"| {r['runtime_module_lines']} |",
        "",
        "## Exported model size",
        "",
        "| model | modes | channels | runtime .json | runtime .npz | toolkit model file |",
        "|---|---|---|---|---|---|",
    ]
    for name, row in res["sizes"].items():
        lines.append(
            f"| {name} | {row['n_modes']} | {row['n_channels']} "
            f"| {row['runtime.json_bytes'] / 1024:.1f} kB "
            f"| {row['runtime.npz_bytes'] / 1024:.1f} kB | {row['toolkit_model_bytes'] / 1024:.1f} kB |"
        )
    lines += [
        "",
        "## glTF export of a one-minute utterance",
        "",
        "| duration | frames x controls | .glb write | .glb size | .gltf write | .gltf size | Khronos validator |",
        "|---|---|---|---|---|---|---|",
        f"| {g['duration_s']:.1f} s | {g['n_frames']} x {g['n_controls']} | {g['glb_seconds'] * 1e3:.0f} ms "
        f"| {g['glb_bytes'] / 1024:.0f} kB | {g['gltf_seconds'] * 1e3:.0f} ms | {g['gltf_bytes'] / 1024:.0f} kB "
        f"| {g.get('validator_errors', '-')} errors, {g.get('validator_warnings', '-')} warnings "
        f"({g['validator']}) |",
        "",
    ]
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"))
    ap.add_argument("--utterances", type=int, default=20)
    args = ap.parse_args(argv)
    model = load_default_model()
    aligns = held_out(model, args.utterances)
    tiny = dam.make("dam").fit(dam.datasets.load("tiny"))
    with tempfile.TemporaryDirectory() as tmp:
        res = {
            "machine": machine(),
            "streaming": bench_streaming(model, aligns),
            # the default DAM has one mode per phone; tiny's has several: modes wait for agreement
            "streaming_multimode_tiny": bench_streaming(tiny, dam.datasets.load("tiny").alignments),
            "runtime": bench_runtime(model, aligns, tmp),
            "sizes": bench_sizes({"default (vtl)": model, "tiny": tiny}, tmp),
            "gltf": bench_gltf(model, tmp),
        }
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "export.json").write_text(json.dumps(res, indent=2) + "\n")
    text = markdown(res)
    (out / "export.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
