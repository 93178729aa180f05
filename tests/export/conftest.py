"""Fixtures for the animation-export tests: the external programs that check dam's files."""

import importlib.util
import json
import os
from pathlib import Path

import numpy as np
import pytest

_spec = importlib.util.spec_from_file_location("dam_export_tools", Path(__file__).with_name("export_tools.py"))
tools = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(tools)

ON_CI = os.environ.get("CI", "").lower() == "true"


@pytest.fixture(scope="session")
def export_tools():
    """The helper module (tests/export/export_tools.py)."""
    return tools


@pytest.fixture(scope="session")
def validate():
    """``validate(paths) -> {path: report}`` with the Khronos glTF-Validator; fails on CI if node is missing."""
    try:
        return tools.gltf_validator()
    except tools.ToolMissing as exc:
        if ON_CI:
            pytest.fail(f"the Khronos glTF-Validator is required on CI: {exc}")
        pytest.skip(str(exc))


@pytest.fixture(scope="session")
def blender():
    """Path of a Python that imports bpy (Blender 4.5).

    On CI it is installed when missing (a venv of its own; bpy 4.5 pins numpy<2) and the test
    fails if that fails; elsewhere the test skips with the command that installs it.
    """
    exe = tools.blender_python()
    if exe is None and ON_CI:
        try:
            exe = tools.install_blender()
        except Exception as exc:  # pip or venv failed: say so, do not hide the check
            pytest.fail(f"Blender's Python module (bpy 4.5) is required on CI and could not be installed: {exc}")
    if exe is None:
        pytest.skip(
            "no Python with bpy (Blender 4.5 pins numpy<2, so it lives in a venv of its own): "
            "run `python tests/export/export_tools.py` to install it"
        )
    return exe


def one_pixel_png() -> bytes:
    """A valid 1 x 1 RGB PNG, built from the PNG specification."""
    import struct
    import zlib

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", struct.pack(">IIBBBBB", 1, 1, 8, 2, 0, 0, 0))
        + chunk(b"IDAT", zlib.compress(b"\x00\xff\x00\x00"))
        + chunk(b"IEND", b"")
    )


def _write_hand_rig(directory, names=()):
    """A rig written by hand from the specification: two meshes, named targets, external .bin.

    The face has targets jawOpen, mouthPucker, mouthClose, then ``names`` (each a small
    displacement); the teeth have jawOpen only.
    """
    tri = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype="<f4")
    targets = {
        "jawOpen": [[0, -0.5, 0], [0, -0.5, 0], [0, 0, 0]],
        "mouthPucker": [[0.2, 0, 0], [-0.2, 0, 0], [0, 0, 0]],
        "mouthClose": [[0, 0.1, 0], [0, 0.1, 0], [0, 0, 0]],
    }
    for k, n in enumerate(x for x in names if x not in targets):
        targets[n] = [[0, 0, 0.01 * (k + 1)], [0, 0, 0], [0, 0, 0]]
    idx = np.array([0, 1, 2, 0], dtype="<u2")  # padded to 8 bytes
    blobs = [idx.tobytes(), tri.tobytes()] + [np.array(v, dtype="<f4").tobytes() for v in targets.values()]
    views, off = [], 0
    for k, b in enumerate(blobs):
        views.append(
            {
                "buffer": 0,
                "byteOffset": off,
                "byteLength": 6 if k == 0 else len(b),
                "target": 34963 if k == 0 else 34962,
            }
        )
        off += len(b)

    def vec(view, arr):
        arr = np.asarray(arr, dtype=float)
        return {
            "bufferView": view,
            "componentType": 5126,
            "count": 3,
            "type": "VEC3",
            "min": arr.min(0).tolist(),
            "max": arr.max(0).tolist(),
        }

    accessors = [{"bufferView": 0, "componentType": 5123, "count": 3, "type": "SCALAR"}, vec(1, tri)]
    accessors += [vec(2 + k, v) for k, v in enumerate(targets.values())]
    names = list(targets)
    doc = {
        "asset": {"version": "2.0", "generator": "hand"},
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"name": "face", "mesh": 0}, {"name": "teeth", "mesh": 1, "translation": [2, 0, 0]}],
        "meshes": [
            {
                "primitives": [
                    {
                        "attributes": {"POSITION": 1},
                        "indices": 0,
                        "targets": [{"POSITION": 2 + k} for k in range(len(names))],
                    }
                ],
                "weights": [0.0, 0.0, 0.25] + [0.0] * (len(names) - 3),
                "extras": {"targetNames": names},
            },
            {
                "primitives": [{"attributes": {"POSITION": 1}, "indices": 0, "targets": [{"POSITION": 2}]}],
                "extras": {"targetNames": ["jawOpen"]},
            },
        ],
        "buffers": [{"uri": "rig.bin", "byteLength": off}],
        "bufferViews": views,
        "accessors": accessors,
        "images": [{"uri": "skin.png"}],
        "textures": [{"source": 0}],
    }
    (directory / "rig.bin").write_bytes(b"".join(blobs))
    (directory / "skin.png").write_bytes(one_pixel_png())
    (directory / "rig.gltf").write_text(json.dumps(doc))
    return directory / "rig.gltf"


@pytest.fixture(scope="session")
def hand_rig():
    """``hand_rig(directory) -> path`` of a rig written by hand from the glTF specification."""
    return _write_hand_rig
