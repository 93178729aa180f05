"""glTF 2.0 export: an animation of morph-target weights, one target per control.

Two ways (see :func:`write_gltf`):

* **dam's own mesh** (:mod:`dam.export.meshes`): the VocalTractLab ribbon for
  VTL tract parameters or toy-rig controls, bars for anything else;
* **a user's rig** (``rig="face.glb"``): the asset is copied whole and gets
  one more animation, ``dam``, whose channels drive every mesh whose morph
  targets carry the controls' names (``mesh.extras.targetNames``, the
  convention Blender, three.js and Babylon.js read).

What the specification asks and this writer does: keyframe times (the
sampler ``input``) are float32, strictly increasing, with ``min``/``max``;
``POSITION`` accessors, base and morph targets, carry ``min``/``max``; the
``weights`` output holds ``n_frames * n_targets`` floats, frame-major; every
accessor starts on a multiple of its component size and every buffer view on
a multiple of 4; vertex data views have ``target`` 34962, index views 34963,
animation views none; GLB chunks are padded to 4 bytes (JSON with spaces,
BIN with zeros). The test suite checks every variant with the Khronos
glTF-Validator and imports the ``.glb`` into Blender.
"""

from __future__ import annotations

import base64
import json
import os
import struct

import numpy as np

from dam.corpus import DataError
from dam.corpus.atomic import atomic_write

from .tables import ExportReport, _toolkit, check_animation, read_json_object

FLOAT, UINT16, UINT32 = 5126, 5123, 5125
ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963
GLB_MAGIC, JSON_CHUNK, BIN_CHUNK = 0x46546C67, 0x4E4F534A, 0x004E4942

__all__ = ["write_gltf", "read_gltf", "target_names", "fit_weights", "read_mapping", "WEIGHT_MODES"]

#: How weights outside [0, 1] are brought into range.
WEIGHT_MODES = ("clip", "scale")


class _Builder:
    """Accumulates one binary buffer and the accessors into it."""

    def __init__(self, doc: dict, data: bytes = b""):
        self.doc = doc
        self.bin = bytearray(data)
        for key in ("bufferViews", "accessors"):
            doc.setdefault(key, [])

    def view(self, raw: bytes, target=None) -> int:
        self.bin.extend(b"\0" * (-len(self.bin) % 4))  # views start on 4 bytes: every component fits
        view = {"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(raw)}
        if target is not None:
            view["target"] = target
        self.bin.extend(raw)
        self.doc["bufferViews"].append(view)
        return len(self.doc["bufferViews"]) - 1

    def accessor(self, array, type_: str, *, target=None, bounds=False) -> int:
        arr = np.ascontiguousarray(array)
        ctype = {np.dtype(np.float32): FLOAT, np.dtype(np.uint16): UINT16, np.dtype(np.uint32): UINT32}[arr.dtype]
        width = {"SCALAR": 1, "VEC3": 3}[type_]
        acc = {
            "bufferView": self.view(arr.tobytes(), target),
            "componentType": ctype,
            "count": int(arr.size // width),
            "type": type_,
        }
        if bounds:
            flat = arr.reshape(-1, width)
            cast = float if ctype == FLOAT else int
            acc["min"] = [cast(v) for v in flat.min(axis=0)]
            acc["max"] = [cast(v) for v in flat.max(axis=0)]
        self.doc["accessors"].append(acc)
        return len(self.doc["accessors"]) - 1


def fit_weights(weights, channels, mode: str = "clip", *, source=None):
    """Bring morph weights into [0, 1].

    Parameters
    ----------
    weights : ndarray, shape (n_frames, n_controls)
    channels : sequence of str
    mode : {"clip", "scale"}, default "clip"
        ``"clip"`` cuts values at 0 and 1; ``"scale"`` maps each control whose
        values leave [0, 1] linearly from ``[min(0, lo), max(1, hi)]`` onto
        [0, 1] (controls within range are untouched).

    Returns
    -------
    weights : ndarray, shape (n_frames, n_controls)
    clipped : dict of str -> int
        Frames clipped per control (``"clip"``).
    scaled : dict of str -> (float, float)
        Original range per rescaled control (``"scale"``).
    """
    if mode not in WEIGHT_MODES:
        raise DataError(source, "weights", mode, f"use one of {', '.join(WEIGHT_MODES)}")
    W = np.asarray(weights, dtype=float)
    out = W.copy()
    clipped, scaled = {}, {}
    for j, name in enumerate(channels):
        col = W[:, j]
        outside = (col < 0) | (col > 1)
        if not outside.any():
            continue
        if mode == "clip":
            out[:, j] = np.clip(col, 0.0, 1.0)
            clipped[name] = int(outside.sum())
        else:
            lo, hi = min(0.0, float(col.min())), max(1.0, float(col.max()))
            out[:, j] = (col - lo) / (hi - lo)
            scaled[name] = (lo, hi)
    return out, clipped, scaled


# -- reading a user's rig ---------------------------------------------------
def read_gltf(path) -> tuple[dict, bytes]:
    """Read a ``.glb`` or ``.gltf`` into its JSON document and one merged binary buffer.

    Every buffer (GLB chunk, data URI or external file) is concatenated into
    buffer 0, each starting on 16 bytes, and the buffer views are rebased;
    images in files beside the rig are moved into the buffer too, so the
    asset written from it stands alone. Returns ``(doc, bin)``.
    """
    path = os.fspath(path)
    try:
        with open(path, "rb") as fh:
            raw = fh.read()
    except OSError as exc:
        raise DataError(path, "rig", path, f"cannot be read: {exc.strerror}") from None
    chunk = None
    try:
        if raw[:4] == b"glTF":
            _, version, length = struct.unpack_from("<III", raw, 0)
            if version != 2:
                raise DataError(path, "GLB version", version, "only glTF 2.0 is supported")
            jlen, jtype = struct.unpack_from("<II", raw, 12)
            if jtype != JSON_CHUNK:
                raise DataError(path, "GLB chunk 0", hex(jtype), "the first chunk must be JSON")
            doc = json.loads(raw[20 : 20 + jlen].decode("utf-8"))
            offset = 20 + jlen
            if offset + 8 <= len(raw):
                blen, btype = struct.unpack_from("<II", raw, offset)
                if btype == BIN_CHUNK:
                    chunk = raw[offset + 8 : offset + 8 + blen]
        else:
            doc = json.loads(raw.decode("utf-8"))
    except (ValueError, UnicodeDecodeError, struct.error) as exc:
        raise DataError(path, "rig", os.path.basename(path), f"not a glTF or GLB file ({exc})") from None
    version = str(doc.get("asset", {}).get("version", ""))
    if not version.startswith("2."):
        raise DataError(path, "asset.version", version, "only glTF 2.0 is supported")
    blobs = []
    for i, buf in enumerate(doc.get("buffers", [])):
        uri = buf.get("uri")
        if uri is None:
            if chunk is None:
                raise DataError(path, f"buffers[{i}]", "no uri", "refers to a GLB binary chunk that is missing")
            blob = chunk
        elif uri.startswith("data:"):
            blob = base64.b64decode(uri.split(",", 1)[1])
        else:
            ext = os.path.join(os.path.dirname(path), uri)
            try:
                with open(ext, "rb") as fh:
                    blob = fh.read()
            except OSError as exc:
                raise DataError(path, f"buffers[{i}].uri", uri, f"cannot be read: {exc.strerror}") from None
        blobs.append(blob[: buf.get("byteLength", len(blob))])
    merged, starts = bytearray(), []
    for blob in blobs:
        merged.extend(b"\0" * (-len(merged) % 16))
        starts.append(len(merged))
        merged.extend(blob)
    for view in doc.get("bufferViews", []):
        view["byteOffset"] = view.get("byteOffset", 0) + starts[view["buffer"]]
        view["buffer"] = 0
    # images in files beside the rig move into the buffer: the output stands alone wherever it is written
    for i, image in enumerate(doc.get("images", [])):
        uri = image.get("uri")
        if uri is None or uri.startswith("data:"):
            continue
        mime = {
            ".png": "image/png",
            ".jpg": "image/jpeg",
            ".jpeg": "image/jpeg",
            ".webp": "image/webp",
            ".ktx2": "image/ktx2",
        }.get(os.path.splitext(uri)[1].lower())
        try:
            with open(os.path.join(os.path.dirname(path), uri), "rb") as fh:
                blob = fh.read()
        except OSError as exc:
            raise DataError(path, f"images[{i}].uri", uri, f"cannot be read: {exc.strerror}") from None
        if mime is None:
            raise DataError(path, f"images[{i}].uri", uri, "not a PNG, JPEG, WebP or KTX2 image")
        merged.extend(b"\0" * (-len(merged) % 16))
        doc.setdefault("bufferViews", []).append({"buffer": 0, "byteOffset": len(merged), "byteLength": len(blob)})
        merged.extend(blob)
        image.pop("uri")
        image.update(bufferView=len(doc["bufferViews"]) - 1, mimeType=mime)
    doc["buffers"] = [{"byteLength": len(merged)}] if merged else []
    return doc, bytes(merged)


def target_names(doc: dict) -> dict[int, list[str]]:
    """Morph-target names of every mesh that has targets: ``{mesh index: names}``.

    Names come from ``mesh.extras.targetNames`` (or the first primitive's
    ``extras.targetNames``); a mesh without names gets ``target_0, ...``.
    """
    out = {}
    for m, mesh in enumerate(doc.get("meshes", [])):
        prims = mesh.get("primitives", [])
        n = len(prims[0].get("targets", [])) if prims else 0
        if not n:
            continue
        names = (mesh.get("extras") or {}).get("targetNames") or (prims[0].get("extras") or {}).get("targetNames")
        out[m] = [str(s) for s in names] if names and len(names) == n else [f"target_{i}" for i in range(n)]
    return out


def read_mapping(mapping, source=None) -> dict[str, str]:
    """A control -> morph-target name mapping from a dict or a JSON file of one object."""
    if mapping is None:
        return {}
    if isinstance(mapping, dict):
        doc, where = mapping, source
    else:
        where = os.fspath(mapping)
        doc = read_json_object(where, "mapping")
    if not isinstance(doc, dict) or not all(isinstance(k, str) and isinstance(v, str) for k, v in doc.items()):
        raise DataError(
            where,
            "mapping",
            type(doc).__name__,
            'must be a JSON object of control name -> morph target name, e.g. {"JA": "jawOpen"}',
        )
    return dict(doc)


# -- writing ------------------------------------------------------------------
def _frame_times(n_frames: int, frame_rate: float, source) -> np.ndarray:
    t = (np.arange(n_frames) / frame_rate).astype(np.float32)
    if n_frames > 1 and not np.all(np.diff(t) > 0):
        raise DataError(
            source, "frame_rate", frame_rate, f"{n_frames} frames are too many for float32 keyframe times at this rate"
        )
    return t


def _own_mesh_doc(b: _Builder, mesh, name: str) -> int:
    pos = mesh.positions.astype(np.float32)
    attrs = {"POSITION": b.accessor(pos, "VEC3", target=ARRAY_BUFFER, bounds=True)}
    idx_type = np.uint16 if len(pos) < 65535 else np.uint32
    indices = b.accessor(mesh.indices.astype(idx_type), "SCALAR", target=ELEMENT_ARRAY_BUFFER, bounds=True)
    targets = [
        {"POSITION": b.accessor(t.astype(np.float32), "VEC3", target=ARRAY_BUFFER, bounds=True)} for t in mesh.targets
    ]
    b.doc.setdefault("materials", []).append(
        {
            "name": "dam_ribbon",
            "doubleSided": True,
            "pbrMetallicRoughness": {
                "baseColorFactor": [0.8, 0.25, 0.3, 1.0],
                "metallicFactor": 0.0,
                "roughnessFactor": 0.7,
            },
        }
    )
    b.doc.setdefault("meshes", []).append(
        {
            "name": name,
            "primitives": [
                {
                    "attributes": attrs,
                    "indices": indices,
                    "mode": 4,
                    "targets": targets,
                    "material": len(b.doc["materials"]) - 1,
                }
            ],
            "weights": [float(w) for w in mesh.default_weights],
            "extras": {"targetNames": list(mesh.names)},
        }
    )
    b.doc.setdefault("nodes", []).append({"name": name, "mesh": len(b.doc["meshes"]) - 1})
    node = len(b.doc["nodes"]) - 1
    b.doc.setdefault("scenes", []).append({"name": "dam", "nodes": [node]})
    b.doc["scene"] = len(b.doc["scenes"]) - 1
    return node


def _rig_targets(doc, channels, mapping, rig_path):
    """For each animated node: (node index, mesh's target names, column of each target or -1)."""
    meshes = target_names(doc)
    all_names = sorted({n for names in meshes.values() for n in names})
    if not meshes:
        raise DataError(rig_path, "meshes", 0, "the rig has no mesh with morph targets")
    bad = {c: t for c, t in mapping.items() if c not in channels}
    if bad:
        raise DataError(
            rig_path, "mapping", sorted(bad), "names controls the model does not have", f"controls: {list(channels)}"
        )
    wanted = [mapping.get(c, c) for c in channels]
    unknown = [(c, t) for c, t in zip(channels, wanted) if t not in all_names]
    if unknown:
        shown = ", ".join(c if c == t else f"{c} -> {t}" for c, t in unknown)
        raise DataError(
            rig_path,
            "morph targets",
            shown,
            "no morph target of that name in the rig",
            f"controls: {list(channels)}; rig morph targets: {all_names}; "
            'map names that differ with a mapping file (JSON: {"control": "target"})',
        )
    dup = [t for t in set(wanted) if wanted.count(t) > 1]
    if dup:
        raise DataError(rig_path, "mapping", sorted(dup), "several controls drive the same morph target")
    column = {t: j for j, t in enumerate(wanted)}
    out = []
    for n, node in enumerate(doc.get("nodes", [])):
        m = node.get("mesh")
        if m in meshes and any(t in column for t in meshes[m]):
            out.append((n, meshes[m], [column.get(t, -1) for t in meshes[m]], m))
    return out


def write_gltf(
    values,
    path,
    *,
    channels,
    frame_rate,
    alignment=None,
    metadata=None,
    rig=None,
    mapping=None,
    weights: str = "clip",
    mesh: str = "auto",
    **options,
) -> ExportReport:
    """Write a glTF 2.0 asset (``.gltf``, one JSON file, or ``.glb``, binary) animating morph weights.

    Parameters
    ----------
    values : ndarray, shape (n_frames, n_channels)
        Control values; frame ``i`` is keyed at ``i / frame_rate`` seconds,
        linearly interpolated between frames.
    path : str
        Ends in ``.gltf`` or ``.glb``.
    channels : sequence of str
    frame_rate : float
    alignment : Alignment, optional
        Its phones go into the animation's ``extras.phones``.
    metadata : dict, optional
        Stored in ``asset.extras``.
    rig : path-like, optional
        A ``.glb``/``.gltf`` with named morph targets. Without it, dam's own
        mesh (``mesh``) is used.
    mapping : dict or path-like, optional
        Control name -> morph target name for names that differ (JSON file
        of one object); other controls match targets of their own name.
    weights : {"clip", "scale"}, default "clip"
        How weights outside [0, 1] are brought into range (see
        :func:`fit_weights`); the report lists what changed.
    mesh : {"auto", "vtl", "toy", "bars"}, default "auto"
        dam's own mesh (see :func:`dam.export.meshes.own_mesh`). With
        ``"vtl"`` the weights are each tract parameter's place in its VTL range.

    Returns
    -------
    ExportReport
    """
    from .meshes import own_mesh

    if options:
        name = sorted(options)[0]
        raise DataError(path, name, options[name], "not an option of the glTF format")
    values, channels, frame_rate = check_animation(values, channels, frame_rate, path, alignment)
    binary = path.lower().endswith(".glb")
    version = _toolkit()["version"]
    if rig is None:
        if mapping is not None:
            raise DataError(path, "mapping", "given", "a mapping needs a rig (rig=MESH.glb)")
        doc = {"asset": {"version": "2.0", "generator": f"dam {version}"}}
        b = _Builder(doc)
        own = own_mesh(channels, mesh, source=path)
        raw_weights = own.to_weights(values)
        node = _own_mesh_doc(b, own, "controls" if own.kind == "bars" else "vocal_tract")
        drives = [(node, list(channels), list(range(len(channels))), None)]
    else:
        rig = os.fspath(rig)
        doc, data = read_gltf(rig)
        b = _Builder(doc, data)
        drives = _rig_targets(doc, channels, read_mapping(mapping), rig)
        raw_weights = values
    W, clipped, scaled = fit_weights(raw_weights, channels, weights, source=path)

    times = _frame_times(len(W), frame_rate, path)
    t_acc = b.accessor(times, "SCALAR", bounds=True)
    samplers, anim_channels = [], []
    for node, names, cols, mesh_index in drives:
        defaults = (doc["meshes"][mesh_index].get("weights") if mesh_index is not None else None) or [0.0] * len(names)
        out = np.empty((len(W), len(names)), dtype=np.float32)
        for k, j in enumerate(cols):
            out[:, k] = W[:, j] if j >= 0 else defaults[k]  # targets no control drives keep their rest weight
        samplers.append({"input": t_acc, "interpolation": "LINEAR", "output": b.accessor(out.ravel(), "SCALAR")})
        anim_channels.append({"sampler": len(samplers) - 1, "target": {"node": node, "path": "weights"}})
    extras = {"frame_rate": frame_rate, "channels": list(channels)}
    if alignment is not None:
        extras["phones"] = [
            [lab, float(s), float(e)] for lab, s, e in zip(alignment.labels, alignment.starts, alignment.ends)
        ]
    doc.setdefault("animations", []).append(
        {"name": "dam", "samplers": samplers, "channels": anim_channels, "extras": extras}
    )
    asset_extras = dict(doc["asset"].get("extras") or {})
    asset_extras["dam"] = {"toolkit": version, **({"metadata": metadata} if metadata else {})}
    doc["asset"]["extras"] = asset_extras
    b.bin.extend(b"\0" * (-len(b.bin) % 4))
    payload = bytes(b.bin)
    if binary:
        doc["buffers"] = [{"byteLength": len(payload)}]
    else:
        doc["buffers"] = [
            {
                "byteLength": len(payload),
                "uri": "data:application/octet-stream;base64," + base64.b64encode(payload).decode(),
            }
        ]
    try:
        text = json.dumps(doc, separators=(",", ":"), allow_nan=False)
    except (TypeError, ValueError) as exc:
        raise DataError(path, "metadata", type(metadata).__name__, f"not JSON-able ({exc})") from None
    with atomic_write(path, "wb") as fh:
        if binary:
            js = text.encode("utf-8")
            js += b" " * (-len(js) % 4)
            total = 12 + 8 + len(js) + 8 + len(payload)
            fh.write(struct.pack("<III", GLB_MAGIC, 2, total))
            fh.write(struct.pack("<II", len(js), JSON_CHUNK) + js)
            fh.write(struct.pack("<II", len(payload), BIN_CHUNK) + payload)
        else:
            fh.write(text.encode("utf-8"))
    rep = ExportReport(
        path, "glb" if binary else "gltf", values.shape[0], values.shape[1], frame_rate, clipped=clipped, scaled=scaled
    )
    if rig is None:
        rep.notes.append(f"mesh: dam's own {own.kind} mesh with {len(channels)} morph targets")
    return rep
