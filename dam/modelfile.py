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

Checked, not trusted (issue 12)
-------------------------------
Reading checks the archive's declared sizes before anything is allocated
(:data:`MAX_TOTAL_BYTES` + :data:`MAX_EXPANSION` times the file size), each
``.npy`` header against its archive entry, the dtypes (numbers, booleans, text),
and the JSON nesting (:data:`MAX_JSON_DEPTH`); any damage is a
:class:`ModelFileError` naming the path. Then the learned state is checked
against the class's declared ``_state_schema`` (:class:`StateArray`,
:class:`StateNames`, :class:`StateCounts`, :class:`StateRanges`, or a
:mod:`dam._params` constraint for a scalar): names, dtypes, shapes consistent
across entries, finite values, ranges. The same check runs before writing, so a
file written by dam always loads. Files are written atomically
(:mod:`dam.corpus.atomic`).
"""

from __future__ import annotations

import json
import os
import zipfile
from typing import Any

import numpy as np

from dam._version import __version__
from dam.corpus.atomic import atomic_write

FORMAT = "dam-model"
FORMAT_VERSION = 1
META_KEY = "__dam__"

__all__ = [
    "ModelFileError",
    "FORMAT",
    "FORMAT_VERSION",
    "read_model_file",
    "write_model_file",
    "load",
    "StateArray",
    "StateNames",
    "StateCounts",
    "StateRanges",
    "check_state",
    "state_schema",
]


class ModelFileError(ValueError):
    """A model file that is corrupt, foreign or from an unknown version."""


def write_model_file(model, path) -> None:
    """Write a fitted synthesizer's hyperparameters and learned state to ``path``, atomically.

    Raises
    ------
    ModelFileError
        The state does not match the class's ``_state_schema`` or holds NaN or
        infinity (nothing is written; an existing file at ``path`` is kept).
    """
    arrays: dict[str, np.ndarray] = {}
    meta = {
        "format": FORMAT,
        "version": FORMAT_VERSION,
        "model": model_name(model),
        "class": f"{type(model).__module__}.{type(model).__qualname__}",
        "dam_version": __version__,
        "params": _encode(model.get_params(), arrays),
        "state": _encode(model._get_state(), arrays),
    }
    path = os.fspath(path)
    try:
        text = json.dumps(meta, allow_nan=False)
    except ValueError:
        bad = [k for k, v in {**meta["params"], **meta["state"]}.items() if not _json_finite(v)]
        raise ModelFileError(
            f"{path}: field {bad[0] if bad else 'params'!r} is NaN or infinite; a model file holds finite numbers only"
        ) from None
    arrays[META_KEY] = np.frombuffer(text.encode("utf-8"), dtype=np.uint8)
    # What load() would refuse is never written: a model file on disk always loads.
    check_state(type(model), _decode(meta["state"], arrays), path)
    with atomic_write(path, "wb") as fh:  # a file handle keeps numpy from appending ".npz"
        np.savez_compressed(fh, **arrays)


def _json_finite(v) -> bool:
    try:
        json.dumps(v, allow_nan=False)
        return True
    except ValueError:
        return False


def model_name(model) -> str:
    """The registry name to record for ``model``: the one its class is registered under
    (``dam.register("smooth-pm", SmoothPhoneMean)`` gives ``"smooth-pm"``), else its ``name``
    attribute, else the class name."""
    from dam.registry import get, registered_name

    own = getattr(model, "name", "") or ""
    try:
        if own and get(own) is type(model):
            return own
    except (KeyError, ImportError):
        pass
    return registered_name(type(model)) or own or type(model).__name__


def _encode(obj: Any, arrays: dict) -> Any:
    """JSON-able form of ``obj``; arrays go to ``arrays`` and are referenced."""
    if isinstance(obj, np.ndarray) or (
        hasattr(obj, "__array__") and not isinstance(obj, (str, bytes)) and not np.isscalar(obj)
    ):
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
            key = obj["__array__"]
            if not isinstance(key, str) or key not in arrays:
                raise KeyError(f"array {key!r} is not in the archive")
            return np.array(arrays[key])
        if "__tuple__" in obj and len(obj) == 1:
            return tuple(_decode(v, arrays) for v in obj["__tuple__"])
        if "__dict_items__" in obj and len(obj) == 1:
            return {_decode(k, arrays): _decode(v, arrays) for k, v in obj["__dict_items__"]}
        return {k: _decode(v, arrays) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_decode(v, arrays) for v in obj]
    return obj


# -- reading: sizes checked before allocation, every failure a ModelFileError -----------------
#: An archive may declare at most this many uncompressed bytes in all ...
MAX_TOTAL_BYTES = 64 * 2**20
#: ... plus this many times the size of the file itself (honest model arrays compress
#: 1-3x; zeros up to ~1000x, which is how a zip bomb expands 1 MB into 1 GiB).
MAX_EXPANSION = 50
#: JSON nesting deeper than this is refused (dam's own records nest 4-5 levels).
MAX_JSON_DEPTH = 64
#: Array kinds a model file may hold: bool, signed/unsigned int, float, unicode text.
ARRAY_KINDS = "biufU"


def _fail(path, field, problem) -> ModelFileError:
    return ModelFileError(f"{path}: field {field!r}: {problem}")


def _read_member(zf, info, path, budget: list) -> np.ndarray:
    """One ``.npy`` member, its header checked against the archive's declared size first."""
    name = info.filename[:-4]
    with zf.open(info) as fh:
        version = np.lib.format.read_magic(fh)
        if version == (1, 0):
            shape, fortran, dtype = np.lib.format.read_array_header_1_0(fh)
        elif version == (2, 0):
            shape, fortran, dtype = np.lib.format.read_array_header_2_0(fh)
        else:
            raise _fail(path, name, f"unsupported .npy version {version}")
        if dtype.hasobject or dtype.fields is not None or dtype.subdtype is not None or dtype.kind not in ARRAY_KINDS:
            raise _fail(
                path, name, f"dtype {dtype.str} is not allowed in a model file (numbers, booleans and text only)"
            )
        count = 1
        for d in shape:
            count *= int(d)
        nbytes = count * dtype.itemsize
        header_len = fh.tell()
        if header_len + nbytes != info.file_size:
            raise _fail(
                path,
                name,
                f"the array header declares shape {shape} of {dtype.str} "
                f"({nbytes} bytes), but the archive declares {info.file_size} bytes",
            )
        budget[0] -= nbytes
        if budget[0] < 0:
            raise _fail(
                path,
                name,
                "the arrays would expand beyond the size limit for this file "
                "(dam.modelfile.MAX_TOTAL_BYTES + MAX_EXPANSION x file size)",
            )
        data = fh.read(nbytes)
        if len(data) != nbytes or fh.read(1):  # reading to the end checks the CRC
            raise _fail(path, name, "truncated array data")
    arr = np.frombuffer(data, dtype=dtype)
    arr = arr.reshape(shape[::-1]).T if fortran else arr.reshape(shape)
    return np.array(arr)  # writable, native order


def _no_constant(name):
    raise ValueError(f"{name} is not a finite number")


def _json_depth_ok(obj, limit: int) -> bool:
    stack = [(obj, 1)]
    while stack:
        o, d = stack.pop()
        if d > limit:
            return False
        if isinstance(o, dict):
            stack.extend((v, d + 1) for v in o.values())
        elif isinstance(o, list):
            stack.extend((v, d + 1) for v in o)
    return True


def read_model_file(path) -> tuple[dict, dict]:
    """Open and check a model file; return ``(meta, arrays)``. numpy only.

    Every declared size is checked before anything is allocated: the zip
    directory's sizes against the file size (:data:`MAX_TOTAL_BYTES`,
    :data:`MAX_EXPANSION`) and each ``.npy`` header's shape and dtype against
    the size the archive declares for it. Any damage (truncation, a flipped
    byte, a foreign or crafted file) raises :class:`ModelFileError` naming the
    path and the field; nothing else escapes.

    Returns
    -------
    meta : dict
        The JSON record (``format``, ``version``, ``model``, ``params``, ``state`` ...).
    arrays : dict of str to ndarray
    """
    path = os.fspath(path)
    if not os.path.exists(path):
        raise ModelFileError(f"{path}: no such model file")
    if os.path.isdir(path):
        raise ModelFileError(f"{path}: is a directory, not a model file")
    try:
        with open(path, "rb") as fh:
            magic = fh.read(4)
        size = os.path.getsize(path)
    except OSError as exc:
        raise ModelFileError(f"{path}: cannot be read ({exc.strerror or exc})") from None
    if magic != b"PK\x03\x04":
        raise ModelFileError(
            f"{path}: not a dam model file (it is not an npz archive; first bytes {magic!r}); "
            "write model files with model.save(path) or `dam fit`"
        )
    try:
        arrays = _read_archive(path, size)
    except ModelFileError:
        raise
    except Exception as exc:  # zipfile, zlib, numpy's header parser: many types for one meaning
        raise ModelFileError(
            f"{path}: not a readable dam model file ({type(exc).__name__}: {' '.join(str(exc).split())[:200]})"
        ) from None
    if META_KEY not in arrays:
        raise ModelFileError(
            f"{path}: not a dam model file (field {META_KEY!r} missing); "
            "write model files with model.save(path) or `dam fit`"
        )
    raw = arrays.pop(META_KEY)
    try:
        if raw.dtype != np.uint8 or raw.ndim != 1:
            raise ValueError(f"it is {raw.dtype.str} of shape {raw.shape}, not uint8 text")
        meta = json.loads(raw.tobytes().decode("utf-8"), parse_constant=_no_constant)
    except RecursionError:
        raise _fail(path, META_KEY, "the JSON record is nested too deeply") from None
    except Exception as exc:
        raise ModelFileError(f"{path}: field {META_KEY!r} is not valid JSON ({exc})") from None
    if not _json_depth_ok(meta, MAX_JSON_DEPTH):
        raise _fail(path, META_KEY, f"the JSON record is nested more than {MAX_JSON_DEPTH} levels deep")
    if not isinstance(meta, dict) or meta.get("format") != FORMAT:
        raise ModelFileError(
            f"{path}: field 'format' is {meta.get('format') if isinstance(meta, dict) else meta!r}, expected {FORMAT!r}"
        )
    version = meta.get("version")
    if not isinstance(version, int) or isinstance(version, bool) or version > FORMAT_VERSION or version < 1:
        raise ModelFileError(
            f"{path}: field 'version' is {version!r}; this dam reads versions 1..{FORMAT_VERSION}"
            " (upgrade dam to read newer files)"
        )
    for fld, kind in (("model", str), ("params", dict), ("state", dict)):
        if fld not in meta:
            raise ModelFileError(f"{path}: field {fld!r} missing")
        if not isinstance(meta[fld], kind):
            raise _fail(path, fld, f"is a {type(meta[fld]).__name__}, expected a {kind.__name__}")
    return meta, arrays


def _read_archive(path: str, size: int) -> dict:
    with zipfile.ZipFile(path) as zf:
        infos = zf.infolist()
        declared = sum(i.file_size for i in infos)
        limit = MAX_TOTAL_BYTES + MAX_EXPANSION * size
        if declared > limit:
            raise ModelFileError(
                f"{path}: the archive declares {declared} bytes of arrays in a {size}-byte "
                f"file (more than the limit of {limit}): refused before reading"
            )
        budget = [limit]
        arrays = {}
        for info in infos:
            if not info.filename.endswith(".npy") or info.is_dir():
                raise _fail(path, info.filename, "not an array (.npy) member")
            name = info.filename[:-4]
            if name in arrays:
                raise _fail(path, name, "appears twice in the archive")
            arrays[name] = _read_member(zf, info, path, budget)
    return arrays


# -- the declared state ----------------------------------------------------------------
class StateArray:
    """A learned array in a class's ``_state_schema``.

    Parameters
    ----------
    kind : {"float", "int", "bool", "str"}, default "float"
        What the array holds. Any float width is accepted for ``"float"``
        (``float32`` from a small runtime too) but never an integer or
        boolean table; ``"int"`` takes signed or unsigned integers.
    shape : tuple of (int, str or None), optional
        Each axis a fixed length, a dimension name shared with the other
        entries (``"n_channels"``: bound by ``channels_``, every array using
        it must agree) or None (any length). Default: any shape.
    low, high : float, int or str, optional
        Inclusive bounds on every value; a str names a dimension (``high="n_modes"``
        bounds indices by that dimension, exclusive).
    finite : bool, default True
        Float values must be finite.
    optional : bool, default False
        The value may be None, or absent (a file written before the entry
        was learned).

    Examples
    --------
    A per-phone table; a file whose table has another number of rows than the model
    has phones, or integer values, is refused at load:

    >>> dam.StateArray("float", ("n_phones", "n_channels"))
    StateArray('float', ('n_phones', 'n_channels'))
    """

    _KINDS = {"float": "f", "int": "iu", "bool": "b", "str": "U"}

    def __init__(
        self, kind: str = "float", shape=None, *, low=None, high=None, finite: bool = True, optional: bool = False
    ):
        if kind not in self._KINDS:
            raise ValueError(f"StateArray kind must be one of {sorted(self._KINDS)}, not {kind!r}")
        self.kind, self.shape, self.low, self.high = kind, None if shape is None else tuple(shape), low, high
        self.finite, self.optional = finite, optional

    def __repr__(self) -> str:
        return f"StateArray({self.kind!r}, {self.shape!r})"

    def check(self, value, dims: dict, where: str) -> None:
        if value is None and self.optional:
            return
        if not isinstance(value, np.ndarray):
            raise ValueError(f"is a {type(value).__name__}, expected an array of {self.kind}")
        if value.dtype.kind not in self._KINDS[self.kind]:
            raise ValueError(f"has dtype {value.dtype}, expected {self.kind} values")
        if self.shape is not None:
            if value.ndim != len(self.shape):
                raise ValueError(
                    f"has {value.ndim} axes (shape {value.shape}), expected {len(self.shape)} "
                    f"({', '.join(str(d) for d in self.shape)})"
                )
            for axis, (n, d) in enumerate(zip(value.shape, self.shape)):
                _bind(dims, d, n, f"axis {axis} of shape {value.shape}")
        if self.kind == "float" and self.finite and value.size and not np.all(np.isfinite(value)):
            raise ValueError(f"holds a non-finite value ({value.ravel()[~np.isfinite(value.ravel())][0]})")
        if value.size and self.kind in ("float", "int"):
            low = dims.get(self.low, 0) if isinstance(self.low, str) else self.low
            if low is not None and value.min() < low:
                raise ValueError(f"holds {value.min()}, below its lower bound {low}")
            if isinstance(self.high, str):
                if self.high in dims and value.max() >= dims[self.high]:
                    raise ValueError(f"holds {value.max()}, but {self.high} is {dims[self.high]}")
            elif self.high is not None and value.max() > self.high:
                raise ValueError(f"holds {value.max()}, above its upper bound {self.high}")


class StateNames:
    """A list of distinct non-empty strings (channel names, phone labels) in ``_state_schema``.

    Parameters
    ----------
    dim : str, optional
        Its length is this dimension.
    unique : bool, default True

    Examples
    --------
    >>> dam.Synthesizer._state_schema["channels_"].dim
    'n_channels'
    """

    def __init__(self, dim: str | None = None, *, unique: bool = True):
        self.dim, self.unique = dim, unique

    def check(self, value, dims: dict, where: str) -> None:
        if not isinstance(value, (list, tuple)) or not all(isinstance(v, str) and v for v in value):
            raise ValueError("must be a list of non-empty strings")
        if self.unique and len(set(value)) != len(value):
            raise ValueError(f"repeats {next(v for v in value if value.count(v) > 1)!r}")
        _bind(dims, self.dim, len(value), "its length")


class StateCounts:
    """A mapping from a non-empty string (a phone) to a positive count, in ``_state_schema``.

    Parameters
    ----------
    dim : str, optional
        The number of keys is this dimension.

    Examples
    --------
    >>> counts = dam.StateCounts("n_phones")
    >>> dims = {}
    >>> counts.check({"a": 3, "sil": 2}, dims, "phone_counts_")
    >>> dims
    {'n_phones': 2}
    """

    def __init__(self, dim: str | None = None):
        self.dim = dim

    def check(self, value, dims: dict, where: str) -> None:
        if not isinstance(value, dict) or not value:
            raise ValueError("must be a non-empty mapping of names to counts")
        for k, v in value.items():
            if not isinstance(k, str) or not k:
                raise ValueError(f"has the key {k!r}, expected a non-empty string")
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
                raise ValueError(f"[{k!r}] is {v!r}, expected a count of at least 1")
        _bind(dims, self.dim, len(value), "its number of entries")


class StateRanges:
    """A mapping from a name (a phone) to ``[first, count]``, a slice of a dimension
    (the DAM's ``phone_modes_``: the modes of each phone), in ``_state_schema``.

    Parameters
    ----------
    dim : str
        The dimension the slices index (bound earlier in the schema).
    keys : str, optional
        The number of names is this dimension.
    """

    def __init__(self, dim: str, *, keys: str | None = None):
        self.dim, self.keys = dim, keys

    def check(self, value, dims: dict, where: str) -> None:
        if not isinstance(value, dict):
            raise ValueError("must be a mapping of names to [first, count]")
        n = dims.get(self.dim)
        for k, v in value.items():
            ok = (
                isinstance(k, str)
                and k
                and isinstance(v, (list, tuple))
                and len(v) == 2
                and all(isinstance(x, (int, np.integer)) and not isinstance(x, bool) for x in v)
            )
            if not ok or v[0] < 0 or v[1] < 1 or (n is not None and v[0] + v[1] > n):
                raise ValueError(f"[{k!r}] is {v!r}, expected [first, count] within {self.dim} = {n}")
        _bind(dims, self.keys, len(value), "its number of entries")


def _bind(dims: dict, d, n: int, what: str) -> None:
    if d is None:
        return
    if isinstance(d, int):
        if n != d:
            raise ValueError(f"{what}: {n}, expected {d}")
    elif dims.setdefault(d, n) != n:
        raise ValueError(f"{what}: {d} is {n} here but {dims[d]} elsewhere in the file")


def state_schema(cls) -> dict:
    """The ``_state_schema`` of ``cls`` merged down its class hierarchy (subclasses override)."""
    merged: dict = {}
    for klass in reversed(cls.__mro__):
        merged.update(klass.__dict__.get("_state_schema") or {})
    return merged


def _declares_schema(cls) -> bool:
    """Whether a class of ``cls``'s hierarchy other than the common base (which marks itself
    ``_state_schema_common = True``) declares state: then the schema is complete and state
    outside it is refused."""
    return any(k.__dict__.get("_state_schema") and not k.__dict__.get("_state_schema_common") for k in cls.__mro__)


def check_state(cls, state: dict, source) -> None:
    """Check learned ``state`` against ``cls``'s declared ``_state_schema``.

    Every name must be a learned-attribute name (``word_``) that the class does
    not define itself; every declared entry must be present (an optional
    one may be absent) and match its declaration (dtype, shape, dimensions
    consistent across entries, finite, in range). A class that declares a schema of its own gets nothing else.

    Raises
    ------
    ModelFileError
        Naming ``source``, the field (``state.<name>``) and what is wrong.
    """
    if not isinstance(state, dict):
        raise ModelFileError(f"{source}: field 'state' is a {type(state).__name__}, expected a mapping")
    for key in state:
        if not (isinstance(key, str) and key.isidentifier() and key.endswith("_") and not key.startswith("_")):
            raise ModelFileError(
                f"{source}: field 'state' holds {key!r}, which is not a learned-attribute name "
                "(an identifier ending in '_')"
            )
        if hasattr(cls, key):
            raise ModelFileError(
                f"{source}: field 'state.{key}' would replace the {cls.__name__} attribute of that name"
            )
    schema = state_schema(cls)
    missing = [k for k in schema if k not in state and not getattr(schema[k], "optional", False)]
    if missing:
        raise ModelFileError(f"{source}: field 'state.{missing[0]}' is missing: this is not a complete {cls.__name__}")
    if _declares_schema(cls):
        extra = sorted(set(state) - set(schema))
        if extra:
            raise ModelFileError(
                f"{source}: field 'state.{extra[0]}' is not part of a {cls.__name__} (its state is {', '.join(schema)})"
            )
    dims: dict = {}
    for key, spec in schema.items():
        value = state.get(key)  # an absent optional entry is None
        try:
            if spec is None:  # declared, any JSON-able value
                continue
            if hasattr(spec, "check"):
                spec.check(value, dims, key)
            elif hasattr(spec, "is_satisfied_by"):  # a dam._params constraint: a scalar
                if not spec.is_satisfied_by(value):
                    raise ValueError(f"is {value!r}; it must be {spec}")
            else:  # pragma: no cover - a schema bug
                raise TypeError(f"{cls.__name__}._state_schema[{key!r}] is not a state declaration")
        except ValueError as exc:
            raise ModelFileError(f"{source}: field 'state.{key}' {exc}") from None


def load(path):
    """Load a model written by ``Synthesizer.save``.

    Raises
    ------
    ModelFileError
        The file is missing, corrupt, foreign or of an unknown version.

    Examples
    --------
    >>> import dam
    >>> model = dam.make("phone-mean").fit(dam.datasets.load("tiny"))
    >>> model.save("phone-mean.dam")
    >>> first = dam.datasets.load("tiny")[0]
    >>> dam.load("phone-mean.dam").predict(first.alignment).shape == first.trajectory.shape
    True
    """
    from dam.registry import get

    path = os.fspath(path)
    meta, arrays = read_model_file(path)
    try:
        cls = get(meta["model"])
    except KeyError as exc:
        raise ModelFileError(
            f"{path}: field 'model' is {meta['model']!r}, which is not registered here "
            f"(class {meta.get('class', '?')}); register it before loading: "
            f"dam.register({meta['model']!r}, TheClass) ({exc})"
        ) from None
    try:
        params = _decode(meta["params"], arrays)
        state = _decode(meta["state"], arrays)
    except (KeyError, TypeError, ValueError) as exc:
        raise ModelFileError(
            f"{path}: the stored {meta['model']!r} model is damaged (an array reference: {type(exc).__name__}: {exc})"
        ) from None
    check_state(cls, state, path)
    try:
        model = cls(**params)
    except TypeError as exc:
        raise ModelFileError(f"{path}: field 'params' does not fit a {cls.__name__} ({exc})") from None
    validate = getattr(model, "_validate_params", None)
    if validate is not None:
        try:
            validate()
        except (TypeError, ValueError) as exc:
            raise ModelFileError(f"{path}: field 'params': {exc}") from None
    try:
        model._set_state(state)
    except (KeyError, IndexError, TypeError, ValueError, AttributeError) as exc:
        raise ModelFileError(
            f"{path}: the stored {meta['model']!r} model is damaged ({type(exc).__name__}: {exc})"
        ) from None
    return model
