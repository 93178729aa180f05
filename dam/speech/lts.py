"""Letter-to-sound rules: English spelling to ARPAbet for words not in the CMU dictionary.

A small, ordered, context-sensitive rule set in the style of Elovitz et al.
(1976, "Letter-to-sound rules for automatic translation of English text to
phonetics", NRL): at each letter the first rule whose grapheme matches and
whose left and right contexts hold gives the phones. Stress: the first vowel
gets primary stress (``1``), the others none (``0``, with AA AE AH EH
reduced to the schwa AH0), the most common English pattern for the short
words that reach this fallback.

It is a fallback, not a dictionary: measured against the CMU dictionary
itself (``benchmarks/bench_speech.py``) it gets simple, regular words right
and long or borrowed words only roughly. Works offline, no data files.
"""

from __future__ import annotations

import re

__all__ = ["letter_to_sound", "LTS_RULES"]

_V = "[aeiouy]"
_C = "[bcdfghjklmnpqrstvwxz]"

# (left context regex anchored at the end, grapheme, right context regex
# anchored at the start, phones). "#" in a context is the word boundary.
# Order matters: the first matching rule wins, so specific rules come first.
LTS_RULES: list[tuple[str, str, str, str]] = [
    # --- multi-letter graphemes, consonants
    ("", "tch", "", "CH"),
    ("", "tion", "", "SH AH N"),
    ("", "sion", "", "ZH AH N"),
    ("", "ture", "", "CH ER"),
    ("", "cious", "", "SH AH S"),
    ("", "tious", "", "SH AH S"),
    ("", "sch", "", "S K"),
    ("", "ch", "", "CH"),
    ("", "sh", "", "SH"),
    ("", "ph", "", "F"),
    ("#", "th", "e#", "DH"),
    ("#", "th", "(is|at|ese|ose|ey|em|en|ere|an|ough|y)#", "DH"),
    ("", "th", "", "TH"),
    ("", "wh", "", "W"),
    ("#", "wr", "", "R"),
    ("#", "kn", "", "N"),
    ("#", "gn", "", "N"),
    ("", "gn", "#", "N"),
    ("", "ck", "", "K"),
    ("", "ng", "#", "NG"),
    ("", "ng", "[^aeiouy]", "NG"),
    ("", "nk", "", "NG K"),
    ("", "qu", "", "K W"),
    ("", "dge", "", "JH"),
    ("", "gh", "t", ""),
    ("#", "gh", "", "G"),
    ("", "gh", "#", ""),
    ("", "mb", "#", "M"),
    ("", "ght", "", "T"),
    ("", "x", "", "K S"),
    # --- doubled consonants read once
    ("", "bb", "", "B"),
    ("", "dd", "", "D"),
    ("", "ff", "", "F"),
    ("", "gg", "", "G"),
    ("", "ll", "", "L"),
    ("", "mm", "", "M"),
    ("", "nn", "", "N"),
    ("", "pp", "", "P"),
    ("", "rr", "", "R"),
    ("", "ss", "", "S"),
    ("", "tt", "", "T"),
    ("", "zz", "", "Z"),
    ("", "cc", "[eiy]", "K S"),
    ("", "cc", "", "K"),
    # --- single consonants
    ("", "c", "[eiy]", "S"),
    ("", "c", "", "K"),
    ("", "g", "e#", "JH"),
    ("", "g", "[ei]" + _C, "JH"),
    ("", "g", "y", "JH"),
    ("", "g", "", "G"),
    ("", "j", "", "JH"),
    ("", "q", "", "K"),
    (_V, "s", "[aeiouy]", "Z"),
    (_V, "s", "#", "Z"),
    ("[bdgvmnlr]", "s", "#", "Z"),
    ("", "s", "", "S"),
    ("", "b", "", "B"),
    ("", "d", "", "D"),
    ("", "f", "", "F"),
    ("#", "h", "", "HH"),
    (_C, "h", "", ""),
    ("", "h", "", "HH"),
    ("", "k", "", "K"),
    ("", "l", "", "L"),
    ("", "m", "", "M"),
    ("", "n", "", "N"),
    ("", "p", "", "P"),
    ("", "r", "", "R"),
    ("", "t", "", "T"),
    ("", "v", "", "V"),
    ("", "w", "", "W"),
    ("", "z", "", "Z"),
    # --- vowels: r-coloured
    ("", "ar", "[^aeiouyr]|#", "AA R"),
    ("", "er", "[^aeiouyr]|#", "ER"),
    ("", "ir", "[^aeiouyr]|#", "ER"),
    ("", "ur", "[^aeiouyr]|#", "ER"),
    ("", "or", "[^aeiouyr]|#", "AO R"),
    ("", "our", "", "AW ER"),
    ("", "ear", "", "IH R"),
    ("", "eer", "", "IH R"),
    ("", "air", "", "EH R"),
    ("", "are", "#", "EH R"),
    ("", "ire", "#", "AY ER"),
    ("", "ore", "#", "AO R"),
    ("", "ure", "#", "Y UH R"),
    # --- vowel digraphs
    ("", "igh", "", "AY"),
    ("", "eigh", "", "EY"),
    ("", "augh", "", "AO"),
    ("", "ough", "t", "AO"),
    ("", "ough", "", "OW"),
    ("", "ee", "", "IY"),
    ("", "ea", "", "IY"),
    ("", "ei", "", "IY"),
    ("", "ie", "#", "AY"),
    ("", "ie", "", "IY"),
    ("", "oo", "k", "UH"),
    ("", "oo", "", "UW"),
    ("", "ou", "", "AW"),
    ("", "ow", "#", "OW"),
    ("", "ow", "", "AW"),
    ("", "oa", "", "OW"),
    ("", "oi", "", "OY"),
    ("", "oy", "", "OY"),
    ("", "ai", "", "EY"),
    ("", "ay", "", "EY"),
    ("", "au", "", "AO"),
    ("", "aw", "", "AO"),
    ("", "ew", "", "UW"),
    ("", "ue", "#", "UW"),
    ("", "ui", "", "UW"),
    ("", "ey", "#", "IY"),
    ("", "ey", "", "EY"),
    # --- final and silent e
    (_V + _C + "+", "e", "#", ""),
    ("#" + _C + "+", "e", "#", "IY"),
    ("", "e", "s#", ""),
    ("", "e", "d#", ""),
    (_C, "le", "#", "AH L"),
    # --- "magic e": vowel + one consonant + e at the end of the word
    ("", "a", _C + "e#", "EY"),
    ("", "i", _C + "e#", "AY"),
    ("", "o", _C + "e#", "OW"),
    ("", "u", _C + "e#", "UW"),
    ("", "e", _C + "e#", "IY"),
    # --- single vowels
    ("#" + _C + "*", "y", "#", "AY"),
    ("", "y", "#", "IY"),
    (_C, "y", _C, "IH"),
    ("", "y", "", "Y"),
    ("", "a", "#", "AH"),
    ("", "a", "", "AE"),
    ("", "e", "", "EH"),
    ("", "i", "", "IH"),
    ("#" + _C + "*", "o", "#", "OW"),
    ("", "o", "", "AA"),
    ("", "u", "", "AH"),
]
_COMPILED = [
    (
        re.compile("(?:" + left + ")$") if left else None,
        g,
        re.compile("(?:" + right + ")") if right else None,
        phones.split(),
    )
    for left, g, right, phones in LTS_RULES
]
_VOWELS = frozenset("AA AE AH AO AW AY EH ER EY IH IY OW OY UH UW".split())
_REDUCED = frozenset("AA AE AH EH".split())


def letter_to_sound(word: str) -> list[str]:
    """ARPAbet phones with stress digits for an English ``word`` by rule.

    Parameters
    ----------
    word : str
        Letters and apostrophes (case ignored); other characters are skipped.

    Returns
    -------
    list of str
        ARPAbet phones; vowels carry a stress digit (first vowel ``1``).

    Examples
    --------
    >>> from dam.speech import letter_to_sound
    >>> letter_to_sound("blick")
    ['B', 'L', 'IH1', 'K']
    >>> letter_to_sound("shade")
    ['SH', 'EY1', 'D']
    """
    w = "".join(ch for ch in word.lower() if "a" <= ch <= "z")
    padded = "#" + w + "#"
    i, phones = 1, []
    while i < len(padded) - 1:
        for left, g, right, out in _COMPILED:
            if not padded.startswith(g, i):
                continue
            if left is not None and not left.search(padded[:i]):
                continue
            if right is not None and not right.match(padded, i + len(g)):
                continue
            phones.extend(out)
            i += len(g)
            break
        else:  # pragma: no cover - every letter has a catch-all rule
            i += 1
    stressed, result = False, []
    for p in phones:
        if p in _VOWELS:
            # unstressed open and mid vowels reduce to schwa, as in most English words
            result.append((("AH" if p in _REDUCED else p) + "0") if stressed else p + "1")
            stressed = True
        else:
            result.append(p)
    return result
