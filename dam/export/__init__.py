"""Animation out: files animators import, streaming synthesis, a tiny runtime.

:func:`export` writes one utterance's control trajectories to a file whose
format is chosen by the extension:

* ``.csv``: a ``time`` column (seconds) and one column per control;
* ``.json``: frame rate, channel names, phones with times (and modes), the
  values, the model and the toolkit version;
* ``.gltf`` (JSON with the buffer embedded) and ``.glb`` (binary glTF): a glTF
  2.0 asset whose animation drives morph-target weights
  (:mod:`dam.export.gltf`);
* ``.TextGrid``: a Praat TextGrid of the phones (and the DAM's chosen modes).

:func:`read_animation` reads the ``.csv`` and ``.json`` files back.
:mod:`dam.export.streaming` synthesizes frames as phones arrive;
:mod:`dam.export.runtime` holds the numpy-only runtime that plays a model
exported with :func:`dam.export.runtime.export_runtime`.
"""

from __future__ import annotations

import os
from pathlib import Path

from .tables import Animation, ExportReport, check_animation, read_animation, write_csv, write_json

__all__ = ["export", "read_animation", "Animation", "ExportReport", "FORMATS", "write_csv", "write_json"]


def _write_gltf(*args, **kw):
    from .gltf import write_gltf  # pulls in the outline geometry only when needed

    return write_gltf(*args, **kw)


def _write_textgrid(*args, **kw):
    from .textgrid import write_phones_textgrid

    return write_phones_textgrid(*args, **kw)


def _write_articulators(*args, **kw):
    from .articulators import write_articulators  # VocalTractLab and matplotlib only when drawing

    return write_articulators(*args, **kw)


#: lower-case extension -> writer(values, path, channels=, frame_rate=, alignment=, metadata=, **options)
FORMATS = {
    ".csv": write_csv,
    ".json": write_json,
    ".gltf": _write_gltf,
    ".glb": _write_gltf,
    ".textgrid": _write_textgrid,
    ".gif": _write_articulators,
    ".mp4": _write_articulators,
    ".html": _write_articulators,
}


def export(trajectories, path, *, channels, frame_rate, alignment=None, metadata=None, **options) -> ExportReport:
    """Write control trajectories to ``path`` in the format its extension names.

    Parameters
    ----------
    trajectories : array-like, shape (n_frames, n_channels)
        Frame ``i`` is the value at ``i / frame_rate`` seconds (one utterance).
    path : path-like
        Output file; ``.csv``, ``.json``, ``.gltf``, ``.glb`` or ``.TextGrid``
        (case-insensitive). Written atomically.
    channels : sequence of str, length n_channels
        Control names (morph-target names in glTF).
    frame_rate : float
        Frames per second.
    alignment : dam.Alignment, optional
        The phones (``.json`` stores them, ``.TextGrid`` needs them).
    metadata : dict, optional
        JSON-able extras; ``metadata["model"]`` names the model. Stored by
        ``.json`` and in glTF ``asset.extras``.
    **options
        Format options: ``decimals`` (``.csv``, default None = round-trip
        exact), ``modes`` (per-segment mode indices for ``.json`` and
        ``.TextGrid``), glTF options (``rig``, ``mapping``, ``weights``,
        ``mesh``) as in :func:`dam.export.gltf.write_gltf`.

    Returns
    -------
    ExportReport
        What was written, and any weights that had to be clipped or scaled.

    Raises
    ------
    dam.DataError
        Unknown extension, a shape or channel mismatch, non-finite values,
        or a bad option value; the message names the file and the field.

    Examples
    --------
    >>> import numpy as np, tempfile, os
    >>> from dam.export import export, read_animation
    >>> d = tempfile.mkdtemp()
    >>> rep = export(np.zeros((3, 2)), os.path.join(d, "a.csv"), channels=["jaw", "lip"], frame_rate=100)
    >>> read_animation(os.path.join(d, "a.csv")).values.shape
    (3, 2)
    """
    from dam.corpus import DataError

    path = os.fspath(path)
    suffix = Path(path).suffix.lower()
    if suffix not in FORMATS:
        raise DataError(
            path,
            "extension",
            Path(path).suffix or "(none)",
            "not an animation format",
            "use .csv, .json, .gltf, .glb, .TextGrid, or .gif, .mp4, .html (moving vocal tract)",
        )
    values, channels, frame_rate = check_animation(trajectories, channels, frame_rate, path, alignment)
    return FORMATS[suffix](
        values, path, channels=channels, frame_rate=frame_rate, alignment=alignment, metadata=metadata, **options
    )


class _CallableModule(type(os)):
    """``dam.export`` is this package and, called, :func:`export` (the issue's ``dam.export(...)``)."""

    def __call__(self, trajectories, path, **kw):
        return export(trajectories, path, **kw)


import sys as _sys  # noqa: E402

_sys.modules[__name__].__class__ = _CallableModule
