"""Speech in: alignment speed and accuracy, text-to-trajectories speed, duration-model accuracy.

Writes ``benchmarks/results/speech.json`` and ``speech.md``.

* Alignment (pocketsphinx 5, en-us) of the shipped test speech
  (``tests/data/speech``: espeak-ng sentences with known phone timing):
  real-time factor (seconds of CPU per second of audio; once with the
  decoder's model loading, once warm) and phone/word onset errors against
  espeak-ng's own phoneme events. Phone recognition (no transcript): its
  phone error rate against the forced alignment's phones.
* Text to trajectories with the shipped default models: microseconds per
  phone end to end (normalize, CMU dictionary, durations, phone mapping,
  DAM synthesis), warm.
* Letter-to-sound: phone error rate against the CMU dictionary.
* Durations: held-out RMSE (ms) of the context-dependent duration model
  against the phone-mean baseline on the bundled vtl corpus (train -> test),
  on tiny (first 3/4 -> last 1/4) and on the English alignments made here
  (leave one utterance out).

    python benchmarks/bench_speech.py
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import machine, median_time  # noqa: E402

import dam  # noqa: E402
from dam.speech import DurationModel, PhoneApproximationWarning, align, phone_error_rate, phone_mean_baseline  # noqa: E402
from dam.speech.aligner import onset_errors  # noqa: E402

DATA = Path(__file__).resolve().parent.parent / "tests" / "data" / "speech"
HARVARD = [
    "The birch canoe slid on the smooth planks.",
    "Glue the sheet to the dark blue background.",
    "It's easy to tell the depth of a well.",
    "These days a chicken leg is a rare dish.",
    "Rice is often served in round bowls.",
    "The juice of lemons makes fine punch.",
    "The box was thrown beside the parked truck.",
    "The hogs were fed chopped corn and garbage.",
    "Four hours of steady work faced us.",
    "A large size in stockings is hard to sell.",
]


def bench_alignment():
    rows, w_all, p_all, results = [], [], [], {}
    per_hyp, per_ref = [], []
    for meta_path in sorted(DATA.glob("*.json")):
        truth = json.loads(meta_path.read_text())
        audio = DATA / truth["audio"]
        t0 = time.perf_counter()
        r = align(audio, truth["text"])
        cold = time.perf_counter() - t0
        warm = median_time(lambda a=audio, t=truth["text"]: align(a, t), repeat=3)
        rec_time = median_time(lambda a=audio: align(a), repeat=1)
        rec = align(audio)
        w, p = onset_errors(r, truth["words"], truth["phones"])
        w_all += w
        p_all += p
        ref = [x for x in r.phones.labels if x != "sil"]
        hyp = [x for x in rec.phones.labels if x != "sil"]
        per_hyp.append(hyp)
        per_ref.append(ref)
        results[meta_path.stem] = r
        rows.append(
            {
                "file": truth["audio"],
                "seconds_audio": r.duration,
                "rate_hz": truth["sample_rate"],
                "format": f"{truth['subtype']}, {truth['channels']} ch",
                "rtf_cold": cold / r.duration,
                "rtf_warm": warm / r.duration,
                "rtf_phone_recognition": rec_time / r.duration,
                "median_phone_onset_error_ms": 1000 * float(np.median(p)) if p else None,
                "phones_compared": len(p),
            }
        )
    p_all, w_all = np.array(p_all), np.array(w_all)
    summary = {
        "median_phone_onset_error_ms": 1000 * float(np.median(p_all)),
        "p90_phone_onset_error_ms": 1000 * float(np.percentile(p_all, 90)),
        "share_within_50ms": float(np.mean(p_all <= 0.05)),
        "median_word_onset_error_ms": 1000 * float(np.median(w_all)),
        "phones_compared": int(len(p_all)),
        "words_compared": int(len(w_all)),
        "rtf_cold_median": float(np.median([r["rtf_cold"] for r in rows])),
        "rtf_warm_median": float(np.median([r["rtf_warm"] for r in rows])),
        "phone_recognition_per": phone_error_rate(per_hyp, per_ref),
    }
    return rows, summary, results


def bench_text():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PhoneApproximationWarning)
        dam.animate(text=HARVARD[0])  # loads the dictionary and the models once
        n_phones = sum(len(dam.animate(text=s).alignment.labels) for s in HARVARD)
        t = median_time(lambda: [dam.animate(text=s) for s in HARVARD], repeat=5)
        from dam.speech import load_default_model

        model = load_default_model()
        aligns = [dam.animate(text=s).alignment for s in HARVARD]
        t_synth = median_time(lambda: [model.predict(a) for a in aligns], repeat=5)
        t_cold = _cold_start()
    return {
        "sentences": len(HARVARD),
        "phones": n_phones,
        "us_per_phone": 1e6 * t / n_phones,
        "us_per_phone_synthesis_only": 1e6 * t_synth / n_phones,
        "seconds_per_sentence": t / len(HARVARD),
        "first_call_seconds_in_a_new_process": t_cold,
    }


def bench_letter_to_sound(n_words: int = 2000):
    """Phone error rate of the letter-to-sound rules on random CMU words (best of their pronunciations)."""
    import random
    import re

    from dam.speech import edit_distance, letter_to_sound
    from dam.speech.text import _cmudict, cmu_lookup

    words = sorted(w for w in _cmudict() if w.isalpha())
    sample = random.Random(0).sample(words, n_words)

    def strip(ps):
        return [re.sub(r"\d", "", p) for p in ps]

    errors = sum(min(edit_distance(strip(letter_to_sound(w)), strip(p)) for p in cmu_lookup(w)) for w in sample)
    exact = sum(any(strip(letter_to_sound(w)) == strip(p) for p in cmu_lookup(w)) for w in sample)
    total = sum(len(cmu_lookup(w)[0]) for w in sample)
    return {"words": n_words, "phone_error_rate": errors / total, "word_accuracy": exact / n_words}


def _cold_start():
    import subprocess

    code = (
        "import time, warnings; t=time.perf_counter(); import dam; warnings.simplefilter('ignore');"
        f"dam.animate(text={HARVARD[0]!r}); print(time.perf_counter()-t)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return float(out.stdout.strip())


def _rmse_ms(model_pred, base_pred, true, mask=None):
    if mask is not None:
        model_pred, base_pred, true = model_pred[mask], base_pred[mask], true[mask]
    return (
        1000 * float(np.sqrt(np.mean((model_pred - true) ** 2))),
        1000 * float(np.sqrt(np.mean((base_pred - true) ** 2))),
        int(len(true)),
    )


def _duration_row(name, train, test, word_ids_train=None, word_ids_test=None):
    model = DurationModel().fit(train, word_ids_train)
    pred = np.concatenate(
        [model.predict(list(a.labels), None if word_ids_test is None else word_ids_test[i]) for i, a in enumerate(test)]
    )
    true = np.concatenate([a.ends - a.starts for a in test])
    base = phone_mean_baseline(train, test)
    speech = np.array([lab != a.silence for a in test for lab in a.labels])
    m_all, b_all, n_all = _rmse_ms(pred, base, true)
    m_sp, b_sp, n_sp = _rmse_ms(pred, base, true, speech)
    return {
        "corpus": name,
        "segments": n_all,
        "rmse_ms": m_all,
        "baseline_rmse_ms": b_all,
        "rmse_ms_phones_only": m_sp,
        "baseline_rmse_ms_phones_only": b_sp,
        "phones": n_sp,
    }


def _word_ids(result):
    """Per phone segment, the index of the word it falls in (-1 for silence)."""
    out = []
    for lab, s, e in zip(result.phones.labels, result.phones.starts, result.phones.ends):
        if lab == "sil":
            out.append(-1)
            continue
        mid = (s + e) / 2
        idx = [
            i
            for i, (w, ws, we) in enumerate(zip(result.words.labels, result.words.starts, result.words.ends))
            if ws <= mid < we and w != "sil"
        ]
        out.append(idx[0] if idx else -1)
    return out


def bench_durations(english):
    rows = []
    from dam.datasets.default_model import vtl_word_ids

    (vtl_train, wid_train), (vtl_test, wid_test) = vtl_word_ids("train"), vtl_word_ids("test")
    rows.append(_duration_row("vtl (train -> test)", vtl_train.alignments, vtl_test.alignments))
    rows.append(
        _duration_row(
            "vtl, with the recorded word boundaries", vtl_train.alignments, vtl_test.alignments, wid_train, wid_test
        )
    )
    tiny = dam.datasets.load("tiny").alignments
    cut = len(tiny) * 3 // 4
    rows.append(_duration_row("tiny (3/4 -> 1/4)", tiny[:cut], tiny[cut:]))
    # English: leave one aligned utterance out, pooled
    names = sorted(english)
    preds, bases, trues, speech = [], [], [], []
    for held in names:
        train = [english[n].phones for n in names if n != held]
        wid = [_word_ids(english[n]) for n in names if n != held]
        model = DurationModel().fit(train, wid)
        a = english[held].phones
        preds.append(model.predict(list(a.labels), _word_ids(english[held])))
        bases.append(phone_mean_baseline(train, [a]))
        trues.append(a.ends - a.starts)
        speech.append(np.array([lab != "sil" for lab in a.labels]))
    pred, base, true, mask = map(np.concatenate, (preds, bases, trues, speech))
    m_all, b_all, n_all = _rmse_ms(pred, base, true)
    m_sp, b_sp, n_sp = _rmse_ms(pred, base, true, mask)
    rows.append(
        {
            "corpus": f"English alignments made here ({len(names)} utterances, leave one out)",
            "segments": n_all,
            "rmse_ms": m_all,
            "baseline_rmse_ms": b_all,
            "rmse_ms_phones_only": m_sp,
            "baseline_rmse_ms_phones_only": b_sp,
            "phones": n_sp,
        }
    )
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"))
    args = ap.parse_args(argv)
    align_rows, align_summary, english = bench_alignment()
    text = bench_text()
    durations = bench_durations(english)
    lts = bench_letter_to_sound()
    res = {
        "machine": machine(),
        "load_average": os.getloadavg()[0],
        "alignment": align_rows,
        "alignment_summary": align_summary,
        "text_to_trajectories": text,
        "durations": durations,
        "letter_to_sound": lts,
    }
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "speech.json").write_text(json.dumps(res, indent=2) + "\n")
    s = align_summary
    md = [
        "### Alignment (pocketsphinx 5, en-us) of the shipped test speech",
        "",
        "| file | audio (s) | format | RTF cold | RTF warm | RTF phone recognition | median phone onset error (ms) |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in align_rows:
        med = "-" if r["median_phone_onset_error_ms"] is None else f"{r['median_phone_onset_error_ms']:.0f}"
        md.append(
            f"| {r['file']} | {r['seconds_audio']:.2f} | {r['rate_hz']} Hz {r['format']} | {r['rtf_cold']:.3f} "
            f"| {r['rtf_warm']:.3f} | {r['rtf_phone_recognition']:.3f} | {med} |"
        )
    md += [
        "",
        f"All files: median phone onset error {s['median_phone_onset_error_ms']:.0f} ms "
        f"(90th percentile {s['p90_phone_onset_error_ms']:.0f} ms, {100 * s['share_within_50ms']:.0f}% "
        f"within 50 ms, {s['phones_compared']} phones); median word onset error "
        f"{s['median_word_onset_error_ms']:.0f} ms ({s['words_compared']} words). Phone recognition "
        f"without a transcript: phone error rate {100 * s['phone_recognition_per']:.0f}% against the "
        "forced alignment.",
        "",
        "### Text to trajectories (default models, warm)",
        "",
        f"{text['us_per_phone']:.0f} µs per phone end to end ({text['phones']} phones in {text['sentences']} "
        f"Harvard sentences; {text['seconds_per_sentence'] * 1000:.1f} ms per sentence), of which DAM synthesis "
        f"{text['us_per_phone_synthesis_only']:.0f} µs. First call in a new Python process (imports, "
        f"dictionary, models): {text['first_call_seconds_in_a_new_process']:.2f} s.",
        "",
        "### Phone durations: held-out RMSE (ms)",
        "",
        "| corpus | segments | model | phone-mean baseline | phones only: model | phones only: baseline |",
        "|---|---|---|---|---|---|",
    ]
    for r in durations:
        md.append(
            f"| {r['corpus']} | {r['segments']} | {r['rmse_ms']:.1f} | {r['baseline_rmse_ms']:.1f} | "
            f"{r['rmse_ms_phones_only']:.1f} | {r['baseline_rmse_ms_phones_only']:.1f} |"
        )
    md += [
        "",
        "### Letter-to-sound fallback",
        "",
        f"Phone error rate {100 * lts['phone_error_rate']:.0f}%, words exactly right "
        f"{100 * lts['word_accuracy']:.0f}%, on {lts['words']} random alphabetic CMU dictionary words "
        "(names and loans included), against the dictionary.",
    ]
    m = res["machine"]
    md += [
        "",
        f"Machine: {m['cpu']}, {m['cores']} cores, {m['date']}; load average while running "
        f"{res['load_average']:.1f} (timings scale with it on a shared machine)",
    ]
    text_md = "\n".join(md) + "\n"
    (out / "speech.md").write_text(text_md)
    print(text_md)


if __name__ == "__main__":
    main()
