"""From a corpus's own tracks to one :class:`~dam.corpus.Corpus`: frame grid, missing data, resampling.

The readers of :mod:`dam.corpus.formats` (EMU-SDMS, MOCHA-TIMIT, mngu0, the
X-ray microbeam database, Haskins/mview) each return, per utterance, an
alignment and a :class:`Track`: the values as stored (converted to
millimetres where the source documents its unit), their channel names, the
file's own sample rate and start time, and the missing values (NaN or a
mask). :func:`build_corpus` turns these into utterances on the toolkit's frame
grid (frame ``i`` at ``i / frame_rate``):

* **Frame rate.** Each file keeps its own rate. If the files disagree, or if
  ``frame_rate=`` is given, the tracks are **resampled by linear interpolation
  in time**, channel by channel, at ``j / frame_rate``, from the observed
  samples only; a file whose first sample is not at time 0 (SSFF
  ``Start_Time``) is put on the grid the same way. Articulator movement lies
  far below the Nyquist frequency of any EMA rate, so linear interpolation is
  enough; no anti-aliasing filter is applied when downsampling.
* **Missing data.** A value that is NaN or masked in the source becomes
  ``False`` in ``Utterance.mask``; a resampled frame is observed only if the
  source samples on both sides of it are. The stored values there are filled
  by :class:`~dam.corpus.Utterance` (interpolation over time), never NaN.
* **Lengths.** Labels running past the end of the trajectory (MOCHA-TIMIT
  labels end with the audio, the EMA may stop a few milliseconds earlier) are
  trimmed to it when only silence, or at most one frame of a phone, is cut;
  cutting more of a phone is an error naming the file.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from dam.corpus.data import Alignment, Corpus, DataError, Utterance

__all__ = ["Track", "regrid", "fit_to_track", "build_corpus", "pair_by_stem", "uniform_rate", "audio_beside"]

# Relative spread of frame steps still counted as one rate (EST and txy times are stored coarsely).
_RATE_TOL = 0.01


@dataclass
class Track:
    """One utterance's trajectory as a source stores it.

    Attributes
    ----------
    values : ndarray, shape (n_frames, n_channels)
        May hold NaN where the source has no value.
    channels : list of str
    frame_rate : float
        The file's own frames per second.
    start_time : float, default 0.0
        Time of the first frame in seconds.
    mask : ndarray of bool, shape (n_frames, n_channels), optional
        True where observed; NaN values count as unobserved either way.
    source : str, optional
        The file, named in errors.
    """

    values: np.ndarray
    channels: list
    frame_rate: float
    start_time: float = 0.0
    mask: np.ndarray | None = None
    source: str | None = None
    times: np.ndarray | None = field(default=None, repr=False)

    def observed(self) -> np.ndarray:
        """Bool array, shape (n_frames, n_channels): True where a value is present."""
        ok = np.isfinite(self.values)
        return ok if self.mask is None else ok & np.asarray(self.mask, dtype=bool)

    @property
    def sample_times(self) -> np.ndarray:
        """Time of every frame in seconds, shape (n_frames,)."""
        if self.times is not None:
            return np.asarray(self.times, dtype=float)
        return self.start_time + np.arange(len(self.values)) / self.frame_rate


def uniform_rate(times, source, *, where: str = "time (frame {})") -> float:
    """Frames per second of evenly spaced ``times`` (seconds); DataError naming the first uneven frame."""
    t = np.asarray(times, dtype=float)
    if len(t) < 2:
        raise DataError(source, "frames", len(t), "need at least 2 frames to know the frame rate")
    step = np.diff(t)
    dt = float(np.median(step))
    bad = np.flatnonzero(~(np.abs(step - dt) <= _RATE_TOL * dt))
    if not dt > 0 or bad.size:
        k = int(bad[0]) + 1 if bad.size else 1
        raise DataError(
            source,
            where.format(k),
            float(t[k]),
            f"the frame times are not evenly spaced (median step {dt:g} s)",
            "pass frame_rate= to resample the track onto an even grid",
        )
    return (len(t) - 1) / float(t[-1] - t[0])


def regrid(track: Track, frame_rate: float) -> tuple[np.ndarray, np.ndarray]:
    """Values and observed-mask of ``track`` at times ``j / frame_rate``.

    Linear interpolation per channel from the observed samples (held
    constant before the first and after the last one). Frame ``j`` is
    observed when the source frames on both sides of ``j / frame_rate`` are
    (the one source frame when the time falls on it).

    Parameters
    ----------
    track : Track
    frame_rate : float

    Returns
    -------
    values : ndarray, shape (n_out, n_channels)
        ``n_out = ceil((last time + 1 / track.frame_rate) * frame_rate)``;
        NaN in channels with no observed sample.
    observed : ndarray of bool, shape (n_out, n_channels)
    """
    t = track.sample_times
    values = np.asarray(track.values, dtype=float)
    ok = track.observed()
    end = float(t[-1]) + 1.0 / track.frame_rate
    n_out = max(1, int(math.ceil(end * frame_rate - 1e-6)))
    t_out = np.arange(n_out) / float(frame_rate)
    out = np.full((n_out, values.shape[1]), np.nan)
    # Source frames on either side of each output time (equal where the time hits a frame).
    hi = np.clip(np.searchsorted(t, t_out - 1e-9, side="left"), 0, len(t) - 1)
    lo = np.where(np.abs(t[hi] - t_out) <= 1e-9, hi, np.clip(hi - 1, 0, len(t) - 1))
    observed = ok[lo] & ok[hi]
    for j in range(values.shape[1]):
        good = ok[:, j]
        if good.any():
            out[:, j] = np.interp(t_out, t[good], values[good, j])
    observed &= np.isfinite(out)
    return out, observed


def fit_to_track(alignment: Alignment, duration: float, source: str | None, *, frame: float = 0.0) -> Alignment:
    """``alignment`` trimmed to end at ``duration`` seconds, cutting only silence and at most ``frame`` of a phone."""
    if alignment.duration <= duration + 1e-9:
        return alignment
    keep = int(np.searchsorted(alignment.starts, duration - 1e-9, side="left"))
    cut = [
        (lab, float(min(e, alignment.duration) - max(s, duration)))
        for lab, s, e in zip(alignment.labels[keep - 1 :], alignment.starts[keep - 1 :], alignment.ends[keep - 1 :])
    ]
    phones = [lab for lab, amount in cut if lab != alignment.silence and amount > frame + 1e-9]
    if keep == 0 or phones:
        raise DataError(
            source,
            "duration",
            f"{duration:.4f} s",
            f"the trajectory ends before the labels ({alignment.duration:.4f} s); "
            f"trimming the labels would cut into {phones or list(alignment.labels)!r}",
        )
    ends = np.minimum(alignment.ends[:keep], duration)
    return Alignment(
        alignment.labels[:keep], alignment.starts[:keep], ends, source=alignment.source, silence=alignment.silence
    )


def build_corpus(
    entries: Iterable[tuple],
    *,
    frame_rate: float | None = None,
    name: str | None = None,
    metadata: dict | None = None,
    source: str | None = None,
) -> Corpus:
    """Utterances on one frame grid from ``(name, alignment, track, audio)`` entries.

    Parameters
    ----------
    entries : iterable of (str, Alignment, Track, str or None)
    frame_rate : float, optional
        Resample every track to this rate (see the module docstring). Default:
        the tracks' own common rate; tracks at different rates are an error
        that says to pass ``frame_rate``.
    name, metadata, source
        Passed to :class:`~dam.corpus.Corpus`.

    Returns
    -------
    Corpus
    """
    entries = list(entries)
    if not entries:
        raise DataError(source, "utterances", 0, "no utterances found")
    if frame_rate is not None:
        try:
            frame_rate = float(frame_rate)
        except (TypeError, ValueError):
            raise DataError(source, "frame_rate", frame_rate, "not a number") from None
        if not (math.isfinite(frame_rate) and frame_rate > 0):
            raise DataError(source, "frame_rate", frame_rate, "must be a positive finite number")
    else:
        first = entries[0][2]
        for _, _, track, _ in entries[1:]:
            if abs(track.frame_rate - first.frame_rate) > 1e-6 * first.frame_rate:
                raise DataError(
                    track.source,
                    "frame_rate",
                    f"{track.frame_rate:g} frames/s",
                    f"differs from the {first.frame_rate:g} frames/s of {first.source}",
                    "pass frame_rate= (load_corpus(..., frame_rate=R)) to resample every "
                    "track to one rate by linear interpolation",
                )
    utts = []
    for utt_name, alignment, track, audio in entries:
        rate = frame_rate if frame_rate is not None else track.frame_rate
        on_grid = (
            (frame_rate is None or abs(rate - track.frame_rate) <= 1e-9 * rate)
            and track.times is None
            and abs(track.start_time) <= 1e-9
        )
        if on_grid:
            values = np.array(track.values, dtype=float)
            observed = track.observed()
        else:
            values, observed = regrid(track, rate)
        n = len(values)
        alignment = fit_to_track(alignment, n / rate, track.source, frame=1.0 / rate)
        mask = None if observed.all() else observed
        utts.append(
            Utterance(
                alignment,
                np.where(observed, values, 0.0),
                rate,
                track.channels,
                mask=mask,
                audio=audio,
                name=utt_name,
                source=track.source,
            )
        )
    return Corpus(utts, name=name, metadata=metadata, source=source)


def pair_by_stem(
    root: Path, trajectory_suffixes: Sequence[str], alignment_suffixes: Sequence[str], *, what: str
) -> list[tuple[str, Path, Path]]:
    """``(stem, trajectory, alignment)`` for every trajectory file in ``root`` with its alignment.

    Alignments are looked for with the same stem, in the order of
    ``alignment_suffixes``; a trajectory without one is an error naming it.
    """
    files = sorted(p for p in root.iterdir() if p.is_file())
    by_stem: dict[str, dict[str, Path]] = {}
    for p in files:
        by_stem.setdefault(p.stem, {})[p.suffix.lower()] = p
    out = []
    for p in files:
        if p.suffix.lower() not in trajectory_suffixes:
            continue
        found = [by_stem[p.stem][s] for s in alignment_suffixes if s in by_stem[p.stem]]
        if not found:
            raise DataError(
                str(p),
                "alignment",
                p.stem,
                f"no label file {p.stem}{{{','.join(alignment_suffixes)}}} beside this {what} file",
            )
        out.append((p.stem, p, found[0]))
    if not out:
        raise DataError(str(root), "files", 0, f"no {what} files ({', '.join(trajectory_suffixes)}) in the directory")
    return out


def audio_beside(path: Path) -> str | None:
    """``<stem>.wav`` beside ``path`` if it exists."""
    wav = path.with_suffix(".wav")
    return str(wav) if wav.exists() else None
