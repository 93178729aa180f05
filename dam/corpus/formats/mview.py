"""Haskins IEEE Rate Comparison database: mview MATLAB ``.mat`` files.

Each utterance is one MATLAB (v5) file holding one variable named after the
file, a 1 x N struct array as written by Mark Tiede's *mview*. Every record
has the fields ``NAME``, ``SRATE``, ``SIGNAL``, ``SOURCE``, ``SENTENCE``,
``WORDS``, ``PHONES`` and ``LABELS``:

* the first record, ``NAME = 'AUDIO'``, holds the waveform (``SRATE``
  44100) and the annotation: ``SENTENCE`` (text), ``WORDS`` and ``PHONES``,
  struct arrays with ``LABEL`` (text) and ``OFFS`` (``[start end]`` in seconds);
* every other record is one sensor (``TR``, ``TB``, ``TT``, ``UL``, ``LL``,
  ``ML``, ``JAW``, ``JAWL``; ``SRATE`` 100), ``SIGNAL`` of shape
  (n_frames, 6): position x, y, z in millimetres and three orientation
  angles, named here ``<sensor>_px, _py, _pz, _ox, _oy, _oz`` as the public
  Python readers of this database name them (3 columns: positions only;
  other widths: ``_c1 ..``). NaN samples (sensor dropouts) become masked frames.

Files without a ``PHONES`` annotation (the ``*_palate.mat`` palate traces) are
skipped. Read with :func:`scipy.io.loadmat`; numpy/scipy only.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from dam.corpus.data import SILENCE, Alignment, DataError
from dam.corpus.formats.tracks import Track, build_corpus

__all__ = ["MVIEW_COLUMNS", "read_mview", "load_mview_corpus"]

MVIEW_COLUMNS = ("px", "py", "pz", "ox", "oy", "oz")


def _text(value) -> str:
    if isinstance(value, np.ndarray):
        value = value.tolist() if value.size else ""
        if isinstance(value, list):
            value = " ".join(str(v) for v in value)
    return str(value).strip()


def _as_list(value) -> list:
    if value is None:
        return []
    if isinstance(value, dict):
        return [value]
    if isinstance(value, np.ndarray):
        return list(value.ravel()) if value.size else []
    return list(value)


def _records(path: str) -> tuple[str, list[dict]]:
    from scipy.io import loadmat
    from scipy.io.matlab import MatReadError

    try:
        mat = loadmat(path, simplify_cells=True)
    except (MatReadError, ValueError, OSError, TypeError) as exc:
        raise DataError(path, "mat", type(exc).__name__, f"not a readable MATLAB file ({exc})") from None
    stem = Path(path).stem
    names = [k for k in mat if not k.startswith("__")]
    var = stem if stem in mat else (names[0] if len(names) == 1 else None)
    if var is None:
        raise DataError(path, "variable", names, f"expected one struct variable named {stem!r}")
    recs = _as_list(mat[var])
    if not recs or not all(isinstance(r, dict) for r in recs):
        raise DataError(path, var, type(mat[var]).__name__, "must be a struct array (mview layout)")
    for i, r in enumerate(recs):
        for fld in ("NAME", "SRATE", "SIGNAL"):
            if fld not in r:
                raise DataError(path, f"{var}({i + 1}).{fld}", None, "missing (mview records need NAME, SRATE, SIGNAL)")
    return var, recs


def _alignment(path: str, var: str, recs: list[dict], silence: str) -> Alignment | None:
    holder = next((r for r in recs if "PHONES" in r and _as_list(r["PHONES"])), None)
    if holder is None:
        return None
    labels, starts, ends = [], [], []
    for k, ph in enumerate(_as_list(holder["PHONES"])):
        where = f"{var}.PHONES({k + 1})"
        if not isinstance(ph, dict) or "LABEL" not in ph or "OFFS" not in ph:
            raise DataError(path, where, ph, "a phone needs LABEL and OFFS")
        offs = np.asarray(ph["OFFS"], dtype=float).ravel()
        if offs.size != 2:
            raise DataError(path, f"{where}.OFFS", offs.tolist(), "must be [start end] in seconds")
        labels.append(_text(ph["LABEL"]))
        starts.append(offs[0])
        ends.append(offs[1])
    return Alignment(labels, starts, ends, source=path, silence=silence)


def read_mview(path, *, silence: str = SILENCE, sensors=None) -> tuple[Alignment | None, Track, dict]:
    """Read one mview ``.mat`` file.

    Parameters
    ----------
    path : path-like
    silence : str, default "sil"
    sensors : sequence of str, optional
        Sensor records to keep, in this order (default: every non-audio record).

    Returns
    -------
    alignment : Alignment or None
        From ``PHONES``; None when the file has no phones.
    track : Track
        All sensors' columns side by side, NaN where the file has NaN.
    info : dict
        ``sentence``, ``words`` (list of (label, start, end)), ``audio_rate``.
    """
    return _read(str(path), silence, sensors, skip_unannotated=False)


def _read(path: str, silence: str, sensors, *, skip_unannotated: bool):
    var, recs = _records(path)
    alignment = _alignment(path, var, recs, silence)
    if alignment is None and skip_unannotated:
        return None, None, {}
    audio = next((r for r in recs if _text(r["NAME"]).upper() == "AUDIO"), None)
    sensor_recs = [r for r in recs if r is not audio]
    by_name = {_text(r["NAME"]): r for r in sensor_recs}
    if sensors is not None:
        missing = [s for s in sensors if s not in by_name]
        if missing:
            raise DataError(path, "sensors", missing, "no such record", f"records: {list(by_name)}")
        sensor_recs = [by_name[s] for s in sensors]
    if not sensor_recs:
        raise DataError(path, var, [_text(r["NAME"]) for r in recs], "no sensor records besides AUDIO")
    blocks, names, rate, n = [], [], None, None
    for r in sensor_recs:
        name = _text(r["NAME"])
        where = f"{var}.{name}"
        try:
            srate = float(np.asarray(r["SRATE"], dtype=float).ravel()[0])
        except (TypeError, ValueError, IndexError):
            raise DataError(path, f"{where}.SRATE", r["SRATE"], "not a number") from None
        if not (np.isfinite(srate) and srate > 0):
            raise DataError(path, f"{where}.SRATE", srate, "must be a positive number")
        try:
            sig = np.asarray(r["SIGNAL"], dtype=float)
        except (TypeError, ValueError):
            raise DataError(path, f"{where}.SIGNAL", type(r["SIGNAL"]).__name__, "not numeric") from None
        sig = sig[:, None] if sig.ndim == 1 else sig
        if sig.ndim != 2 or sig.shape[0] < 2:
            raise DataError(path, f"{where}.SIGNAL", sig.shape, "must be (n_frames, n_columns) with 2+ frames")
        if rate is None:
            rate, n = srate, sig.shape[0]
        elif abs(srate - rate) > 1e-9 * rate or sig.shape[0] != n:
            raise DataError(
                path,
                f"{where}",
                f"{sig.shape[0]} frames at {srate:g}/s",
                f"sensors of one file must share rate and length ({n} frames at {rate:g}/s)",
            )
        cols = MVIEW_COLUMNS[: sig.shape[1]] if sig.shape[1] in (3, 6) else [f"c{k + 1}" for k in range(sig.shape[1])]
        names += [f"{name}_{c}" for c in cols]
        blocks.append(sig)
    track = Track(np.hstack(blocks), names, rate, source=path)
    info = {
        "sentence": _text(audio.get("SENTENCE", "")) if audio else "",
        "audio_rate": float(np.asarray(audio["SRATE"]).ravel()[0]) if audio else None,
        "words": [
            (_text(w.get("LABEL", "")), *np.asarray(w.get("OFFS", [np.nan, np.nan]), float).ravel()[:2])
            for w in _as_list((audio or {}).get("WORDS"))
            if isinstance(w, dict)
        ],
    }
    return alignment, track, info


def load_mview_corpus(path, *, frame_rate: float | None = None, silence: str = SILENCE, sensors=None, **_ignored):
    """Read a directory of Haskins/mview ``.mat`` files (one utterance each).

    Parameters
    ----------
    path : path-like
        The speaker's ``data`` directory.
    frame_rate : float, optional
        Resample (default: the files' own rate, 100 frames/s).
    silence : str, default "sil"
    sensors : sequence of str, optional
        Sensors to keep (default all: every file must have the same ones).

    Returns
    -------
    Corpus
        Positions in mm, orientations in the file's unit; ``metadata`` has
        ``format: "mview"``, ``length_unit: "mm"`` and the ``sentences``.
    """
    root = Path(path)
    if not root.is_dir():
        raise DataError(str(root), "path", str(root), "not a directory")
    files = sorted(p for p in root.iterdir() if p.is_file() and p.suffix.lower() == ".mat")
    if not files:
        raise DataError(str(root), "files", 0, "no .mat files in the directory")
    entries, sentences = [], {}
    for f in files:
        alignment, track, info = _read(str(f), silence, sensors, skip_unannotated=True)
        if alignment is None:  # palate traces and other unannotated files
            continue
        wav = f.with_suffix(".wav")
        entries.append((f.stem, alignment, track, str(wav) if wav.exists() else None))
        sentences[f.stem] = info["sentence"]
    if not entries:
        raise DataError(str(root), "PHONES", 0, "no .mat file in the directory has a PHONES annotation")
    return build_corpus(
        entries,
        frame_rate=frame_rate,
        name=root.name,
        source=str(root),
        metadata={"format": "mview", "length_unit": "mm", "sentences": sentences},
    )
