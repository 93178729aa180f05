"""Label files: HTK ``.lab`` (times in 100 ns units) and ESPS/xwaves ``.lab`` (Festival, MOCHA-TIMIT, mngu0)."""

from __future__ import annotations

import os

from dam.corpus.atomic import atomic_write
from dam.corpus.data import SILENCE, Alignment, DataError
from dam.corpus.encoding import read_text

__all__ = ["read_lab", "write_lab", "HTK_UNITS"]

HTK_UNITS = 1e7  # HTK label times are in 100 ns units


def read_lab(path, *, silence: str = SILENCE) -> Alignment:
    """Read a ``.lab`` label file in either of the two formats speech corpora use.

    * HTK: ``start end label`` per line, integer times in 100 ns units.
    * ESPS/xwaves (Festival, MOCHA-TIMIT, mngu0): header lines up to a line
      ``#``, then ``end_time colour label`` per line, times in seconds; each
      segment starts where the previous one ended.

    Decimal times in an HTK-looking file are refused rather than guessed at.
    """
    path = os.fspath(path)
    lines = read_text(path).splitlines()  # UTF-8, BOM dropped (dam.corpus.encoding)
    if any(line.strip() == "#" for line in lines):
        return _read_xlabel(path, lines, silence)
    labels, starts, ends = [], [], []
    for lineno, line in enumerate(lines, 1):
        parts = line.split()
        if not parts or parts[0] == ".":  # '.' ends an HTK master-label entry
            continue
        if len(parts) < 2:
            raise DataError(
                path,
                f"line {lineno}",
                line.strip(),
                "expected 'start end label' with times in 100 ns units",
                "this looks like a plain transcript, not a time-aligned label file",
            )
        try:
            s, e = int(parts[0]), int(parts[1])
        except ValueError:
            raise DataError(
                path,
                f"line {lineno} times",
                " ".join(parts[:2]),
                "HTK label times must be integers in 100 ns units",
                "for times in seconds use an ESPS/xwaves label file (header ending in '#') or a TextGrid",
            ) from None
        try:
            starts.append(s / HTK_UNITS)
            ends.append(e / HTK_UNITS)
        except OverflowError:  # a 400-digit time: the Alignment's bound names the segment otherwise
            raise DataError(
                path,
                f"line {lineno} times",
                " ".join(parts[:2])[:60],
                "time out of range (HTK times are in 100 ns units)",
            ) from None
        labels.append(parts[2] if len(parts) > 2 else "")
    return Alignment(labels, starts, ends, source=path, silence=silence)


def _read_xlabel(path: str, lines: list[str], silence: str) -> Alignment:
    body = lines[next(i for i, line in enumerate(lines) if line.strip() == "#") + 1 :]
    labels, ends = [], []
    for lineno, line in enumerate(body, len(lines) - len(body) + 1):
        parts = line.split(None, 2)
        if not parts:
            continue
        try:
            ends.append(float(parts[0]))
        except (ValueError, OverflowError):
            raise DataError(path, f"line {lineno} end time", parts[0], "not a number (seconds)") from None
        labels.append(parts[2].strip() if len(parts) > 2 else "")
    while ends and ends[0] == 0.0:  # a marker at time 0 opens some files; it spans nothing
        ends.pop(0)
        labels.pop(0)
    if not ends:
        raise DataError(path, "segments", 0, "no labels after the '#' header line")
    starts = [0.0] + ends[:-1]  # each segment starts where the previous one ended
    return Alignment(labels, starts, ends, source=path, silence=silence)


def write_lab(alignment: Alignment, path) -> None:
    """Write an HTK label file (times in 100 ns units)."""
    with atomic_write(path, "w", encoding="utf-8") as fh:
        for lab, s, e in zip(alignment.labels, alignment.starts, alignment.ends):
            fh.write(f"{int(round(s * HTK_UNITS))} {int(round(e * HTK_UNITS))} {lab}\n")
