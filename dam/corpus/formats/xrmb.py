"""The Wisconsin X-ray Microbeam Speech Production Database: ``.txy`` pellet files.

Westbury (1994), *X-ray Microbeam Speech Production Database User's
Handbook*, as implemented by the ASSP library (wrassp, ``uwm_xrmb.h``): a
``.txy`` file is ASCII, one frame a line, 17 whitespace-separated integers
(tab in the distribution)::

    time  UL_x UL_y  LL_x LL_y  T1_x T1_y  T2_x T2_y  T3_x T3_y  T4_x T4_y  MNI_x MNI_y  MNM_x MNM_y

``time`` in microseconds, pellet coordinates in micrometres, for the eight
pellets upper lip, lower lip, four tongue pellets from tip (T1) to dorsum
(T4), mandible at the incisors (MNI) and at the molars (MNM). The value
**1000000** marks a pellet position the tracker lost (and fills the first
frame at time 0); the frame period is nominally 6866 µs (145.6 frames/s).
This reader turns the marker into a mask (never NaN in outputs), converts
positions to **millimetres** and names the channels ``<pellet>_x``,
``<pellet>_y``. The 16-column ``xyd`` variant (no time column, default frame
period) is read too.

Labels come beside each ``.txy`` file with the same stem: a TextGrid, an HTK
or xwaves ``.lab`` file, or a BAS ``.par`` file (the database's own word
segmentations are not phones). :func:`write_txy` writes the format back.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from dam.corpus.atomic import atomic_write
from dam.corpus.data import SILENCE, DataError
from dam.corpus.formats.tracks import Track, audio_beside, build_corpus, pair_by_stem

__all__ = ["XRMB_PELLETS", "XRMB_MISSING", "XRMB_FRAME_US", "read_txy", "write_txy", "load_xrmb_corpus"]

XRMB_PELLETS = ("UL", "LL", "T1", "T2", "T3", "T4", "MNI", "MNM")
#: the database's marker of a lost pellet position (and of the first frame)
XRMB_MISSING = 1000000
#: nominal frame period in microseconds
XRMB_FRAME_US = 6866
_CHANNELS = [f"{p}_{a}" for p in XRMB_PELLETS for a in "xy"]
_UM_PER_MM = 1000.0


def read_txy(path) -> Track:
    """Read a ``.txy`` (or 16-column ``.xyd``) pellet file.

    Returns
    -------
    Track
        ``values`` in mm, shape (n_frames, 16), NaN where the file has the
        missing marker; ``times`` in seconds from the file.

    Raises
    ------
    DataError
        Naming the file, line and value: a line without 17 (or 16) numbers,
        a non-integer value, times that do not increase. Unevenly spaced
        frames are kept with their times and put on an even grid by
        :func:`~dam.corpus.formats.tracks.build_corpus`.
    """
    path = os.fspath(path)
    rows = []
    with open(path, encoding="ascii", errors="replace") as fh:
        for lineno, line in enumerate(fh, 1):
            parts = line.split()
            if not parts:
                continue
            if len(parts) not in (16, 17) or (rows and len(parts) != len(rows[0][1])):
                raise DataError(
                    path, f"line {lineno}", len(parts), "expected 17 numbers (time, then x y of 8 pellets) per line"
                )
            try:
                rows.append((lineno, [int(v) for v in parts]))
            except ValueError:
                bad = next(v for v in parts if not v.lstrip("-").isdigit())
                raise DataError(path, f"line {lineno}", bad, "not a whole number (µs or µm)") from None
    if len(rows) < 2:
        raise DataError(path, "frames", len(rows), "need at least 2 frames")
    table = np.array([r for _, r in rows], dtype=np.int64)
    if table.shape[1] == 17:
        times_us, xy = table[:, 0].astype(float), table[:, 1:]
    else:
        times_us, xy = np.arange(len(table)) * float(XRMB_FRAME_US), table
    values = np.where(xy == XRMB_MISSING, np.nan, xy / _UM_PER_MM)
    times = times_us * 1e-6
    back = np.flatnonzero(np.diff(times) <= 0)
    if back.size:
        i = int(back[0]) + 1
        raise DataError(path, f"line {rows[i][0]} time", int(times_us[i]), "times must increase (microseconds)")
    # The frame period is nominally the same in every file (6866 µs): the median integer step gives
    # one rate for the whole corpus; frames off that grid are resampled onto it.
    rate = 1e6 / float(np.median(np.diff(times_us)))
    even = bool(np.allclose(times, times[0] + np.arange(len(times)) / rate, atol=0.05 / rate))
    return Track(values, list(_CHANNELS), rate, start_time=float(times[0]), source=path, times=None if even else times)


def write_txy(path, values, *, times=None, mask=None, frame_us: int = XRMB_FRAME_US) -> None:
    """Write pellet positions as a ``.txy`` file (atomically).

    Parameters
    ----------
    path : path-like
    values : array-like, shape (n_frames, 16)
        Millimetres, pellets in :data:`XRMB_PELLETS` order, x then y; NaN is missing.
    times : array-like, shape (n_frames,), optional
        Seconds; default ``i * frame_us`` µs.
    mask : array-like of bool, shape (n_frames, 16), optional
        False where missing.
    frame_us : int, default 6866
    """
    path = os.fspath(path)
    v = np.asarray(values, dtype=float)
    if v.ndim != 2 or v.shape[1] != 16:
        raise DataError(path, "values", v.shape, "must be (n_frames, 16): x, y of 8 pellets")
    missing = ~np.isfinite(v)
    if mask is not None:
        m = np.asarray(mask, dtype=bool)
        if m.shape != v.shape:
            raise DataError(path, "mask", m.shape, f"must match values {v.shape}")
        missing |= ~m
    um = np.where(missing, XRMB_MISSING, np.rint(np.nan_to_num(v) * _UM_PER_MM)).astype(np.int64)
    if np.any(np.abs(um[~missing]) >= XRMB_MISSING):
        raise DataError(path, "values", float(np.max(np.abs(v[~missing]))), "beyond ±1000 mm, the format's range")
    t = np.arange(len(v)) * frame_us if times is None else np.rint(np.asarray(times, float) * 1e6).astype(np.int64)
    lines = ["\t".join(str(int(x)) for x in (t[i], *um[i])) for i in range(len(v))]
    with atomic_write(path, "wb") as fh:
        fh.write(("\n".join(lines) + "\n").encode("ascii"))


def load_xrmb_corpus(
    path,
    *,
    read_alignment,
    frame_rate: float | None = None,
    silence: str = SILENCE,
    tier: str | None = "phones",
    **_ignored,
):
    """Read a directory of ``.txy`` files with their labels (see the module docstring).

    Parameters
    ----------
    path : path-like
    read_alignment : callable
        Handed in by :func:`dam.corpus.io.load_corpus`.
    frame_rate : float, optional
        Resample (default: the files' own rate, 1 / frame period).
    silence : str, default "sil"
    tier : str, default "phones"

    Returns
    -------
    Corpus
        Channels ``UL_x .. MNM_y`` in mm, lost pellets masked; ``metadata``
        has ``format: "xrmb"`` and ``length_unit: "mm"``.
    """
    root = Path(path)
    if not root.is_dir():
        raise DataError(str(root), "path", str(root), "not a directory")
    entries = []
    for stem, txy, lab in pair_by_stem(root, (".txy", ".xyd"), (".textgrid", ".lab", ".par"), what="pellet"):
        track = read_txy(txy)
        entries.append((stem, read_alignment(lab, tier=tier, silence=silence), track, audio_beside(txy)))
    return build_corpus(
        entries,
        frame_rate=frame_rate,
        name=root.name,
        source=str(root),
        metadata={"format": "xrmb", "length_unit": "mm"},
    )
