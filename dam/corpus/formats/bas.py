"""BAS Partitur Format (``.par``): the output of WebMAUS and the BAS web services.

A BPF file is a header of ``KEY: value`` lines ending with ``LBD:``, then
tiers, one entry a line, the tier's key first::

    LHD: Partitur 1.3
    SAM: 16000                  sample rate of the signal: times are in samples
    LBD:
    ORT: 0 guten                word tier: word number, word
    KAN: 0 g'u:t@n              canonical pronunciation of word 0
    MAU: 0 4799 -1 <p:>         phone tier: begin, duration, word number, phone
    MAU: 4800 799 0 g

In the ``MAU`` tier (and the other segment tiers, ``PHO``, ``SAP``) a segment
covers samples ``begin .. begin + duration`` inclusive, so it starts at
``begin / SAM`` and ends at ``(begin + duration + 1) / SAM`` seconds, where the
next segment begins. Word number ``-1`` marks a segment outside every word
(MAUS pauses ``<p:>``, ``<p>``, and ``<nib>``/``<usb>`` for non-speech). Pauses
become dam's silence label.

Files holding only ``MAU:`` lines (no header) are read too; their sample rate
comes from ``sample_rate=``, else from the WAV file with the same stem.
:func:`write_par` writes a minimal BPF file (LHD, SAM, LBD, MAU, and ORT when
words are given) that :func:`read_par` reads back.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from dam.corpus.atomic import atomic_write
from dam.corpus.data import SILENCE, Alignment, DataError

__all__ = ["read_par", "read_par_tiers", "write_par", "MAUS_PAUSES"]

#: MAUS labels for segments that are not speech sounds, read as silence
MAUS_PAUSES = frozenset({"<p:>", "<p>", "<nib>", "<usb>", "<sil>", "#", "<"})
_SEGMENT_TIERS = ("MAU", "PHO", "SAP")


def read_par_tiers(path) -> tuple[dict, dict]:
    """``(header, tiers)`` of a BPF file: header key -> value; tier key -> list of (line number, fields)."""
    path = os.fspath(path)
    from dam.corpus.encoding import read_text

    lines = read_text(path).splitlines()  # UTF-8 (BOM dropped); other bytes refused with their offset
    header: dict = {}
    tiers: dict = {}
    in_header = not any(line.startswith("MAU:") for line in lines[:1])
    for lineno, line in enumerate(lines, 1):
        if not line.strip():
            continue
        key, sep, rest = line.partition(":")
        if not sep or not key.strip().isalnum():
            raise DataError(path, f"line {lineno}", line.strip(), "expected 'KEY: value' (a BPF tier or header line)")
        key = key.strip()
        if in_header and key == "LBD":
            in_header = False
            continue
        if key in _SEGMENT_TIERS or not in_header:
            tiers.setdefault(key, []).append((lineno, rest.strip()))
        else:
            header[key] = rest.strip()
    return header, tiers


def _wav_rate(path: Path) -> float | None:
    wav = path.with_suffix(".wav")
    if not wav.exists():
        return None
    import wave

    try:
        with wave.open(str(wav), "rb") as w:
            return float(w.getframerate())
    except (wave.Error, EOFError):
        return None


def read_par(path, *, tier: str = "MAU", sample_rate: float | None = None, silence: str = SILENCE) -> Alignment:
    """Read the phone segments of a BAS Partitur file.

    Parameters
    ----------
    path : path-like
    tier : {"MAU", "PHO", "SAP"}, default "MAU"
        The segment tier with the phones.
    sample_rate : float, optional
        Samples per second for files without a ``SAM`` header line
        (default: the rate of ``<stem>.wav`` beside the file).
    silence : str, default "sil"
        MAUS pauses (:data:`MAUS_PAUSES`) become this label.

    Returns
    -------
    Alignment

    Raises
    ------
    DataError
        Naming the file, the line and the value: a missing or non-numeric
        SAM, a tier line that is not ``begin duration word label`` with whole
        numbers, no such tier, overlapping segments.
    """
    p = Path(path)
    path = os.fspath(path)
    header, tiers = read_par_tiers(path)
    rate = header.get("SAM")
    if rate is None:
        rate = sample_rate if sample_rate is not None else _wav_rate(p)
        if rate is None:
            raise DataError(
                path,
                "SAM",
                None,
                "the sample rate is unknown",
                f"add a 'SAM: <rate>' header line, put {p.stem}.wav beside the file, or pass sample_rate=",
            )
    try:
        rate = float(rate)
    except (TypeError, ValueError):
        raise DataError(path, "SAM", rate, "not a number (samples per second)") from None
    if not (np.isfinite(rate) and rate > 0):
        raise DataError(path, "SAM", rate, "must be a positive number")
    if tier not in tiers:
        raise DataError(path, "tier", tier, "no such tier in the file", f"tiers: {sorted(tiers)}")
    labels, starts, ends = [], [], []
    for lineno, rest in tiers[tier]:
        parts = rest.split(None, 3)
        if len(parts) < 4:
            raise DataError(path, f"line {lineno} ({tier})", rest, "expected 'begin duration word label'")
        try:
            begin, dur, _word = int(parts[0]), int(parts[1]), int(parts[2].split(",")[0])
        except ValueError:
            raise DataError(
                path,
                f"line {lineno} ({tier}) begin/duration/word",
                " ".join(parts[:3]),
                "must be whole numbers (samples, samples, word number)",
            ) from None
        if begin < 0 or dur < 0:
            raise DataError(path, f"line {lineno} ({tier}) begin/duration", (begin, dur), "must not be negative")
        label = parts[3].strip()
        labels.append(silence if label in MAUS_PAUSES else label)
        starts.append(begin / rate)
        ends.append((begin + dur + 1) / rate)
    return Alignment(labels, starts, ends, source=path, silence=silence)


def write_par(alignment: Alignment, path, sample_rate: float, *, words=None, header=None) -> None:
    """Write ``alignment`` as a BPF file with a ``MAU`` tier (atomically).

    Parameters
    ----------
    alignment : Alignment
        Silence segments are written as the MAUS pause ``<p:>`` with word number -1.
    path : path-like
    sample_rate : float
        The ``SAM`` rate; segment boundaries are rounded to whole samples.
    words : sequence of (str, sequence of int), optional
        ``(word, indices of its segments)``; written as the ``ORT`` tier and the
        word numbers of ``MAU``. Default: every non-silence segment is its own
        word, numbered 0, 1, ... in order; pauses have word number -1.
    header : dict, optional
        Further header lines (``{"SPN": "speaker1"}``).

    Examples
    --------
    >>> import tempfile, os
    >>> from dam.corpus import Alignment
    >>> p = os.path.join(tempfile.mkdtemp(), "a.par")
    >>> write_par(Alignment(["sil", "a", "b"], [0, 0.1, 0.2], [0.1, 0.2, 0.35]), p, 16000)
    >>> read_par(p).labels
    ('sil', 'a', 'b')
    """
    path = os.fspath(path)
    rate = float(sample_rate)
    if not (np.isfinite(rate) and rate > 0):
        raise DataError(path, "sample_rate", sample_rate, "must be a positive number")
    bounds = np.rint(np.append(alignment.starts, alignment.ends[-1]) * rate).astype(np.int64)
    word_of = {}
    if words is not None:
        for w, (_, idx) in enumerate(words):
            for i in idx:
                word_of[int(i)] = w
    lines = ["LHD: Partitur 1.3", f"SAM: {rate:g}"]
    lines += [f"{k}: {v}" for k, v in (header or {}).items()]
    lines.append("LBD:")
    if words is not None:
        lines += [f"ORT: {w} {word}" for w, (word, _) in enumerate(words)]
    count = 0
    for i, lab in enumerate(alignment.labels):
        begin, end = int(bounds[i]), int(bounds[i + 1])
        if end - begin < 1:
            raise DataError(
                path,
                f"segment {i} ({lab!r})",
                (alignment.starts[i], alignment.ends[i]),
                f"shorter than one sample at {rate:g} samples/s",
            )
        if lab == alignment.silence:
            word, lab = -1, "<p:>"
        elif words is not None:
            word = word_of.get(i, -1)
        else:
            word, count = count, count + 1
        if any(ch.isspace() for ch in lab):
            raise DataError(path, f"segment {i} label", lab, "BPF labels cannot contain white space")
        lines.append(f"MAU: {begin} {end - begin - 1} {word} {lab}")
    with atomic_write(path, "wb") as fh:
        fh.write(("\n".join(lines) + "\n").encode("utf-8"))
