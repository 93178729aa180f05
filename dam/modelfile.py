"""The model file format: a documented, versioned npz + JSON archive that never unpickles.

Format (version 1)
------------------
A ``.npz`` archive (zip of ``.npy`` arrays, read with ``allow_pickle=False``):

* ``__dam__``: uint8 array holding UTF-8 JSON
  ``{"format": "dam-model", "version": 1, "model": <registry name>,
  "class": <module.Class>, "params": {...}, "state": {...}, "dam_version": ...}``.
  In ``params`` and ``state``, an array is referenced as ``{"__array__": "<key>"}``,
  a tuple as ``{"__tuple__": [...]}`` and a dict with non-string keys as
  ``{"__dict_items__": [[k, v], ...]}``.
* every other key: a numeric array of the learned state.

Nothing is ever unpickled; a file that is not such an archive is refused with
:class:`ModelFileError` naming the path and the field. A saved classical model
loads and synthesizes with numpy alone.
"""
from __future__ import annotations

import json
import os
import zipfile
from typing import Any

import numpy as np

from dam._version import __version__

FORMAT = "dam-model"
FORMAT_VERSION = 1
META_KEY = "__dam__"

__all__ = ["ModelFileError", "FORMAT", "FORMAT_VERSION", "read_model_file", "write_model_file", "load"]


class ModelFileError(ValueError):
    """A model file that is corrupt, foreign or from an unknown version."""


def write_model_file(model, path) -> None:
    """Write a fitted synthesizer's hyperparameters and learned state to ``path``."""
    arrays: dict[str, np.ndarray] = {}
    meta = {"format": FORMAT, "version": FORMAT_VERSION, "model": model.name or type(model).__name__,
            "class": f"{type(model).__module__}.{type(model).__qualname__}",
            "dam_version": __version__, "params": _encode(model.get_params(), arrays),
            "state": _encode(model._get_state(), arrays)}
    arrays[META_KEY] = np.frombuffer(json.dumps(meta).encode("utf-8"), dtype=np.uint8)
    path = os.fspath(path)
    with open(path, "wb") as fh:  # a file handle keeps numpy from appending ".npz"
        np.savez_compressed(fh, **arrays)


def _encode(obj: Any, arrays: dict) -> Any:
    """JSON-able form of ``obj``; arrays go to ``arrays`` and are referenced."""
    if isinstance(obj, np.ndarray) or (hasattr(obj, "__array__") and not isinstance(obj, (str, bytes))
                                       and not np.isscalar(obj)):
        arr = np.asarray(obj)
        if arr.dtype == object:
            raise TypeError("object arrays cannot be saved; convert to numeric or a list of str")
        key = f"a{len(arrays)}"
        arrays[key] = arr
        return {"__array__": key}
    if isinstance(obj, dict):
        if not all(isinstance(k, str) for k in obj):
            return {"__dict_items__": [[_encode(k, arrays), _encode(v, arrays)] for k, v in obj.items()]}
        return {k: _encode(v, arrays) for k, v in obj.items()}
    if isinstance(obj, tuple):
        return {"__tuple__": [_encode(v, arrays) for v in obj]}
    if isinstance(obj, list):
        return [_encode(v, arrays) for v in obj]
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, (np.floating,)):
        return float(obj)
    if isinstance(obj, (np.bool_,)):
        return bool(obj)
    if obj is None or isinstance(obj, (str, int, float, bool)):
        return obj
    raise TypeError(f"cannot save a value of type {type(obj).__name__}; override _get_state")


def _decode(obj: Any, arrays) -> Any:
    if isinstance(obj, dict):
        if "__array__" in obj and len(obj) == 1:
            return np.array(arrays[obj["__array__"]])
        if "__tuple__" in obj and len(obj) == 1:
            return tuple(_decode(v, arrays) for v in obj["__tuple__"])
        if "__dict_items__" in obj and len(obj) == 1:
            return {_decode(k, arrays): _decode(v, arrays) for k, v in obj["__dict_items__"]}
        return {k: _decode(v, arrays) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_decode(v, arrays) for v in obj]
    return obj


def read_model_file(path) -> tuple[dict, Any]:
    """Open and check a model file; return ``(meta, arrays)``. numpy only."""
    path = os.fspath(path)
    if not os.path.exists(path):
        raise ModelFileError(f"{path}: no such model file")
    with open(path, "rb") as fh:
        magic = fh.read(4)
    if magic != b"PK\x03\x04":
        raise ModelFileError(f"{path}: not a dam model file (it is not an npz archive; first bytes {magic!r}); "
                             "write model files with model.save(path) or `dam fit`")
    try:
        arrays = np.load(path, allow_pickle=False)
    except (zipfile.BadZipFile, ValueError, OSError, EOFError) as exc:
        raise ModelFileError(f"{path}: not a dam model file (not a readable npz archive: {exc})") from None
    if not hasattr(arrays, "files") or META_KEY not in arrays.files:
        raise ModelFileError(f"{path}: not a dam model file (field {META_KEY!r} missing); "
                             "write model files with model.save(path) or `dam fit`")
    try:
        meta = json.loads(bytes(arrays[META_KEY]).decode("utf-8"))
    except Exception as exc:
        raise ModelFileError(f"{path}: field {META_KEY!r} is not valid JSON ({exc})") from None
    if not isinstance(meta, dict) or meta.get("format") != FORMAT:
        raise ModelFileError(f"{path}: field 'format' is {meta.get('format') if isinstance(meta, dict) else meta!r}, "
                             f"expected {FORMAT!r}")
    version = meta.get("version")
    if not isinstance(version, int) or version > FORMAT_VERSION or version < 1:
        raise ModelFileError(f"{path}: field 'version' is {version!r}; this dam reads versions 1..{FORMAT_VERSION}"
                             " (upgrade dam to read newer files)")
    for fld in ("model", "params", "state"):
        if fld not in meta:
            raise ModelFileError(f"{path}: field {fld!r} missing")
    return meta, arrays


def load(path):
    """Load a model written by ``Synthesizer.save``.

    Raises
    ------
    ModelFileError
        The file is missing, corrupt, foreign or of an unknown version.
    """
    from dam.registry import get
    meta, arrays = read_model_file(path)
    try:
        cls = get(meta["model"])
    except KeyError as exc:
        raise ModelFileError(f"{path}: field 'model' is {meta['model']!r}, which is not registered ({exc})") from None
    try:
        params = _decode(meta["params"], arrays)
        state = _decode(meta["state"], arrays)
        model = cls(**params)
        model._set_state(state)
    except (KeyError, TypeError, ValueError) as exc:
        raise ModelFileError(f"{path}: the stored {meta['model']!r} model is damaged ({type(exc).__name__}: {exc})") from None
    return model
