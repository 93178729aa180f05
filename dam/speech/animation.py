"""Text, audio or an alignment in; a model's control trajectories out.

:func:`animate` is the one pipeline behind ``dam animate``:

1. phones with times: from ``text`` (CMU dictionary + letter-to-sound, then
   durations from a :class:`~dam.speech.DurationModel`), from ``audio`` with
   or without its transcript (:func:`dam.speech.align`), or from an
   ``alignment`` (an :class:`~dam.Alignment` or any file
   :func:`dam.read_alignment` reads);
2. the phones are mapped onto the model's phone set through IPA
   (:func:`dam.corpus.phonetics.map_phones`); every phone that has no exact
   counterpart is approximated, warned about once per call
   (:class:`PhoneApproximationWarning`) and listed in ``metadata``;
3. the model predicts the trajectories.

Without a model, the default ships in the package
(:mod:`dam.datasets.default_model`): a DAM fitted on the bundled vtl corpus
(German SAMPA, 19 VocalTractLab tract parameters at 100 Hz).
"""

from __future__ import annotations

import functools
import os
import time
import warnings
from dataclasses import dataclass, field

import numpy as np

from dam.corpus import SILENCE, Alignment, DataError
from dam.corpus.phonetics import GERMAN_SAMPA_TO_IPA, SAMPA_TO_IPA, base_phone, guess_alphabet, map_phones

__all__ = [
    "animate",
    "SpeechAnimation",
    "PhoneApproximationWarning",
    "load_default_model",
    "load_default_durations",
    "model_alphabet",
]


class PhoneApproximationWarning(UserWarning):
    """Input phones were replaced by the nearest phones the model knows."""


@dataclass
class SpeechAnimation:
    """What :func:`animate` produced.

    Attributes
    ----------
    trajectories : ndarray, shape (n_frames, n_channels)
        Frame ``i`` at ``i / frame_rate`` seconds; finite.
    channels : list of str, length n_channels
    frame_rate : float
    alignment : Alignment
        The phones the model was driven with (its own phone set).
    phones : Alignment
        The input phones with their times (ARPAbet for text and audio).
    words : Alignment or None
    metadata : dict
        ``source`` (text/audio/alignment), ``method``, ``model``,
        ``phones`` (input phones), ``model_phones``, ``approximations``
        (list of dicts: phone, ipa, replacement, replacement_ipa, reason,
        used_for), ``guessed_words``, ``rate``, ``seconds`` (time taken).
    """

    trajectories: np.ndarray
    channels: list
    frame_rate: float
    alignment: Alignment
    phones: Alignment
    words: Alignment | None
    metadata: dict = field(default_factory=dict)


def load_default_model():
    """The default animation model shipped in the package (numpy only; a new object each call)."""
    from dam.datasets.default_model import DEFAULT_MODEL_PATH
    from dam.modelfile import load

    return load(DEFAULT_MODEL_PATH)


def load_default_durations():
    """The default :class:`~dam.speech.DurationModel` shipped in the package (a new object each call)."""
    from dam.datasets.default_model import DEFAULT_DURATIONS_PATH

    from .durations import DurationModel

    return DurationModel.load(DEFAULT_DURATIONS_PATH)


@functools.lru_cache(maxsize=1)
def _shared_defaults():
    # read once per process: animate() never changes a model, so calls can share them
    return load_default_model(), load_default_durations()


def model_alphabet(phones) -> str:
    """The phone set of a model's phones: ``arpabet``, ``german-sampa``, ``sampa`` or ``ipa``."""
    phones = [p for p in phones if p != SILENCE]
    if guess_alphabet(phones) == "arpabet":
        return "arpabet"
    for name, table in (("german-sampa", GERMAN_SAMPA_TO_IPA), ("sampa", SAMPA_TO_IPA)):
        if all(p in table for p in phones):
            return name
    if all(_is_ipa(p) for p in phones):
        return "ipa"
    return "german-sampa"


def _is_ipa(p: str) -> bool:
    return any(ord(ch) > 127 for ch in p)


def _resolve_model(model):
    if model is None or (isinstance(model, str) and model == "default"):
        return _shared_defaults()[0], "default (DAM on the bundled vtl corpus)"
    if isinstance(model, (str, os.PathLike)):
        from dam.modelfile import load

        return load(model), os.fspath(model)
    if hasattr(model, "predict") and hasattr(model, "phone_counts_"):
        return model, type(model).__name__
    raise TypeError(f"model must be a fitted synthesizer, a model file or 'default'; got {type(model).__name__}")


def _map(labels, source, target, inventory, used_for, approx: dict):
    """Map, and record each approximation once per (phone, replacement), with what it was used for."""
    mapped, found = map_phones(labels, source, target, inventory)
    for a in found:
        entry = approx.setdefault((a.phone, a.replacement), (a, []))
        if used_for not in entry[1]:
            entry[1].append(used_for)
    return mapped


def animate(
    *,
    text: str | None = None,
    audio=None,
    alignment=None,
    model=None,
    durations=None,
    rate: float = 1.0,
    sample_rate: float | None = None,
    alphabet: str | None = None,
    source: str | None = None,
) -> SpeechAnimation:
    """Animate English text, speech audio or a phone alignment with a model.

    Give exactly one of ``text`` (alone), ``audio`` (with or without
    ``text`` as its transcript) or ``alignment``.

    Parameters
    ----------
    text : str, optional
        English text (read with :func:`dam.speech.text_to_phones`), or the
        transcript of ``audio``.
    audio : path or array-like, optional
        Speech; aligned with :func:`dam.speech.align` (phone recognition
        when there is no transcript, less accurate).
    alignment : Alignment or path, optional
        Phones with times (TextGrid, HTK/xwaves .lab ...).
    model : Synthesizer, path or "default", optional
        A fitted model; default: the DAM shipped in the package.
    durations : DurationModel or path, optional
        For text input; default: the duration model shipped in the package.
    rate : float, default 1.0
        Speaking-rate factor for text input (durations are divided by it).
    sample_rate : float, optional
        The rate of ``audio`` when it is an array.
    alphabet : str, optional
        The phone set of ``alignment`` (guessed when omitted):
        ``arpabet``, ``ipa``, ``xsampa``, ``sampa``, ``german-sampa``.
    source : str, optional
        Named in errors.

    Returns
    -------
    SpeechAnimation
        ``.trajectories`` (n_frames, n_channels), ``.alignment``,
        ``.metadata`` (with the approximations made).

    Raises
    ------
    DataError
        Unreadable input; AlignmentError when audio does not fit its transcript.
    ValueError
        Not exactly one input.

    Examples
    --------
    >>> import warnings
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     result = dam.animate(text="The birch canoe.")
    >>> result.trajectories.shape[1] == len(result.channels)
    True
    >>> [a["phone"] for a in result.metadata["approximations"]]
    ['DH', 'ER', 'CH', 'UW']
    """
    t0 = time.perf_counter()
    given = [
        name
        for name, v in (("text", text if audio is None else None), ("audio", audio), ("alignment", alignment))
        if v is not None
    ]
    if len(given) != 1 or (alignment is not None and text is not None):
        raise ValueError(
            "give exactly one of text=, audio= (optionally with text= as its transcript) "
            f"or alignment=; got {', '.join(given) or 'none'}"
            + (" and text" if alignment is not None and text is not None else "")
        )
    synth, model_name = _resolve_model(model)
    if audio is not None and "audio" in getattr(synth, "reads", lambda: ())():
        return _animate_audio(synth, model_name, audio, sample_rate, source, text, t0)
    inventory = list(synth.phone_counts_)
    target = model_alphabet(inventory)
    approx: dict = {}
    words = None
    guessed: list[str] = []
    stressed = None  # ARPAbet with stress digits, when known (AH0 is a schwa, AH1 is not)
    if audio is not None:
        from .aligner import align

        result = align(audio, text, sample_rate=sample_rate, source=source)
        phones, words, method, guessed = result.phones, result.words, result.method, result.guessed
        src_alphabet = "arpabet"
        stressed = _dictionary_stress(phones, words)
    elif alignment is not None:
        if not isinstance(alignment, Alignment):
            from dam.corpus import read_alignment

            alignment = read_alignment(alignment)
        phones, method = alignment, "given alignment"
        labels = [p for p in alignment.labels if p != alignment.silence]
        src_alphabet = alphabet or model_alphabet(labels)
    else:
        phones, words, guessed, stressed = _text_alignment(text, durations, rate, approx, source)
        method, src_alphabet = "text (CMU dictionary + letter-to-sound, durations from the duration model)", "arpabet"
    try:
        mapped = _map(stressed or list(phones.labels), src_alphabet, target, inventory, "animation", approx)
    except KeyError as exc:
        raise DataError(
            phones.source or source,
            "phone",
            exc.args[0],
            f"not a phone of the {src_alphabet} phone set",
            "pass alphabet= (arpabet, ipa, xsampa, sampa, german-sampa)",
        ) from None
    driven = Alignment(mapped, phones.starts, phones.ends, source=phones.source, silence=phones.silence)
    traj = np.asarray(synth.predict(driven), dtype=float)
    if not np.all(np.isfinite(traj)):  # pragma: no cover - predict() already refuses this
        raise RuntimeError("the model produced non-finite values")
    approximations = [dict(a.as_dict(), used_for=", ".join(u)) for a, u in approx.values()]
    if approximations:
        warnings.warn(
            "phones approximated for the model's phone set ("
            + target
            + "): "
            + "; ".join(f"{a['phone']} -> {a['replacement']} ({a['used_for']})" for a in approximations),
            PhoneApproximationWarning,
            stacklevel=2,
        )
    meta = {
        "source": given[0] if audio is None else ("audio+text" if text is not None else "audio"),
        "method": method,
        "model": model_name,
        "model_alphabet": target,
        "input_alphabet": src_alphabet,
        "phones": [base_phone(p) if src_alphabet == "arpabet" else p for p in phones.labels],
        "model_phones": list(driven.labels),
        "approximations": approximations,
        "guessed_words": guessed,
        "rate": rate,
        "duration": float(phones.duration),
        "seconds": time.perf_counter() - t0,
    }
    return SpeechAnimation(traj, list(synth.channels_), float(synth.frame_rate_), driven, phones, words, meta)


def _animate_audio(synth, model_name, audio, sample_rate, source, text, t0) -> SpeechAnimation:
    """An audio-driven model (issue 15) reads the audio itself: no transcript, no alignment, no phones."""
    from dam.corpus import AudioClip

    from .audio import load_audio

    x, src = load_audio(audio, sample_rate, rate=16000, source=source)
    clip = AudioClip(x, 16000, name=src)
    traj = np.asarray(synth.predict(clip), dtype=float)
    # No phones are known: the animation's alignment is one silence-labelled span of the audio.
    span = Alignment([SILENCE], [0.0], [clip.duration], source=src)
    meta = {
        "source": "audio",
        "method": "audio-driven model (reads the audio; no alignment"
        + (", the transcript is not used)" if text is not None else ")"),
        "model": model_name,
        "model_alphabet": "",
        "input_alphabet": "",
        "phones": [],
        "model_phones": [],
        "approximations": [],
        "guessed_words": [],
        "rate": 1.0,
        "duration": clip.duration,
        "seconds": time.perf_counter() - t0,
    }
    return SpeechAnimation(traj, list(synth.channels_), float(synth.frame_rate_), span, span, None, meta)


def _dictionary_stress(phones: Alignment, words: Alignment | None) -> list[str] | None:
    """The aligned phones with the stress digits of the CMU entry they match (AH0 is a schwa).

    pocketsphinx aligns phones without stress; for each aligned word whose
    phones equal one of its dictionary pronunciations, the digits are taken
    from that entry. Other phones are left as they are.
    """
    if words is None:
        return None
    from .text import cmu_lookup

    out = list(phones.labels)
    for w, ws, we in zip(words.labels, words.starts, words.ends):
        if w == words.silence:
            continue
        idx = [
            k
            for k, (s, e) in enumerate(zip(phones.starts, phones.ends))
            if s >= ws - 1e-9 and e <= we + 1e-9 and phones.labels[k] != phones.silence
        ]
        bare = [phones.labels[k] for k in idx]
        for pron in cmu_lookup(w):
            if [base_phone(p) for p in pron] == bare:
                for k, p in zip(idx, pron):
                    out[k] = p
                break
    return out


def _text_alignment(text, durations, rate, approx, source):
    """Phones with predicted durations for English text: (phones, words, guessed, stressed labels)."""
    from .durations import DurationModel
    from .text import PAUSE, text_to_phones

    if durations is None:
        durations = _shared_defaults()[1]
    elif isinstance(durations, (str, os.PathLike)):
        durations = DurationModel.load(durations)
    pron = text_to_phones(text, source=source)
    labels, word_ids, word_of = [SILENCE], [-1], []
    for i, (w, ps) in enumerate(zip(pron.words, pron.phones)):
        if w == PAUSE:
            labels.append(SILENCE)
            word_ids.append(-1)
            continue
        labels += list(ps)
        word_ids += [i] * len(ps)
        word_of.append(i)
    labels.append(SILENCE)
    word_ids.append(-1)
    dur_inventory = list(durations.phone_means_)
    dur_alphabet = model_alphabet(dur_inventory)
    dur_labels = _map(labels, "arpabet", dur_alphabet, dur_inventory, "durations", approx)
    if dur_alphabet == "arpabet":  # keep stress, which the duration model reads
        dur_labels = [lab if m != SILENCE else m for lab, m in zip(labels, dur_labels)]
    d = durations.predict(dur_labels, word_ids, rate=rate)
    ends = np.cumsum(d)
    starts = ends - d
    phones = Alignment([base_phone(p) for p in labels], starts, ends, source=source or "<text>")
    w_lab, w_s, w_e = [], [], []
    for i in word_of:
        idx = [k for k, w in enumerate(word_ids) if w == i]
        if idx:
            w_lab.append(pron.words[i])
            w_s.append(starts[idx[0]])
            w_e.append(ends[idx[-1]])
    words = Alignment(w_lab, w_s, w_e, source=source or "<text>") if w_lab else None
    return phones, words, list(pron.guessed), labels
