"""Phonetic categories shared by every model that needs them.

One table of phone -> broad articulatory class for ARPAbet (CMU, as used by
the Montreal Forced Aligner and pocketsphinx, stress digits ignored) and for
German SAMPA (VocalTractLab). Used by the unseen-phone fallback chain and by
the linguistic features of the window-based predictors.

Below them, the phone-set mapping tables (issue 14): ARPAbet (with and
without stress), IPA, X-SAMPA, English SAMPA and the German SAMPA of the vtl
corpus, each mapped to IPA; :func:`map_phones` converts between sets (or onto
the phones a model knows) and reports every approximation it makes.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

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
    "front_vowel": (
        "iy",
        "ih",
        "eh",
        "ae",
        "ey",
        "i",
        "i:",
        "I",
        "e",
        "e:",
        "E",
        "E:",
        "y:",
        "2:",
        "9",
        "Y",
        "2",
        "IY",
        "IH",
        "EH",
        "AE",
        "EY",
    ),
    "central_vowel": ("ah", "ax", "@", "6", "a", "a:", "aI", "aU", "ay", "aw", "AH", "AX", "AY", "AW"),
    "back_vowel": (
        "uw",
        "uh",
        "ao",
        "aa",
        "ow",
        "oy",
        "u",
        "u:",
        "U",
        "o",
        "o:",
        "O",
        "OY",
        "UW",
        "UH",
        "AO",
        "AA",
        "OW",
        "OY_",
    ),
}
_PHONE_TO_CLASS = {p: c for c, phones in _CLASSES.items() for p in phones}
_STRESS = re.compile(r"[012]$")

__all__ = [
    "phone_class",
    "base_phone",
    "fallback_phone",
    "TAYLOR_CATEGORIES",
    "CONSONANTS",
    "guess_alphabet",
    "taylor_categories",
    "is_vowel",
    "is_consonant",
    "ARPABET_TO_IPA",
    "ARPABET_UNSTRESSED_TO_IPA",
    "ARPABET_CMU",
    "GERMAN_SAMPA_TO_IPA",
    "SAMPA_TO_IPA",
    "XSAMPA_TO_IPA",
    "IPA_APPROXIMATIONS",
    "Approximation",
    "to_ipa",
    "from_ipa",
    "convert_phone",
    "map_phones",
]


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
TAYLOR_CATEGORIES: dict[str, frozenset[str]] = {
    name: frozenset(members.split())
    for name, members in [
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
    ]
}
CONSONANTS: frozenset[str] = frozenset("b ch d dh f g hh jh k l m n ng p r s sh t th v w y z zh".split())

# German SAMPA (VocalTractLab) -> the nearest ARPAbet phone(s), used only to
# look up TAYLOR_CATEGORIES. An approximation: German has sounds English lacks.
# A tuple means the union of the categories (affricates /ts/, /pf/).
_SAMPA_TO_ARPABET: dict[str, tuple[str, ...]] = {
    "a": ("aa",),
    "a:": ("aa",),
    "aI": ("ay",),
    "aU": ("aw",),
    "OY": ("oy",),
    "e": ("ey",),
    "e:": ("ey",),
    "E": ("eh",),
    "E:": ("eh",),
    "i": ("iy",),
    "i:": ("iy",),
    "I": ("ih",),
    "o": ("ow",),
    "o:": ("ow",),
    "O": ("ao",),
    "u": ("uw",),
    "u:": ("uw",),
    "U": ("uh",),
    "y": ("iy",),
    "y:": ("iy",),
    "Y": ("ih",),
    "2": ("ey",),
    "2:": ("ey",),
    "9": ("eh",),
    "@": ("ah",),
    "6": ("er",),
    "p": ("p",),
    "b": ("b",),
    "t": ("t",),
    "d": ("d",),
    "k": ("k",),
    "g": ("g",),
    "m": ("m",),
    "n": ("n",),
    "N": ("ng",),
    "f": ("f",),
    "v": ("v",),
    "s": ("s",),
    "z": ("z",),
    "S": ("sh",),
    "Z": ("zh",),
    "C": ("sh",),
    "x": ("hh",),
    "h": ("hh",),
    "j": ("y",),
    "l": ("l",),
    "r": ("r",),
    "R": ("r",),
    "ts": ("t", "s"),
    "pf": ("p", "f"),
    "tS": ("ch",),
    "dZ": ("jh",),
    "?": ("hh",),
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


# ---------------------------------------------------------------------------
# Phone sets and the mapping tables between them (issue 14).
#
# Every phone set is mapped to and from IPA, the pivot: ARPAbet (CMU, with or
# without stress digits), X-SAMPA, English SAMPA and the German SAMPA of the
# bundled vtl corpus (VocalTractLab's symbols). A phone of one set that has an
# exact IPA counterpart in another converts exactly; otherwise the nearest
# phone by the documented table :data:`IPA_APPROXIMATIONS` is used and the
# substitution is reported as an :class:`Approximation`, never made silently.

#: ARPAbet (CMU Pronouncing Dictionary, its 39 phones, plus the TIMIT-era
#: extras) -> IPA, General American values. ``AH0`` and ``ER0`` (unstressed)
#: are the reduced vowels, see :data:`ARPABET_UNSTRESSED_TO_IPA`.
ARPABET_TO_IPA: dict[str, str] = {
    "AA": "ɑ",
    "AE": "æ",
    "AH": "ʌ",
    "AO": "ɔ",
    "AW": "aʊ",
    "AY": "aɪ",
    "EH": "ɛ",
    "ER": "ɝ",
    "EY": "eɪ",
    "IH": "ɪ",
    "IY": "i",
    "OW": "oʊ",
    "OY": "ɔɪ",
    "UH": "ʊ",
    "UW": "u",
    "B": "b",
    "CH": "tʃ",
    "D": "d",
    "DH": "ð",
    "F": "f",
    "G": "ɡ",
    "HH": "h",
    "JH": "dʒ",
    "K": "k",
    "L": "l",
    "M": "m",
    "N": "n",
    "NG": "ŋ",
    "P": "p",
    "R": "ɹ",
    "S": "s",
    "SH": "ʃ",
    "T": "t",
    "TH": "θ",
    "V": "v",
    "W": "w",
    "Y": "j",
    "Z": "z",
    "ZH": "ʒ",
    # extras outside the CMU 39 (TIMIT, Buckeye)
    "AX": "ə",
    "AXR": "ɚ",
    "IX": "ɨ",
    "UX": "ʉ",
    "DX": "ɾ",
    "NX": "ɾ̃",
    "Q": "ʔ",
    "WH": "ʍ",
    "EL": "l̩",
    "EM": "m̩",
    "EN": "n̩",
}
#: Unstressed ARPAbet vowels whose quality differs from the stressed one.
ARPABET_UNSTRESSED_TO_IPA: dict[str, str] = {"AH0": "ə", "ER0": "ɚ"}
#: The 39 phones of the CMU Pronouncing Dictionary.
ARPABET_CMU = frozenset(list(ARPABET_TO_IPA)[:39])

#: German SAMPA as VocalTractLab and the bundled vtl corpus write it -> IPA.
GERMAN_SAMPA_TO_IPA: dict[str, str] = {
    "a": "a",
    "a:": "aː",
    "e": "e",
    "e:": "eː",
    "E": "ɛ",
    "E:": "ɛː",
    "i": "i",
    "i:": "iː",
    "I": "ɪ",
    "o": "o",
    "o:": "oː",
    "O": "ɔ",
    "u": "u",
    "u:": "uː",
    "U": "ʊ",
    "y": "y",
    "y:": "yː",
    "Y": "ʏ",
    "2": "ø",
    "2:": "øː",
    "9": "œ",
    "@": "ə",
    "6": "ɐ",
    "aI": "aɪ",
    "aU": "aʊ",
    "OY": "ɔʏ",
    "p": "p",
    "b": "b",
    "t": "t",
    "d": "d",
    "k": "k",
    "g": "ɡ",
    "?": "ʔ",
    "f": "f",
    "v": "v",
    "T": "θ",
    "D": "ð",
    "s": "s",
    "z": "z",
    "S": "ʃ",
    "Z": "ʒ",
    "C": "ç",
    "j": "j",
    "x": "x",
    "r": "r",
    "R": "ʁ",
    "h": "h",
    "pf": "pf",
    "ts": "ts",
    "tS": "tʃ",
    "dZ": "dʒ",
    "m": "m",
    "n": "n",
    "N": "ŋ",
    "l": "l",
}

#: English SAMPA (Wells) -> IPA.
SAMPA_TO_IPA: dict[str, str] = {
    "A:": "ɑː",
    "{": "æ",
    "V": "ʌ",
    "Q": "ɒ",
    "O:": "ɔː",
    "aU": "aʊ",
    "aI": "aɪ",
    "e": "e",
    "3:": "ɜː",
    "eI": "eɪ",
    "I": "ɪ",
    "i:": "iː",
    "@U": "əʊ",
    "OI": "ɔɪ",
    "U": "ʊ",
    "u:": "uː",
    "@": "ə",
    "I@": "ɪə",
    "e@": "eə",
    "U@": "ʊə",
    "i": "i",
    "u": "u",
    "p": "p",
    "b": "b",
    "t": "t",
    "d": "d",
    "k": "k",
    "g": "ɡ",
    "tS": "tʃ",
    "dZ": "dʒ",
    "f": "f",
    "v": "v",
    "T": "θ",
    "D": "ð",
    "s": "s",
    "z": "z",
    "S": "ʃ",
    "Z": "ʒ",
    "h": "h",
    "m": "m",
    "n": "n",
    "N": "ŋ",
    "l": "l",
    "r": "ɹ",
    "w": "w",
    "j": "j",
    "?": "ʔ",
}

#: X-SAMPA -> IPA for the single symbols (sequences such as ``aI`` or ``t_h``
#: are read symbol by symbol, longest match first).
XSAMPA_TO_IPA: dict[str, str] = {
    "a": "a",
    "b": "b",
    "c": "c",
    "d": "d",
    "e": "e",
    "f": "f",
    "g": "ɡ",
    "h": "h",
    "i": "i",
    "j": "j",
    "k": "k",
    "l": "l",
    "m": "m",
    "n": "n",
    "o": "o",
    "p": "p",
    "q": "q",
    "r": "r",
    "s": "s",
    "t": "t",
    "u": "u",
    "v": "v",
    "w": "w",
    "x": "x",
    "y": "y",
    "z": "z",
    "A": "ɑ",
    "B": "β",
    "C": "ç",
    "D": "ð",
    "E": "ɛ",
    "F": "ɱ",
    "G": "ɣ",
    "H": "ɥ",
    "I": "ɪ",
    "J": "ɲ",
    "K": "ɬ",
    "L": "ʎ",
    "M": "ɯ",
    "N": "ŋ",
    "O": "ɔ",
    "P": "ʋ",
    "Q": "ɒ",
    "R": "ʁ",
    "S": "ʃ",
    "T": "θ",
    "U": "ʊ",
    "V": "ʌ",
    "W": "ʍ",
    "X": "χ",
    "Y": "ʏ",
    "Z": "ʒ",
    "@": "ə",
    "{": "æ",
    "}": "ʉ",
    "1": "ɨ",
    "2": "ø",
    "3": "ɜ",
    "4": "ɾ",
    "5": "ɫ",
    "6": "ɐ",
    "7": "ɤ",
    "8": "ɵ",
    "9": "œ",
    "&": "ɶ",
    "?": "ʔ",
    "?\\": "ʕ",
    "r\\": "ɹ",
    "R\\": "ʀ",
    "h\\": "ɦ",
    "j\\": "ʝ",
    "l\\": "ɺ",
    "z\\": "ʑ",
    "s\\": "ɕ",
    "x\\": "ɧ",
    "3`": "ɝ",
    "@`": "ɚ",
    "r`": "ɽ",
    "t`": "ʈ",
    "d`": "ɖ",
    "n`": "ɳ",
    "s`": "ʂ",
    "z`": "ʐ",
    "l`": "ɭ",
    "O\\": "ʘ",
    ":": "ː",
    "=": "̩",
    "_0": "̥",
    "~": "̃",
}

#: What to use for an IPA phone that a phone set or a model lacks, nearest
#: first (by the visible articulators: lips and jaw first, then tongue). The
#: first candidate the target has wins; the substitution is reported.
IPA_APPROXIMATIONS: dict[str, tuple[str, ...]] = {
    "θ": ("s", "f", "t"),
    "ð": ("d", "z", "v"),
    "w": ("v", "u", "ʊ"),
    "ʍ": ("w", "v", "f"),
    "ɹ": ("ʁ", "r", "ɐ"),
    "r": ("ʁ", "ɹ"),
    "ʁ": ("r", "ɹ"),
    "ɾ": ("t", "d"),
    "ɾ̃": ("n",),
    "ʔ": ("t",),
    "ç": ("ʃ", "h"),
    "x": ("h", "k"),
    "pf": ("f", "p"),
    "ts": ("s", "t"),
    "tʃ": ("ʃ", "t"),
    "dʒ": ("ʒ", "d", "ʃ"),
    "ʒ": ("ʃ", "z"),
    "ŋ": ("n",),
    "j": ("i", "ɪ"),
    "l̩": ("l",),
    "m̩": ("m",),
    "n̩": ("n",),
    "ɫ": ("l",),
    "h": ("ʔ",),
    "æ": ("ɛ", "a", "ɛː"),
    "ʌ": ("a", "ɐ", "ə"),
    "ɑ": ("aː", "a"),
    "ɒ": ("ɔ", "a"),
    "ɔ": ("ɔː", "o", "oː"),
    "ɝ": ("ɐ", "œ", "ə"),
    "ɚ": ("ɐ", "ə"),
    "ɜ": ("œ", "ɐ", "ə"),
    "ɜː": ("œ", "ɐ", "ə"),
    "ə": ("ɐ", "ɛ"),
    "ɐ": ("ə", "a"),
    "ɨ": ("ɪ", "ə"),
    "ʉ": ("u", "ʊ"),
    "eɪ": ("eː", "e", "ɛ"),
    "oʊ": ("oː", "o", "ɔ"),
    "əʊ": ("oː", "o"),
    "ɔɪ": ("ɔʏ",),
    "ɔʏ": ("ɔɪ",),
    "ɪə": ("iː", "ɪ"),
    "eə": ("ɛː", "ɛ"),
    "ʊə": ("uː", "ʊ"),
    "i": ("iː", "ɪ"),
    "u": ("uː", "ʊ"),
    "e": ("eː", "ɛ"),
    "o": ("oː", "ɔ"),
    "a": ("aː", "ɐ"),
    "y": ("yː", "ʏ", "i"),
    "ø": ("øː", "œ", "e"),
    "iː": ("i", "ɪ"),
    "uː": ("u", "ʊ"),
    "eː": ("e", "eɪ", "ɛ"),
    "oː": ("o", "oʊ", "ɔ"),
    "aː": ("a", "ɑ"),
    "ɑː": ("ɑ", "aː", "a"),
    "ɔː": ("ɔ", "o"),
    "ɛː": ("ɛ", "eə"),
    "yː": ("y", "i"),
    "øː": ("ø", "e"),
    "œ": ("ɛ", "ɜː", "ɝ"),
    "ʏ": ("ɪ", "ʊ"),
    "ɪ": ("i", "e"),
    "ʊ": ("u", "o"),
    "ɛ": ("e", "æ"),
}

_ALPHABETS = ("arpabet", "ipa", "xsampa", "sampa", "german-sampa")


def _invert(table: dict[str, str]) -> dict[str, str]:
    out: dict[str, str] = {}
    for k, v in table.items():
        out.setdefault(v, k)  # first listed symbol wins for shared IPA values
    return out


_IPA_TO_ARPABET = _invert(ARPABET_TO_IPA)
_IPA_TO_ARPABET.update({"ə": "AH", "ɚ": "ER"})  # the reduced vowels read back without stress
_IPA_TO_GERMAN = _invert(GERMAN_SAMPA_TO_IPA)
_IPA_TO_SAMPA = _invert(SAMPA_TO_IPA)
_IPA_TO_XSAMPA = _invert(XSAMPA_TO_IPA)
_XSAMPA_KEYS = sorted(XSAMPA_TO_IPA, key=len, reverse=True)


_IPA_KEYS = sorted(_IPA_TO_XSAMPA, key=len, reverse=True)


def _greedy(text: str, table: dict[str, str], keys: list[str]) -> str:
    """Rewrite ``text`` symbol by symbol, longest match first (KeyError if a piece is unknown)."""
    out, i = [], 0
    while i < len(text):
        for k in keys:
            if text.startswith(k, i):
                out.append(table[k])
                i += len(k)
                break
        else:
            raise KeyError(text)
    return "".join(out)


def _xsampa_to_ipa(label: str) -> str:
    return _greedy(label, XSAMPA_TO_IPA, _XSAMPA_KEYS)


def _ipa_to_xsampa(ipa: str) -> str:
    return _greedy(ipa, _IPA_TO_XSAMPA, _IPA_KEYS)


def _check_alphabet(name: str) -> str:
    key = name.lower().replace("_", "-")
    if key == "x-sampa":
        key = "xsampa"
    if key not in _ALPHABETS:
        raise ValueError(f"alphabet is {name!r}; use one of {', '.join(_ALPHABETS)}")
    return key


def to_ipa(label: str, alphabet: str) -> str:
    """The IPA of one phone ``label`` of ``alphabet``.

    Parameters
    ----------
    label : str
        One phone, e.g. ``"TH"``, ``"AH0"`` (ARPAbet, stress digits allowed,
        any case), ``"T"`` (X-SAMPA), ``"a:"`` (German SAMPA).
    alphabet : {"arpabet", "ipa", "xsampa", "sampa", "german-sampa"}

    Raises
    ------
    KeyError
        ``label`` is not a phone of ``alphabet``.

    Examples
    --------
    >>> from dam.corpus.phonetics import to_ipa
    >>> to_ipa("TH", "arpabet"), to_ipa("AH0", "arpabet"), to_ipa("a:", "german-sampa")
    ('θ', 'ə', 'aː')
    """
    a = _check_alphabet(alphabet)
    if a == "ipa":
        return label.replace("g", "ɡ")
    if a == "arpabet":
        up = label.upper()
        if up in ARPABET_UNSTRESSED_TO_IPA:
            return ARPABET_UNSTRESSED_TO_IPA[up]
        return ARPABET_TO_IPA[base_phone(up)]
    if a == "xsampa":
        return _xsampa_to_ipa(label)
    return (SAMPA_TO_IPA if a == "sampa" else GERMAN_SAMPA_TO_IPA)[label]


def from_ipa(ipa: str, alphabet: str) -> str:
    """The phone of ``alphabet`` whose IPA is exactly ``ipa`` (ARPAbet without stress).

    Raises
    ------
    KeyError
        ``alphabet`` has no phone with that IPA; see :func:`map_phones` for
        the nearest one.
    """
    a = _check_alphabet(alphabet)
    ipa = ipa.replace("g", "ɡ")
    if a == "ipa":
        return ipa
    if a == "xsampa":
        return _ipa_to_xsampa(ipa)
    table = {"arpabet": _IPA_TO_ARPABET, "sampa": _IPA_TO_SAMPA, "german-sampa": _IPA_TO_GERMAN}[a]
    return table[ipa]


def convert_phone(label: str, source: str, target: str) -> str:
    """Convert one phone exactly between phone sets (KeyError if there is no exact counterpart).

    Examples
    --------
    >>> from dam.corpus.phonetics import convert_phone
    >>> convert_phone("SH", "arpabet", "german-sampa"), convert_phone("ts", "german-sampa", "xsampa")
    ('S', 'ts')
    """
    return from_ipa(to_ipa(label, source), target)


@dataclass(frozen=True)
class Approximation:
    """One phone replaced by a different one of the target phone set.

    Attributes
    ----------
    phone : str
        The input phone (as given, stress digits removed for ARPAbet).
    ipa : str
        Its IPA.
    replacement : str
        The phone of the target set used instead.
    replacement_ipa : str or None
    reason : str
        Why: ``"nearest in IPA_APPROXIMATIONS"``, ``"same broad class"`` or ``"silence"``.
    """

    phone: str
    ipa: str
    replacement: str
    replacement_ipa: str | None
    reason: str

    def as_dict(self) -> dict:
        return {
            "phone": self.phone,
            "ipa": self.ipa,
            "replacement": self.replacement,
            "replacement_ipa": self.replacement_ipa,
            "reason": self.reason,
        }

    def __str__(self) -> str:
        return (
            f"{self.phone} /{self.ipa}/ -> {self.replacement}"
            + (f" /{self.replacement_ipa}/" if self.replacement_ipa else "")
            + f" ({self.reason})"
        )


def map_phones(
    labels, source: str, target: str, inventory=None, *, silence: str = SILENCE
) -> tuple[list[str], list[Approximation]]:
    """Map phone labels from one phone set onto another (or onto a model's phones).

    Each phone goes through IPA. If the target set (restricted to
    ``inventory`` when given, e.g. the phones a model was trained on) has the
    same IPA phone, the mapping is exact. Otherwise the first candidate of
    :data:`IPA_APPROXIMATIONS` that the target has is used; failing that, the
    most frequent-listed target phone of the same broad class
    (:func:`phone_class`); failing that, silence. Each distinct substitution
    is reported once.

    Parameters
    ----------
    labels : sequence of str, length n
    source, target : {"arpabet", "ipa", "xsampa", "sampa", "german-sampa"}
    inventory : iterable of str, optional
        The allowed target phones (default: every phone of ``target``).
    silence : str, default "sil"
        Passed through unchanged.

    Returns
    -------
    mapped : list of str, length n
    approximations : list of Approximation
        One entry per distinct input phone that was not mapped exactly, in
        order of first appearance.

    Raises
    ------
    KeyError
        A label that is not a phone of ``source``.

    Examples
    --------
    >>> from dam.corpus.phonetics import map_phones
    >>> mapped, approx = map_phones(["TH", "IH1", "NG", "K"], "arpabet", "german-sampa",
    ...                             inventory=["s", "I", "N", "k", "sil"])
    >>> mapped, [a.phone for a in approx]
    (['s', 'I', 'N', 'k'], ['TH'])
    """
    src, tgt = _check_alphabet(source), _check_alphabet(target)
    if inventory is None:
        table = {
            "arpabet": ARPABET_CMU,
            "ipa": None,
            "xsampa": None,
            "sampa": SAMPA_TO_IPA,
            "german-sampa": GERMAN_SAMPA_TO_IPA,
        }[tgt]
        inventory = list(table) if table is not None else None
    inv_ipa: dict[str, str] = {}
    if inventory is not None:
        for p in inventory:
            if p == silence:
                continue
            try:
                inv_ipa.setdefault(to_ipa(p, tgt), base_phone(p) if tgt == "arpabet" else p)
            except KeyError:
                continue  # model phones outside the set (noise labels) are never targets

    def exact(ipa: str) -> str | None:
        if inventory is None:
            try:
                return from_ipa(ipa, tgt)
            except KeyError:
                return None
        return inv_ipa.get(ipa)

    cache: dict[str, tuple[str, Approximation | None]] = {}
    out, approx = [], []
    for lab in labels:
        if lab == silence:
            out.append(silence)
            continue
        if lab not in cache:
            ipa = to_ipa(lab, src)
            shown = base_phone(lab).upper() if src == "arpabet" else lab
            hit = exact(ipa)
            note = None
            if hit is None:
                for cand in IPA_APPROXIMATIONS.get(ipa, ()):
                    hit = exact(cand)
                    if hit is not None:
                        note = Approximation(shown, ipa, hit, cand, "nearest in IPA_APPROXIMATIONS")
                        break
            if hit is None:
                cls = phone_class(_IPA_CLASS_KEY.get(ipa, ipa))
                same = [
                    p for i, p in inv_ipa.items() if cls is not None and phone_class(_IPA_CLASS_KEY.get(i, i)) == cls
                ]
                if same:
                    hit = same[0]
                    note = Approximation(shown, ipa, hit, to_ipa(hit, tgt), "same broad class")
                else:
                    hit = silence
                    note = Approximation(shown, ipa, silence, None, "silence")
            cache[lab] = (hit, note)
            if note is not None and all(a.phone != note.phone for a in approx):
                approx.append(note)
        out.append(cache[lab][0])
    return out, approx


# IPA -> a key that :func:`phone_class` understands (German SAMPA / ARPAbet).
_IPA_CLASS_KEY = {
    **{v: k for k, v in GERMAN_SAMPA_TO_IPA.items()},
    **{v: k.lower() for k, v in ARPABET_TO_IPA.items() if k.lower() in _PHONE_TO_CLASS},
}
