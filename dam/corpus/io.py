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
* optionally ``<stem>.wav``, the utterance's audio.

Every error names the file, the field and the value.
"""
from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Callable

from dam.corpus.data import SILENCE, Alignment, Corpus, DataError, Utterance
from dam.corpus.formats.est import read_est_trajectory
from dam.corpus.formats.htk import read_lab, write_lab
from dam.corpus.formats.tables import frame_rate_from_times, read_csv, read_npy, write_csv, write_npy
from dam.corpus.formats.textgrid import read_textgrid, write_textgrid

__all__ = ["read_alignment", "read_trajectory", "load_corpus", "write_utterance", "save_corpus",
           "frame_rate_from_times", "TRAJECTORY_READERS", "ALIGNMENT_SUFFIXES"]

ALIGNMENT_SUFFIXES = (".textgrid", ".lab")


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
#: suffix -> reader(path) returning (data, channel names or None, frame rate or None)
TRAJECTORY_READERS: dict[str, Callable] = {".csv": read_csv, ".npy": read_npy, ".ema": read_est_trajectory,
                                           ".est": read_est_trajectory, ".trk": read_est_trajectory}


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
