"""Trajectory tables: CSV with a header row (and an optional leading ``time`` column) and ``.npy``."""
from __future__ import annotations

import os

import numpy as np

from dam.corpus.data import DataError

__all__ = ["read_csv", "read_npy", "write_csv", "write_npy", "frame_rate_from_times"]


def read_csv(path: str) -> tuple[np.ndarray, list[str], float | None]:
    """Read a CSV trajectory; returns ``(data, channel names, frame rate or None)``."""
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


def read_npy(path: str) -> tuple[np.ndarray, list[str] | None, float | None]:
    """Read an ``.npy`` trajectory of shape (n_frames, n_channels); no names, no frame rate."""
    try:
        data = np.load(path, allow_pickle=False)
    except Exception as exc:
        raise DataError(path, "npy", type(exc).__name__, f"cannot be read: {exc}") from None
    if data.ndim == 1:
        data = data[:, None]
    if data.ndim != 2:
        raise DataError(path, "shape", data.shape, "must be (n_frames, n_channels)")
    return data, None, None


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
