"""Trajectory tables: CSV with a header row (and an optional leading ``time`` column) and ``.npy``."""

from __future__ import annotations

import io
import os

import numpy as np

from dam.corpus.atomic import atomic_write
from dam.corpus.data import DataError
from dam.corpus.encoding import read_text

__all__ = ["read_csv", "read_npy", "write_csv", "write_npy", "frame_rate_from_times"]


def read_csv(path: str) -> tuple[np.ndarray, list[str], float | None]:
    """Read a CSV trajectory; returns ``(data, channel names, frame rate or None)``."""
    path = os.fspath(path)
    header, _, body = read_text(path).partition("\n")  # UTF-8, BOM dropped (dam.corpus.encoding)
    names = [h.strip().strip('"') for h in header.strip().split(",")]
    if not header.strip() or not names:
        raise DataError(path, "header", header.strip(), "expected a header row of channel names")
    try:
        data = np.loadtxt(io.StringIO(body), delimiter=",", ndmin=2, dtype=float)
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
        raise DataError(
            source,
            where.format(k + 1 + first),
            float(t[k + 1]),
            f"the frame times are not evenly spaced (median step {dt:g} s)",
        )
    if abs(t[0]) > 0.5 * dt:
        raise DataError(
            source,
            where.format(first),
            float(t[0]),
            "the first frame must be at time 0 (frame i is at i / frame_rate)",
            "pad the trajectory to start at 0 or shift the alignment",
        )
    return 1.0 / dt


def read_npy(path: str) -> tuple[np.ndarray, list[str] | None, float | None]:
    """Read an ``.npy`` trajectory of shape (n_frames, n_channels); no names, no frame rate."""
    try:
        # Memory-mapped first: a header declaring more data than the file holds fails here,
        # before anything that size is allocated.
        data = np.array(np.load(path, allow_pickle=False, mmap_mode="r"))
    except Exception as exc:
        raise DataError(path, "npy", type(exc).__name__, f"cannot be read: {exc}") from None
    if data.dtype.kind not in "biuf":
        raise DataError(
            path,
            "dtype",
            str(data.dtype),
            "a trajectory must hold real numbers",
            "complex values have no meaning as articulator positions: store the part you mean",
        )
    if data.ndim == 1:
        data = data[:, None]
    if data.ndim != 2:
        raise DataError(path, "shape", data.shape, "must be (n_frames, n_channels)")
    return data, None, None


def write_csv(trajectory, channels, path, *, frame_rate: float | None = None, decimals: int | None = 6) -> None:
    """Write a trajectory CSV with a header row; a leading ``time`` column if ``frame_rate`` is given.

    ``path`` is a path (written atomically, :mod:`dam.corpus.atomic`) or an open text file
    (e.g. ``sys.stdout``). Non-finite values are refused: no NaN reaches an output.
    """
    is_file = hasattr(path, "write")
    where = "<stdout>" if is_file else os.fspath(path)
    data = np.asarray(trajectory, dtype=float)
    names = list(channels)
    if data.ndim != 2 or data.shape[1] != len(names):
        raise DataError(where, "channels", len(names), f"trajectory has shape {data.shape}")
    bad = [n for n in names if any(ch in n for ch in ',"\n\r')]
    if bad:
        raise DataError(where, "channels", bad[0], "a CSV channel name cannot contain a comma, quote or line break")
    if not np.all(np.isfinite(data)):
        i, j = (int(v) for v in np.argwhere(~np.isfinite(data))[0])
        raise DataError(where, f"trajectory[{i}, {names[j]!r}]", float(data[i, j]), "value is not finite")
    if frame_rate is not None:
        data = np.column_stack([np.arange(len(data)) / frame_rate, data])
        names = ["time"] + names
    fmt = "%.17g" if decimals is None else f"%.{decimals}g"
    if is_file:  # an open stream (stdout): not an output path of ours
        np.savetxt(path, data, delimiter=",", header=",".join(names), comments="", fmt=fmt)
        return
    with atomic_write(where, "w", encoding="utf-8", newline="") as fh:
        np.savetxt(fh, data, delimiter=",", header=",".join(names), comments="", fmt=fmt)


def write_npy(trajectory, path) -> None:
    """Write a trajectory as ``.npy`` (atomically; non-finite values are refused)."""
    data = np.asarray(trajectory)
    if data.dtype.kind not in "biuf":
        raise DataError(os.fspath(path), "trajectory", str(data.dtype), "must be a real numeric array")
    if data.dtype.kind == "f" and not np.all(np.isfinite(data)):
        raise DataError(os.fspath(path), "trajectory", "non-finite values", "value is not finite")
    with atomic_write(path, "wb") as fh:  # a file handle keeps numpy from appending ".npy"
        np.save(fh, data)
