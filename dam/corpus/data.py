"""The data model: alignments, utterances and corpora.

Validation happens here, once, where data enters the toolkit. Every error
names the source (file), the field and the offending value.

Conventions
-----------
* Times are in seconds. Frame ``i`` of a trajectory is the sample at time
  ``i / frame_rate``; an alignment ending at ``T`` covers
  ``ceil(T * frame_rate)`` frames.
* Silence: empty labels and ``sil``, ``sp``, ``spn``, ``pau`` (any case)
  become one canonical silence label (``SILENCE``, configurable per call).
  A gap between two segments becomes a silence segment of its own; nothing
  is merged or dropped.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Iterable, Iterator, Sequence

import numpy as np

SILENCE = "sil"
SILENCE_LABELS = frozenset({"", "sil", "sp", "spn", "pau", "<sil>", "silence"})
# Times closer than this (seconds) count as equal: TextGrids store decimals.
TIME_TOL = 1e-6

__all__ = [
    "SILENCE", "SILENCE_LABELS", "DataError", "Alignment", "Utterance", "Corpus",
    "frame_times", "frame_labels",
]


class DataError(ValueError):
    """Bad input data. The message names the source, the field and the value."""

    def __init__(self, source, field_, value, problem, hint=None):
        self.source, self.field, self.value = source, field_, value
        msg = f"{source or '<input>'}: field {field_!r}: {problem} (got {value!r})"
        if hint:
            msg += f"; {hint}"
        super().__init__(msg)


def _n_frames(duration: float, frame_rate: float) -> int:
    return int(math.ceil(duration * frame_rate - 1e-6))


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
    """

    __slots__ = ("labels", "starts", "ends", "source", "silence")

    def __init__(self, labels: Sequence[str], starts, ends, *, source: str | None = None,
                 silence: str = SILENCE):
        labels = [canonical_label(lab, silence) for lab in labels]
        starts = np.array(starts, dtype=float).ravel()  # copies: snapped below, frozen after
        ends = np.array(ends, dtype=float).ravel()
        if not (len(labels) == len(starts) == len(ends)):
            raise DataError(source, "segments", (len(labels), len(starts), len(ends)),
                            "labels, starts and ends differ in length")
        if len(labels) == 0:
            raise DataError(source, "segments", 0, "the alignment has no segments")
        for name, arr in (("start", starts), ("end", ends)):
            bad = np.flatnonzero(~np.isfinite(arr))
            if bad.size:
                i = int(bad[0])
                raise DataError(source, f"segment {i} ({labels[i]!r}) {name}", float(arr[i]),
                                "time is not finite")
        if starts[0] < -TIME_TOL:
            raise DataError(source, f"segment 0 ({labels[0]!r}) start", float(starts[0]),
                            "time is negative")
        length = ends - starts
        bad = np.flatnonzero(length <= TIME_TOL)
        if bad.size:
            i = int(bad[0])
            raise DataError(source, f"segment {i} ({labels[i]!r})", (float(starts[i]), float(ends[i])),
                            "zero-length or reversed segment (start >= end)")
        back = np.flatnonzero(starts[1:] < starts[:-1])
        if back.size:
            i = int(back[0]) + 1
            raise DataError(source, f"segment {i} ({labels[i]!r}) start", float(starts[i]),
                            f"times are not sorted (previous segment starts at {starts[i - 1]:g})")
        over = np.flatnonzero(starts[1:] < ends[:-1] - TIME_TOL)
        if over.size:
            i = int(over[0]) + 1
            raise DataError(source, f"segment {i} ({labels[i]!r}) start", float(starts[i]),
                            f"overlaps the previous segment {labels[i - 1]!r}, which ends at {ends[i - 1]:g}")
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
            for k, (i, lab) in enumerate(reversed(ins_lab)):
                new_labels.insert(i, lab)
            labels = new_labels
            starts = np.insert(starts, gap, ins_s)
            ends = np.insert(ends, gap, ins_e)
        # Snap near-equal boundaries so segments tile exactly.
        starts[1:] = np.where(np.abs(starts[1:] - ends[:-1]) <= TIME_TOL, ends[:-1], starts[1:])
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
        return (isinstance(other, Alignment) and self.labels == other.labels
                and np.allclose(self.starts, other.starts, atol=TIME_TOL)
                and np.allclose(self.ends, other.ends, atol=TIME_TOL))

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
        """Number of frames ``i`` with ``i / frame_rate < duration``."""
        return _n_frames(self.duration, frame_rate)

    def shifted(self, seconds: float) -> "Alignment":
        """The same segments ``seconds`` later; the new leading gap is silence."""
        if seconds < 0:
            raise DataError(self.source, "shift", seconds, "must be non-negative")
        return Alignment(self.labels, self.starts + seconds, self.ends + seconds,
                         source=self.source, silence=self.silence)

    def with_end(self, end: float) -> "Alignment":
        """Extend with trailing silence, or trim the last segment, to end at ``end``."""
        if end > self.duration + TIME_TOL:
            return Alignment(self.labels + (self.silence,), np.append(self.starts, self.duration),
                             np.append(self.ends, end), source=self.source, silence=self.silence)
        if end < self.duration - TIME_TOL:
            if end <= self.starts[-1] + TIME_TOL:
                raise DataError(self.source, "end", end,
                                f"trimming would remove the last segment {self.labels[-1]!r}")
            ends = self.ends.copy()
            ends[-1] = end
            return Alignment(self.labels, self.starts, ends, source=self.source, silence=self.silence)
        return self

    def relabel(self, mapping) -> "Alignment":
        """Return a copy with labels mapped through ``mapping`` (dict or callable)."""
        f = mapping if callable(mapping) else (lambda x: mapping.get(x, x))
        return Alignment([f(lab) for lab in self.labels], self.starts, self.ends,
                         source=self.source, silence=self.silence)

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
        Path of a WAV file with the utterance's audio.
    name : str, optional
        Defaults to the alignment's source file stem.
    """

    __slots__ = ("alignment", "trajectory", "frame_rate", "channels", "audio", "name")

    def __init__(self, alignment: Alignment, trajectory, frame_rate: float,
                 channels: Sequence[str], *, audio: str | None = None, name: str | None = None,
                 source: str | None = None):
        source = source or alignment.source
        if not isinstance(alignment, Alignment):
            raise TypeError(f"{source or '<input>'}: alignment must be an Alignment, got {type(alignment).__name__}")
        try:
            fr = float(frame_rate)
        except (TypeError, ValueError):
            raise DataError(source, "frame_rate", frame_rate, "not a number") from None
        if not (math.isfinite(fr) and fr > 0):
            raise DataError(source, "frame_rate", frame_rate, "must be a positive finite number")
        traj = np.array(trajectory, dtype=float, copy=True)
        if traj.ndim == 1:
            traj = traj[:, None]
        if traj.ndim != 2:
            raise DataError(source, "trajectory", traj.shape, "must be 2-D (n_frames, n_channels)")
        channels = tuple(str(c) for c in channels)
        if len(channels) != traj.shape[1]:
            raise DataError(source, "channels", len(channels),
                            f"the trajectory has {traj.shape[1]} columns but {len(channels)} channel names")
        if len(set(channels)) != len(channels):
            dup = next(c for c in channels if channels.count(c) > 1)
            raise DataError(source, "channels", dup, "duplicate channel name")
        bad = np.argwhere(~np.isfinite(traj))
        if bad.size:
            i, j = (int(v) for v in bad[0])
            raise DataError(source, f"trajectory[{i}, {channels[j]!r}] (frame {i}, t={i / fr:.3f} s)",
                            float(traj[i, j]), "value is not finite",
                            f"{len(bad)} non-finite value(s) in all; interpolate or drop them before loading")
        n = traj.shape[0]
        if n == 0:
            raise DataError(source, "trajectory", traj.shape, "the trajectory has no frames")
        need = alignment.n_frames(fr)
        if n < need - 1:
            raise DataError(source, "trajectory", f"{n} frames",
                            f"shorter than its alignment, which needs {need} frames "
                            f"({alignment.duration:.3f} s at {fr:g} frames/s)")
        if n != need:
            alignment = alignment.with_end(n / fr)
        traj.setflags(write=False)
        self.alignment = alignment
        self.trajectory = traj
        self.frame_rate = fr
        self.channels = channels
        self.audio = audio
        self.name = name or (_stem(alignment.source) if alignment.source else None)

    def __repr__(self) -> str:
        return (f"Utterance({self.name!r}, {len(self.alignment)} segments, "
                f"{self.n_frames} frames x {self.n_channels} channels @ {self.frame_rate:g} Hz)")

    @property
    def n_frames(self) -> int:
        return self.trajectory.shape[0]

    @property
    def n_channels(self) -> int:
        return self.trajectory.shape[1]

    @property
    def duration(self) -> float:
        return self.n_frames / self.frame_rate

    def replace(self, **changes) -> "Utterance":
        """A copy with some fields replaced (``alignment``, ``trajectory``, ...)."""
        kw = dict(alignment=self.alignment, trajectory=self.trajectory, frame_rate=self.frame_rate,
                  channels=self.channels, audio=self.audio, name=self.name)
        kw.update(changes)
        alignment, trajectory, fr, channels = (kw.pop(k) for k in ("alignment", "trajectory",
                                                                   "frame_rate", "channels"))
        return Utterance(alignment, trajectory, fr, channels, **kw)


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
    """

    def __init__(self, utterances: Iterable[Utterance], *, name: str | None = None,
                 metadata: dict | None = None, source: str | None = None):
        utts = list(utterances)
        if not utts:
            raise DataError(source, "utterances", 0, "the corpus is empty",
                            "a corpus needs at least one utterance")
        for k, u in enumerate(utts):
            if not isinstance(u, Utterance):
                raise TypeError(f"{source or '<corpus>'}: item {k} is a {type(u).__name__}, not an Utterance")
        ref = utts[0]
        for u in utts[1:]:
            where = u.alignment.source or u.name or source
            if abs(u.frame_rate - ref.frame_rate) > 1e-9 * ref.frame_rate:
                raise DataError(where, "frame_rate", u.frame_rate,
                                f"differs from the corpus frame rate {ref.frame_rate:g} (of {ref.name!r})")
            if u.channels != ref.channels:
                if len(u.channels) != len(ref.channels):
                    raise DataError(where, "channels", len(u.channels),
                                    f"channel count differs from {len(ref.channels)} in {ref.name!r}")
                raise DataError(where, "channels", u.channels,
                                f"channel names differ from {ref.channels} in {ref.name!r}")
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
        return (f"Corpus({nm}{len(self)} utterances, {self.duration / 60:.1f} min, "
                f"{len(self.channels)} channels @ {self.frame_rate:g} Hz, {len(self.phones)} phones)")

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

    def select_channels(self, channels: Sequence[str]) -> "Corpus":
        """A corpus with only ``channels``, in that order (names must exist)."""
        names = list(self.channels)
        missing = [c for c in channels if c not in names]
        if missing or not channels:
            raise DataError(self.source, "channels", missing or list(channels),
                            "not channels of this corpus" if missing else "no channels selected",
                            f"its channels are {names}")
        cols = [names.index(c) for c in channels]
        return Corpus([u.replace(trajectory=u.trajectory[:, cols], channels=list(channels)) for u in self],
                      name=self.name, metadata=self.metadata, source=self.source)

    # -- splitting ---------------------------------------------------------
    def subset(self, indices) -> "Corpus":
        return Corpus([self.utterances[i] for i in indices], name=self.name,
                      metadata=self.metadata, source=self.source)

    def train_test_split(self, test_size: float | int = 0.2, *, random_state: int | None = 0
                         ) -> tuple["Corpus", "Corpus"]:
        """Utterance-level split; both parts keep at least one utterance."""
        n = len(self)
        if n < 2:
            raise DataError(self.source, "utterances", n, "need at least 2 utterances to split")
        n_test = int(round(test_size * n)) if isinstance(test_size, float) else int(test_size)
        n_test = min(max(n_test, 1), n - 1)
        perm = np.random.default_rng(random_state).permutation(n)
        return self.subset(sorted(perm[n_test:])), self.subset(sorted(perm[:n_test]))

    def kfold(self, n_splits: int = 5, *, shuffle: bool = True, random_state: int | None = 0
              ) -> Iterator[tuple["Corpus", "Corpus"]]:
        """Yield ``(train, test)`` corpora for utterance-level K-fold cross-validation."""
        n = len(self)
        if not 2 <= n_splits <= n:
            raise DataError(self.source, "n_splits", n_splits, f"must be between 2 and the {n} utterances")
        order = np.random.default_rng(random_state).permutation(n) if shuffle else np.arange(n)
        for test in np.array_split(order, n_splits):
            test_set = set(test.tolist())
            yield self.subset([i for i in range(n) if i not in test_set]), self.subset(sorted(test_set))
