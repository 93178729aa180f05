"""The external programs that check dam's animation files: Khronos glTF-Validator and Blender.

Both live in a cache folder (``$DAM_TOOL_CACHE``, default ``~/.cache/dam-tools``):

* ``gltf-validator`` from the npm registry, installed with ``npm`` when node
  is present (a few hundred kB, seconds);
* Blender's ``bpy`` 4.5 from the package index, in a virtual environment of
  its own because it pins ``numpy<2`` (about 370 MB; minutes).

``python tests/export/export_tools.py`` installs both (CI can run it before the
tests). The tests call :func:`gltf_validator` and :func:`blender_python`.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

VALIDATOR_VERSION = "2.0.0-dev.3.10"
BPY_SPEC = "bpy==4.5.*"
CACHE = Path(os.environ.get("DAM_TOOL_CACHE", Path.home() / ".cache" / "dam-tools"))

_VALIDATE_JS = r"""
const validator = require(process.argv[2]);
const fs = require('fs');
(async () => {
  const out = {};
  for (const f of process.argv.slice(3)) {
    const data = new Uint8Array(fs.readFileSync(f));
    out[f] = await validator.validateBytes(data, {uri: f, maxIssues: 200,
      externalResourceFunction: (uri) => new Promise((ok, fail) => {
        fs.readFile(require('path').resolve(require('path').dirname(f), decodeURIComponent(uri)),
                    (err, d) => err ? fail(err.toString()) : ok(new Uint8Array(d)));
      })});
  }
  process.stdout.write(JSON.stringify(out));
})().catch(e => { console.error(String(e)); process.exit(1); });
"""

_BLENDER_DUMP = r"""
import json, sys
import bpy
path, out = sys.argv[-2], sys.argv[-1]
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath=path)
scene = bpy.context.scene
res = {"fps": scene.render.fps / scene.render.fps_base, "version": bpy.app.version_string, "objects": {}}
for ob in bpy.data.objects:
    if ob.type != "MESH" or ob.data.shape_keys is None:
        continue
    sk = ob.data.shape_keys
    curves = {}
    act = sk.animation_data.action if sk.animation_data else None
    if act is not None:
        fcs = list(getattr(act, "fcurves", []))
        if not fcs and hasattr(act, "layers"):  # Blender 4.4+ layered actions
            fcs = [fc for layer in act.layers for strip in layer.strips
                   for bag in strip.channelbags for fc in bag.fcurves]
        for fc in fcs:
            curves[fc.data_path] = [[kp.co[0], kp.co[1]] for kp in fc.keyframe_points]
    res["objects"][ob.name] = {"keys": [kb.name for kb in sk.key_blocks], "curves": curves,
                               "n_vertices": len(ob.data.vertices)}
with open(out, "w") as fh:
    json.dump(res, fh)
"""


class ToolMissing(RuntimeError):
    """A checking tool is not installed and cannot be installed here."""


def _validator_module() -> Path:
    return CACHE / "gltf-validator" / "node_modules" / "gltf-validator"


def install_validator() -> Path:
    """Install the Khronos glTF-Validator into the cache (needs node and npm)."""
    if not shutil.which("node") or not shutil.which("npm"):
        raise ToolMissing("node and npm are needed for the Khronos glTF-Validator")
    mod = _validator_module()
    if not (mod / "index.js").exists():
        mod.parent.parent.mkdir(parents=True, exist_ok=True)
        proc = subprocess.run(
            [
                "npm",
                "install",
                "--no-audit",
                "--no-fund",
                "--prefix",
                str(mod.parent.parent),
                f"gltf-validator@{VALIDATOR_VERSION}",
            ],
            capture_output=True,
            text=True,
            timeout=600,
        )
        if proc.returncode or not (mod / "index.js").exists():
            raise ToolMissing(f"npm install gltf-validator failed: {proc.stderr[-2000:]}")
    return mod


def gltf_validator():
    """A function ``validate(paths) -> {path: report}`` running the Khronos validator, installing it if needed."""
    mod = install_validator()
    script = CACHE / "gltf-validator" / "validate.js"
    if not script.exists() or script.read_text() != _VALIDATE_JS:
        script.write_text(_VALIDATE_JS)

    def validate(paths):
        paths = [os.fspath(p) for p in paths]
        proc = subprocess.run(["node", str(script), str(mod)] + paths, capture_output=True, text=True, timeout=600)
        if proc.returncode:
            raise RuntimeError(f"gltf-validator failed: {proc.stderr[-2000:]}")
        return json.loads(proc.stdout)

    return validate


def _venv_python() -> Path:
    return CACHE / "bpy-venv" / "bin" / "python"


def blender_python() -> str | None:
    """A Python that imports ``bpy``: ``$DAM_BPY_PYTHON``, this one, or the cache's venv; None if none."""
    candidates = [os.environ.get("DAM_BPY_PYTHON"), sys.executable, str(_venv_python())]
    for exe in candidates:
        if exe and Path(exe).exists():
            proc = subprocess.run([exe, "-c", "import bpy"], capture_output=True, timeout=120)
            if proc.returncode == 0:
                return exe
    return None


def install_blender() -> str:
    """Create the cache's venv with ``bpy`` 4.5 (Python 3.11 only)."""
    exe = blender_python()
    if exe:
        return exe
    if sys.version_info[:2] != (3, 11):
        raise ToolMissing(f"bpy 4.5 needs Python 3.11, this is {sys.version.split()[0]}")
    venv = CACHE / "bpy-venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
    subprocess.run([str(_venv_python()), "-m", "pip", "install", "-q", BPY_SPEC], check=True, timeout=1800)
    return str(_venv_python())


def blender_import(glb, python: str, workdir) -> dict:
    """Import ``glb`` into Blender; returns its shape keys and their keyframes per mesh object."""
    script = Path(workdir) / "blender_dump.py"
    script.write_text(_BLENDER_DUMP)
    out = Path(workdir) / "blender_dump.json"
    proc = subprocess.run([python, str(script), os.fspath(glb), str(out)], capture_output=True, text=True, timeout=600)
    if proc.returncode:
        raise RuntimeError(f"Blender import failed: {proc.stderr[-3000:]}")
    return json.loads(out.read_text())


if __name__ == "__main__":
    print("gltf-validator:", install_validator())
    print("bpy python:", install_blender())
