"""Animation out: text -> DAM -> a .glb with a moving vocal tract, and a picture of it.

Animates a sentence with the shipped default DAM (VocalTractLab tract
parameters), writes ``face.glb`` (dam's own VocalTractLab ribbon, one morph
target per tract parameter) and renders four of its frames to a PNG *from
the file itself*: base mesh + weights x morph targets, read back from the
GLB bytes as any glTF viewer does.

    python examples/animation_out.py [--out DIR] [--blender PYTHON] [--quick]

Output goes to ``--out`` (default ``dam-examples/animation_out/`` in the working directory, which
git ignores; a positional OUT_DIR works too). The example takes seconds, so ``--quick`` changes
nothing.

With ``--blender PYTHON`` (a Python that imports Blender's ``bpy``, e.g. the
venv ``tests/export/export_tools.py`` installs), the same frames are also
rendered by Blender after importing the ``.glb`` (``animation_out_blender.png``).
The README's pictures (docs/animation_out*.png) are this script's output.
"""

from __future__ import annotations

import json
import os
import struct
import subprocess
import sys
import warnings

import numpy as np

import dam
from dam.export import export

TEXT = "Hello, we shall animate you."


def read_glb(path):
    raw = open(path, "rb").read()
    jlen = struct.unpack_from("<I", raw, 12)[0]
    doc = json.loads(raw[20 : 20 + jlen])
    base = 28 + jlen

    def acc(i):
        a = doc["accessors"][i]
        v = doc["bufferViews"][a["bufferView"]]
        dtype = {5126: "<f4", 5123: "<u2", 5125: "<u4"}[a["componentType"]]
        width = {"SCALAR": 1, "VEC3": 3}[a["type"]]
        arr = np.frombuffer(raw, dtype, a["count"] * width, base + v["byteOffset"] + a.get("byteOffset", 0))
        return arr.reshape(a["count"], width) if width > 1 else arr

    return doc, acc


BLENDER_RENDER = r"""
import sys, bpy, mathutils
glb, out, frames = sys.argv[-3], sys.argv[-2], [int(x) for x in sys.argv[-1].split(",")]
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath=glb)
ob = next(o for o in bpy.data.objects if o.type == "MESH")
sc = bpy.context.scene
pts = [ob.matrix_world @ mathutils.Vector(c) for c in ob.bound_box]
cx, cz = sum(p.x for p in pts) / 8, sum(p.z for p in pts) / 8
size = max(max(p.x for p in pts) - min(p.x for p in pts), max(p.z for p in pts) - min(p.z for p in pts))
cam_data = bpy.data.cameras.new("cam")
cam_data.type, cam_data.ortho_scale = "ORTHO", size * 1.15
cam = bpy.data.objects.new("cam", cam_data)
sc.collection.objects.link(cam)
cam.location, cam.rotation_euler = (cx, -1.0, cz), (1.5707963, 0, 0)   # glTF's +z faces Blender's -y
sc.camera = cam
sc.render.engine = "BLENDER_WORKBENCH"
sc.display.shading.light, sc.display.shading.color_type = "FLAT", "MATERIAL"
sc.render.resolution_x, sc.render.resolution_y = 420, 400
for i, f in enumerate(frames):
    sc.frame_set(f)
    sc.render.filepath = f"{out}_{i}.png"
    bpy.ops.render.render(write_still=True)
"""


def blender_frames(python, glb, times, out_dir):
    """Render the .glb at ``times`` (seconds) in Blender; returns the PNG paths."""
    script = os.path.join(out_dir, "blender_render.py")
    with open(script, "w") as fh:
        fh.write(BLENDER_RENDER)
    frames = ",".join(str(int(round(t * 24))) for t in times)  # Blender keys glTF time t at frame 24 t
    prefix = os.path.join(out_dir, "blender")
    subprocess.run([python, script, glb, prefix, frames], check=True, capture_output=True, timeout=600)
    return [f"{prefix}_{i}.png" for i in range(len(times))]


def run(out_dir, blender=None):
    os.makedirs(out_dir, exist_ok=True)
    from dam.speech import PhoneApproximationWarning

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PhoneApproximationWarning)  # English phones on a German model
        result = dam.animate(text=TEXT)
    glb = os.path.join(out_dir, "face.glb")
    rep = export(
        result.trajectories, glb, channels=result.channels, frame_rate=result.frame_rate, alignment=result.alignment
    )
    print(f"wrote {glb}: {rep.n_frames} frames; " + "; ".join(rep.messages()))

    doc, acc = read_glb(glb)
    prim = doc["meshes"][0]["primitives"][0]
    positions = acc(prim["attributes"]["POSITION"])
    targets = np.stack([acc(t["POSITION"]) for t in prim["targets"]])
    tri = acc(prim["indices"]).reshape(-1, 3)
    sampler = doc["animations"][0]["samplers"][0]
    times = acc(sampler["input"])
    weights = acc(sampler["output"]).reshape(len(times), len(targets))

    a = result.alignment
    wanted = ["a", "i:", "u:", "m", "S", "@"]
    picks = []
    for lab, s, e in zip(a.labels, a.starts, a.ends):
        if lab in wanted and lab not in [p[0] for p in picks]:
            picks.append((lab, 0.5 * (s + e)))
    picks = picks[:4]

    from matplotlib.collections import PolyCollection

    from dam import plotting

    plt = plotting.pyplot()
    fig, axes = plt.subplots(1, len(picks), figsize=(3.2 * len(picks), 3.4))
    for ax, (lab, t) in zip(np.atleast_1d(axes), picks):
        f = int(np.argmin(np.abs(times - t)))
        v = positions + np.einsum("k,kvd->vd", weights[f], targets)
        xy = v[:, :2] * 100  # metres -> cm
        ax.add_collection(PolyCollection(xy[tri], facecolor="#c8404f", edgecolor="#c8404f", linewidth=0.3))
        ax.set_xlim(xy[:, 0].min() - 0.5, xy[:, 0].max() + 0.5)
        ax.set_ylim(xy[:, 1].min() - 0.5, xy[:, 1].max() + 0.5)
        ax.set_aspect("equal")
        ax.set_title(f"/{lab}/  t = {times[f]:.2f} s", fontsize=10)
        ax.set_xticks([])
        ax.set_yticks([])
    fig.suptitle(f'"{TEXT}" -> face.glb (frames read back from the file)', fontsize=10)
    fig.tight_layout()
    png = plotting.save(fig, os.path.join(out_dir, "animation_out.png"), dpi=110)
    print(f"wrote {png}")
    if blender:
        shots = blender_frames(blender, glb, [round(t * 24) / 24 for _, t in picks], out_dir)
        fig, axes = plt.subplots(1, len(picks), figsize=(3.2 * len(picks), 3.4))
        for ax, (lab, t), shot in zip(np.atleast_1d(axes), picks, shots):
            ax.imshow(plt.imread(shot))
            ax.set_title(f"/{lab}/  frame {round(t * 24)} (24 fps)", fontsize=10)
            ax.set_axis_off()
        fig.suptitle(f'"{TEXT}": face.glb imported into Blender {blender_version(blender)}, rendered', fontsize=10)
        fig.tight_layout()
        png = plotting.save(fig, os.path.join(out_dir, "animation_out_blender.png"), dpi=110)
        print(f"wrote {png}")


def blender_version(python):
    out = subprocess.run(
        [python, "-c", "import bpy; print(bpy.app.version_string)"], capture_output=True, text=True, timeout=120
    )
    return out.stdout.strip().splitlines()[-1] if out.returncode == 0 else "?"


def main(argv=None) -> int:
    import argparse

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out_dir", nargs="?", help="output directory (same as --out)")
    ap.add_argument(
        "--out",
        default=os.path.join(os.getcwd(), "dam-examples", "animation_out"),
        help="output directory (default: ./dam-examples/animation_out)",
    )
    ap.add_argument("--blender", metavar="PYTHON", help="a Python that imports bpy: also render in Blender")
    ap.add_argument("--quick", action="store_true", help="(the example is quick already)")
    args = ap.parse_args(argv)
    run(args.out_dir or args.out, blender=args.blender)
    return 0


if __name__ == "__main__":
    sys.exit(main())
