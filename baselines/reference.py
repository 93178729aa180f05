"""Reference synthesizers: the simplest things people ship, for every model to beat.

* ``phone-mean``: each frame takes the mean value of its phone (a step function).
* ``target-interpolation``: one target per phone at the segment midpoint
  (the mean of the training frames nearest the midpoints), interpolated by
  a cubic Hermite spline with Catmull-Rom tangents: the classic viseme
  keyframe approach.

Both synthesize with numpy alone.
"""

from __future__ import annotations

import numpy as np

from dam import Alignment, Corpus, StateArray, Synthesizer

__all__ = ["PhoneMean", "TargetInterpolation"]


class _PerPhoneTable(Synthesizer):
    """Shared machinery: one vector per phone, looked up by label."""

    _tags = {"numpy_runtime": True}  # unknown_phone's constraint: declared by Synthesizer
    _state_schema = {"table_": StateArray("float", ("n_phones", "n_channels"))}  # checked at save and load

    def __init__(self, *, unknown_phone: str = "error"):
        self.unknown_phone = unknown_phone

    @classmethod
    def get_test_params(cls) -> list[dict]:
        return [{}, {"unknown_phone": "fallback"}]

    def _rows(self, alignment: Alignment) -> np.ndarray:
        """Row of ``table_`` for each segment."""
        index = {p: i for i, p in enumerate(self.phone_counts_)}
        return np.array([index[p] for p in self._known_labels(alignment, self.unknown_phone)])


class PhoneMean(_PerPhoneTable):
    """Each frame takes the mean trajectory value of its phone.

    Parameters
    ----------
    unknown_phone : {"error", "fallback"}, default "error"
        What to do with a phone never seen in training (see
        :meth:`dam.Synthesizer._known_labels`).

    Attributes
    ----------
    table_ : ndarray, shape (n_phones, n_channels)
        Mean value of every phone, rows in the order of ``phones_``.
    """

    name = "phone-mean"
    _tags = {"reference": True}  # the baseline the conformance suite measures others against

    def _fit(self, corpus: Corpus) -> None:
        index = {p: i for i, p in enumerate(self.phone_counts_)}
        sums = np.zeros((len(index), corpus.n_channels))
        counts = np.zeros((len(index), corpus.n_channels))
        for u in corpus:
            seg = u.alignment.segment_index(u.frame_rate, u.n_frames)
            rows = np.array([index[lab] for lab in u.alignment.labels])[seg]
            # missing values (Utterance.mask) do not count: the mean is over observed values only
            w = np.ones(u.trajectory.shape) if u.mask is None else u.mask.astype(float)
            np.add.at(sums, rows, u.trajectory * w)
            np.add.at(counts, rows, w)
        # A phone shorter than a frame (or never observed in a channel) gets the corpus mean.
        overall = sums.sum(axis=0) / np.maximum(counts.sum(axis=0), 1)
        self.table_ = np.where(counts > 0, sums / np.maximum(counts, 1), overall)

    def _predict(self, alignment: Alignment, n_frames: int) -> np.ndarray:
        rows = self._rows(alignment)
        return self.table_[rows[alignment.segment_index(self.frame_rate_, n_frames)]]


class TargetInterpolation(_PerPhoneTable):
    """One target per phone at the segment midpoint, interpolated smoothly.

    Parameters
    ----------
    unknown_phone : {"error", "fallback"}, default "error"

    Attributes
    ----------
    table_ : ndarray, shape (n_phones, n_channels)
        Target of every phone: the mean of the trajectory at its midpoints.
    """

    name = "target-interpolation"

    def _fit(self, corpus: Corpus) -> None:
        index = {p: i for i, p in enumerate(self.phone_counts_)}
        sums = np.zeros((len(index), corpus.n_channels))
        counts = np.zeros(len(index))
        for u in corpus:
            a = u.alignment
            mid = 0.5 * (a.starts + a.ends) * u.frame_rate
            # Linear interpolation of the trajectory at the exact midpoint time.
            vals = np.stack(
                [np.interp(mid, np.arange(u.n_frames), u.trajectory[:, c]) for c in range(u.n_channels)], axis=1
            )
            rows = np.array([index[lab] for lab in a.labels])
            np.add.at(sums, rows, vals)
            np.add.at(counts, rows, 1.0)
        self.table_ = sums / counts[:, None]

    def _predict(self, alignment: Alignment, n_frames: int) -> np.ndarray:
        keys_t = 0.5 * (alignment.starts + alignment.ends)
        keys_y = self.table_[self._rows(alignment)]
        return hermite_catmull_rom(keys_t, keys_y, np.arange(n_frames) / self.frame_rate_)


def hermite_catmull_rom(kt: np.ndarray, ky: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Cubic Hermite interpolation through keys ``(kt, ky)`` with Catmull-Rom tangents.

    Holds the first/last key outside the key range. ``ky`` has shape
    (n_keys, n_channels); returns (len(t), n_channels).
    """
    n = len(kt)
    if n == 1:
        return np.repeat(ky, len(t), axis=0)
    m = np.zeros_like(ky)
    m[1:-1] = (ky[2:] - ky[:-2]) / (kt[2:] - kt[:-2])[:, None]
    tc = np.clip(t, kt[0], kt[-1])
    k = np.clip(np.searchsorted(kt, tc, side="right") - 1, 0, n - 2)
    h = (kt[k + 1] - kt[k])[:, None]
    s = (tc[:, None] - kt[k][:, None]) / h
    s2, s3 = s * s, s * s * s
    return (
        (2 * s3 - 3 * s2 + 1) * ky[k]
        + (s3 - 2 * s2 + s) * h * m[k]
        + (-2 * s3 + 3 * s2) * ky[k + 1]
        + (s3 - s2) * h * m[k + 1]
    )
