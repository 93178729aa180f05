"""Phonetic categories shared by every model that needs them.

One table of phone -> broad articulatory class for ARPAbet (CMU, as used by
the Montreal Forced Aligner and pocketsphinx, stress digits ignored) and for
German SAMPA (VocalTractLab). Used by the unseen-phone fallback chain and by
the linguistic features of the window-based predictors.
"""
from __future__ import annotations

import re

from dam.corpus.data import SILENCE

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
                    "Y", "2", "IY", "IH", "EH", "AE", "EY"),
    "central_vowel": ("ah", "ax", "@", "6", "a", "a:", "aI", "aU", "ay", "aw", "AH", "AX", "AY", "AW"),
    "back_vowel": ("uw", "uh", "ao", "aa", "ow", "oy", "u", "u:", "U", "o", "o:", "O", "OY", "UW", "UH",
                   "AO", "AA", "OW", "OY_"),
}
_PHONE_TO_CLASS = {p: c for c, phones in _CLASSES.items() for p in phones}
_STRESS = re.compile(r"[012]$")

__all__ = ["phone_class", "base_phone", "fallback_phone", "TAYLOR_CATEGORIES", "CONSONANTS",
           "guess_alphabet", "taylor_categories", "is_vowel", "is_consonant"]


def base_phone(label: str) -> str:
    """The phone without ARPAbet stress digits (``AH0`` -> ``AH``)."""
    return _STRESS.sub("", label) if len(label) > 1 else label


def phone_class(label: str, alphabet: str | None = None) -> str | None:
    """Broad articulatory class of ``label``; ``"silence"``; or None if unknown.

    ``alphabet="arpabet"`` reads upper-case symbols as ARPAbet: ``T D S Z N Y``
    are /t d s z n j/ there, but /θ ð ʃ ʒ ŋ ʏ/ in SAMPA (the default reading).
    """
    if label == SILENCE:
        return "silence"
    b = base_phone(label)
    keys = (b.lower(), b) if alphabet == "arpabet" else (b, b.lower())
    return _PHONE_TO_CLASS.get(keys[0]) or _PHONE_TO_CLASS.get(keys[1]) or _PHONE_TO_CLASS.get(b.rstrip(":"))


def fallback_phone(label: str, counts: dict[str, int], silence: str = SILENCE) -> str | None:
    """The documented fallback chain for a phone never seen in training.

    1. the same phone without stress digits, if seen, in any case for ARPAbet
       (``AA1`` -> ``aa``; SAMPA's /S/ and /s/ differ);
    2. the most frequent seen phone of the same broad class (:func:`phone_class`);
    3. silence, if seen.
    Returns None when every step fails.
    """
    b = base_phone(label)
    if b in counts:
        return b
    alphabet = guess_alphabet([*counts, label])  # the alphabet decides what case means
    same_case = [p for p in counts if p.lower() == b.lower()] if alphabet == "arpabet" else []
    if same_case:
        return same_case[0]
    cls = phone_class(label, alphabet)
    if cls is not None:
        same = [p for p in counts if phone_class(p, alphabet) == cls]
        if same:
            return max(same, key=lambda p: (counts[p], p))
    return silence if silence in counts else None


# ---------------------------------------------------------------------------
# Taylor et al. (2017), supplementary Table 1: the 60 phonetic categories of the
# linguistic indicator features (largely Odell's 1995 questions), as printed,
# in ARPAbet (lower case, no stress). Kept verbatim, typos included: /en/ in
# Front-Vowel (probably /eh/), and /oh/, /ax/, /dx/, /ia/, /ua/, /ea/, /pau/,
# /h/, which are not in the 41-phone set the paper uses; they simply match
# nothing unless a corpus uses them.
TAYLOR_CATEGORIES: dict[str, frozenset[str]] = {name: frozenset(members.split()) for name, members in [
    ("Vowel", "ih uh aa ae ow er iy eh ah aw oy uw ey ao ay"),
    ("Vowel-starting-a", "aa ae ah aw ao ay"),
    ("Vowel-starting-e", "eh ey"),
    ("Vowel-starting-i", "ih iy"),
    ("Vowel-starting-o", "ow oy"),
    ("Vowel-starting-u", "uh uw"),
    ("Vowel-ending-h", "ih uh eh ah"),
    ("Vowel-ending-w", "ow aw uw"),
    ("Vowel-ending-y", "iy oy ey ay"),
    ("Plosive", "b d g k p t"),
    ("Affricative", "ch jh"),
    ("Nasal", "m n ng"),
    ("Fricative", "f v th dh s z sh zh hh"),
    ("Approximant", "w r y"),
    ("Bilabial", "p b m"),
    ("Labiodental", "f v"),
    ("Dental", "th dh"),
    ("Alveolar", "t d n s z l"),
    ("PostAlveolar", "ch jh sh zh r"),
    ("Velar", "k g ng w"),
    ("Unvoiced-Consonant", "p f th t s ch sh k hh"),
    ("Voiced-Consonant", "b m v dh d n z l jh zh r y g ng w"),
    ("Voiced-Plosive", "b d g"),
    ("Unvoiced-Plosive", "p t k"),
    ("Voiced-Fricative", "v dh z zh"),
    ("Unvoiced-Fricative", "f th s sh hh"),
    ("Semi-Consonant", "y w"),
    ("Sibilant-Consonant", "ch jh s z sh zh"),
    ("Sibilant-Affricate", "ch jh"),
    ("Sibilant-Fricative", "s z sh zh"),
    ("Front-Vowel", "iy ih en ae"),
    ("Central-Vowel", "er ax ah"),
    ("Back-Vowel", "uw uh ao aa oh"),
    ("Front-Consonant", "b f m p v w"),
    ("Central-Consonant", "d dh dx l n r s t th z zh"),
    ("Back-Consonant", "ch g hh jh k ng sh y"),
    ("Front-Stop", "b p"),
    ("Central-Stop", "d t"),
    ("Back-Stop", "g k"),
    ("Front-Fricative", "f v"),
    ("Central-Fricative", "dh s th z"),
    ("Back-Fricative", "ch jh sh zh"),
    ("Front", "b f m p v w iy ih en ae"),
    ("Central", "d dh dx l n r s t th z zh er ax ah"),
    ("Back", "ch g hh jh k ng sh y uw uh ao aa oh"),
    ("Long-Vowel", "iy er uw ao aa"),
    ("Short-Vowel", "ih eh ae ax ah uh oh"),
    ("Vowel-Close", "iy ih uw uh"),
    ("Vowel-Mid", "eh er ax ao"),
    ("Vowel-Open", "ae ah aa oh"),
    ("Vowel-Front", "iy ih eh ae"),
    ("Vowel-Central", "er ax ah"),
    ("Vowel-Back", "uw uh ao aa oh"),
    ("Diphthong-Vowel", "ey ay oy ow aw ia ua ea"),
    ("Diphthong-Closing", "ey ay oy ow aw"),
    ("Diphthong-centring", "ia ua ea"),
    ("AVowel", "ay ae aa aw ao"),
    ("OVowel", "ao ow oy oh"),
    ("UVowel", "ah ax ua uh uw"),
    ("silences", "sil pau h"),
]}
CONSONANTS: frozenset[str] = frozenset(
    "b ch d dh f g hh jh k l m n ng p r s sh t th v w y z zh".split())

# German SAMPA (VocalTractLab) -> the nearest ARPAbet phone(s), used only to
# look up TAYLOR_CATEGORIES. An approximation: German has sounds English lacks.
# A tuple means the union of the categories (affricates /ts/, /pf/).
_SAMPA_TO_ARPABET: dict[str, tuple[str, ...]] = {
    "a": ("aa",), "a:": ("aa",), "aI": ("ay",), "aU": ("aw",), "OY": ("oy",), "e": ("ey",), "e:": ("ey",),
    "E": ("eh",), "E:": ("eh",), "i": ("iy",), "i:": ("iy",), "I": ("ih",), "o": ("ow",), "o:": ("ow",),
    "O": ("ao",), "u": ("uw",), "u:": ("uw",), "U": ("uh",), "y": ("iy",), "y:": ("iy",), "Y": ("ih",),
    "2": ("ey",), "2:": ("ey",), "9": ("eh",), "@": ("ah",), "6": ("er",),
    "p": ("p",), "b": ("b",), "t": ("t",), "d": ("d",), "k": ("k",), "g": ("g",), "m": ("m",),
    "n": ("n",), "N": ("ng",), "f": ("f",), "v": ("v",), "s": ("s",), "z": ("z",), "S": ("sh",),
    "Z": ("zh",), "C": ("sh",), "x": ("hh",), "h": ("hh",), "j": ("y",), "l": ("l",), "r": ("r",),
    "R": ("r",), "ts": ("t", "s"), "pf": ("p", "f"), "tS": ("ch",), "dZ": ("jh",), "?": ("hh",),
}
_ARPABET = frozenset().union(*TAYLOR_CATEGORIES.values()) | CONSONANTS


def guess_alphabet(phones) -> str:
    """``"arpabet"`` or ``"sampa"`` for a phone set (case matters: SAMPA /S/ is ARPAbet /sh/).

    ARPAbet when some phone, stress removed, is a two-letter ARPAbet phone
    (lower or upper case: ``AH0``, ``iy``) that is not also SAMPA (``OY``);
    SAMPA otherwise.
    """
    two = {p for p in _ARPABET if len(p) == 2}

    def arpabet_only(p: str) -> bool:
        b = base_phone(p)
        return b not in _SAMPA_TO_ARPABET and (b in two or (b.isupper() and b.lower() in two))
    return "arpabet" if any(arpabet_only(p) for p in phones) else "sampa"


def taylor_categories(label: str, alphabet: str = "arpabet", silence: str = SILENCE) -> frozenset[str]:
    """Names of the :data:`TAYLOR_CATEGORIES` that ``label`` belongs to.

    ``alphabet`` is ``"arpabet"`` or ``"sampa"`` (see :func:`guess_alphabet`);
    SAMPA phones are looked up through their nearest ARPAbet phone. Silence is
    in ``"silences"``; an unknown phone is in no category.
    """
    if label == silence:
        return frozenset({"silences"})
    if alphabet == "sampa":
        arpa = _SAMPA_TO_ARPABET.get(label, ())
    elif alphabet == "arpabet":
        arpa = (base_phone(label).lower(),)
    else:
        raise ValueError(f"alphabet is {alphabet!r}; use 'arpabet' or 'sampa'")
    return frozenset(name for name, members in TAYLOR_CATEGORIES.items() if any(a in members for a in arpa))


def is_vowel(label: str, alphabet: str = "arpabet", silence: str = SILENCE) -> bool:
    """Whether ``label`` is in Taylor et al.'s "Vowel" category (diphthongs included)."""
    return "Vowel" in taylor_categories(label, alphabet, silence)


def is_consonant(label: str, alphabet: str = "arpabet", silence: str = SILENCE) -> bool:
    """Whether ``label`` is a consonant (not silence, not a vowel, a known phone)."""
    if label == silence:
        return False
    if alphabet == "sampa":
        return any(a in CONSONANTS for a in _SAMPA_TO_ARPABET.get(label, ()))
    return base_phone(label).lower() in CONSONANTS
