"""Edinburgh Speech Tools (EST) track files: the EMA format of mngu0 and MOCHA-TIMIT.

An EST track file is a text header followed by the frames, in ASCII or in
binary::

    EST_File Track
    DataType binary          (or ascii)
    ByteOrder 01             (binary only: 01 little-endian, 10 big-endian)
    NumFrames 3
    NumChannels 2
    EqualSpace 1
    BreaksPresent true
    CommentChar ;
    Channel_0 T1_py
    Channel_1 T1_pz
    EST_Header_End

Every frame is ``time``, a value flag (1 = a frame, 0 = a *break*: no
data) and ``NumChannels`` values. In binary files these are 32-bit floats
in the declared byte order, ``(NumChannels + 2) * 4`` bytes per frame and
nothing else after the header; in ASCII files one frame per line. This is
the layout written by the Edinburgh Speech Tools and Festival/Flite
(``cst_track_save_est_binary``) and read by the mngu0 tools.

:func:`read_est` / :func:`write_est` handle the files;
:func:`read_est_trajectory` is the reader that :mod:`dam.io` uses for
``.ema``, ``.est`` and ``.trk`` trajectories in a corpus directory.
"""

from __future__ import annotations

import os
import sys
from dataclasses import dataclass, field

import numpy as np

from dam.corpus.atomic import atomic_write
from dam.corpus.data import DataError
from dam.corpus.encoding import decode_text
from dam.corpus.formats.tables import frame_rate_from_times

__all__ = ["EstTrack", "read_est", "write_est", "read_est_trajectory", "stored_frame_rate", "BYTE_ORDERS"]

#: EST ByteOrder code -> numpy byte-order character.
BYTE_ORDERS = {"01": "<", "10": ">"}
_MAGIC = b"EST_File Track"
_END = b"EST_Header_End"


@dataclass
class EstTrack:
    """The content of an EST track file.

    Attributes
    ----------
    times : ndarray, shape (n_frames,)
        Frame times in seconds.
    values : ndarray, shape (n_frames, n_channels)
    present : ndarray of bool, shape (n_frames,)
        False where the file marks a break (no data at that frame).
    channels : list of str or None
        ``Channel_N`` names, None when the header names none.
    header : dict
        Every header field as text (``DataType``, ``NumFrames``, ...).
    """

    times: np.ndarray
    values: np.ndarray
    present: np.ndarray
    channels: list | None = None
    header: dict = field(default_factory=dict)

    @property
    def frame_rate(self) -> float | None:
        """Frames per second from the times (None with fewer than 2 frames)."""
        if len(self.times) < 2:
            return None
        return 1.0 / float(np.median(np.diff(self.times)))


def _parse_header(raw: bytes, path: str) -> tuple[dict, list | None, int]:
    """Header fields, channel names and the byte offset where the data start."""
    if not raw.startswith(_MAGIC):
        raise DataError(
            path,
            "header",
            raw[:20].decode("latin-1"),
            "not an EST track file (the first line must be 'EST_File Track')",
        )
    end = raw.find(_END)
    if end < 0:
        raise DataError(path, "header", "EST_Header_End", "the header has no end line")
    data_start = raw.find(b"\n", end)
    data_start = len(raw) if data_start < 0 else data_start + 1
    header: dict = {}
    names: dict[int, str] = {}
    for line in decode_text(raw[len(_MAGIC) : end], path, field="header").splitlines():
        parts = line.split(None, 1)
        if not parts:
            continue
        key, value = parts[0], (parts[1].strip() if len(parts) > 1 else "")
        if key.startswith("Channel_"):
            try:
                names[int(key[len("Channel_") :])] = value
            except ValueError:
                raise DataError(path, key, value, "channel names are written 'Channel_<number> <name>'") from None
        else:
            header[key] = value
    for key in ("NumFrames", "NumChannels"):
        if key not in header:
            raise DataError(path, key, None, "missing from the header")
        try:
            header[key] = int(header[key])
        except ValueError:
            raise DataError(path, key, header[key], "must be a whole number") from None
        if header[key] < 0:
            raise DataError(path, key, header[key], "must not be negative")
    channels = None
    if names:
        n = header["NumChannels"]
        missing = [i for i in range(n) if i not in names]
        if missing or max(names) >= n:
            bad = missing[0] if missing else max(names)
            raise DataError(
                path,
                f"Channel_{bad}",
                names.get(bad),
                f"channel names must be Channel_0 .. Channel_{n - 1} (NumChannels {n})",
            )
        channels = [names[i] for i in range(n)]
    return header, channels, data_start


def read_est(path) -> EstTrack:
    """Read an EST track file, binary or ASCII.

    Raises
    ------
    DataError
        Naming the file and the field: a bad header, a byte order other than
        01/10, a data size that does not match NumFrames x (NumChannels + 2)
        floats, or non-numeric ASCII values.
    """
    path = os.fspath(path)
    try:
        with open(path, "rb") as fh:
            raw = fh.read()
    except OSError as exc:
        raise DataError(path, "path", path, f"cannot be read ({exc.strerror or exc})") from None
    if raw.startswith(b"\xef\xbb\xbf"):  # a UTF-8 byte-order mark (dam.corpus.encoding)
        raw = raw[3:]
    header, channels, start = _parse_header(raw, path)
    n_frames, n_channels = header["NumFrames"], header["NumChannels"]
    width = n_channels + 2
    dtype = header.get("DataType", "ascii").lower()
    if dtype == "binary":
        order = header.get("ByteOrder", "01")
        if order not in BYTE_ORDERS:
            raise DataError(path, "ByteOrder", order, "must be 01 (little-endian) or 10 (big-endian)")
        body = raw[start:]
        expected = n_frames * width * 4
        if len(body) != expected:
            hint = None
            if len(body) == n_frames * n_channels * 4:
                hint = "the size fits frames without the time and break columns, which EST always writes"
            raise DataError(
                path,
                "data size",
                f"{len(body)} bytes",
                f"NumFrames {n_frames} x (NumChannels {n_channels} + 2) float32 need {expected}",
                hint,
            )
        table = np.frombuffer(body, dtype=BYTE_ORDERS[order] + "f4").reshape(n_frames, width)
    elif dtype == "ascii":
        rows = [ln.split() for ln in decode_text(raw[start:], path, field="frames").splitlines() if ln.strip()]
        if len(rows) != n_frames:
            raise DataError(path, "frames", len(rows), f"the header says NumFrames {n_frames}")
        for i, r in enumerate(rows):
            if len(r) != width:
                raise DataError(
                    path,
                    f"frame {i} (line {i + 1} after the header)",
                    len(r),
                    f"expected time, break flag and {n_channels} values = {width} columns",
                )
        try:
            table = np.array(rows, dtype=float).reshape(n_frames, width)
        except ValueError as exc:
            raise DataError(path, "values", str(exc), "not numbers") from None
    else:
        raise DataError(path, "DataType", dtype, "must be ascii or binary")
    table = table.astype(float)
    return EstTrack(times=table[:, 0], values=table[:, 2:], present=table[:, 1] != 0, channels=channels, header=header)


def write_est(
    path,
    values,
    *,
    times=None,
    frame_rate: float | None = None,
    channels=None,
    binary: bool = True,
    byte_order: str | None = None,
    present=None,
) -> None:
    """Write an EST track file.

    Parameters
    ----------
    path : path-like
    values : array-like, shape (n_frames, n_channels)
    times : array-like, shape (n_frames,), optional
        Frame times in seconds; or give ``frame_rate`` (frame i at i / frame_rate).
    frame_rate : float, optional
    channels : sequence of str, optional
        Written as ``Channel_N name`` in UTF-8 (names must not contain white space).
    binary : bool, default True
        Binary float32 frames (as mngu0 and MOCHA ship them) or ASCII.
    byte_order : {"01", "10"}, optional
        Binary byte order, default this machine's.
    present : array-like of bool, shape (n_frames,), optional
        False marks a break; default all True.
    """
    path = os.fspath(path)
    values = np.asarray(values, dtype=float)
    if values.ndim == 1:
        values = values[:, None]
    if values.ndim != 2:
        raise DataError(path, "values", values.shape, "must be (n_frames, n_channels)")
    n, m = values.shape
    if times is None:
        if frame_rate is None:
            raise DataError(path, "times", None, "give times or frame_rate")
        times = np.arange(n) / float(frame_rate)
    times = np.asarray(times, dtype=float)
    if times.shape != (n,):
        raise DataError(path, "times", times.shape, f"must have one time per frame ({n})")
    flags = np.ones(n) if present is None else np.asarray(present, dtype=bool).astype(float)
    if flags.shape != (n,):
        raise DataError(path, "present", flags.shape, f"must have one flag per frame ({n})")
    if channels is not None:
        channels = [str(c) for c in channels]
        if len(channels) != m:
            raise DataError(path, "channels", len(channels), f"the values have {m} columns")
        bad = [c for c in channels if not c or any(ch.isspace() for ch in c)]
        if bad:
            raise DataError(path, "channels", bad[0], "EST channel names cannot be empty or contain white space")
    if byte_order is None:
        byte_order = "01" if sys.byteorder == "little" else "10"
    if byte_order not in BYTE_ORDERS:
        raise DataError(path, "byte_order", byte_order, "must be '01' (little-endian) or '10' (big-endian)")
    step = np.diff(times)
    equal = n > 1 and bool(np.allclose(step, step[0], rtol=1e-6, atol=1e-9))
    lines = ["EST_File Track", f"DataType {'binary' if binary else 'ascii'}"]
    if binary:
        lines.append(f"ByteOrder {byte_order}")
    lines += [f"NumFrames {n}", f"NumChannels {m}", f"EqualSpace {int(equal)}", "BreaksPresent true", "CommentChar ;"]
    lines += [f"Channel_{i} {c}" for i, c in enumerate(channels or [])]
    lines.append("EST_Header_End")
    table = np.column_stack([times, flags, values])
    with atomic_write(path, "wb") as fh:
        fh.write(("\n".join(lines) + "\n").encode("utf-8"))
        if binary:
            fh.write(table.astype(BYTE_ORDERS[byte_order] + "f4").tobytes())
        else:
            for row in table:
                fh.write(
                    (f"{row[0]:.6f} {int(row[1])} " + " ".join(f"{v:.7g}" for v in row[2:]) + "\n").encode("ascii")
                )


def read_est_trajectory(path) -> tuple[np.ndarray, list | None, float | None]:
    """Reader for :data:`dam.io.TRAJECTORY_READERS`: ``(values, channels, frame_rate)``.

    The frames must be evenly spaced and start at time 0 (within half a
    frame), as the corpus convention "frame i is at i / frame_rate" needs;
    a break (value flag 0) is an error naming its frame and time, since a
    trajectory with holes cannot be fitted.
    """
    path = os.fspath(path)
    track = read_est(path)
    if len(track.times) == 0:
        raise DataError(path, "NumFrames", 0, "the track has no frames")
    gaps = np.flatnonzero(~track.present)
    if gaps.size:
        i = int(gaps[0])
        raise DataError(
            path,
            f"frame {i} (t={track.times[i]:.4f} s)",
            "break",
            f"the track has a break (value flag 0) here; {gaps.size} break frame(s) in all",
            "interpolate across breaks before loading",
        )
    fr = frame_rate_from_times(track.times, path, where="time (frame {})", first=0)
    return track.values, track.channels, None if fr is None else stored_frame_rate(track.times)


def stored_frame_rate(times) -> float:
    """The frame rate that float32 (binary) or 6-decimal (ASCII) frame times were written from.

    Times stored this coarsely put ``1 / median(diff)`` off by up to 1e-5
    relative, differently in every file, so two tracks of one 200 Hz corpus
    would disagree about their rate. This returns the rate with the fewest
    significant digits whose frame times ``i / rate`` match ``times`` within
    their storage precision (200.0, not 200.000191), and the best estimate
    ``(n - 1) / (t[-1] - t[0])`` if none does.
    """
    t = np.asarray(times, dtype=float)
    best = (len(t) - 1) / (t[-1] - t[0])
    # float32 rounding (a few ulps, EST may accumulate in float) or the ASCII writer's 6 decimals.
    tol = 8 * np.finfo(np.float32).eps * float(np.max(np.abs(t))) + 1e-6
    i = np.arange(len(t))
    for digits in range(1, 13):
        rate = float(f"{best:.{digits}g}")
        if np.max(np.abs(i / rate - t)) <= tol:
            return rate
    return best
