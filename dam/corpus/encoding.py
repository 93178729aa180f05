"""How dam reads text files: one stated rule, so nothing is misread.

The rule
--------
* A file that starts with a UTF-8 byte-order mark is UTF-8; the mark is dropped
  (spreadsheet programs write it in front of CSV headers: without this rule a
  ``time`` column would be read as a channel named ``\\ufefftime``).
* A file that starts with a UTF-16 byte-order mark (little or big endian) is
  UTF-16; Praat writes TextGrids so when a label is not ASCII.
* Anything else must be UTF-8. Bytes that are not (Latin-1 labels from older
  corpora, e.g. ``0xe9`` for ``é``) are refused with a :class:`DataError`
  naming the file and the byte offset; dam never guesses an encoding. Convert
  such a file once, e.g. ``iconv -f latin1 -t utf-8 old.lab > new.lab``.

Every text reader of :mod:`dam.corpus` (CSV, label files, ``corpus.json``,
TextGrids, EST headers) goes through :func:`read_text` or :func:`decode_text`.
"""

from __future__ import annotations

import codecs
import os

from dam.corpus.data import DataError

__all__ = ["read_text", "decode_text", "ENCODING_HINT"]

ENCODING_HINT = (
    "dam reads text as UTF-8 (a byte-order mark is allowed) or UTF-16 with a byte-order mark; "
    "convert the file, e.g. iconv -f latin1 -t utf-8"
)


def decode_text(data: bytes, source=None, *, field: str = "encoding") -> str:
    """Decode ``data`` by the rule above.

    Parameters
    ----------
    data : bytes
    source : str, optional
        The file name, for the error message.
    field : str, default "encoding"

    Returns
    -------
    str
        The text, without a byte-order mark.

    Raises
    ------
    DataError
        The bytes are not valid UTF-8 (or UTF-16 after its mark); the message
        gives the byte offset and the byte.

    Examples
    --------
    >>> from dam.corpus.encoding import decode_text
    >>> decode_text(b"\\xef\\xbb\\xbftime,x\\n")
    'time,x\\n'
    >>> decode_text("é".encode("utf-16"))
    'é'
    >>> decode_text(b"caf\\xe9", "old.lab")
    Traceback (most recent call last):
    ...
    dam.corpus.data.DataError: old.lab: field 'encoding': byte 0xe9 at offset 3 is not UTF-8 (got 'caf\\ufffd'); ...
    """
    if data.startswith(codecs.BOM_UTF8):
        data, codec = data[len(codecs.BOM_UTF8) :], "utf-8"
        start = len(codecs.BOM_UTF8)
    elif data.startswith((codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE)):
        codec, start = "utf-16", 0
    else:
        codec, start = "utf-8", 0
    try:
        return data.decode(codec)
    except UnicodeDecodeError as exc:
        offset = start + exc.start
        context = data[max(0, exc.start - 20) : exc.start + 1].decode(codec, errors="replace")
        raise DataError(
            source,
            field,
            context,
            f"byte 0x{data[exc.start]:02x} at offset {offset} is not {codec.upper()}",
            ENCODING_HINT,
        ) from None


def read_text(path, *, field: str = "encoding") -> str:
    """Read a text file by the rule above; errors name the file.

    Parameters
    ----------
    path : path-like

    Returns
    -------
    str

    Raises
    ------
    DataError
        The file cannot be read (missing, a directory, no permission) or is not
        UTF-8 / BOM-marked UTF-16.
    """
    path = os.fspath(path)
    try:
        with open(path, "rb") as fh:
            data = fh.read()
    except OSError as exc:
        raise DataError(path, "path", path, f"cannot be read ({exc.strerror or exc})") from None
    return decode_text(data, path, field=field)
