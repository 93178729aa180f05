"""Plain-table animation files: ``.csv`` and ``.json``, and what every writer shares.

JSON animation format (``"format": "dam-animation"``, version 1)::

    {"format": "dam-animation", "version": 1,
     "toolkit": {"name": "dam", "version": "0.1.0"},
     "frame_rate": 100.0, "n_frames": 57, "channels": ["jaw", ...],
     "phones": [{"label": "h", "start": 0.0, "end": 0.08, "mode": 0}, ...] | null,
     "model": "dam" | {...} | null, "metadata": {...},
     "values": [[...one row per frame...], ...]}

Frame ``i`` is at ``i / frame_rate`` seconds. Floats are written with
Python's shortest round-trip representation, so values read back exactly.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from dam.corpus import Alignment, DataError
from dam.corpus.atomic import atomic_write

JSON_FORMAT = "dam-animation"
JSON_VERSION = 1

__all__ = [
    "ExportReport",
    "Animation",
    "check_animation",
    "write_csv",
    "write_json",
    "read_animation",
    "JSON_FORMAT",
    "JSON_VERSION",
]


@dataclass
class ExportReport:
    """What :func:`dam.export.export` wrote.

    Attributes
    ----------
    path : str
    format : str
        ``"csv"``, ``"json"``, ``"gltf"``, ``"glb"`` or ``"textgrid"``.
    n_frames, n_channels : int
    frame_rate : float
    clipped : dict of str -> int
        Per control, how many frames had a weight outside [0, 1] that was
        clipped (glTF only; empty when nothing was clipped).
    scaled : dict of str -> (float, float)
        Per control whose weights were rescaled into [0, 1], the original
        ``(min, max)`` range mapped to ``(0, 1)`` (glTF ``weights="scale"``).
    notes : list of str
        Anything else a user should know (printed by the CLI on stderr).
    """

    path: str
    format: str
    n_frames: int
    n_channels: int
    frame_rate: float
    clipped: dict = field(default_factory=dict)
    scaled: dict = field(default_factory=dict)
    notes: list = field(default_factory=list)

    def messages(self) -> list[str]:
        """Human-readable lines about clipping, scaling and notes (empty if nothing to say)."""
        out = []
        if self.clipped:
            parts = ", ".join(f"{k} ({v} frames)" for k, v in self.clipped.items())
            out.append(f"{self.path}: weights outside [0, 1] clipped for {parts}")
        if self.scaled:
            parts = ", ".join(f"{k} [{lo:.4g}, {hi:.4g}]" for k, (lo, hi) in self.scaled.items())
            out.append(f"{self.path}: weights rescaled to [0, 1] from {parts}")
        return out + [f"{self.path}: {n}" for n in self.notes]


class Animation(NamedTuple):
    """An animation read back by :func:`read_animation`.

    Attributes
    ----------
    values : ndarray, shape (n_frames, n_channels)
    channels : tuple of str
    frame_rate : float or None
        None for a CSV of fewer than two frames.
    alignment : Alignment or None
    modes : tuple of int or None
        Per-segment mode indices, when the file stores them.
    metadata : dict
        ``model``, ``toolkit`` and the user's ``metadata`` (JSON only).
    """

    values: np.ndarray
    channels: tuple
    frame_rate: float | None
    alignment: Alignment | None
    modes: tuple | None
    metadata: dict


def check_animation(trajectories, channels, frame_rate, source, alignment=None):
    """Validate what every writer gets; returns ``(values, channels, frame_rate)``.

    ``values`` is a float array (n_frames, n_channels); a 1-D array is one
    channel. The alignment, if given, must cover the frames to within one.
    """
    try:
        values = np.array(trajectories, dtype=float)
    except (TypeError, ValueError) as exc:
        raise DataError(source, "trajectories", type(trajectories).__name__, f"not numeric ({exc})") from None
    if values.ndim == 1:
        values = values[:, None]
    if values.ndim != 2 or values.shape[0] == 0 or values.shape[1] == 0:
        raise DataError(source, "trajectories", values.shape, "must be (n_frames, n_channels), both positive")
    if isinstance(channels, str):
        channels = [channels]
    channels = tuple(str(c) for c in channels)
    if len(channels) != values.shape[1]:
        raise DataError(
            source,
            "channels",
            len(channels),
            f"the trajectories have {values.shape[1]} columns but {len(channels)} channel names",
        )
    for c in channels:
        if not c.strip() or any(ch in c for ch in ',"\n\r'):
            raise DataError(
                source, "channels", c, "a channel name must be non-empty without commas, quotes or line breaks"
            )
    if len(set(channels)) != len(channels):
        dup = next(c for c in channels if channels.count(c) > 1)
        raise DataError(source, "channels", dup, "duplicate channel name")
    try:
        fr = float(frame_rate)
    except (TypeError, ValueError):
        raise DataError(source, "frame_rate", frame_rate, "not a number") from None
    if not (math.isfinite(fr) and fr > 0):
        raise DataError(source, "frame_rate", frame_rate, "must be a positive finite number")
    bad = np.argwhere(~np.isfinite(values))
    if bad.size:
        i, j = (int(v) for v in bad[0])
        raise DataError(
            source,
            f"trajectories[{i}, {channels[j]!r}] (t={i / fr:.3f} s)",
            float(values[i, j]),
            "value is not finite",
            f"{len(bad)} non-finite value(s) in all",
        )
    if alignment is not None:
        if not isinstance(alignment, Alignment):
            raise DataError(source, "alignment", type(alignment).__name__, "must be a dam.Alignment")
        need = alignment.n_frames(fr)
        if abs(need - values.shape[0]) > 1:
            raise DataError(
                source,
                "alignment",
                f"{alignment.duration:.4f} s",
                f"covers {need} frames at {fr:g} frames/s but the trajectories have {values.shape[0]}",
            )
    return values, channels, fr


def _check_modes(modes, alignment, source):
    if modes is None:
        return None
    if alignment is None:
        raise DataError(source, "modes", "given", "modes need the alignment they belong to")
    modes = [int(m) for m in modes]
    if len(modes) != len(alignment):
        raise DataError(source, "modes", len(modes), f"one mode per segment: the alignment has {len(alignment)}")
    return modes


def _no_options(fmt, source, options):
    if options:
        name = sorted(options)[0]
        raise DataError(source, name, options[name], f"not an option of the {fmt} format")


def write_csv(
    values, path, *, channels, frame_rate, alignment=None, metadata=None, decimals=None, **options
) -> ExportReport:
    """Write a CSV: a ``time`` column (``i / frame_rate``) and one column per channel.

    Parameters
    ----------
    values : ndarray, shape (n_frames, n_channels)
    path : str
    channels : sequence of str
    frame_rate : float
    alignment, metadata : ignored (a CSV holds only the table)
    decimals : int or None, default None
        Significant digits; None writes every float exactly (``%.17g``).
    """
    from dam.corpus import write_csv as write_table  # the corpus CSV layout, read back by load_corpus

    _no_options("csv", path, options)
    values, channels, frame_rate = check_animation(values, channels, frame_rate, path, alignment)
    write_table(values, channels, path, frame_rate=frame_rate, decimals=decimals)  # atomic itself
    return ExportReport(path, "csv", values.shape[0], values.shape[1], frame_rate)


def _toolkit():
    from dam._version import __version__

    return {"name": "dam", "version": __version__}


def _model_entry(metadata):
    model = (metadata or {}).get("model")
    return model if model is None or isinstance(model, (str, dict)) else str(model)


def write_json(
    values, path, *, channels, frame_rate, alignment=None, metadata=None, modes=None, **options
) -> ExportReport:
    """Write the JSON animation format described in this module's docstring.

    Parameters
    ----------
    values : ndarray, shape (n_frames, n_channels)
    path : str
    channels : sequence of str
    frame_rate : float
    alignment : Alignment, optional
        Stored as ``phones`` (label, start, end in seconds).
    metadata : dict, optional
        JSON-able; ``metadata["model"]`` is stored as ``model``, the rest as ``metadata``.
    modes : sequence of int, optional
        One mode index per alignment segment (the DAM's chosen modes).
    """
    _no_options("json", path, options)
    values, channels, frame_rate = check_animation(values, channels, frame_rate, path, alignment)
    modes = _check_modes(modes, alignment, path)
    phones = None
    if alignment is not None:
        phones = [
            {"label": lab, "start": float(s), "end": float(e)}
            for lab, s, e in zip(alignment.labels, alignment.starts, alignment.ends)
        ]
        for p, m in zip(phones, modes or ()):
            p["mode"] = m
    meta = {k: v for k, v in (metadata or {}).items() if k != "model"}
    doc = {
        "format": JSON_FORMAT,
        "version": JSON_VERSION,
        "toolkit": _toolkit(),
        "frame_rate": frame_rate,
        "n_frames": int(values.shape[0]),
        "channels": list(channels),
        "phones": phones,
        "model": _model_entry(metadata),
        "metadata": meta,
        "values": values.tolist(),
    }
    try:
        text = json.dumps(doc, allow_nan=False)
    except TypeError as exc:
        raise DataError(path, "metadata", type(metadata).__name__, f"not JSON-able ({exc})") from None
    with atomic_write(path, "w") as fh:
        fh.write(text.replace('"values": [[', '"values": [\n[').replace("], [", "],\n["))
        fh.write("\n")
    return ExportReport(path, "json", values.shape[0], values.shape[1], frame_rate)


def read_json_object(path, field: str) -> dict:
    """The JSON object in the file ``path``; a DataError naming ``field`` if it cannot be read or is not one."""
    path = os.fspath(path)
    try:
        with open(path, encoding="utf-8") as fh:
            doc = json.load(fh)
    except OSError as exc:
        raise DataError(path, field, path, f"cannot be read: {exc.strerror}") from None
    except ValueError as exc:
        raise DataError(path, field, type(exc).__name__, f"not JSON: {exc}") from None
    if not isinstance(doc, dict):
        raise DataError(path, field, type(doc).__name__, "must be a JSON object")
    return doc


def _read_json(path: str) -> Animation:
    doc = read_json_object(path, "JSON")
    if doc.get("format") != JSON_FORMAT:
        raise DataError(path, "format", doc.get("format"), f"not a {JSON_FORMAT} file")
    if doc.get("version") != JSON_VERSION:
        raise DataError(path, "version", doc.get("version"), f"this dam reads version {JSON_VERSION}")
    for key in ("frame_rate", "channels", "values"):
        if key not in doc:
            raise DataError(path, key, None, "missing")
    values, channels, fr = check_animation(doc["values"], doc["channels"], doc["frame_rate"], path)
    alignment = modes = None
    if doc.get("phones"):
        try:
            ph = doc["phones"]
            alignment = Alignment(
                [p["label"] for p in ph], [p["start"] for p in ph], [p["end"] for p in ph], source=path
            )
            if all("mode" in p for p in ph):
                modes = tuple(int(p["mode"]) for p in ph)
        except (KeyError, TypeError) as exc:
            raise DataError(path, "phones", str(exc), "each phone needs label, start and end") from None
    meta = {"model": doc.get("model"), "toolkit": doc.get("toolkit"), **(doc.get("metadata") or {})}
    return Animation(values, channels, fr, alignment, modes, meta)


def read_animation(path) -> Animation:
    """Read a ``.csv`` or ``.json`` file written by :func:`dam.export.export`.

    Parameters
    ----------
    path : path-like

    Returns
    -------
    Animation
        ``values`` (n_frames, n_channels), ``channels``, ``frame_rate``; for
        JSON also the ``alignment``, ``modes`` and ``metadata``.
    """
    from dam.corpus import read_trajectory

    path = os.fspath(path)
    suffix = os.path.splitext(path)[1].lower()
    if suffix == ".json":
        return _read_json(path)
    if suffix == ".csv":
        data, names, fr = read_trajectory(path)
        return Animation(np.asarray(data, dtype=float), tuple(names), fr, None, None, {})
    raise DataError(path, "extension", suffix, "read_animation reads .csv and .json animation files")
