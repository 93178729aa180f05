"""The data model: alignments, utterances and corpora.

Validation happens here, once, where data enters the toolkit. Every error
names the source (file), the field and the offending value.

Conventions
-----------
* Times are in seconds. Frame ``i`` of a trajectory is the sample at time
  ``i / frame_rate``; an alignment ending at ``T`` covers the frames at
  times ``<= T``: ``floor(T * frame_rate) + 1`` of them
  (:meth:`Alignment.n_frames`). So an alignment of an ``n``-frame
  trajectory ends at the last frame time ``(n - 1) / frame_rate`` or less
  than one frame after it.
* Silence: empty labels and ``sil``, ``sp``, ``spn``, ``pau`` (any case)
  become one canonical silence label (``SILENCE``, configurable per call).
  A gap between two segments (or before the first) becomes silence, and
  adjacent silence segments (from the file or from gap filling) are merged
  into one (:class:`Alignment`).
* Edges (:class:`Utterance`, where the frame rate is known; every loader
  builds utterances through it, and writers write the alignment it keeps):
  an alignment ending at, or within one frame of, the trajectory's last
  frame time is kept as it is, with no padding. A shorter gap than one frame
  or a longer overhang than the last frame time is absorbed into the last
  segment (its end moves to the last frame time), never made a segment of
  its own; a silence segment shorter than one frame anywhere is absorbed
  into its neighbour. A longer gap at the end becomes (or extends) a
  trailing silence; an alignment running more than two frames past the
  last frame time is an error.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Iterator, Mapping, Sequence

import numpy as np

SILENCE = "sil"
SILENCE_LABELS = frozenset({"", "sil", "sp", "spn", "pau", "<sil>", "silence"})
# Times closer than this (seconds) count as equal: TextGrids store decimals.
TIME_TOL = 1e-6
# Bounds that catch misread units before anything is allocated (issue 12): an alignment
# ending after a day, or a frame rate above 10 kHz (EMA runs at 100-1250 Hz, video at 24-240).
MAX_DURATION = 86400.0
MAX_FRAME_RATE = 10000.0

__all__ = [
    "SILENCE",
    "SILENCE_LABELS",
    "DataError",
    "Alignment",
    "Utterance",
    "Corpus",
    "frame_times",
    "frame_labels",
    "fill_masked",
    "infer_sensors",
    "resolve_sensors",
    "fit_to_frames",
]


class DataError(ValueError):
    """Bad input data. The message names the source, the field and the value."""

    def __init__(self, source, field_, value, problem, hint=None):
        self.source, self.field, self.value = source, field_, value
        msg = f"{source or '<input>'}: field {field_!r}: {problem} (got {value!r})"
        if hint:
            msg += f"; {hint}"
        super().__init__(msg)


def real_array(values, source, field_: str) -> np.ndarray:
    """``values`` as a new float array; ragged, text and complex input is a DataError.

    numpy would raise its own errors for ragged or object input, and silently drop the
    imaginary part of complex input (with only a warning): neither names the file or field.

    Parameters
    ----------
    values : array-like
        Numbers of any shape (bool, int, float; an object array of numbers).
    source : str or None
        The file, for the message.
    field_ : str
        The field, for the message.

    Returns
    -------
    ndarray of float64, the shape of ``values``

    Examples
    --------
    >>> from dam.corpus.data import real_array
    >>> real_array([[1, 2], [3, 4]], "u.csv", "trajectory").dtype
    dtype('float64')
    >>> real_array([[1.0], [2.0, 3.0]], "u.csv", "trajectory")
    Traceback (most recent call last):
    ...
    dam.corpus.data.DataError: u.csv: field 'trajectory': must be an array of real numbers ...
    """
    import warnings

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", _ComplexWarning)
            raw = np.asarray(values)
            if raw.dtype.kind == "c":
                raise DataError(
                    source,
                    field_,
                    str(raw.dtype),
                    "complex values are not accepted",
                    "store the real quantity you mean (e.g. np.abs or .real)",
                )
            if raw.dtype.kind not in "biufO":
                raise TypeError(raw.dtype)
            return np.array(raw, dtype=float, copy=True)
    except DataError:
        raise
    except (TypeError, ValueError, OverflowError, _ComplexWarning) as exc:
        kind = "out of range" if isinstance(exc, OverflowError) else "ragged, complex or not numbers"
        shown = repr(values)
        raise DataError(
            source,
            field_,
            shown if len(shown) <= 80 else shown[:77] + "...",
            f"must be an array of real numbers ({kind})",
        ) from None


_ComplexWarning = getattr(np, "exceptions", np).ComplexWarning


def _n_frames(duration: float, frame_rate: float) -> int:
    # frames at times <= duration (TIME_TOL: TextGrids store decimals)
    return int(math.floor(duration * frame_rate + TIME_TOL * frame_rate)) + 1


def canonical_label(label: str, silence: str = SILENCE) -> str:
    """Map every silence spelling to ``silence``; strip white space."""
    label = str(label).strip()
    return silence if label.lower() in SILENCE_LABELS else label


class Alignment:
    """Phone labels with start and end times in seconds.

    Parameters
    ----------
    labels : sequence of str, length n_segments
    starts, ends : array-like of float, shape (n_segments,)
        Segment boundaries in seconds; sorted, non-overlapping, each
        segment of positive length. A gap between segments (and before the
        first one) becomes a silence segment.
    source : str, optional
        Where the alignment came from (a file name); used in error messages.
    silence : str, default "sil"
        The canonical silence label.

    Attributes
    ----------
    labels : tuple of str
    starts, ends : ndarray of float, shape (n_segments,)

    Examples
    --------
    >>> import dam
    >>> a = dam.Alignment(["sil", "a", "b", "sil"], [0.0, 0.1, 0.25, 0.4], [0.1, 0.25, 0.4, 0.5])
    >>> len(a), a.duration
    (4, 0.5)
    >>> a.n_frames(100)
    51
    """

    __slots__ = ("labels", "starts", "ends", "source", "silence")

    def __init__(self, labels: Sequence[str], starts, ends, *, source: str | None = None, silence: str = SILENCE):
        labels = [canonical_label(lab, silence) for lab in labels]
        starts = real_array(starts, source, "starts").ravel()  # copies: snapped below, frozen after
        ends = real_array(ends, source, "ends").ravel()
        if not (len(labels) == len(starts) == len(ends)):
            raise DataError(
                source, "segments", (len(labels), len(starts), len(ends)), "labels, starts and ends differ in length"
            )
        if len(labels) == 0:
            raise DataError(source, "segments", 0, "the alignment has no segments")
        for name, arr in (("start", starts), ("end", ends)):
            bad = np.flatnonzero(~np.isfinite(arr))
            if bad.size:
                i = int(bad[0])
                raise DataError(source, f"segment {i} ({labels[i]!r}) {name}", float(arr[i]), "time is not finite")
            bad = np.flatnonzero(np.abs(arr) > MAX_DURATION)
            if bad.size:
                i = int(bad[0])
                raise DataError(
                    source,
                    f"segment {i} ({labels[i]!r}) {name}",
                    float(arr[i]),
                    f"time is more than {MAX_DURATION:g} s (a day): a misread unit?",
                    "split the recording into utterances",
                )
        if starts[0] < -TIME_TOL:
            raise DataError(source, f"segment 0 ({labels[0]!r}) start", float(starts[0]), "time is negative")
        length = ends - starts
        bad = np.flatnonzero(length <= TIME_TOL)
        if bad.size:
            i = int(bad[0])
            raise DataError(
                source,
                f"segment {i} ({labels[i]!r})",
                (float(starts[i]), float(ends[i])),
                "zero-length or reversed segment (start >= end)",
            )
        back = np.flatnonzero(starts[1:] < starts[:-1])
        if back.size:
            i = int(back[0]) + 1
            raise DataError(
                source,
                f"segment {i} ({labels[i]!r}) start",
                float(starts[i]),
                f"times are not sorted (previous segment starts at {starts[i - 1]:g})",
            )
        over = np.flatnonzero(starts[1:] < ends[:-1] - TIME_TOL)
        if over.size:
            i = int(over[0]) + 1
            raise DataError(
                source,
                f"segment {i} ({labels[i]!r}) start",
                float(starts[i]),
                f"overlaps the previous segment {labels[i - 1]!r}, which ends at {ends[i - 1]:g}",
            )
        # Gaps (including one before the first segment) become silence segments.
        prev_end = np.concatenate([[0.0], ends[:-1]])
        gap = np.flatnonzero(starts > prev_end + TIME_TOL)
        if gap.size:
            ins_lab, ins_s, ins_e = [], [], []
            for i in gap:
                ins_lab.append((int(i), silence))
                ins_s.append(prev_end[i])
                ins_e.append(starts[i])
            new_labels = list(labels)
            for _k, (i, lab) in enumerate(reversed(ins_lab)):
                new_labels.insert(i, lab)
            labels = new_labels
            starts = np.insert(starts, gap, ins_s)
            ends = np.insert(ends, gap, ins_e)
        # Snap near-equal boundaries so segments tile exactly.
        starts[1:] = np.where(np.abs(starts[1:] - ends[:-1]) <= TIME_TOL, ends[:-1], starts[1:])
        # Adjacent silences are one pause.
        labels, starts, ends = _merge_silences(labels, starts, ends, silence)
        starts[0] = max(starts[0], 0.0)
        self.labels = tuple(labels)
        self.starts = starts
        self.ends = ends
        self.source = source
        self.silence = silence
        self.starts.setflags(write=False)
        self.ends.setflags(write=False)

    # -- views ---------------------------------------------------------
    def __len__(self) -> int:
        return len(self.labels)

    def __repr__(self) -> str:
        src = f", source={self.source!r}" if self.source else ""
        return f"Alignment({len(self)} segments, {self.duration:.3f} s{src})"

    def __eq__(self, other) -> bool:
        return (
            isinstance(other, Alignment)
            and self.labels == other.labels
            and np.allclose(self.starts, other.starts, atol=TIME_TOL)
            and np.allclose(self.ends, other.ends, atol=TIME_TOL)
        )

    __hash__ = None

    @property
    def duration(self) -> float:
        """End time of the last segment, in seconds."""
        return float(self.ends[-1])

    @property
    def durations(self) -> np.ndarray:
        return self.ends - self.starts

    @property
    def phones(self) -> set[str]:
        return set(self.labels)

    def n_frames(self, frame_rate: float) -> int:
        """Number of frames ``i`` with ``i / frame_rate <= duration`` (see the module's conventions)."""
        return _n_frames(self.duration, frame_rate)

    def shifted(self, seconds: float) -> Alignment:
        """The same segments ``seconds`` later; the new leading gap is silence."""
        if seconds < 0:
            raise DataError(self.source, "shift", seconds, "must be non-negative")
        return Alignment(
            self.labels, self.starts + seconds, self.ends + seconds, source=self.source, silence=self.silence
        )

    def with_end(self, end: float) -> Alignment:
        """Extend with trailing silence, or trim the last segment, to end at ``end``."""
        if end > self.duration + TIME_TOL:
            return Alignment(
                self.labels + (self.silence,),
                np.append(self.starts, self.duration),
                np.append(self.ends, end),
                source=self.source,
                silence=self.silence,
            )
        if end < self.duration - TIME_TOL:
            if end <= self.starts[-1] + TIME_TOL:
                raise DataError(self.source, "end", end, f"trimming would remove the last segment {self.labels[-1]!r}")
            ends = self.ends.copy()
            ends[-1] = end
            return Alignment(self.labels, self.starts, ends, source=self.source, silence=self.silence)
        return self

    def relabel(self, mapping) -> Alignment:
        """Return a copy with labels mapped through ``mapping`` (dict or callable)."""
        f = mapping if callable(mapping) else (lambda x: mapping.get(x, x))
        return Alignment(
            [f(lab) for lab in self.labels], self.starts, self.ends, source=self.source, silence=self.silence
        )

    def segment_index(self, frame_rate: float, n_frames: int | None = None) -> np.ndarray:
        """Index of the segment each frame falls in, shape (n_frames,)."""
        n = self.n_frames(frame_rate) if n_frames is None else n_frames
        t = np.arange(n) / frame_rate
        idx = np.searchsorted(self.ends, t + 1e-9, side="right")
        return np.minimum(idx, len(self) - 1)


def frame_times(n_frames: int, frame_rate: float) -> np.ndarray:
    """Times of frames ``0 .. n_frames-1``: ``i / frame_rate``."""
    return np.arange(n_frames) / float(frame_rate)


def frame_labels(alignment: Alignment, frame_rate: float, n_frames: int | None = None) -> list[str]:
    """The phone label of every frame."""
    idx = alignment.segment_index(frame_rate, n_frames)
    return [alignment.labels[i] for i in idx]


class Utterance:
    """An alignment with its trajectory.

    Parameters
    ----------
    alignment : Alignment
    trajectory : array-like, shape (n_frames, n_channels)
        Frame ``i`` is the sample at ``i / frame_rate``. If the trajectory is
        longer than the alignment the alignment gets trailing silence; it may
        be shorter by at most one frame (the last segment is trimmed).
    frame_rate : float
        Frames per second.
    channels : sequence of str, length n_channels
    audio : str, optional
        Path of a WAV or FLAC file with the utterance's audio.
    name : str, optional
        Defaults to the alignment's source file stem.
    mask : array-like of bool, shape (n_frames, n_channels), optional
        Missing data: False where the value was not observed (a sensor
        dropout). Default None: everything observed. The stored trajectory
        is always finite: masked values (whatever was passed, NaN included)
        are replaced by linear interpolation over time between the channel's
        observed values (:func:`fill_masked`). Scoring ignores them; see
        ``Synthesizer.fit`` for how models treat them.

    Examples
    --------
    >>> import numpy as np, dam
    >>> a = dam.Alignment(["sil", "a", "sil"], [0.0, 0.1, 0.3], [0.1, 0.3, 0.4])
    >>> u = dam.Utterance(a, np.zeros((41, 2)), 100.0, ["jaw", "lip"], name="u1")
    >>> u.trajectory.shape, u.channels
    ((41, 2), ('jaw', 'lip'))
    """

    __slots__ = ("alignment", "trajectory", "frame_rate", "channels", "audio", "name", "mask")

    def __init__(
        self,
        alignment: Alignment,
        trajectory,
        frame_rate: float,
        channels: Sequence[str],
        *,
        audio: str | None = None,
        name: str | None = None,
        source: str | None = None,
        mask=None,
    ):
        if not isinstance(alignment, Alignment):
            raise TypeError(f"{source or '<input>'}: alignment must be an Alignment, got {type(alignment).__name__}")
        source = source or alignment.source
        try:
            fr = float(frame_rate)
        except (TypeError, ValueError):
            raise DataError(source, "frame_rate", frame_rate, "not a number") from None
        if not (math.isfinite(fr) and 0 < fr <= MAX_FRAME_RATE):
            raise DataError(
                source,
                "frame_rate",
                frame_rate,
                f"must be a positive finite number of at most {MAX_FRAME_RATE:g} frames/s",
            )
        traj = real_array(trajectory, source, "trajectory")
        if traj.ndim == 1:
            traj = traj[:, None]
        if traj.ndim != 2:
            raise DataError(source, "trajectory", traj.shape, "must be 2-D (n_frames, n_channels)")
        if isinstance(channels, (str, bytes)) or not hasattr(channels, "__iter__"):
            raise DataError(source, "channels", channels, "must be a sequence of channel names")
        channels = tuple(str(c) for c in channels)
        if len(channels) != traj.shape[1]:
            raise DataError(
                source,
                "channels",
                len(channels),
                f"the trajectory has {traj.shape[1]} columns but {len(channels)} channel names",
            )
        if len(set(channels)) != len(channels):
            dup = next(c for c in channels if channels.count(c) > 1)
            raise DataError(source, "channels", dup, "duplicate channel name")
        if mask is not None:
            mask = real_array(mask, source, "mask") != 0
            if mask.shape != traj.shape:
                raise DataError(source, "mask", mask.shape, f"must have the trajectory's shape {traj.shape}")
            mask = None if mask.all() else mask
        bad = np.argwhere(~np.isfinite(traj) & (True if mask is None else mask))
        if bad.size:
            i, j = (int(v) for v in bad[0])
            raise DataError(
                source,
                f"trajectory[{i}, {channels[j]!r}] (frame {i}, t={i / fr:.3f} s)",
                float(traj[i, j]),
                "value is not finite",
                f"{len(bad)} non-finite value(s) in all; interpolate or drop them before loading",
            )
        n = traj.shape[0]
        if n == 0:
            raise DataError(source, "trajectory", traj.shape, "the trajectory has no frames")
        alignment = fit_to_frames(alignment, n, fr, source)
        if mask is not None:
            traj = fill_masked(traj, mask)
            mask.setflags(write=False)
        traj.setflags(write=False)
        self.mask = mask
        self.alignment = alignment
        self.trajectory = traj
        self.frame_rate = fr
        self.channels = channels
        self.audio = audio
        self.name = name or (_stem(alignment.source) if alignment.source else None)

    def __repr__(self) -> str:
        return (
            f"Utterance({self.name!r}, {len(self.alignment)} segments, "
            f"{self.n_frames} frames x {self.n_channels} channels @ {self.frame_rate:g} Hz)"
        )

    @property
    def n_frames(self) -> int:
        return self.trajectory.shape[0]

    @property
    def n_channels(self) -> int:
        return self.trajectory.shape[1]

    @property
    def duration(self) -> float:
        return self.n_frames / self.frame_rate

    def replace(self, **changes) -> Utterance:
        """A copy with some fields replaced (``alignment``, ``trajectory``, ...)."""
        kw = dict(
            alignment=self.alignment,
            trajectory=self.trajectory,
            frame_rate=self.frame_rate,
            channels=self.channels,
            audio=self.audio,
            name=self.name,
            mask=self.mask,
        )
        if (
            "mask" not in changes
            and self.mask is not None
            and np.shape(changes.get("trajectory", self.trajectory)) != self.mask.shape
        ):
            kw["mask"] = None  # a trajectory of another shape: the old mask cannot describe it
        kw.update(changes)
        alignment, trajectory, fr, channels = (kw.pop(k) for k in ("alignment", "trajectory", "frame_rate", "channels"))
        return Utterance(alignment, trajectory, fr, channels, **kw)


def _merge_silences(labels, starts, ends, silence):
    """Adjacent ``silence`` segments merged into one (labels list, starts, ends arrays)."""
    sil = np.array([lab == silence for lab in labels])
    if len(labels) < 2 or not np.any(sil[1:] & sil[:-1]):
        return labels, starts, ends
    keep = ~np.r_[False, sil[1:] & sil[:-1]]  # first of every run of silences
    last = np.r_[~(sil[1:] & sil[:-1]), True]  # last of every run
    return ([lab for lab, k in zip(labels, keep) if k], starts[keep], ends[last])


def fit_to_frames(alignment: Alignment, n_frames: int, frame_rate: float, source=None) -> Alignment:
    """The alignment an utterance of ``n_frames`` frames keeps: the edge convention.

    See the module's conventions: silence segments shorter than one frame
    are absorbed into their neighbour; an end within one frame of the last
    frame time ``(n_frames - 1) / frame_rate`` is kept; a shorter gap or any
    overhang (up to two frames) moves the last segment's end to the last
    frame time; a longer gap becomes trailing silence. Afterwards
    ``alignment.n_frames(frame_rate) == n_frames``.

    Raises
    ------
    DataError
        If the alignment runs more than two frames past the last frame time.

    Examples
    --------
    >>> a = Alignment(["sil", "a", "sil"], [0.0, 0.1, 0.2], [0.1, 0.2, 0.29])
    >>> fit_to_frames(a, 30, 100.0) is a        # ends at the last frame time
    True
    >>> float(fit_to_frames(a, 40, 100.0).ends[-1])    # the pause grows to the last frame
    0.39
    """
    a = alignment
    source = source or a.source
    last = (n_frames - 1) / frame_rate
    frame = 1.0 / frame_rate
    if a.duration > last + 2 * frame + TIME_TOL:
        raise DataError(
            source,
            "trajectory",
            f"{n_frames} frames",
            f"shorter than its alignment, which needs {a.n_frames(frame_rate)} frames "
            f"({a.duration:.3f} s at {frame_rate:g} frames/s)",
        )
    labels, starts, ends = list(a.labels), a.starts.copy(), a.ends.copy()
    short = [
        j
        for j, lab in enumerate(labels)
        if lab == a.silence and ends[j] - starts[j] < frame - TIME_TOL and len(labels) > 1
    ]
    for j in reversed(short):  # into the previous segment (the next one for the first)
        if j > 0:
            ends[j - 1] = ends[j]
        else:
            starts[1] = starts[0]
        del labels[j]
        starts, ends = np.delete(starts, j), np.delete(ends, j)
    end = ends[-1]
    if end >= last + frame - TIME_TOL:  # overhang: trim to the last frame time
        keep = starts < last - TIME_TOL
        if not keep.any():
            raise DataError(
                source, "trajectory", f"{n_frames} frames", f"the alignment starts after the last frame ({last:.3f} s)"
            )
        labels = [lab for lab, k in zip(labels, keep) if k]
        starts, ends = starts[keep], ends[keep]
        ends[-1] = last
    elif end < last - frame + TIME_TOL:  # a real pause: trailing silence
        labels.append(a.silence)
        starts, ends = np.append(starts, end), np.append(ends, last)
    elif end < last - TIME_TOL:  # a sub-frame gap: absorbed
        ends[-1] = last
    if not short and len(labels) == len(a) and np.array_equal(ends, a.ends):
        return a
    return Alignment(labels, starts, ends, source=a.source, silence=a.silence)


def fill_masked(trajectory, mask) -> np.ndarray:
    """``trajectory`` with its masked values replaced by interpolation over time.

    Parameters
    ----------
    trajectory : ndarray, shape (n_frames, n_channels)
    mask : ndarray of bool, same shape
        True where observed.

    Returns
    -------
    ndarray, same shape
        Per channel, unobserved frames get the linear interpolation between
        the nearest observed frames (the nearest observed value before the
        first or after the last one); a channel with no observed frame is 0.

    Examples
    --------
    >>> fill_masked(np.array([[1.0], [99.0], [3.0]]), np.array([[True], [False], [True]])).ravel().tolist()
    [1.0, 2.0, 3.0]
    """
    out = np.array(trajectory, dtype=float, copy=True)
    frames = np.arange(out.shape[0])
    for j in np.flatnonzero(~mask.all(axis=0)):
        ok = mask[:, j]
        out[~ok, j] = np.interp(frames[~ok], frames[ok], out[ok, j]) if ok.any() else 0.0
    return out


def _stem(path: str) -> str:
    import os

    return os.path.splitext(os.path.basename(str(path)))[0]


class Corpus:
    """Utterances sharing one frame rate and one set of channel names.

    Parameters
    ----------
    utterances : iterable of Utterance
        At least one.
    name : str, optional
    metadata : dict, optional
        Anything else (kept from ``corpus.json``).
    source : str, optional
        Directory the corpus was read from; used in error messages.

    Examples
    --------
    >>> import dam
    >>> corpus = dam.datasets.load("tiny")
    >>> train, test = corpus.train_test_split(0.25, random_state=0)
    >>> len(train) + len(test) == len(corpus)
    True
    >>> corpus.frame_rate, len(corpus.channels)
    (100.0, 4)
    """

    def __init__(
        self,
        utterances: Iterable[Utterance],
        *,
        name: str | None = None,
        metadata: dict | None = None,
        source: str | None = None,
    ):
        utts = list(utterances)
        if not utts:
            raise DataError(source, "utterances", 0, "the corpus is empty", "a corpus needs at least one utterance")
        for k, u in enumerate(utts):
            if not isinstance(u, Utterance):
                raise TypeError(f"{source or '<corpus>'}: item {k} is a {type(u).__name__}, not an Utterance")
        ref = utts[0]
        for u in utts[1:]:
            where = u.alignment.source or u.name or source
            if abs(u.frame_rate - ref.frame_rate) > 1e-9 * ref.frame_rate:
                raise DataError(
                    where,
                    "frame_rate",
                    u.frame_rate,
                    f"differs from the corpus frame rate {ref.frame_rate:g} (of {ref.name!r})",
                )
            if u.channels != ref.channels:
                if len(u.channels) != len(ref.channels):
                    raise DataError(
                        where,
                        "channels",
                        len(u.channels),
                        f"channel count differs from {len(ref.channels)} in {ref.name!r}",
                    )
                raise DataError(
                    where, "channels", u.channels, f"channel names differ from {ref.channels} in {ref.name!r}"
                )
        self.utterances = utts
        self.name = name
        self.metadata = dict(metadata or {})
        self.source = source

    # -- container protocol --------------------------------------------
    def __len__(self) -> int:
        return len(self.utterances)

    def __iter__(self) -> Iterator[Utterance]:
        return iter(self.utterances)

    def __getitem__(self, key):
        if isinstance(key, slice):
            return self.subset(range(len(self))[key])
        if isinstance(key, str):
            for u in self.utterances:
                if u.name == key:
                    return u
            raise KeyError(f"{self.source or '<corpus>'}: no utterance named {key!r}")
        return self.utterances[key]

    def __repr__(self) -> str:
        nm = f"{self.name!r}, " if self.name else ""
        return (
            f"Corpus({nm}{len(self)} utterances, {self.duration / 60:.1f} min, "
            f"{len(self.channels)} channels @ {self.frame_rate:g} Hz, {len(self.phones)} phones)"
        )

    # -- shared properties -----------------------------------------------
    @property
    def frame_rate(self) -> float:
        return self.utterances[0].frame_rate

    @property
    def channels(self) -> tuple[str, ...]:
        return self.utterances[0].channels

    @property
    def n_channels(self) -> int:
        return len(self.channels)

    @property
    def alignments(self) -> list[Alignment]:
        return [u.alignment for u in self.utterances]

    @property
    def trajectories(self) -> list[np.ndarray]:
        return [u.trajectory for u in self.utterances]

    @property
    def masks(self) -> list:
        """Each utterance's missing-data mask (None where all is observed)."""
        return [u.mask for u in self.utterances]

    @property
    def sensors(self) -> dict[str, tuple[str, ...]]:
        """Sensor name -> its x/y(/z) channels: ``metadata["sensors"]`` (from ``corpus.json``)
        if given, else inferred from the channel names (:func:`infer_sensors`)."""
        return resolve_sensors(self.channels, self.metadata.get("sensors"), source=self.source)

    @property
    def phones(self) -> set[str]:
        out: set[str] = set()
        for u in self.utterances:
            out.update(u.alignment.labels)
        return out

    @property
    def n_frames(self) -> int:
        return sum(u.n_frames for u in self.utterances)

    @property
    def n_segments(self) -> int:
        return sum(len(u.alignment) for u in self.utterances)

    @property
    def duration(self) -> float:
        return sum(u.duration for u in self.utterances)

    def select_channels(self, channels: Sequence[str]) -> Corpus:
        """A corpus with only ``channels``, in that order (names must exist)."""
        names = list(self.channels)
        missing = [c for c in channels if c not in names]
        if missing or not channels:
            raise DataError(
                self.source,
                "channels",
                missing or list(channels),
                "not channels of this corpus" if missing else "no channels selected",
                f"its channels are {names}",
            )
        cols = [names.index(c) for c in channels]
        meta = dict(self.metadata)
        if isinstance(meta.get("sensors"), dict):  # keep the sensors whose channels all remain
            meta["sensors"] = {k: v for k, v in meta["sensors"].items() if set(v) <= set(channels)}
        return Corpus(
            [
                u.replace(
                    trajectory=u.trajectory[:, cols],
                    channels=list(channels),
                    mask=None if u.mask is None else u.mask[:, cols],
                )
                for u in self
            ],
            name=self.name,
            metadata=meta,
            source=self.source,
        )

    # -- splitting ---------------------------------------------------------
    def subset(self, indices) -> Corpus:
        return Corpus([self.utterances[i] for i in indices], name=self.name, metadata=self.metadata, source=self.source)

    def train_test_split(self, test_size: float | int = 0.2, *, random_state: int | None = 0) -> tuple[Corpus, Corpus]:
        """Utterance-level split; both parts keep at least one utterance."""
        n = len(self)
        if n < 2:
            raise DataError(self.source, "utterances", n, "need at least 2 utterances to split")
        n_test = int(round(test_size * n)) if isinstance(test_size, float) else int(test_size)
        n_test = min(max(n_test, 1), n - 1)
        perm = np.random.default_rng(random_state).permutation(n)
        return self.subset(sorted(perm[n_test:])), self.subset(sorted(perm[:n_test]))

    def kfold(
        self, n_splits: int = 5, *, shuffle: bool = True, random_state: int | None = 0
    ) -> Iterator[tuple[Corpus, Corpus]]:
        """Yield ``(train, test)`` corpora for utterance-level K-fold cross-validation."""
        n = len(self)
        if not 2 <= n_splits <= n:
            raise DataError(self.source, "n_splits", n_splits, f"must be between 2 and the {n} utterances")
        order = np.random.default_rng(random_state).permutation(n) if shuffle else np.arange(n)
        for test in np.array_split(order, n_splits):
            test_set = set(test.tolist())
            yield self.subset([i for i in range(n) if i not in test_set]), self.subset(sorted(test_set))


# -- sensors ------------------------------------------------------------------
# EMA and X-ray microbeam corpora record each sensor (coil, pellet) as 2 or 3 position
# channels; Corpus.sensors groups them for the per-sensor error of Medina et al. (2022, Eq. 1).
_SEPARATED = re.compile(r"^(?P<sensor>.+?)_p?(?P<axis>[xyzXYZ])$")
_UPPER = re.compile(r"^(?P<sensor>[A-Z][A-Z0-9]*?)(?P<axis>[XYZ])$")


def _split(name: str) -> tuple[str, str] | None:
    m = _SEPARATED.match(name) or _UPPER.match(name)
    if not m:
        return None
    return m.group("sensor"), m.group("axis").lower()


def infer_sensors(channels: Sequence[str]) -> dict[str, tuple[str, ...]]:
    """Group position channels into sensors by their names.

    Recognised names: ``<sensor>_<axis>`` with axis ``x``, ``y`` or ``z``
    (MOCHA-TIMIT ``tt_x``, X-ray microbeam ``T1_x``); ``<sensor>_p<axis>``, a
    position channel (mngu0 ``T1_py``, Haskins/mview ``TT_px``; orientation
    channels ``_ox`` ... are no positions); an upper-case ``<SENSOR><AXIS>``
    (VocalTractLab ``TTX``, ``TTY``). A group needs two or three distinct
    axes; a lone ``JX`` beside ``JA`` is no sensor. ``corpus.json`` can name
    the sensors instead: ``{"sensors": {"TT": ["tt_x", "tt_y"]}}``.

    Parameters
    ----------
    channels : sequence of str
        Channel names, in corpus order.

    Returns
    -------
    dict of str to tuple of str
        Sensor name -> its channels ordered x, y, z; sensors in the order of
        their first channel. Channels that fit no pattern belong to no sensor.

    Examples
    --------
    >>> infer_sensors(["tt_x", "tt_y", "T1_px", "T1_pz", "T1_ox", "JX", "JA"])
    {'tt': ('tt_x', 'tt_y'), 'T1': ('T1_px', 'T1_pz')}
    """
    groups: dict[str, dict[str, str]] = {}
    for name in channels:
        parts = _split(str(name))
        if parts is None:
            continue
        sensor, axis = parts
        axes = groups.setdefault(sensor, {})
        if axis in axes:  # two channels claim one axis: the names do not describe a sensor
            axes["?"] = name
        else:
            axes[axis] = name
    return {
        s: tuple(axes[a] for a in "xyz" if a in axes)
        for s, axes in groups.items()
        if "?" not in axes and len(axes) >= 2
    }


def resolve_sensors(
    channels: Sequence[str], given: Mapping | None = None, *, source: str | None = None
) -> dict[str, tuple[str, ...]]:
    """The sensors of a corpus: ``given`` (from ``corpus.json``) if any, else inferred.

    Parameters
    ----------
    channels : sequence of str
    given : mapping of str to sequence of str, optional
        Sensor name -> its 2 or 3 channel names.
    source : str, optional
        Named in errors (the corpus directory).

    Raises
    ------
    DataError
        A given sensor names a channel the corpus does not have, has fewer
        than two or more than three channels, or shares a channel with another.
    """
    if given is None:
        return infer_sensors(channels)
    if not isinstance(given, Mapping):
        raise DataError(
            source,
            "sensors",
            type(given).__name__,
            'must map sensor names to lists of channels, e.g. {"TT": ["tt_x", "tt_y"]}',
        )
    names = set(channels)
    seen: dict[str, str] = {}
    out: dict[str, tuple[str, ...]] = {}
    for sensor, chans in given.items():
        if isinstance(chans, str) or not isinstance(chans, Sequence) or not 2 <= len(chans) <= 3:
            raise DataError(source, f"sensors[{sensor!r}]", chans, "a sensor is a list of 2 or 3 channels")
        for c in chans:
            if c not in names:
                raise DataError(
                    source,
                    f"sensors[{sensor!r}]",
                    c,
                    "not a channel of this corpus",
                    f"its channels are {list(channels)}",
                )
            if c in seen:
                raise DataError(source, f"sensors[{sensor!r}]", c, f"already a channel of sensor {seen[c]!r}")
            seen[c] = sensor
        out[str(sensor)] = tuple(str(c) for c in chans)
    return out
