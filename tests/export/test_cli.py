"""`dam predict` and `dam animate` write animation files by extension; `--stream`; `dam export-runtime`."""

from __future__ import annotations

import io
import json

import numpy as np
import pytest

import dam
import dam.datasets
from dam.cli import main
from dam.corpus import write_textgrid
from dam.export import read_animation


@pytest.fixture(scope="module")
def fitted(tmp_path_factory):
    d = tmp_path_factory.mktemp("cli")
    corpus = dam.datasets.load("tiny")
    model = dam.make("dam").fit(corpus)
    model.save(d / "m.npz")
    u = corpus[2]
    write_textgrid(u.alignment, d / "u.TextGrid")
    return d, model, u


def test_predict_writes_every_format_by_extension(fitted, validate, capsys):
    d, model, u = fitted
    ref = model.predict(u.alignment)
    for ext in ("csv", "json", "glb", "gltf", "TextGrid"):
        assert main(["predict", str(d / "m.npz"), str(d / "u.TextGrid"), "-o", str(d / f"p.{ext}")]) == 0
    for ext in ("csv", "json"):
        np.testing.assert_allclose(read_animation(d / f"p.{ext}").values, ref, atol=1e-12)
    doc = json.load(open(d / "p.json"))
    assert doc["model"] == "dam"
    glob = model.select_modes(u.alignment)[0]
    assert [p["mode"] for p in doc["phones"]] == [
        int(g - model.phone_modes_[lab][0]) for g, lab in zip(glob, u.alignment.labels)
    ]
    reports = validate([d / "p.glb", d / "p.gltf"])
    assert all(r["issues"]["numErrors"] == 0 for r in reports.values())
    err = capsys.readouterr().err
    assert "clipped" in err or "mesh" in err
    # stdout stays CSV
    assert main(["predict", str(d / "m.npz"), str(d / "u.TextGrid")]) == 0
    out = capsys.readouterr().out
    table = np.loadtxt(io.StringIO(out), delimiter=",", skiprows=1)
    np.testing.assert_allclose(table[:, 1:], ref, atol=1e-5)


def test_predict_usage_and_data_errors(fitted, capsys):
    d, _, _ = fitted
    with pytest.raises(SystemExit) as exc:
        main(["predict", str(d / "m.npz"), str(d / "u.TextGrid"), "-o", str(d / "x.csv"), "--rig", "r.glb"])
    assert exc.value.code == 2
    assert main(["predict", str(d / "m.npz"), str(d / "u.TextGrid"), "-o", str(d / "x.fbx")]) == 1
    err = capsys.readouterr().err
    assert err.strip().splitlines()[-1].startswith("dam: error:") and "x.fbx" in err
    assert (
        main(
            [
                "predict",
                str(d / "m.npz"),
                str(d / "u.TextGrid"),
                "-o",
                str(d / "x.glb"),
                "--rig",
                str(d / "missing.glb"),
            ]
        )
        == 1
    )
    assert "missing.glb" in capsys.readouterr().err


def test_predict_through_a_linear_map_onto_an_arkit_rig(fitted, tmp_path, validate, hand_rig):
    d, model, u = fitted
    rig = hand_rig(tmp_path)
    (tmp_path / "map.json").write_text(
        json.dumps(
            {
                "preset": "arkit",
                "targets": ["jawOpen", "mouthPucker"],
                "matrix": {"jaw_open": {"jawOpen": 2.0}, "lip_protrusion": {"mouthPucker": 1.0}},
            }
        )
    )
    out = tmp_path / "face.glb"
    assert (
        main(
            [
                "predict",
                str(d / "m.npz"),
                str(d / "u.TextGrid"),
                "-o",
                str(out),
                "--map",
                str(tmp_path / "map.json"),
                "--rig",
                str(rig),
                "--weights",
                "scale",
            ]
        )
        == 0
    )
    reports = validate([out])
    assert reports[str(out)]["issues"]["numErrors"] == 0
    y = model.predict(u.alignment)
    jaw = 2.0 * y[:, model.channels_.index("jaw_open")]
    raw = open(out, "rb").read()
    import struct

    jlen = struct.unpack_from("<I", raw, 12)[0]
    doc = json.loads(raw[20 : 20 + jlen])
    anim = doc["animations"][-1]
    assert anim["name"] == "dam" and anim["extras"]["channels"] == ["jawOpen", "mouthPucker"]
    face = next(ch for ch in anim["channels"] if doc["nodes"][ch["target"]["node"]]["name"] == "face")
    acc = doc["accessors"][anim["samplers"][face["sampler"]]["output"]]
    view = doc["bufferViews"][acc["bufferView"]]
    W = np.frombuffer(raw, "<f4", acc["count"], 28 + jlen + view["byteOffset"]).reshape(len(y), 3)
    lo, hi = min(0.0, jaw.min()), max(1.0, jaw.max())
    np.testing.assert_allclose(W[:, 0], (jaw - lo) / (hi - lo), atol=1e-6)


def test_animate_stream_equals_the_batch_file(tmp_path, capsys):
    out = tmp_path / "hw.csv"
    assert main(["animate", "--text", "Hello world.", "-o", str(out)]) == 0
    capsys.readouterr()
    assert main(["animate", "--text", "Hello world.", "--stream"]) == 0
    streamed = capsys.readouterr().out
    a = np.loadtxt(io.StringIO(streamed), delimiter=",", skiprows=1)
    b = read_animation(out)
    assert streamed.splitlines()[0].split(",") == ["time", *b.channels]
    np.testing.assert_allclose(a[:, 1:], b.values, atol=1e-9)
    np.testing.assert_allclose(a[:, 0], np.arange(len(a)) / b.frame_rate, atol=1e-12)


def test_export_runtime_command(fitted, tmp_path, capsys):
    d, model, u = fitted
    assert main(["export-runtime", str(d / "m.npz"), "-o", str(tmp_path / "face.json")]) == 0
    assert (tmp_path / "dam_runtime.py").exists()
    import importlib.util

    spec = importlib.util.spec_from_file_location("dam_runtime_cli", tmp_path / "dam_runtime.py")
    rt_mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(rt_mod)
    rt = rt_mod.load(tmp_path / "face.json")
    a = u.alignment
    np.testing.assert_allclose(rt.synthesize(a.labels, a.ends, a.starts), model.predict(a), atol=1e-9)
    with pytest.raises(SystemExit) as exc:
        main(["export-runtime", str(d / "m.npz"), "-o", str(tmp_path / "face.bin")])
    assert exc.value.code == 2


def test_animate_text_onto_an_arkit_rig_through_the_fitted_vtl_map(tmp_path, validate, hand_rig):
    """dam animate (default VTL model) -> vtl:arkit map -> a rig carrying all 52 ARKit names."""
    from dam.export.presets import ARKIT_52, LinearMap

    rig = hand_rig(tmp_path, ARKIT_52)
    out = tmp_path / "face.glb"
    assert main(["animate", "--text", "Hello world.", "-o", str(tmp_path / "ref.csv")]) == 0
    assert main(["animate", "--text", "Hello world.", "--map", "vtl:arkit", "--rig", str(rig), "-o", str(out)]) == 0
    assert validate([out])[str(out)]["issues"]["numErrors"] == 0
    ref = read_animation(tmp_path / "ref.csv")
    m = LinearMap.vtl("arkit")
    expect = np.clip(m.apply(ref.values, ref.channels), 0, 1)
    raw = open(out, "rb").read()
    import struct

    jlen = struct.unpack_from("<I", raw, 12)[0]
    doc = json.loads(raw[20 : 20 + jlen])
    anim = doc["animations"][-1]
    face = next(ch for ch in anim["channels"] if doc["nodes"][ch["target"]["node"]]["name"] == "face")
    names = doc["meshes"][0]["extras"]["targetNames"]
    acc = doc["accessors"][anim["samplers"][face["sampler"]]["output"]]
    view = doc["bufferViews"][acc["bufferView"]]
    W = np.frombuffer(raw, "<f4", acc["count"], 28 + jlen + view["byteOffset"]).reshape(len(ref.values), len(names))
    for t in ("jawOpen", "mouthPucker", "mouthFunnel", "mouthClose"):
        np.testing.assert_allclose(W[:, names.index(t)], expect[:, ARKIT_52.index(t)], atol=1e-6)
    assert np.all(W[:, names.index("eyeBlinkLeft")] == 0)  # never moved by the map: rest weight
    assert W[:, names.index("jawOpen")].max() > 0.2  # the mouth opens
