"""Corpus I/O in the formats speech scientists already have.

A corpus directory holds

* ``corpus.json`` (optional): ``frame_rate``, ``channels``; anything else is
  kept as ``Corpus.metadata``;
* per utterance, a phone alignment: a Praat TextGrid (long or short text
  format; the tier named ``phones``, else the first interval tier) or an HTK
  ``.lab`` file (``start end label`` per line, times in 100 ns units);
* with the same file stem, a trajectory: ``.csv`` with a header row of channel
  names and an optional leading ``time`` column in seconds (which then fixes
  the frame rate), ``.npy`` of shape (n_frames, n_channels), or an EST track
  (``.ema``, ``.est``, ``.trk``; mngu0/MOCHA-TIMIT EMA, see :mod:`dam.est`);
  other readers can be added to :data:`TRAJECTORY_READERS`;
* optionally ``<stem>.wav``, the utterance's audio.

Every error names the file, the field and the value.
"""
from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Callable

import numpy as np

from .data import SILENCE, Alignment, Corpus, DataError, Utterance

__all__ = ["read_alignment", "read_textgrid", "read_lab", "read_trajectory", "load_corpus",
           "write_textgrid", "write_lab", "write_csv", "write_npy", "write_utterance", "save_corpus",
           "TRAJECTORY_READERS", "ALIGNMENT_SUFFIXES"]

HTK_UNITS = 1e7  # HTK label times are in 100 ns units
ALIGNMENT_SUFFIXES = (".textgrid", ".lab")


# -- alignments -----------------------------------------------------------
def read_textgrid(path, *, tier: str | None = "phones", silence: str = SILENCE) -> Alignment:
    """Read one interval tier of a Praat TextGrid (long or short text format).

    Parameters
    ----------
    path : path-like
    tier : str or None, default "phones"
        Tier name. If the TextGrid has no tier of that name (and ``tier`` is
        the default), the first interval tier is used; a name given
        explicitly must exist.
    silence : str, default "sil"
    """
    from praatio import textgrid as ptg
    path = os.fspath(path)
    try:
        tg = ptg.openTextgrid(path, includeEmptyIntervals=True, reportingMode="silence")
    except Exception as exc:  # praatio raises many types for malformed files
        detail = " ".join(str(exc).split())
        raise DataError(path, "TextGrid", type(exc).__name__, f"cannot be parsed: {detail}") from None
    interval_tiers = [n for n in tg.tierNames if isinstance(tg.getTier(n), ptg.IntervalTier)]
    if tier in tg.tierNames and tier in interval_tiers:
        name = tier
    elif tier is not None and tier != "phones":
        raise DataError(path, "tier", tier, "no interval tier of that name",
                        f"interval tiers: {interval_tiers}")
    elif interval_tiers:
        name = interval_tiers[0]
    else:
        raise DataError(path, "tier", tier, "the TextGrid has no interval tier")
    entries = tg.getTier(name).entries
    if not entries:
        raise DataError(path, f"tier {name!r}", 0, "the tier has no intervals")
    labels = [e.label for e in entries]
    return Alignment(labels, [e.start for e in entries], [e.end for e in entries],
                     source=path, silence=silence)


def read_lab(path, *, silence: str = SILENCE) -> Alignment:
    """Read a ``.lab`` label file in either of the two formats speech corpora use.

    * HTK: ``start end label`` per line, integer times in 100 ns units.
    * ESPS/xwaves (Festival, MOCHA-TIMIT, mngu0): header lines up to a line
      ``#``, then ``end_time colour label`` per line, times in seconds; each
      segment starts where the previous one ended.

    Decimal times in an HTK-looking file are refused rather than guessed at.
    """
    path = os.fspath(path)
    with open(path, encoding="utf-8") as fh:
        lines = fh.read().splitlines()
    if any(line.strip() == "#" for line in lines):
        return _read_xlabel(path, lines, silence)
    labels, starts, ends = [], [], []
    for lineno, line in enumerate(lines, 1):
        parts = line.split()
        if not parts or parts[0] == ".":  # '.' ends an HTK master-label entry
            continue
        if len(parts) < 2:
            raise DataError(path, f"line {lineno}", line.strip(),
                            "expected 'start end label' with times in 100 ns units",
                            "this looks like a plain transcript, not a time-aligned label file")
        try:
            s, e = int(parts[0]), int(parts[1])
        except ValueError:
            raise DataError(path, f"line {lineno} times", " ".join(parts[:2]),
                            "HTK label times must be integers in 100 ns units",
                            "for times in seconds use an ESPS/xwaves label file (header ending in '#') "
                            "or a TextGrid") from None
        starts.append(s / HTK_UNITS)
        ends.append(e / HTK_UNITS)
        labels.append(parts[2] if len(parts) > 2 else "")
    return Alignment(labels, starts, ends, source=path, silence=silence)


def _read_xlabel(path: str, lines: list[str], silence: str) -> Alignment:
    body = lines[next(i for i, line in enumerate(lines) if line.strip() == "#") + 1:]
    labels, ends = [], []
    for lineno, line in enumerate(body, len(lines) - len(body) + 1):
        parts = line.split(None, 2)
        if not parts:
            continue
        try:
            ends.append(float(parts[0]))
        except ValueError:
            raise DataError(path, f"line {lineno} end time", parts[0], "not a number (seconds)") from None
        labels.append(parts[2].strip() if len(parts) > 2 else "")
    while ends and ends[0] == 0.0:  # a marker at time 0 opens some files; it spans nothing
        ends.pop(0)
        labels.pop(0)
    if not ends:
        raise DataError(path, "segments", 0, "no labels after the '#' header line")
    starts = [0.0] + ends[:-1]  # each segment starts where the previous one ended
    return Alignment(labels, starts, ends, source=path, silence=silence)


def read_alignment(path, *, tier: str | None = "phones", silence: str = SILENCE) -> Alignment:
    """Read a TextGrid or HTK ``.lab`` alignment, by file extension."""
    suffix = Path(path).suffix.lower()
    if suffix == ".textgrid":
        return read_textgrid(path, tier=tier, silence=silence)
    if suffix == ".lab":
        return read_lab(path, silence=silence)
    raise DataError(os.fspath(path), "extension", suffix, "not an alignment format",
                    "use a Praat .TextGrid or an HTK .lab file")


# -- trajectories ---------------------------------------------------------
def _read_csv(path: str) -> tuple[np.ndarray, list[str], float | None]:
    with open(path, encoding="utf-8") as fh:
        header = fh.readline()
    names = [h.strip().strip('"') for h in header.strip().split(",")]
    if not header.strip() or not names:
        raise DataError(path, "header", header.strip(), "expected a header row of channel names")
    try:
        data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    except ValueError as exc:
        raise DataError(path, "values", str(exc).split("\n")[0], "not a numeric CSV table") from None
    if data.shape[0] and data.shape[1] != len(names):
        raise DataError(path, "columns", data.shape[1], f"the header names {len(names)} columns")
    frame_rate = None
    if names and names[0].lower() == "time":
        t, data, names = data[:, 0], data[:, 1:], names[1:]
        frame_rate = frame_rate_from_times(t, path, where="time (row {})")
    return data, names, frame_rate


def frame_rate_from_times(times, source, *, where: str = "time (frame {})", first: int = 1) -> float | None:
    """Frames per second of evenly spaced frame times that start at 0; None for < 2 frames.

    ``where`` formats the field of an error with the 1-based index of the
    offending frame (counted from ``first``).
    """
    t = np.asarray(times, dtype=float)
    if len(t) < 2:
        return None
    step = np.diff(t)
    dt = float(np.median(step))
    if not dt > 0 or np.max(np.abs(step - dt)) > 0.01 * dt:
        k = int(np.argmax(np.abs(step - dt)))
        raise DataError(source, where.format(k + 1 + first), float(t[k + 1]),
                        f"the frame times are not evenly spaced (median step {dt:g} s)")
    if abs(t[0]) > 0.5 * dt:
        raise DataError(source, where.format(first), float(t[0]),
                        "the first frame must be at time 0 (frame i is at i / frame_rate)",
                        "pad the trajectory to start at 0 or shift the alignment")
    return 1.0 / dt


def _read_npy(path: str) -> tuple[np.ndarray, list[str] | None, float | None]:
    try:
        data = np.load(path, allow_pickle=False)
    except Exception as exc:
        raise DataError(path, "npy", type(exc).__name__, f"cannot be read: {exc}") from None
    if data.ndim == 1:
        data = data[:, None]
    if data.ndim != 2:
        raise DataError(path, "shape", data.shape, "must be (n_frames, n_channels)")
    return data, None, None


def _read_est(path: str) -> tuple[np.ndarray, list[str] | None, float | None]:
    from .est import read_est_trajectory  # EST tracks (mngu0, MOCHA-TIMIT EMA)
    return read_est_trajectory(path)


#: suffix -> reader(path) returning (data, channel names or None, frame rate or None)
TRAJECTORY_READERS: dict[str, Callable] = {".csv": _read_csv, ".npy": _read_npy,
                                           ".ema": _read_est, ".est": _read_est, ".trk": _read_est}


def read_trajectory(path) -> tuple[np.ndarray, list[str] | None, float | None]:
    """Read a trajectory file; returns ``(data, channels or None, frame_rate or None)``."""
    path = os.fspath(path)
    suffix = Path(path).suffix.lower()
    if suffix not in TRAJECTORY_READERS:
        raise DataError(path, "extension", suffix, "not a trajectory format",
                        f"supported: {', '.join(TRAJECTORY_READERS)}")
    return TRAJECTORY_READERS[suffix](path)


# -- corpora --------------------------------------------------------------
def load_corpus(path, *, tier: str | None = "phones", silence: str = SILENCE,
                frame_rate: float | None = None) -> Corpus:
    """Read a corpus directory (see the module docstring).

    Parameters
    ----------
    path : path-like
        The directory.
    tier : str, default "phones"
        TextGrid tier holding the phones.
    silence : str, default "sil"
        Canonical silence label.
    frame_rate : float, optional
        Overrides ``corpus.json``; needed when neither it nor a CSV ``time``
        column gives the frame rate.

    Returns
    -------
    Corpus
    """
    root = Path(path)
    if not root.is_dir():
        raise DataError(os.fspath(path), "path", os.fspath(path), "not a directory")
    meta: dict = {}
    meta_path = root / "corpus.json"
    if meta_path.exists():
        try:
            meta = json.loads(meta_path.read_text(encoding="utf-8"))
        except json.JSONDecodeError as exc:
            raise DataError(str(meta_path), "json", exc.msg, f"invalid JSON at line {exc.lineno}") from None
        if not isinstance(meta, dict):
            raise DataError(str(meta_path), "json", type(meta).__name__, "must hold a JSON object")
    fr = frame_rate if frame_rate is not None else meta.get("frame_rate")
    channels = meta.get("channels")
    files = sorted(p for p in root.iterdir() if p.is_file())
    aligns = [p for p in files if p.suffix.lower() in ALIGNMENT_SUFFIXES]
    if not aligns:
        raise DataError(str(root), "alignments", 0, "no .TextGrid or .lab files in the directory",
                        "a corpus directory holds <stem>.TextGrid (or .lab) + <stem>.csv (or .npy) per utterance")
    by_stem: dict[str, list[Path]] = {}
    for p in files:
        by_stem.setdefault(p.stem, []).append(p)
    seen_stems = set()
    utts = []
    for apath in aligns:
        stem = apath.stem
        if stem in seen_stems:
            raise DataError(str(apath), "stem", stem, "two alignment files share this stem")
        seen_stems.add(stem)
        trajs = [p for p in by_stem[stem] if p.suffix.lower() in TRAJECTORY_READERS]
        if not trajs:
            raise DataError(str(apath), "trajectory", stem,
                            f"no trajectory file {stem}{{{','.join(TRAJECTORY_READERS)}}} beside the alignment")
        if len(trajs) > 1:
            raise DataError(str(apath), "trajectory", [p.name for p in trajs], "more than one trajectory file")
        tpath = str(trajs[0])
        alignment = read_alignment(apath, tier=tier, silence=silence)
        data, names, file_fr = read_trajectory(tpath)
        if names is None:
            if channels is None:
                names = [f"c{i}" for i in range(data.shape[1])]
            else:
                names = list(channels)
        elif channels is not None and list(channels) != list(names):
            raise DataError(tpath, "channels", names, f"differ from corpus.json channels {list(channels)}")
        this_fr = fr
        if file_fr is not None:
            if fr is not None and abs(file_fr - float(fr)) > 0.01 * float(fr):
                raise DataError(tpath, "time", f"{file_fr:g} frames/s",
                                f"the time column disagrees with frame_rate {float(fr):g} of corpus.json")
            this_fr = float(fr) if fr is not None else round(file_fr, 6)
        if this_fr is None:
            raise DataError(tpath, "frame_rate", None, "the frame rate is unknown",
                            "add corpus.json with \"frame_rate\", a leading time column, or pass frame_rate=")
        wav = by_stem[stem]
        audio = next((str(p) for p in wav if p.suffix.lower() == ".wav"), None)
        utts.append(Utterance(alignment, data, this_fr, names, audio=audio, name=stem, source=tpath))
    extra = {k: v for k, v in meta.items() if k not in ("frame_rate", "channels")}
    return Corpus(utts, name=meta.get("name", root.name), metadata=extra, source=str(root))


# -- writers --------------------------------------------------------------
def write_textgrid(alignment: Alignment, path, *, tier: str = "phones",
                   format: str = "long_textgrid") -> None:
    """Write ``alignment`` as a one-tier Praat TextGrid (silence keeps its canonical label)."""
    from praatio import textgrid as ptg
    entries = list(zip(alignment.starts.tolist(), alignment.ends.tolist(), alignment.labels))
    tg = ptg.Textgrid()
    tg.addTier(ptg.IntervalTier(tier, entries, 0.0, alignment.duration))
    tg.save(os.fspath(path), format=format, includeBlankSpaces=True, reportingMode="silence")


def write_lab(alignment: Alignment, path) -> None:
    """Write an HTK label file (times in 100 ns units)."""
    with open(path, "w", encoding="utf-8") as fh:
        for lab, s, e in zip(alignment.labels, alignment.starts, alignment.ends):
            fh.write(f"{int(round(s * HTK_UNITS))} {int(round(e * HTK_UNITS))} {lab}\n")


def write_csv(trajectory, channels, path, *, frame_rate: float | None = None, decimals: int | None = 6) -> None:
    """Write a trajectory CSV with a header row; a leading ``time`` column if ``frame_rate`` is given."""
    data = np.asarray(trajectory, dtype=float)
    names = list(channels)
    if data.ndim != 2 or data.shape[1] != len(names):
        raise DataError(os.fspath(path), "channels", len(names), f"trajectory has shape {data.shape}")
    if frame_rate is not None:
        data = np.column_stack([np.arange(len(data)) / frame_rate, data])
        names = ["time"] + names
    fmt = "%.17g" if decimals is None else f"%.{decimals}g"
    np.savetxt(path, data, delimiter=",", header=",".join(names), comments="", fmt=fmt)


def write_npy(trajectory, path) -> None:
    np.save(path, np.asarray(trajectory))


def write_utterance(utt: Utterance, directory, *, alignment_format: str = "TextGrid",
                    trajectory_format: str = "csv", decimals: int | None = 6) -> None:
    """Write one utterance as ``<name>.TextGrid|.lab`` + ``<name>.csv|.npy`` in ``directory``."""
    d = Path(directory)
    d.mkdir(parents=True, exist_ok=True)
    name = utt.name or "utterance"
    if alignment_format.lower() == "textgrid":
        write_textgrid(utt.alignment, d / f"{name}.TextGrid")
    elif alignment_format.lower() == "lab":
        write_lab(utt.alignment, d / f"{name}.lab")
    else:
        raise ValueError(f"alignment_format is {alignment_format!r}; use 'TextGrid' or 'lab'")
    if trajectory_format == "csv":
        write_csv(utt.trajectory, utt.channels, d / f"{name}.csv", frame_rate=utt.frame_rate, decimals=decimals)
    elif trajectory_format == "npy":
        write_npy(utt.trajectory, d / f"{name}.npy")
    else:
        raise ValueError(f"trajectory_format is {trajectory_format!r}; use 'csv' or 'npy'")


def save_corpus(corpus: Corpus, directory, *, alignment_format: str = "TextGrid",
                trajectory_format: str = "csv", decimals: int | None = 6, metadata: dict | None = None) -> None:
    """Write ``corpus`` as a corpus directory that :func:`load_corpus` reads back."""
    d = Path(directory)
    d.mkdir(parents=True, exist_ok=True)
    meta = {"frame_rate": corpus.frame_rate, "channels": list(corpus.channels)}
    if corpus.name:
        meta["name"] = corpus.name
    # frame_rate and channels describe the files written here: metadata may not override them.
    meta.update({k: v for k, v in {**corpus.metadata, **(metadata or {})}.items()
                 if k not in ("frame_rate", "channels")})
    (d / "corpus.json").write_text(json.dumps(meta, indent=2) + "\n", encoding="utf-8")
    for k, u in enumerate(corpus):
        if u.name is None:
            u = u.replace(name=f"utt{k:04d}")
        write_utterance(u, d, alignment_format=alignment_format, trajectory_format=trajectory_format,
                        decimals=decimals)
