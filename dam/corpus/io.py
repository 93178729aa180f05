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
  (``.ema``, ``.est``, ``.trk``; mngu0/MOCHA-TIMIT EMA, see :mod:`dam.corpus.formats.est`);
  other readers can be added to :data:`TRAJECTORY_READERS`;
* optionally ``<stem>.wav`` or ``<stem>.flac``, the utterance's audio (its sample rate
  checked against ``audio_rate`` of corpus.json when given), and ``<stem>.mask.npy``, its
  missing-data mask (bool, shape of the trajectory, True = observed; written by
  :func:`save_corpus` for utterances that have one).

Every error names the file, the field and the value.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable
from pathlib import Path

import numpy as np

from dam.corpus.atomic import atomic_write
from dam.corpus.data import SILENCE, Alignment, Corpus, DataError, Utterance, resolve_sensors
from dam.corpus.encoding import read_text
from dam.corpus.formats.audio import AUDIO_SUFFIXES, audio_header
from dam.corpus.formats.bas import read_par
from dam.corpus.formats.detect import CORPUS_FORMATS, detect_format, load_formatted
from dam.corpus.formats.est import read_est_trajectory
from dam.corpus.formats.htk import read_lab, write_lab
from dam.corpus.formats.tables import frame_rate_from_times, read_csv, read_npy, write_csv, write_npy
from dam.corpus.formats.textgrid import read_textgrid, write_textgrid

__all__ = [
    "read_alignment",
    "read_trajectory",
    "read_mask",
    "load_corpus",
    "write_utterance",
    "save_corpus",
    "frame_rate_from_times",
    "TRAJECTORY_READERS",
    "ALIGNMENT_SUFFIXES",
]

ALIGNMENT_SUFFIXES = (".textgrid", ".lab", ".par")


def read_alignment(path, *, tier: str | None = "phones", silence: str = SILENCE) -> Alignment:
    """Read a TextGrid, HTK/xwaves ``.lab`` or BAS Partitur ``.par`` alignment, by file extension.

    Examples
    --------
    >>> import dam
    >>> from dam.datasets import DATA
    >>> a = dam.read_alignment(DATA / "tiny" / "tiny000.TextGrid")
    >>> a.labels[0]
    'sil'
    """
    suffix = Path(path).suffix.lower()
    if suffix == ".par":
        return read_par(path, silence=silence)
    if suffix == ".textgrid":
        return read_textgrid(path, tier=tier, silence=silence)
    if suffix == ".lab":
        return read_lab(path, silence=silence)
    raise DataError(
        os.fspath(path), "extension", suffix, "not an alignment format", "use a Praat .TextGrid or an HTK .lab file"
    )


# -- trajectories ---------------------------------------------------------
#: suffix -> reader(path) returning (data, channel names or None, frame rate or None)
TRAJECTORY_READERS: dict[str, Callable] = {
    ".csv": read_csv,
    ".npy": read_npy,
    ".ema": read_est_trajectory,
    ".est": read_est_trajectory,
    ".trk": read_est_trajectory,
}


def read_trajectory(path) -> tuple[np.ndarray, list[str] | None, float | None]:
    """Read a trajectory file; returns ``(data, channels or None, frame_rate or None)``."""
    path = os.fspath(path)
    suffix = Path(path).suffix.lower()
    if suffix not in TRAJECTORY_READERS:
        raise DataError(
            path, "extension", suffix, "not a trajectory format", f"supported: {', '.join(TRAJECTORY_READERS)}"
        )
    return TRAJECTORY_READERS[suffix](path)


# -- corpora --------------------------------------------------------------
def load_corpus(
    path,
    *,
    tier: str | None = "phones",
    silence: str = SILENCE,
    frame_rate: float | None = None,
    format: str | None = None,
    **options,
) -> Corpus:
    """Read a corpus: a directory as described above, or a corpus as distributed.

    Parameters
    ----------
    path : path-like
        The directory (or one EMU ``_bndl.json`` bundle document).
    tier : str, default "phones"
        TextGrid tier holding the phones (EMU: the SEGMENT level; default its lowest).
    silence : str, default "sil"
        Canonical silence label.
    frame_rate : float, optional
        Here: overrides ``corpus.json``; needed when neither it nor a CSV
        ``time`` column gives the frame rate. For the corpora read by
        :mod:`dam.corpus.formats` (EMU, MOCHA-TIMIT, mngu0, X-ray microbeam,
        mview): resample every track to this rate by linear interpolation
        (:mod:`dam.corpus.formats.tracks`); default each file's own rate.
    format : str, optional
        Force a layout (:data:`dam.corpus.formats.detect.CORPUS_FORMATS`:
        ``directory``, ``bas``, ``emu``, ``mocha``, ``mngu0``, ``xrmb``,
        ``mview``); default detected from the files (:func:`detect_format`).
    **options
        Passed to the layout's loader (EMU ``level=``, ``tracks=``; mview ``sensors=``).

    Returns
    -------
    Corpus

    Examples
    --------
    >>> import dam
    >>> from dam.datasets import DATA
    >>> corpus = dam.load_corpus(DATA / "tiny")
    >>> corpus.name, len(corpus), corpus.channels
    ('tiny', 30, ('lip_aperture', 'lip_protrusion', 'jaw_open', 'tongue_tip'))
    """
    fmt = detect_format(path) if format is None else format
    if CORPUS_FORMATS.get(fmt, "unknown") is not None:  # a layout with a loader of its own
        # a corpus.json dropped beside the data still sets the frame rate, the sensors, the length unit
        meta_path = Path(path) / "corpus.json"
        meta = read_corpus_json(meta_path) if meta_path.is_file() else {}
        corpus = load_formatted(
            fmt,
            path,
            read_alignment=read_alignment,
            tier=tier,
            silence=silence,
            frame_rate=frame_rate if frame_rate is not None else meta.get("frame_rate"),
            **options,
        )
        extra = {k: v for k, v in meta.items() if k not in ("frame_rate", "channels")}
        resolve_sensors(corpus.channels, extra.get("sensors"), source=str(meta_path))
        corpus.metadata.update(extra)
        return corpus
    if options:
        raise TypeError(f"load_corpus: unexpected option(s) {sorted(options)} for a {fmt!r} corpus directory")
    root = Path(path)
    if not root.is_dir():
        raise DataError(os.fspath(path), "path", os.fspath(path), "not a directory")
    meta_path = root / "corpus.json"
    meta = read_corpus_json(meta_path) if meta_path.exists() else {}
    fr = frame_rate if frame_rate is not None else meta.get("frame_rate")
    channels = meta.get("channels")
    files = sorted(p for p in root.iterdir() if p.is_file())
    aligns = [p for p in files if p.suffix.lower() in ALIGNMENT_SUFFIXES]
    if not aligns:
        raise DataError(
            str(root),
            "alignments",
            0,
            "no .TextGrid or .lab files in the directory",
            "a corpus directory holds <stem>.TextGrid (or .lab) + <stem>.csv (or .npy) per utterance",
        )
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
            raise DataError(
                str(apath),
                "trajectory",
                stem,
                f"no trajectory file {stem}{{{','.join(TRAJECTORY_READERS)}}} beside the alignment",
            )
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
                raise DataError(
                    tpath,
                    "time",
                    f"{file_fr:g} frames/s",
                    f"the time column disagrees with frame_rate {float(fr):g} of corpus.json",
                )
            this_fr = float(fr) if fr is not None else round(file_fr, 6)
        if this_fr is None:
            raise DataError(
                tpath,
                "frame_rate",
                None,
                "the frame rate is unknown",
                'add corpus.json with "frame_rate", a leading time column, or pass frame_rate=',
            )
        audio = _utterance_audio(by_stem[stem], meta.get("audio_rate"), meta_path)
        mask = read_mask(root / f"{stem}.mask.npy") if (root / f"{stem}.mask.npy").is_file() else None
        utts.append(Utterance(alignment, data, this_fr, names, audio=audio, name=stem, source=tpath, mask=mask))
    extra = {k: v for k, v in meta.items() if k not in ("frame_rate", "channels")}
    resolve_sensors(utts[0].channels, extra.get("sensors"), source=str(meta_path))  # checked where they enter
    return Corpus(utts, name=meta.get("name", root.name), metadata=extra, source=str(root))


def _utterance_audio(paths, audio_rate, meta_path) -> str | None:
    """The utterance's ``.flac`` or ``.wav`` (at most one), its sample rate checked
    against ``audio_rate`` of corpus.json when that is given."""
    found = [p for p in paths if p.suffix.lower() in AUDIO_SUFFIXES]
    if not found:
        return None
    if len(found) > 1:
        raise DataError(str(found[0]), "audio", [p.name for p in found], "more than one audio file")
    rate = audio_header(found[0])[0]
    if audio_rate is not None and rate != audio_rate:
        raise DataError(
            str(found[0]),
            "sample rate",
            rate,
            f"{meta_path} says audio_rate {audio_rate}",
            "resample the file or correct audio_rate",
        )
    return str(found[0])


def read_corpus_json(path) -> dict:
    """Read and check ``corpus.json``: a JSON object whose ``frame_rate`` is a positive
    number, ``channels`` a list of distinct strings and ``name`` a string (when present).

    Raises
    ------
    DataError
        Naming the file, the field and the value (bad encoding, invalid or too
        deeply nested JSON, a field of the wrong type).
    """
    path = str(path)
    try:
        meta = json.loads(read_text(path))
    except json.JSONDecodeError as exc:
        raise DataError(path, "json", exc.msg, f"invalid JSON at line {exc.lineno}, column {exc.colno}") from None
    except RecursionError:
        raise DataError(path, "json", "nesting", "nested too deeply to be a corpus description") from None
    if not isinstance(meta, dict):
        raise DataError(path, "json", type(meta).__name__, "must hold a JSON object")
    fr = meta.get("frame_rate")
    if fr is not None and (isinstance(fr, bool) or not isinstance(fr, (int, float)) or not (0 < fr < float("inf"))):
        raise DataError(path, "frame_rate", fr, "must be a positive finite number (frames per second)")
    ch = meta.get("channels")
    if ch is not None:
        if not isinstance(ch, list) or not ch or not all(isinstance(c, str) and c for c in ch):
            raise DataError(path, "channels", ch, "must be a non-empty list of channel names (strings)")
        if len(set(ch)) != len(ch):
            raise DataError(path, "channels", next(c for c in ch if ch.count(c) > 1), "duplicate channel name")
    if "name" in meta and not isinstance(meta["name"], str):
        raise DataError(path, "name", meta["name"], "must be a string")
    return meta


# -- writers --------------------------------------------------------------
def write_utterance(
    utt: Utterance,
    directory,
    *,
    alignment_format: str = "TextGrid",
    trajectory_format: str = "csv",
    decimals: int | None = 6,
) -> None:
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
    if utt.mask is not None:  # missing data survives the round trip (see read_mask)
        write_npy(utt.mask, d / f"{name}.mask.npy")


def read_mask(path) -> np.ndarray:
    """``<stem>.mask.npy``: the missing-data mask of an utterance (bool, True = observed)."""
    path = os.fspath(path)
    try:
        mask = np.load(path, allow_pickle=False)
    except Exception as exc:
        raise DataError(path, "npy", type(exc).__name__, f"cannot be read: {exc}") from None
    if mask.dtype != bool or mask.ndim != 2:
        raise DataError(path, "mask", f"{mask.dtype} {mask.shape}", "must be a 2-D bool array (True = observed)")
    return mask


def save_corpus(
    corpus: Corpus,
    directory,
    *,
    alignment_format: str = "TextGrid",
    trajectory_format: str = "csv",
    decimals: int | None = 6,
    metadata: dict | None = None,
) -> None:
    """Write ``corpus`` as a corpus directory that :func:`load_corpus` reads back.

    Examples
    --------
    >>> import dam
    >>> corpus = dam.datasets.load("tiny")
    >>> dam.save_corpus(corpus, "tiny-copy")
    >>> len(dam.load_corpus("tiny-copy")) == len(corpus)
    True
    """
    d = Path(directory)
    d.mkdir(parents=True, exist_ok=True)
    meta = {"frame_rate": corpus.frame_rate, "channels": list(corpus.channels)}
    if corpus.name:
        meta["name"] = corpus.name
    # frame_rate and channels describe the files written here: metadata may not override them.
    meta.update(
        {k: v for k, v in {**corpus.metadata, **(metadata or {})}.items() if k not in ("frame_rate", "channels")}
    )
    try:
        text = json.dumps(meta, indent=2, allow_nan=False) + "\n"
    except (TypeError, ValueError) as exc:
        raise DataError(
            str(d / "corpus.json"), "metadata", type(exc).__name__, f"cannot be written as JSON: {exc}"
        ) from None
    with atomic_write(d / "corpus.json", "w", encoding="utf-8") as fh:
        fh.write(text)
    for k, u in enumerate(corpus):
        if u.name is None:
            u = u.replace(name=f"utt{k:04d}")
        write_utterance(u, d, alignment_format=alignment_format, trajectory_format=trajectory_format, decimals=decimals)
