"""Audio (+ transcript) to a word and phone alignment with pocketsphinx 5.

Forced alignment, as the DAM paper aligned its recordings with SPHINX:
pocketsphinx's bundled en-us acoustic model (continuous HMMs, 16 kHz, 10 ms
frames) and its CMU dictionary; words it lacks get their pronunciation from
:func:`dam.speech.text.text_to_phones` (the CMU dictionary package or the
letter-to-sound rules). Two decoding passes, as pocketsphinx's API needs:
the first aligns words (allowing optional pauses between them, picking among
alternative pronunciations), the second aligns phones and HMM states inside
them. Beams are wide open: the search is exhaustive over the one sentence,
so clean but unusual speech (synthetic voices, fast talkers) still aligns.

Without a transcript, pocketsphinx recognizes phones with its phone n-gram
model (allphone search). That is much less accurate (phone error rates of
30-50% are usual); the result says so in ``method`` and has no word tier.

Times are multiples of 10 ms (pocketsphinx's frame step).
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field

from dam.corpus import SILENCE, Alignment, DataError

from .audio import ALIGN_RATE, load_audio, to_pcm16

__all__ = [
    "align",
    "SpeechAlignment",
    "AlignmentError",
    "write_speech_textgrid",
    "onset_errors",
    "FORCED",
    "PHONE_RECOGNITION",
]

FORCED = "forced alignment (pocketsphinx 5, en-us)"
PHONE_RECOGNITION = (
    "phone recognition (pocketsphinx 5, en-us; no transcript: LESS ACCURATE than forced alignment, phones may be wrong)"
)
_FRAME = 0.01  # pocketsphinx's frame step, seconds
_WIDE = {"beam": 1e-200, "wbeam": 1e-200, "pbeam": 1e-200}


class AlignmentError(DataError):
    """The audio could not be aligned to the transcript (the message says why)."""


@dataclass
class SpeechAlignment:
    """What :func:`align` found: a phone tier, a word tier and how.

    Attributes
    ----------
    phones : Alignment
        ARPAbet without stress digits, pauses ``"sil"``. Usable wherever the
        toolkit takes an alignment (``model.predict(result.phones)``).
    words : Alignment or None
        Lower-case words, pauses ``"sil"``; None for phone recognition.
    method : str
        :data:`FORCED` or :data:`PHONE_RECOGNITION`.
    guessed : list of str
        Transcript words pronounced by the letter-to-sound rules.
    duration : float
        Audio length in seconds.
    """

    phones: Alignment
    words: Alignment | None
    method: str
    guessed: list[str] = field(default_factory=list)
    duration: float = 0.0

    @property
    def less_accurate(self) -> bool:
        """True for phone recognition (no transcript)."""
        return self.method == PHONE_RECOGNITION

    def write_textgrid(self, path) -> None:
        """Write a Praat TextGrid with interval tiers ``words`` and ``phones`` (atomically)."""
        write_speech_textgrid(path, self.phones, self.words)


def _t(frame: int) -> float:
    return round(frame * _FRAME, 6)


def _decoder(**kw):
    try:
        from pocketsphinx import Decoder
    except ImportError as exc:  # pragma: no cover - depends on the install
        raise ImportError('alignment needs pocketsphinx 5: pip install "dam[audio]"') from exc
    return Decoder(loglevel="FATAL", **kw)


def _decode(decoder, pcm: bytes) -> None:
    decoder.start_utt()
    decoder.process_raw(pcm, no_search=False, full_utt=True)
    decoder.end_utt()


def align(
    audio, text: str | None = None, *, sample_rate: float | None = None, source: str | None = None
) -> SpeechAlignment:
    """Align English speech to its transcript (or recognize its phones).

    Parameters
    ----------
    audio : path or array-like, shape (n_samples,) or (n_samples, n_channels)
        Any sample rate and bit depth libsndfile reads; stereo is mixed down
        and everything is resampled to 16 kHz.
    text : str, optional
        The transcript. Numbers and punctuation are read as
        :func:`dam.speech.text.normalize_text` says. Without it, phone
        recognition (:data:`PHONE_RECOGNITION`, much less accurate).
    sample_rate : float, optional
        Needed when ``audio`` is an array.
    source : str, optional
        Named in errors (default: the file name).

    Returns
    -------
    SpeechAlignment
        ``.phones`` (an :class:`~dam.Alignment`, ARPAbet, ``sil`` pauses),
        ``.words``, ``.method``.

    Raises
    ------
    AlignmentError
        The audio does not fit the transcript (wrong words, silence, noise,
        too short); the message says which.
    DataError
        Unreadable audio or unreadable text.

    Examples
    --------
    >>> result = dam.align("speech.wav", "The birch canoe slid on the smooth planks.")  # doctest: +SKIP
    >>> result.phones.labels[:4]  # doctest: +SKIP
    ('sil', 'DH', 'AH', 'B')
    >>> result.write_textgrid("speech.TextGrid")  # doctest: +SKIP
    """
    samples, source = load_audio(audio, sample_rate, rate=ALIGN_RATE, source=source)
    duration = len(samples) / ALIGN_RATE
    if duration < 0.1:
        raise AlignmentError(source, "audio", f"{duration:.3f} s", "too short to align (under 0.1 s)")
    if float(abs(samples).max()) < 1e-4:
        raise AlignmentError(source, "audio", "silence", "the audio is silent; nothing to align")
    pcm = to_pcm16(samples)
    if text is None:
        return _recognize_phones(pcm, duration, source)
    return _force_align(pcm, text, duration, source)


def _force_align(pcm: bytes, text: str, duration: float, source) -> SpeechAlignment:
    from .text import PAUSE, normalize_text, pronounce

    words = [w for w in normalize_text(text, source=source) if w != PAUSE]
    decoder = _decoder(lm=None, bestpath=False, **_WIDE)
    guessed, n_phones = [], 0
    for w in dict.fromkeys(words):
        known = decoder.lookup_word(w)
        if known is None:  # not in pocketsphinx's copy of the CMU dictionary
            phones, by_rule = pronounce(w)
            if by_rule:
                guessed.append(w)
            known = " ".join(re.sub(r"\d$", "", p) for p in phones)
            decoder.add_word(w, known, True)
        n_phones += len(known.split()) * words.count(w)
    n_frames = int(duration / _FRAME)
    if n_frames < 3 * n_phones:
        raise AlignmentError(
            source,
            "audio",
            f"{duration:.2f} s",
            f"too short for the transcript ({len(words)} words); each phone needs 30 ms",
        )
    try:
        decoder.set_align_text(" ".join(words))
        _decode(decoder, pcm)
        decoder.set_alignment()
        _decode(decoder, pcm)
        al = decoder.get_alignment()
    except RuntimeError as exc:
        raise AlignmentError(
            source,
            "transcript",
            " ".join(words),
            "pocketsphinx could not align the audio to this transcript (does the audio say "
            f"these words? is it speech, and not too noisy?) [{exc}]",
        ) from None
    if al is None:  # pragma: no cover - pocketsphinx returns None only without set_alignment
        raise AlignmentError(source, "transcript", " ".join(words), "pocketsphinx returned no alignment")
    w_lab, w_s, w_e, p_lab, p_s, p_e = [], [], [], [], [], []
    for word in al:
        name = re.sub(r"\(\d+\)$", "", word.name)
        start, end = _t(word.start), _t(word.start + word.duration)
        if name in ("<sil>", "<s>", "</s>", "(NULL)") or name.startswith("+"):
            name = SILENCE
        w_lab.append(name)
        w_s.append(start)
        w_e.append(end)
        for ph in word:
            lab = SILENCE if ph.name.upper() == "SIL" or ph.name.startswith("+") else ph.name
            p_lab.append(lab)
            p_s.append(_t(ph.start))
            p_e.append(_t(ph.start + ph.duration))
    got = [w for w in w_lab if w != SILENCE]
    if got != words:
        raise AlignmentError(
            source, "transcript", " ".join(words), f"pocketsphinx aligned different words ({' '.join(got)})"
        )
    phones = _finish(p_lab, p_s, p_e, duration, source)
    word_al = _finish(w_lab, w_s, w_e, duration, source)
    return SpeechAlignment(phones, word_al, FORCED, guessed, duration)


def _finish(labels, starts, ends, duration, source) -> Alignment:
    """Clip to the audio (frames may overrun its last sample); drop empty pieces; stretch the
    last segment (or add silence) to the audio's end."""
    ends = [min(e, duration) for e in ends]
    keep = [i for i in range(len(labels)) if ends[i] - starts[i] > 1e-9]
    labels = [labels[i] for i in keep]
    starts = [starts[i] for i in keep]
    ends = [ends[i] for i in keep]
    if ends and ends[-1] < duration - 1e-9:
        if labels[-1] == SILENCE:
            ends[-1] = duration
        else:
            labels.append(SILENCE)
            starts.append(ends[-1])
            ends.append(duration)
    return Alignment(labels, starts, ends, source=source)


def _recognize_phones(pcm: bytes, duration: float, source) -> SpeechAlignment:
    from pocketsphinx import get_model_path

    lm = os.path.join(get_model_path(), "en-us", "en-us-phone.lm.bin")
    decoder = _decoder(allphone=lm, lm=None, lw=2.0, pip=0.3, beam=1e-200, pbeam=1e-20)
    _decode(decoder, pcm)
    labels, starts, ends = [], [], []
    for seg in decoder.seg():
        lab = SILENCE if seg.word.upper() == "SIL" or seg.word.startswith("+") or seg.word.startswith("<") else seg.word
        s, e = _t(seg.start_frame), _t(seg.end_frame + 1)
        if labels and labels[-1] == lab == SILENCE:
            ends[-1] = e
            continue
        labels.append(lab)
        starts.append(s)
        ends.append(e)
    if not labels or all(lab == SILENCE for lab in labels):
        raise AlignmentError(source, "audio", "no phones", "phone recognition found no speech in the audio")
    return SpeechAlignment(_finish(labels, starts, ends, duration, source), None, PHONE_RECOGNITION, [], duration)


def write_speech_textgrid(path, phones: Alignment, words: Alignment | None = None) -> None:
    """A Praat TextGrid with interval tiers ``words`` (pauses blank) and ``phones`` (pauses ``sil``).

    Written to a temporary file beside ``path`` and moved into place, so a
    failure never leaves a partial TextGrid.
    """
    from praatio import textgrid as ptg

    end = phones.duration if words is None else max(phones.duration, words.duration)
    tg = ptg.Textgrid()
    w_entries = (
        []
        if words is None
        else [
            (s, e, lab)
            for s, e, lab in zip(words.starts.tolist(), words.ends.tolist(), words.labels)
            if lab != words.silence
        ]
    )
    tg.addTier(ptg.IntervalTier("words", w_entries, 0.0, end))
    tg.addTier(
        ptg.IntervalTier("phones", list(zip(phones.starts.tolist(), phones.ends.tolist(), phones.labels)), 0.0, end)
    )
    from dam.corpus.atomic import atomic_path

    with atomic_path(path) as tmp:
        tg.save(tmp, format="long_textgrid", includeBlankSpaces=True, reportingMode="silence")


def onset_errors(result: SpeechAlignment, words, phones) -> tuple[list[float], list[float]]:
    """Onset errors of an alignment against reference timing (tests and benchmarks).

    Parameters
    ----------
    result : SpeechAlignment
        A forced alignment (with a word tier).
    words : list of dict
        Reference word groups in order: ``{"words": "on the", "start": s, "end": e}``
        (a group may hold several words, as espeak-ng joins function words).
    phones : list of dict
        Reference phones: ``{"start": s, "end": e}``.

    Returns
    -------
    word_errors : list of float
        ``|aligned onset - reference onset|`` in seconds, one per group.
    phone_errors : list of float
        The same for phones, inside groups whose phone counts agree (a
        dictionary and a synthesizer may disagree on the phones of a word).

    Raises
    ------
    ValueError
        The aligned words differ from the reference words.
    """
    mine = [
        (w, s, e)
        for w, s, e in zip(result.words.labels, result.words.starts, result.words.ends)
        if w != result.words.silence
    ]
    got_phones = [
        (s, e)
        for p, s, e in zip(result.phones.labels, result.phones.starts, result.phones.ends)
        if p != result.phones.silence
    ]
    w_err, p_err, k = [], [], 0
    for group in words:
        names = group["words"].split()
        part = mine[k : k + len(names)]
        k += len(names)
        if [w for w, _, _ in part] != names:
            raise ValueError(f"aligned words {[w for w, _, _ in part]} differ from the reference {names}")
        w_err.append(abs(part[0][1] - group["start"]))
        got = [s for s, e in got_phones if s >= part[0][1] - 1e-9 and e <= part[-1][2] + 1e-9]
        want = [p["start"] for p in phones if p["start"] >= group["start"] - 1e-9 and p["end"] <= group["end"] + 1e-9]
        if len(got) == len(want):
            p_err += [abs(a - b) for a, b in zip(got, want)]
    return w_err, p_err
