"""Speech in: audio and text to timed phones, and on to a model's trajectories.

- :func:`align`: audio (+ transcript) to words and phones with pocketsphinx 5
  (:mod:`dam.speech.aligner`); phone recognition when there is no transcript.
- :func:`text_to_phones`: English text to ARPAbet with the CMU dictionary and
  letter-to-sound rules (:mod:`dam.speech.text`, :mod:`dam.speech.lts`).
- :class:`DurationModel`: context-dependent phone durations
  (:mod:`dam.speech.durations`).
- :func:`animate`: text, audio or an alignment to trajectories
  (:mod:`dam.speech.animation`).

Needs the ``audio`` extra for alignment and the dictionary
(``pip install "dam[audio]"``); imports nothing heavy until used.
"""

from __future__ import annotations

from dam._lazy import lazy_exports

_EXPORTS = {
    **dict.fromkeys(["align", "SpeechAlignment", "AlignmentError", "write_speech_textgrid"], ".aligner"),
    **dict.fromkeys(["text_to_phones", "normalize_text", "number_to_words", "Pronunciation", "cmu_lookup"], ".text"),
    **dict.fromkeys(["letter_to_sound"], ".lts"),
    **dict.fromkeys(["DurationModel", "context_features", "phone_mean_baseline"], ".durations"),
    **dict.fromkeys(
        ["animate", "SpeechAnimation", "PhoneApproximationWarning", "load_default_model", "load_default_durations"],
        ".animation",
    ),
    **dict.fromkeys(["load_audio"], ".audio"),
    **dict.fromkeys(["edit_distance", "phone_error_rate"], ".scoring"),
}
__getattr__, __dir__ = lazy_exports(
    __name__, _EXPORTS, ("aligner", "text", "lts", "durations", "animation", "audio", "scoring")
)

__all__ = list(_EXPORTS)
