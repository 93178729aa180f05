"""The tiny runtime: a fitted model in one small file, played by one numpy-only module.

:func:`export_runtime` writes a fitted :class:`dam.model.DAM` (or
:class:`dam.model.DAMM0`), or the numpy-only classical baselines
``cohen-massaro`` (Cohen & Massaro 1993) and ``phone-mean``, to a ``.json``
or ``.npz`` file;
``dam_runtime.py`` (this folder; :func:`runtime_source` gives its path,
:func:`copy_runtime` copies it) loads that file and synthesizes with numpy
alone, without this toolkit installed. Its output equals ``model.predict``
to 1e-9.

The runtime repeats, on purpose, the few formulas of synthesis (Eq. 1, Eq. 2,
``E_c`` back-off and ``E_s``) that live in :mod:`dam.model`: an application
embeds one file, so it cannot import them. The tests hold the two to each
other on the bundled models.
"""

from __future__ import annotations

import json
import os

import numpy as np

from dam.corpus import DataError
from dam.corpus.atomic import atomic_write

from ..tables import _toolkit

__all__ = ["export_runtime", "runtime_source", "copy_runtime", "RUNTIME_FORMAT", "RUNTIME_VERSION"]

RUNTIME_FORMAT = "dam-runtime"
RUNTIME_VERSION = 1


def runtime_source() -> str:
    """Path of ``dam_runtime.py``, the single-file runtime."""
    return os.path.join(os.path.dirname(__file__), "dam_runtime.py")


def copy_runtime(directory) -> str:
    """Copy ``dam_runtime.py`` into ``directory``; returns the new path."""
    dest = os.path.join(os.fspath(directory), "dam_runtime.py")
    with open(runtime_source(), "rb") as src, atomic_write(dest, "wb") as fh:
        fh.write(src.read())
    return dest


#: What the runtime plays: registry name -> learned attributes it reads (besides the DAM's).
_TABLES = {"phone-mean": ("table_",), "cohen-massaro": ("target_", "alpha_", "theta_left_", "theta_right_", "c_")}


def _tables(model):
    """The runtime file's JSON header and arrays for a fitted model."""
    from dam.model import DAM

    name = getattr(model, "name", type(model).__name__)
    if not isinstance(model, DAM) and name not in _TABLES:
        raise DataError(
            None,
            "model",
            name,
            "the tiny runtime plays dam, dam-m0, cohen-massaro and phone-mean; other models save with model.save()",
        )
    model._check_fitted()
    meta = {
        "format": RUNTIME_FORMAT,
        "version": RUNTIME_VERSION,
        "model": "dam" if isinstance(model, DAM) else name,
        "toolkit": _toolkit(),
        "frame_rate": float(model.frame_rate_),
        "channels": list(model.channels_),
    }
    if not isinstance(model, DAM):
        # baselines are read by their attributes: dam never imports baselines
        meta["phones"] = list(model.phone_counts_)
        if name == "cohen-massaro":
            import importlib

            cm = importlib.import_module(type(model).__module__)
            meta.update(block_frames=int(cm.BLOCK_FRAMES), neighbours=int(cm.NEIGHBOURS))
        return meta, {k.rstrip("_"): np.asarray(getattr(model, k), dtype=float) for k in _TABLES[name]}
    from dam.model.animeme import boundary_derivatives, legendre_to_monomial

    phones = list(model.phone_modes_)
    support = model._support_of(np.arange(len(model.mode_phone_)))
    meta.update(
        {
            "phones": phones,
            "first": [int(model.phone_modes_[p][0]) for p in phones],
            "count": [int(model.phone_modes_[p][1]) for p in phones],
            "normalize": bool(model.normalize),
            # "trained" without a learned range (given parameters) is the polynomial itself
            "extrapolate": "polynomial" if model.extrapolate == "trained" and support is None else model.extrapolate,
            "eps": float(model.eps),
            "tol": float(model.dominance_tol),
            "w_c": float(model.w_c),
            "w_s": float(model.w_s),
            "context_smoothing": float(model.context_smoothing),
            "time_scale": float(model.time_scale_),
            "context": model.context_counts_,
        }
    )
    arrays = {
        # the same monomial coefficients the toolkit evaluates by Horner's rule
        "power": np.ascontiguousarray(legendre_to_monomial(model.coef_.transpose(1, 0, 2)).transpose(1, 0, 2)),
        "sigma": np.asarray(model.sigma_, dtype=float),
        "edges": boundary_derivatives(model.coef_, order=2),
        "channel_scale": np.asarray(model.channel_scale_, dtype=float),
    }
    if support is not None:  # extrapolate="trained": where training evaluated each animeme
        arrays["support"] = np.asarray(support, dtype=float)
    return meta, arrays


def export_runtime(model, path) -> int:
    """Write a fitted model for ``dam_runtime.py``.

    Parameters
    ----------
    model : Synthesizer
        Fitted ``dam``, ``dam-m0``, ``cohen-massaro`` or ``phone-mean``.
    path : path-like
        ``.json`` (human-readable; floats written exactly) or ``.npz``
        (smaller; arrays as float64, the rest as JSON in ``__meta__``).

    Returns
    -------
    int
        Size of the file written, in bytes.

    Examples
    --------
    >>> import dam, dam.datasets, tempfile, os, sys
    >>> from dam.export.runtime import export_runtime, runtime_source
    >>> model = dam.make("dam").fit(dam.datasets.load("tiny"))
    >>> d = tempfile.mkdtemp()
    >>> size = export_runtime(model, os.path.join(d, "m.json"))
    >>> sys.path.insert(0, os.path.dirname(runtime_source()))
    >>> import dam_runtime
    >>> rt = dam_runtime.load(os.path.join(d, "m.json"))
    >>> rt.synthesize(["sil", "aa", "sil"], ends=[0.1, 0.3, 0.4]).shape
    (41, 4)
    """
    path = os.fspath(path)
    meta, arrays = _tables(model)
    suffix = os.path.splitext(path)[1].lower()
    if suffix == ".json":
        doc = dict(meta, arrays={k: v.tolist() for k, v in arrays.items()})
        with atomic_write(path, "w") as fh:
            json.dump(doc, fh, separators=(",", ":"), allow_nan=False)
    elif suffix == ".npz":
        blob = np.frombuffer(json.dumps(meta, separators=(",", ":")).encode("utf-8"), dtype=np.uint8)
        with atomic_write(path, "wb") as fh:
            np.savez_compressed(fh, __meta__=blob, **arrays)
    else:
        raise DataError(path, "extension", suffix or "(none)", "the runtime model is .json or .npz")
    return os.path.getsize(path)
