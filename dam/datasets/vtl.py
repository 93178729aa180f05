"""The ``vtl`` corpus: German phrases spoken by VocalTractLab's articulatory model.

VocalTractLab (VTL, Birkholz; GPL-3.0; Python binding ``vocaltractlab-cython``,
which ships the library and the JD3 speaker) turns a *segment sequence*
(German SAMPA phones with durations) into a *gestural score* and the gestural
score into the 19 tract parameters of its vocal tract model, one state every
110 audio samples at 44.1 kHz (400.9 Hz). Its gestures overlap and blend, so
the trajectories coarticulate in a way nobody on this project designed.

The pipeline, one phrase at a time:

1. words with SAMPA phones and phone durations measured in real speech come
   from :data:`LEXICON_PATH` (extracted once from the ``articubench`` package,
   see :func:`extract_articubench_lexicon`);
2. :func:`plan_phrases` draws phrases of several words, a speaking rate per
   phrase, per-phone jitter and pauses between some words (all randomness
   lives here, in the parent process, so the corpus is deterministic for a
   seed whatever ``n_jobs`` is);
3. every phone is mapped through :data:`SYMBOL_MAP` and checked against
   :data:`VTL_PHONEMES` *before* synthesis (VTL drops unknown symbols
   silently);
4. :func:`synthesize_phrase` writes the VTL segment file, calls
   ``vtlSegmentSequenceToGesturalScore`` and
   ``vtlGesturalScoreToTractSequence``, reads the 19 tract parameters
   (:func:`read_tract_sequence`) and resamples them to the chosen frame rate
   with a polyphase anti-aliasing filter (:func:`resample_tract`); for some
   phrases it also synthesizes 16 kHz audio from the gestural score;
5. :func:`generate_vtl_corpus` writes ``train/`` and ``test/`` corpus
   directories (``corpus.json``, ``<stem>.TextGrid`` with tier ``phones``,
   ``<stem>.npy`` float32 or ``<stem>.csv``, ``<stem>.wav``). Train and test
   phrases use disjoint words.

Regenerate the bundled corpus (same seed, same files)::

    python -m dam.datasets.vtl generate dam/datasets/data/vtl --seed 0 --overwrite

Needs the ``vtl`` extra (``pip install dam[vtl]``): vocaltractlab-cython and
scipy; pandas only for :func:`extract_articubench_lexicon`.
"""

from __future__ import annotations

import gzip
import json
import math
import os
import shutil
import sys
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass, replace
from fractions import Fraction
from pathlib import Path

import numpy as np

from dam.corpus.atomic import atomic_write
from dam.corpus.data import Alignment, Corpus, DataError, Utterance

__all__ = [
    "VTL_CHANNELS",
    "VTL_UNITS",
    "VTL_PHONEMES",
    "SYMBOL_MAP",
    "VTL_STATE_RATE",
    "LEXICON_PATH",
    "Word",
    "PhrasePlan",
    "load_lexicon",
    "extract_articubench_lexicon",
    "map_phones",
    "import_vtl",
    "check_vtl_symbols",
    "probe_vtl_symbol",
    "split_words",
    "plan_phrases",
    "plan_corpus",
    "segment_file_text",
    "read_tract_sequence",
    "resample_tract",
    "synthesize_phrase",
    "generate_vtl_corpus",
]

#: The 19 tract parameters of VTL's vocal tract model, in VTL's order.
VTL_CHANNELS = (
    "HX",
    "HY",
    "JX",
    "JA",
    "LP",
    "LD",
    "VS",
    "VO",
    "TCX",
    "TCY",
    "TTX",
    "TTY",
    "TBX",
    "TBY",
    "TRX",
    "TRY",
    "TS1",
    "TS2",
    "TS3",
)

#: Units of the tract parameters, as VTL's own parameter table gives them
#: (``vocaltractlab_cython.get_param_info("tract")``; VS, the velum shape, has none).
VTL_UNITS = {
    "HX": "cm",
    "HY": "cm",
    "JX": "cm",
    "JA": "deg",
    "LP": "cm",
    "LD": "cm",
    "VS": "",
    "VO": "cm²",
    "TCX": "cm",
    "TCY": "cm",
    "TTX": "cm",
    "TTY": "cm",
    "TBX": "cm",
    "TBY": "cm",
    "TRX": "cm",
    "TRY": "cm",
    "TS1": "cm",
    "TS2": "cm",
    "TS3": "cm",
}

#: VTL's audio rate and the audio samples per tract state: states come at 44100/110 = 400.9 Hz.
VTL_AUDIO_RATE = 44100
VTL_SAMPLES_PER_STATE = 110
VTL_STATE_RATE = VTL_AUDIO_RATE / VTL_SAMPLES_PER_STATE

#: The segment symbols VTL turns into gestures (``Sampa::PHONEME`` of the VTL
#: backend). Anything else is dropped without a word: no gesture, its time
#: absorbed by its neighbours. Checked against the installed library by
#: ``tests/test_vtl.py`` with :func:`probe_vtl_symbol`.
VTL_PHONEMES = frozenset(
    (
        # vowels
        "a:",
        "e:",
        "i:",
        "o:",
        "u:",
        "E:",
        "2:",
        "y:",
        "a",
        "e",
        "i",
        "o",
        "u",
        "E",
        "2",
        "y",
        "I",
        "O",
        "U",
        "9",
        "Y",
        "@",
        "6",
        # diphthongs (German ones; English "eI", "oU" are unknown)
        "aI",
        "aU",
        "OY",
        "i:6",
        "i6",
        "I6",
        "y:6",
        "y6",
        "Y6",
        "e:6",
        "e6",
        "E6",
        "E:6",
        "2:6",
        "26",
        "96",
        "a:6",
        "a6",
        "u:6",
        "u6",
        "U6",
        "o:6",
        "o6",
        "O6",
        # plosives, fricatives, affricates, nasals and lateral
        "?",
        "p",
        "b",
        "t",
        "d",
        "k",
        "g",
        "f",
        "v",
        "T",
        "D",
        "s",
        "z",
        "S",
        "Z",
        "C",
        "j",
        "x",
        "r",
        "R",
        "h",
        "pf",
        "ts",
        "tS",
        "dZ",
        "m",
        "n",
        "N",
        "l",
    )
)

#: Lexicon symbol -> VTL symbol. The articubench transcriptions write German
#: short (lax) vowels without a length mark, as ``i e o u`` (``Abschnitte``
#: = ``a p S n i t @``); VTL reads ``i e o u`` as short *tense* vowels with
#: the tense tongue shapes, so they become the lax ``I E O U``. ``r`` becomes
#: the uvular ``R`` of Standard German (VTL gives both the same gestures; the
#: label then matches the usual German SAMPA). Symbols not listed pass
#: through unchanged and must be in :data:`VTL_PHONEMES`.
SYMBOL_MAP = {"i": "I", "e": "E", "o": "O", "u": "U", "r": "R"}

_DATA = Path(__file__).parent / "data"
#: German words with SAMPA phones and measured mean phone durations (seconds).
LEXICON_PATH = _DATA / "articubench_words.tsv.gz"

LICENCE_NOTE = (
    "Trajectories and audio are output of VocalTractLab (GPL-3.0) with its JD3 speaker: the GPL "
    "covers the program, not what the program computes (GNU GPL FAQ, 'Is there some way that I "
    "can GPL the output people get from use of my program?'), so the numbers are generally not "
    "under the GPL. Words, phones and durations come from the articubench package (GPL-3.0-or-later; "
    "durations measured in Mozilla Common Voice, CC0); dam/datasets/data/articubench_words.tsv.gz "
    "is redistributed under GPL-3.0-or-later (text in dam/datasets/data/LICENSES/GPL-3.0.txt). "
    "To be safe, treat the corpus as derived from GPL-3.0-or-later data."
)


def import_vtl():
    """``vocaltractlab_cython``, or an ImportError that says how to install it."""
    try:
        import vocaltractlab_cython
    except ImportError as exc:  # pragma: no cover - depends on the install
        raise ImportError(
            f"this needs VocalTractLab: pip install 'dam[vtl]' (vocaltractlab-cython); import failed: {exc}"
        ) from None
    return vocaltractlab_cython


# -- the lexicon ------------------------------------------------------------
@dataclass(frozen=True)
class Word:
    """One lexicon entry: orthography, SAMPA phones, mean phone durations (s)."""

    word: str
    phones: tuple
    durations: tuple


def extract_articubench_lexicon(pkl_path, out_path=LEXICON_PATH) -> int:
    """Extract words, phones and phone durations from articubench's word table.

    ``pip download --no-deps articubench`` and unzip the wheel; the table is
    ``articubench/data/lexical_embedding_vectors.pkl``, a pandas DataFrame
    with columns ``label`` (the word), ``phones`` (list of SAMPA symbols),
    ``phone_durations`` (array of seconds: means over the word's tokens in
    Common Voice, force-aligned) and, for two words, ``durations`` instead.
    The semantic vectors are not kept. Durations are rounded to 0.1 ms; the
    gzip header carries no time stamp, so the file is reproducible.

    Returns the number of words written.
    """
    import pandas as pd  # only needed for this one-time extraction

    pkl_path = os.fspath(pkl_path)
    df = pd.read_pickle(pkl_path)
    rows = []
    for k, rec in enumerate(df.itertuples(index=False)):
        durs = rec.phone_durations
        if not isinstance(durs, (list, tuple, np.ndarray)):
            durs = rec.durations
        phones = [str(p) for p in rec.phones]
        durs = [float(d) for d in np.ravel(durs)]
        if len(durs) != len(phones) or not phones:
            raise DataError(
                pkl_path,
                f"row {k} ({rec.label!r}) phone_durations",
                len(durs),
                f"{len(phones)} phones but {len(durs)} durations",
            )
        if not all(math.isfinite(d) and d > 0 for d in durs):
            raise DataError(
                pkl_path, f"row {k} ({rec.label!r}) phone_durations", durs, "durations must be positive and finite"
            )
        rows.append(f"{rec.label}\t{' '.join(phones)}\t{' '.join(f'{d:.4f}' for d in durs)}\n")
    text = "word\tphones\tdurations_s\n" + "".join(rows)
    out_path = Path(out_path)
    out_path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_write(out_path, "wb") as raw, gzip.GzipFile(filename="", mode="wb", fileobj=raw, mtime=0) as gz:
        gz.write(text.encode("utf-8"))
    return len(rows)


def load_lexicon(path=LEXICON_PATH) -> list[Word]:
    """Read the lexicon (``word<TAB>phones<TAB>durations_s``, gzip or plain).

    Symbols are as in the source; :func:`map_phones` turns them into VTL's.
    """
    path = os.fspath(path)
    opener = gzip.open if path.endswith(".gz") else open
    words = []
    with opener(path, "rt", encoding="utf-8") as fh:
        header = fh.readline().rstrip("\n").split("\t")
        if header != ["word", "phones", "durations_s"]:
            raise DataError(path, "header", header, "expected word, phones, durations_s")
        for lineno, line in enumerate(fh, 2):
            parts = line.rstrip("\n").split("\t")
            if len(parts) != 3:
                raise DataError(path, f"line {lineno}", line.strip(), "expected 3 tab-separated fields")
            phones = tuple(parts[1].split())
            try:
                durs = tuple(float(d) for d in parts[2].split())
            except ValueError:
                raise DataError(path, f"line {lineno} durations_s", parts[2], "not numbers") from None
            if len(durs) != len(phones) or not phones:
                raise DataError(
                    path,
                    f"line {lineno} ({parts[0]!r})",
                    (len(phones), len(durs)),
                    "phones and durations differ in number",
                )
            if not all(math.isfinite(d) and d > 0 for d in durs):
                raise DataError(
                    path, f"line {lineno} ({parts[0]!r}) durations_s", parts[2], "durations must be positive and finite"
                )
            words.append(Word(parts[0], phones, durs))
    return words


def check_vtl_symbols(phones: Sequence[str], *, source=None) -> None:
    """Raise :class:`DataError` naming the first symbol VTL does not know.

    VTL would drop such a symbol silently, so this runs before synthesis.
    """
    for i, p in enumerate(phones):
        if p not in VTL_PHONEMES:
            raise DataError(
                source,
                f"phone {i}",
                p,
                "not a VocalTractLab segment symbol (VTL would drop it silently)",
                "map it to a known German SAMPA symbol in SYMBOL_MAP or the mapping "
                f"argument; known: {' '.join(sorted(VTL_PHONEMES))}",
            )


def map_phones(phones: Sequence[str], mapping: dict | None = None, *, source=None) -> tuple:
    """Map lexicon symbols to VTL symbols (default :data:`SYMBOL_MAP`) and check them."""
    mapping = SYMBOL_MAP if mapping is None else mapping
    out = tuple(mapping.get(p, p) for p in phones)
    check_vtl_symbols(out, source=source)
    return out


def probe_vtl_symbol(symbol: str, workdir=None) -> bool:
    """Ask the installed VTL whether it makes a gesture for ``symbol``.

    Builds the gestural score of ``a <symbol> a`` and compares it with the
    score of ``a <nonsense> a``, which VTL certainly drops: equal scores mean
    the symbol is dropped too.
    """
    vtl = import_vtl()

    def score(sym):
        plan = PhrasePlan("probe", (), ("", "a", sym, "a", ""), (0.1, 0.12, 0.1, 0.12, 0.1), (), 1.0, False)
        with tempfile.TemporaryDirectory(dir=workdir) as tmp:
            seg, ges = os.path.join(tmp, "p.seg"), os.path.join(tmp, "p.ges")
            with open(seg, "w", encoding="utf-8") as fh:  # scratch input for VTL, not an output
                fh.write(segment_file_text(plan))
            vtl.phoneme_file_to_gesture_file(seg, ges)
            with open(ges, encoding="utf-8") as fh:
                return fh.read()

    return score(symbol) != score("#not-a-phone#")


# -- planning (all randomness) -----------------------------------------------
@dataclass(frozen=True)
class PhrasePlan:
    """One phrase to synthesize.

    Attributes
    ----------
    name : str
        File stem.
    words : tuple of str
    labels : tuple of str
        VTL symbols; ``""`` is a pause (leading, trailing, between words).
    durations : tuple of float
        Seconds, rounded to 1 ms, one per label.
    word_starts : tuple of int
        Index into ``labels`` of each word's first phone.
    rate : float
        Speaking-rate factor of the phrase (durations were divided by it).
    audio : bool
        Whether to synthesize audio too.
    """

    name: str
    words: tuple
    labels: tuple
    durations: tuple
    word_starts: tuple
    rate: float
    audio: bool


def split_words(words: Sequence[Word], test_fraction: float, rng) -> tuple[list[Word], list[Word]]:
    """Disjoint train/test word lists (a random ``test_fraction`` of the words for test)."""
    perm = rng.permutation(len(words))
    n_test = int(round(test_fraction * len(words)))
    return [words[i] for i in sorted(perm[n_test:])], [words[i] for i in sorted(perm[:n_test])]


def plan_phrases(
    words: Sequence[Word],
    *,
    minutes: float,
    rng,
    prefix: str = "utt",
    words_per_phrase=(2, 6),
    rate=(0.8, 1.3),
    jitter: float = 0.1,
    pause_prob: float = 0.2,
    pause=(0.1, 0.35),
    edge=(0.15, 0.3),
    min_phone: float = 0.03,
    max_phone: float = 0.35,
    audio_fraction: float = 0.0,
    mapping: dict | None = None,
) -> list[PhrasePlan]:
    """Draw phrases until their total duration reaches ``minutes``.

    Words are drawn without replacement (a new shuffled pass when the list
    runs out), so a corpus smaller than the lexicon repeats no word.

    Parameters
    ----------
    words : sequence of Word
    minutes : float
        Total duration to reach, pauses included.
    rng : numpy.random.Generator
    prefix : str
        File stems are ``f"{prefix}{k:04d}"``.
    words_per_phrase : (int, int), default (2, 6)
        Inclusive range of words per phrase.
    rate : (float, float), default (0.8, 1.3)
        Range of the per-phrase speaking-rate factor (uniform); phone
        durations are divided by it.
    jitter : float, default 0.1
        Standard deviation of a per-phone log-normal duration factor.
    pause_prob : float, default 0.2
        Probability of a pause between two words.
    pause, edge : (float, float)
        Ranges (s) of pauses between words and of the silence before and
        after the phrase.
    min_phone, max_phone : float, default 0.03, 0.35
        Phone durations are clipped to this range (s); the lexicon's longest
        phones (up to 1 s) are alignment outliers.
    audio_fraction : float, default 0
        Share of the phrases that also get audio: ``round(audio_fraction *
        n_phrases)`` of them, at least one if ``audio_fraction > 0``, evenly
        spread over the list.
    mapping : dict, optional
        Symbol map, default :data:`SYMBOL_MAP`.

    Returns
    -------
    list of PhrasePlan
    """
    if not words:
        raise DataError(None, "words", 0, "no words to draw phrases from")
    mapped = [map_phones(w.phones, mapping, source=f"lexicon word {w.word!r}") for w in words]
    target = 60.0 * minutes
    order: list[int] = []
    plans, total = [], 0.0
    while total < target:
        n = int(rng.integers(words_per_phrase[0], words_per_phrase[1] + 1))
        picked = []
        for _ in range(n):
            if not order:
                order = rng.permutation(len(words)).tolist()
            picked.append(order.pop())
        r = float(rng.uniform(*rate))
        labels, durs, starts = [""], [float(rng.uniform(*edge))], []
        for j, wi in enumerate(picked):
            if j and rng.random() < pause_prob:
                labels.append("")
                durs.append(float(rng.uniform(*pause)))
            starts.append(len(labels))
            factors = np.exp(jitter * rng.standard_normal(len(mapped[wi])))
            for p, d, f in zip(mapped[wi], words[wi].durations, factors):
                labels.append(p)
                durs.append(float(np.clip(d * f / r, min_phone, max_phone)))
        labels.append("")
        durs.append(float(rng.uniform(*edge)))
        durs = tuple(round(d, 3) for d in durs)
        plans.append(
            PhrasePlan(
                f"{prefix}{len(plans):04d}",
                tuple(words[i].word for i in picked),
                tuple(labels),
                durs,
                tuple(starts),
                round(r, 4),
                False,
            )
        )
        total += sum(durs)
    # Audio for an exact, evenly spread share of the phrases (at least one when asked for):
    # a random draw could leave a small test part without any.
    n_audio = min(len(plans), max(1, round(audio_fraction * len(plans)))) if audio_fraction > 0 else 0
    for k in np.unique(np.linspace(0, len(plans) - 1, n_audio).round().astype(int)) if n_audio else ():
        plans[k] = replace(plans[k], audio=True)
    return plans


# -- synthesis (pure functions of a plan) ------------------------------------
def segment_file_text(plan: PhrasePlan) -> str:
    """The VTL segment sequence file of a phrase (``name = ..; duration_s = ..;`` per line)."""
    lines = []
    word_of = {s: w for s, w in zip(plan.word_starts, plan.words)}
    for i, (lab, d) in enumerate(zip(plan.labels, plan.durations)):
        line = f"name = {lab}; duration_s = {d:.6f};"
        if i in word_of:
            # VTL's parser splits on ';' and '=': keep them out of the annotation.
            orth = word_of[i].replace(";", "").replace("=", "")
            line += f" start_of_word = 1; word_orthographic = {orth};"
        lines.append(line)
    return "\n".join(lines) + "\n"


def read_tract_sequence(path) -> np.ndarray:
    """Read the vocal tract states of a VTL tract sequence file.

    The file has ``#`` comment lines, the glottis model name, the number of
    states N, then per state one line of glottis parameters and one line of
    the 19 tract parameters.

    Returns
    -------
    ndarray, shape (N, 19)
    """
    path = os.fspath(path)
    with open(path, encoding="utf-8") as fh:
        lines = [ln for ln in fh.read().splitlines() if ln.strip() and not ln.startswith("#")]
    try:
        n = int(lines[1])
    except (IndexError, ValueError):
        raise DataError(
            path, "number of states", lines[1] if len(lines) > 1 else None, "not a VTL tract sequence file"
        ) from None
    body = lines[2:]
    if len(body) != 2 * n:
        raise DataError(path, "states", len(body) // 2, f"the header announces {n} states")
    tract = np.array([ln.split() for ln in body[1::2]], dtype=float)
    if tract.shape[1] != len(VTL_CHANNELS):
        raise DataError(path, "tract parameters", tract.shape[1], f"expected {len(VTL_CHANNELS)}")
    return tract


def resample_tract(states: np.ndarray, frame_rate: float) -> np.ndarray:
    """Resample VTL states (400.9 Hz, state k at k*110/44100 s) to ``frame_rate``.

    Polyphase resampling by the exact rational ratio, with its anti-aliasing
    low-pass; frame i of the output is the sample at i / frame_rate. The
    ends are padded by linear extrapolation so the filter does not pull them
    towards zero.
    """
    from scipy.signal import resample_poly

    ratio = Fraction(frame_rate).limit_denominator(1000) * Fraction(VTL_SAMPLES_PER_STATE, VTL_AUDIO_RATE)
    if ratio == 1:
        return np.array(states, dtype=float)
    return resample_poly(states, ratio.numerator, ratio.denominator, axis=0, padtype="line")


def synthesize_phrase(plan: PhrasePlan, *, frame_rate: float = 100.0, audio_rate: int = 16000, workdir=None) -> dict:
    """Run VTL on one phrase.

    Returns
    -------
    dict with ``name``, ``alignment`` (:class:`Alignment`), ``trajectory``
    (ndarray, shape (n_frames, 19), ``n_frames = alignment.n_frames(frame_rate)``),
    ``audio`` (int16 ndarray at ``audio_rate`` or None) and ``n_states``.
    """
    vtl = import_vtl()

    check_vtl_symbols([lab for lab in plan.labels if lab], source=plan.name)
    # Durations are whole milliseconds: rounding the sums keeps boundaries exact in the TextGrid.
    ends = np.round(np.cumsum(plan.durations), 3)
    alignment = Alignment(plan.labels, ends - np.asarray(plan.durations), ends, source=plan.name)
    with tempfile.TemporaryDirectory(prefix="dam_vtl_", dir=workdir) as tmp:
        seg, ges, trk = (os.path.join(tmp, f"{plan.name}.{ext}") for ext in ("seg", "ges", "tract"))
        with open(seg, "w", encoding="utf-8") as fh:  # scratch input for VTL, not an output
            fh.write(segment_file_text(plan))
        vtl.phoneme_file_to_gesture_file(seg, ges)
        vtl.gesture_file_to_motor_file(ges, trk)
        states = read_tract_sequence(trk)
        audio = None
        if plan.audio:
            from scipy.signal import resample_poly

            wave = vtl.gesture_file_to_audio(ges)
            r = Fraction(audio_rate, VTL_AUDIO_RATE)
            wave = resample_poly(wave, r.numerator, r.denominator)
            n_audio = int(math.ceil(alignment.duration * audio_rate))
            wave = np.pad(wave, (0, max(0, n_audio - len(wave))))[:n_audio]
            audio = np.round(np.clip(wave, -1.0, 1.0) * 32767).astype(np.int16)
    traj = resample_tract(states, frame_rate)
    n = alignment.n_frames(frame_rate)
    if len(traj) < n:
        raise DataError(
            plan.name,
            "tract sequence",
            f"{len(states)} states",
            f"VTL returned {len(traj)} frames at {frame_rate:g} Hz, the alignment needs {n}",
        )
    return {"name": plan.name, "alignment": alignment, "trajectory": traj[:n], "audio": audio, "n_states": len(states)}


# -- writing --------------------------------------------------------------
def _write_split(
    results: list[dict],
    plans: list[PhrasePlan],
    directory: Path,
    *,
    frame_rate: float,
    trajectory_format: str,
    decimals: int,
    audio_rate: int,
    metadata: dict,
) -> Corpus:
    from scipy.io import wavfile

    from dam.corpus.io import write_csv, write_npy, write_textgrid

    directory.mkdir(parents=True, exist_ok=True)
    utts = []
    for res in results:
        stem = res["name"]
        # npy as float32: half the size of float64 and far finer than any articulograph.
        traj = res["trajectory"].astype(np.float32)
        # The short text format: half the bytes of the long one, read by Praat and praatio alike.
        write_textgrid(res["alignment"], directory / f"{stem}.TextGrid", format="short_textgrid")
        if trajectory_format == "npy":
            write_npy(traj, directory / f"{stem}.npy")
        else:
            write_csv(traj, VTL_CHANNELS, directory / f"{stem}.csv", frame_rate=frame_rate, decimals=decimals)
        audio = None
        if res["audio"] is not None:
            audio = str(directory / f"{stem}.wav")
            with atomic_write(audio, "wb") as fh:
                wavfile.write(fh, audio_rate, res["audio"])
        utts.append(Utterance(res["alignment"], traj, frame_rate, VTL_CHANNELS, audio=audio, name=stem))
    meta = {
        "frame_rate": frame_rate,
        "channels": list(VTL_CHANNELS),
        "units": dict(VTL_UNITS),
        **metadata,
        "utterances": {p.name: {"words": list(p.words), "rate": p.rate, "audio": p.audio} for p in plans},
    }
    with atomic_write(directory / "corpus.json", "w", encoding="utf-8") as fh:
        fh.write(json.dumps(meta, indent=1, ensure_ascii=False) + "\n")
    return Corpus(utts, name=metadata.get("name"), metadata=meta, source=str(directory))


def _run(plans, *, frame_rate, audio_rate, n_jobs, verbose, desc):
    from joblib import Parallel, delayed
    from tqdm.auto import tqdm

    jobs = (delayed(synthesize_phrase)(p, frame_rate=frame_rate, audio_rate=audio_rate) for p in plans)
    # Workers are processes: VTL keeps global state in its C library.
    stream = Parallel(n_jobs=n_jobs, return_as="generator")(jobs)
    show = verbose > 0 and sys.stderr.isatty()
    return list(tqdm(stream, total=len(plans), desc=desc, disable=not show, file=sys.stderr))


def plan_corpus(
    *,
    seed: int = 0,
    n_train_minutes: float = 10.0,
    n_test_minutes: float = 2.5,
    test_word_fraction: float = 0.2,
    audio_fraction: float = 0.05,
    lexicon=None,
    mapping: dict | None = None,
    **plan_options,
) -> tuple[dict, dict]:
    """The phrases :func:`generate_vtl_corpus` synthesizes for these arguments.

    Returns
    -------
    plans : dict
        ``{"train": [PhrasePlan, ...], "test": [...]}``.
    n_words : dict
        Words available to each split.
    """
    words = lexicon if isinstance(lexicon, list) else load_lexicon(lexicon or LEXICON_PATH)
    rng = np.random.default_rng(seed)
    train_words, test_words = split_words(words, test_word_fraction, rng)
    plans = {
        "train": plan_phrases(
            train_words,
            minutes=n_train_minutes,
            rng=rng,
            prefix="train",
            audio_fraction=audio_fraction,
            mapping=mapping,
            **plan_options,
        ),
        "test": plan_phrases(
            test_words,
            minutes=n_test_minutes,
            rng=rng,
            prefix="test",
            audio_fraction=audio_fraction,
            mapping=mapping,
            **plan_options,
        ),
    }
    return plans, {"train": len(train_words), "test": len(test_words)}


def generate_vtl_corpus(
    out_dir,
    *,
    seed: int = 0,
    n_train_minutes: float = 10.0,
    n_test_minutes: float = 2.5,
    test_word_fraction: float = 0.2,
    frame_rate: float = 100.0,
    audio_fraction: float = 0.05,
    audio_rate: int = 16000,
    trajectory_format: str = "npy",
    decimals: int = 5,
    n_jobs: int = 1,
    verbose: int = 1,
    overwrite: bool = False,
    lexicon=None,
    mapping: dict | None = None,
    **plan_options,
) -> dict[str, Corpus]:
    """Generate a VocalTractLab corpus with ``train/`` and ``test/`` parts.

    Parameters
    ----------
    out_dir : path-like
        Receives ``train/`` and ``test/`` corpus directories.
    seed : int, default 0
        Same seed, same files (whatever ``n_jobs``).
    n_train_minutes, n_test_minutes : float, default 10.0, 2.5
        Durations of the two parts, pauses included.
    test_word_fraction : float, default 0.2
        Share of the lexicon's words reserved for test: train and test
        phrases use disjoint words.
    frame_rate : float, default 100.0
        Output frame rate in Hz (at most VTL's 400.9 Hz).
    audio_fraction : float, default 0.05
        Share of phrases that also get a 16-bit WAV (synthesis of audio
        takes about 4 s of CPU per second of speech; trajectories 0.05 s).
    audio_rate : int, default 16000
    trajectory_format : {"npy", "csv"}, default "npy"
        ``npy`` is float32 (n_frames, 19); ``csv`` has a ``time`` column and
        ``decimals`` significant digits.
    n_jobs : int, default 1
        Worker processes (joblib); -1 for all cores.
    verbose : int, default 1
        0 silences the progress bars (shown on a terminal only).
    overwrite : bool, default False
        Replace existing ``train/`` and ``test/`` directories.
    lexicon : path-like or list of Word, optional
        Default :data:`LEXICON_PATH`.
    mapping : dict, optional
        Symbol map, default :data:`SYMBOL_MAP`.
    **plan_options
        Passed to :func:`plan_phrases` (``words_per_phrase``, ``rate``,
        ``pause_prob``, ...).

    Returns
    -------
    dict with keys ``"train"`` and ``"test"``: the corpora as written.
    """
    vtl = import_vtl()

    if not 0 < frame_rate <= VTL_STATE_RATE:
        raise DataError(None, "frame_rate", frame_rate, f"must be in (0, {VTL_STATE_RATE:.1f}] Hz")
    if trajectory_format not in ("npy", "csv"):
        raise DataError(None, "trajectory_format", trajectory_format, "use 'npy' or 'csv'")
    out = Path(out_dir)
    full = [out / split for split in ("train", "test") if (out / split).exists() and any((out / split).iterdir())]
    if full and not overwrite:
        raise DataError(
            str(full[0]),
            "out_dir",
            str(full[0]),
            "exists and is not empty",
            "pass overwrite=True (--overwrite) to replace it",
        )
    # Plan (and check every symbol) before anything is deleted: a bad lexicon must not cost the old corpus.
    plans, n_words = plan_corpus(
        seed=seed,
        n_train_minutes=n_train_minutes,
        n_test_minutes=n_test_minutes,
        test_word_fraction=test_word_fraction,
        audio_fraction=audio_fraction,
        lexicon=lexicon,
        mapping=mapping,
        **plan_options,
    )
    for d in full:
        shutil.rmtree(d)
    version = vtl.get_version()
    corpora = {}
    for split, split_plans in plans.items():
        results = _run(
            split_plans,
            frame_rate=frame_rate,
            audio_rate=audio_rate,
            n_jobs=n_jobs,
            verbose=verbose,
            desc=f"vtl {split}",
        )
        meta = {
            "name": f"vtl-{split}",
            "split": split,
            "generator": "dam.datasets.vtl",
            "seed": seed,
            "vtl_version": f"vocaltractlab-cython {_package_version()}, {version}",
            "speaker": "JD3",
            "lexicon": "articubench 0.3.5 data/lexical_embedding_vectors.pkl",
            "symbol_map": dict(SYMBOL_MAP if mapping is None else mapping),
            "n_words": n_words[split],
            "licence": LICENCE_NOTE,
        }
        corpora[split] = _write_split(
            results,
            split_plans,
            out / split,
            frame_rate=frame_rate,
            trajectory_format=trajectory_format,
            decimals=decimals,
            audio_rate=audio_rate,
            metadata=meta,
        )
    return corpora


def _package_version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("vocaltractlab-cython")
    except PackageNotFoundError:
        return "unknown"


# -- audio for an existing corpus (issue 15) ----------------------------------
#: Audio files of the bundled corpus: FLAC (lossless, about half the bytes of 16-bit WAV).
AUDIO_SUFFIX = ".flac"


def audio_priority(n: int, first=()) -> list[int]:
    """The order in which the ``n`` phrases of a split get audio.

    ``first`` (phrases that already have audio) come first, then the rest in
    bit-reversal (van der Corput) order of their index: any prefix of the
    order is spread evenly over the split, and a larger share always contains
    a smaller one, so audio generated under a CPU budget and audio generated
    later add up to the same set.

    Parameters
    ----------
    n : int
        Number of phrases.
    first : iterable of int
        Indices to put first, in the given order.

    Returns
    -------
    list of int
        A permutation of ``range(n)``.

    Examples
    --------
    >>> audio_priority(8)
    [0, 4, 2, 6, 1, 5, 3, 7]
    """
    bits = max(1, (n - 1).bit_length())
    rev = sorted(range(1 << bits), key=lambda i: int(format(i, f"0{bits}b")[::-1], 2))
    head = [i for i in dict.fromkeys(int(k) for k in first) if 0 <= i < n]
    seen = set(head)
    return head + [i for i in rev if i < n and i not in seen]


def synthesize_audio(plan: PhrasePlan, *, audio_rate: int = 16000, frame_rate: float = 100.0, workdir=None) -> dict:
    """VTL audio of one phrase (deterministic: a pure function of the plan).

    Returns :func:`synthesize_phrase`'s dict (its ``trajectory`` too, so the
    caller can prove the phrase is the one on disk).
    """
    return synthesize_phrase(replace(plan, audio=True), frame_rate=frame_rate, audio_rate=audio_rate, workdir=workdir)


def write_flac(path, samples: np.ndarray, audio_rate: int) -> None:
    """Write int16 ``samples`` as 16-bit FLAC, atomically (needs soundfile, the ``audio`` extra)."""
    try:
        import soundfile
    except ImportError as exc:  # pragma: no cover - depends on the install
        raise ImportError('writing FLAC needs soundfile: pip install "dam[audio]"') from exc
    with atomic_write(path, "wb") as fh:
        soundfile.write(fh, np.asarray(samples, np.int16), int(audio_rate), format="FLAC", subtype="PCM_16")


def add_vtl_audio(
    root,
    *,
    fraction: float = 1.0,
    max_cpu_seconds: float | None = None,
    deadline: float | None = None,
    audio_rate: int = 16000,
    verbose: int = 1,
    splits=("train", "test"),
    lexicon=None,
    mapping: dict | None = None,
) -> dict:
    """Give (more of) a generated vtl corpus its audio, in place; cached and resumable.

    The phrases are planned again from the seed in ``corpus.json`` (the plans
    do not depend on the audio share), checked against the words on disk,
    and synthesized with audio in :func:`audio_priority` order until
    ``fraction`` of every split has a ``<stem>.flac``. Each phrase's
    trajectory is synthesized again on the way and must equal the stored
    ``<stem>.npy`` bit for bit (over its frames: files of an older generator
    may lack the last frame); the trajectories are never rewritten. A
    phrase that has its FLAC is skipped (the cache), so the command can be
    stopped and run again; a phrase that ``corpus.json`` marks as having
    audio but whose file is gone comes first. Older ``<stem>.wav`` files are
    converted to FLAC (same samples) and removed.

    Parameters
    ----------
    root : path-like
        Directory with ``train/`` and ``test/`` (e.g. the bundled
        ``dam/datasets/data/vtl``).
    fraction : float, default 1.0
        Share of the phrases of each split that should have audio.
    max_cpu_seconds : float, optional
        Stop starting new phrases once this process has used that much CPU
        (VTL needs about 4 s per second of speech).
    deadline : float, optional
        Stop starting new phrases after this ``time.time()``.
    audio_rate : int, default 16000
    verbose : int, default 1
        0 silences the progress bar (shown on a terminal only).
    splits : tuple of str, default ("train", "test")
        The splits to work on, in this order.
    lexicon, mapping
        As for :func:`generate_vtl_corpus` (defaults: the bundled ones).

    Returns
    -------
    dict
        ``{split: {"n": phrases, "audio": phrases with audio, "added": new
        this run, "seconds": seconds of speech with audio, "bytes": bytes of
        FLAC}}``.

    Raises
    ------
    DataError
        A ``corpus.json`` that the seed does not reproduce, or a trajectory
        that VTL no longer reproduces bit for bit.
    """
    import time

    from tqdm.auto import tqdm

    root = Path(root)
    t_cpu0 = time.process_time()
    report = {}
    for split in splits:
        d = root / split
        meta_path = d / "corpus.json"
        if not meta_path.exists():
            raise DataError(str(d), "corpus.json", None, "no such file: not a generated vtl corpus split")
        meta = json.loads(meta_path.read_text(encoding="utf-8"))
        frame_rate = float(meta["frame_rate"])
        plans, _ = plan_corpus(
            seed=int(meta.get("seed", 0)),
            lexicon=lexicon,
            mapping=mapping if mapping is not None else meta.get("symbol_map"),
        )
        plans = plans[split]
        stored = meta.get("utterances", {})
        if [p.name for p in plans] != list(stored) or any(list(p.words) != stored[p.name]["words"] for p in plans):
            raise DataError(
                str(meta_path),
                "utterances",
                f"{len(stored)} phrases",
                f"seed {meta.get('seed')} with the default sizes does not plan these phrases; "
                "regenerate the corpus with the audio share you need instead (--audio-fraction)",
            )
        # Old WAVs become FLAC (same int16 samples): one audio format per corpus.
        for p in plans:
            wav = d / f"{p.name}.wav"
            if wav.exists() and not (d / f"{p.name}{AUDIO_SUFFIX}").exists():
                from scipy.io import wavfile

                sr, x = wavfile.read(wav)
                if sr != audio_rate:
                    raise DataError(str(wav), "sample rate", sr, f"expected {audio_rate} Hz")
                write_flac(d / f"{p.name}{AUDIO_SUFFIX}", x, sr)
            if wav.exists():
                wav.unlink()
        have = [i for i, p in enumerate(plans) if (d / f"{p.name}{AUDIO_SUFFIX}").exists()]
        # Phrases corpus.json says have audio come next: a deleted file is made again first.
        lost = [i for i, p in enumerate(plans) if stored[p.name].get("audio") and i not in set(have)]
        order = audio_priority(len(plans), first=have + lost)
        n_target = min(len(plans), math.ceil(fraction * len(plans) - 1e-9))
        todo = [i for i in order[:n_target] if i not in set(have)]
        added = 0
        show = verbose > 0 and sys.stderr.isatty()
        with tqdm(total=len(todo), desc=f"vtl audio {split}", disable=not show, file=sys.stderr) as bar:
            for i in todo:
                if max_cpu_seconds is not None and time.process_time() - t_cpu0 >= max_cpu_seconds:
                    break
                if deadline is not None and time.time() >= deadline:
                    break
                p = plans[i]
                res = synthesize_audio(p, audio_rate=audio_rate, frame_rate=frame_rate)
                npy = d / f"{p.name}.npy"
                if npy.exists():
                    # Bit for bit over the stored frames: an older generator stored one frame fewer
                    # when duration x frame rate fell a rounding error short of a whole frame.
                    old = np.load(npy)
                    new = res["trajectory"].astype(np.float32)
                    if (
                        old.ndim != 2
                        or old.shape[1] != new.shape[1]
                        or not 0 <= len(new) - len(old) <= 1
                        or old.tobytes() != new[: len(old)].tobytes()
                    ):
                        raise DataError(
                            str(npy),
                            "trajectory",
                            p.name,
                            "VTL does not reproduce the stored trajectory bit for bit; the audio "
                            "would not belong to it (another VTL version?)",
                        )
                write_flac(d / f"{p.name}{AUDIO_SUFFIX}", res["audio"], audio_rate)
                added += 1
                bar.update(1)
        on_disk = {p.name for p in plans if (d / f"{p.name}{AUDIO_SUFFIX}").exists()}
        for name, entry in stored.items():
            entry["audio"] = name in on_disk
        meta["audio_rate"] = int(audio_rate)
        meta["audio_format"] = AUDIO_SUFFIX.lstrip(".")
        with atomic_write(meta_path, "w", encoding="utf-8") as fh:
            fh.write(json.dumps(meta, indent=1, ensure_ascii=False) + "\n")
        report[split] = {
            "n": len(plans),
            "audio": len(on_disk),
            "added": added,
            "seconds": float(sum(sum(p.durations) for p in plans if p.name in on_disk)),
            "bytes": int(sum((d / f"{n}{AUDIO_SUFFIX}").stat().st_size for n in on_disk)),
        }
    return report
