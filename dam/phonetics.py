"""Phonetic categories shared by every model that needs them.

One table of phone -> broad articulatory class for ARPAbet (CMU, as used by
the Montreal Forced Aligner and pocketsphinx, stress digits ignored) and for
German SAMPA (VocalTractLab). Used by the unseen-phone fallback chain and by
the linguistic features of the window-based predictors.
"""
from __future__ import annotations

import re

from .data import SILENCE

# Broad classes by place/manner of the visible articulators: the fallback
# replaces an unseen phone by a seen phone of the same class.
_CLASSES: dict[str, tuple[str, ...]] = {
    "bilabial": ("p", "b", "m", "P", "B", "M"),
    "labiodental": ("f", "v", "pf", "F", "V"),
    "dental": ("th", "dh", "TH", "DH", "T", "D"),
    "alveolar": ("t", "d", "n", "s", "z", "l", "ts", "N_alv", "S_", "Z_"),
    "postalveolar": ("sh", "zh", "ch", "jh", "S", "Z", "tS", "dZ", "SH", "ZH", "CH", "JH", "r", "R"),
    "palatal": ("y", "j", "C", "Y_"),
    "velar": ("k", "g", "ng", "x", "N", "K", "G", "NG", "X"),
    "glottal": ("hh", "h", "?", "HH", "Q"),
    "approximant": ("w", "W", "er", "ER", "L"),
    "front_vowel": ("iy", "ih", "eh", "ae", "ey", "i", "i:", "I", "e", "e:", "E", "E:", "y:", "2:", "9",
                    "IY", "IH", "EH", "AE", "EY"),
    "central_vowel": ("ah", "ax", "@", "6", "a", "a:", "aI", "aU", "ay", "aw", "AH", "AX", "AY", "AW"),
    "back_vowel": ("uw", "uh", "ao", "aa", "ow", "oy", "u", "u:", "U", "o", "o:", "O", "OY", "UW", "UH",
                   "AO", "AA", "OW", "OY_"),
}
_PHONE_TO_CLASS = {p: c for c, phones in _CLASSES.items() for p in phones}
_STRESS = re.compile(r"[012]$")

__all__ = ["phone_class", "base_phone"]


def base_phone(label: str) -> str:
    """The phone without ARPAbet stress digits (``AH0`` -> ``AH``)."""
    return _STRESS.sub("", label) if len(label) > 1 else label


def phone_class(label: str) -> str | None:
    """Broad articulatory class of ``label``; ``"silence"``; or None if unknown."""
    if label == SILENCE:
        return "silence"
    b = base_phone(label)
    return _PHONE_TO_CLASS.get(b) or _PHONE_TO_CLASS.get(b.lower()) or _PHONE_TO_CLASS.get(b.rstrip(":"))


def fallback_phone(label: str, counts: dict[str, int], silence: str = SILENCE) -> str | None:
    """The documented fallback chain for a phone never seen in training.

    1. the same phone without stress digits, if seen;
    2. the most frequent seen phone of the same broad class (:func:`phone_class`);
    3. silence, if seen.
    Returns None when every step fails.
    """
    b = base_phone(label)
    if b in counts:
        return b
    cls = phone_class(label)
    if cls is not None:
        same = [p for p in counts if phone_class(p) == cls]
        if same:
            return max(same, key=lambda p: (counts[p], p))
    return silence if silence in counts else None
