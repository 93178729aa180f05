"""The tiny runtime: run in a subprocess where dam cannot be imported; output equals the toolkit's."""

from __future__ import annotations

import ast
import json
import os
import subprocess
import sys

import numpy as np
import pytest

import dam
import dam.datasets
from dam.corpus import Alignment, DataError
from dam.export.runtime import copy_runtime, export_runtime, runtime_source

NUMPY_HOME = os.path.dirname(os.path.dirname(np.__file__))

# Run with -S (no site: neither dam's editable install nor any .pth) and only numpy's folder on the path.
PLAYER = r"""
import json, sys
sys.path.append(sys.argv[1])
try:
    import dam
except ImportError:
    pass
else:
    raise SystemExit("dam is importable in the runtime's process")
import numpy as np
import dam_runtime
assert "dam" not in sys.modules
jobs = json.load(open(sys.argv[2]))
out = {}
for name, model_path in jobs["models"].items():
    rt = dam_runtime.load(model_path)
    for k, a in enumerate(jobs["alignments"]):
        y = rt.synthesize(a["labels"], a["ends"], a["starts"])
        out[f"{name}/{k}"] = y
        if rt.kind.startswith("dam"):
            out[f"{name}/{k}/modes"] = rt.modes(a["labels"], a["ends"], a["starts"])
np.savez(sys.argv[3], **out)
"""


def random_alignments(phones, n, rng):
    out = []
    for _ in range(n):
        k = int(rng.integers(1, 30))
        d = rng.uniform(0.02, 0.3, size=k)
        ends = np.cumsum(d)
        out.append(Alignment(list(rng.choice(sorted(phones), size=k)), ends - d, ends))
    return out


def play(tmp_path, models: dict, alignments):
    """Export each model, run the copied runtime in a dam-free Python, return its outputs."""
    work = tmp_path / "app"
    work.mkdir()
    copy_runtime(work)
    paths = {}
    for name, m in models.items():
        for ext in (".json", ".npz"):
            paths[name + ext] = str(work / f"{name}{ext}")
            export_runtime(m, paths[name + ext])
    jobs = {
        "models": paths,
        "alignments": [
            {"labels": list(a.labels), "starts": a.starts.tolist(), "ends": a.ends.tolist()} for a in alignments
        ],
    }
    (work / "jobs.json").write_text(json.dumps(jobs))
    (work / "player.py").write_text(PLAYER)
    # numpy alone on the path: links to its package (and its bundled libraries), not to the
    # site-packages folder where an installed dam also lives
    numpy_only = tmp_path / "numpy-only"
    numpy_only.mkdir()
    for name in os.listdir(NUMPY_HOME):
        if name == "numpy" or name.startswith("numpy.libs") or name.startswith("numpy-"):
            os.symlink(os.path.join(NUMPY_HOME, name), numpy_only / name)
    proc = subprocess.run(
        [
            sys.executable,
            "-S",
            str(work / "player.py"),
            str(numpy_only),
            str(work / "jobs.json"),
            str(work / "out.npz"),
        ],
        cwd=work,
        capture_output=True,
        text=True,
        timeout=600,
        env={k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")},
    )
    assert proc.returncode == 0, proc.stderr[-3000:] + proc.stdout[-1000:]
    with np.load(work / "out.npz") as z:
        return {k: z[k] for k in z.files}


@pytest.fixture(scope="module")
def tiny_models():
    tiny = dam.datasets.load("tiny")
    return tiny, {
        "dam": dam.make("dam").fit(tiny),
        "dam-m0": dam.make("dam-m0").fit(tiny),
        "dam-plain-hold": dam.make("dam", normalize=False, extrapolate="hold", degree=2).fit(tiny),
        "cohen-massaro": dam.make("cohen-massaro").fit(tiny),
        "phone-mean": dam.make("phone-mean").fit(tiny),
    }


DAMS = ("dam", "dam-m0", "dam-plain-hold")


def test_runtime_equals_toolkit_on_tiny_without_dam(tmp_path, tiny_models):
    tiny, models = tiny_models
    rng = np.random.default_rng(0)
    aligns = list(tiny.alignments[:5]) + random_alignments(models["dam"].phone_modes_, 25, rng)
    out = play(tmp_path, models, aligns)
    for name, m in models.items():
        for ext in (".json", ".npz"):
            for k, a in enumerate(aligns):
                np.testing.assert_allclose(
                    out[f"{name}{ext}/{k}"], m.predict(a), atol=1e-9, rtol=0, err_msg=f"{name}{ext} alignment {k}"
                )
                if name in DAMS:
                    np.testing.assert_array_equal(out[f"{name}{ext}/{k}/modes"], m.select_modes(a)[0])


def test_runtime_equals_toolkit_on_vtl(tmp_path):
    vtl = dam.datasets.load("vtl")
    m = dam.make("dam").fit(vtl[:12])
    rng = np.random.default_rng(1)
    held = [u.alignment for u in vtl[150:] if u.alignment.phones <= set(m.phone_modes_)][:5]
    assert len(held) == 5
    aligns = held + random_alignments(m.phone_modes_, 10, rng)
    out = play(tmp_path, {"vtl": m}, aligns)
    for ext in (".json", ".npz"):
        for k, a in enumerate(aligns):
            np.testing.assert_allclose(out[f"vtl{ext}/{k}"], m.predict(a), atol=1e-9, rtol=0)


def test_runtime_is_one_small_numpy_only_module():
    src = open(runtime_source(), encoding="utf-8").read()
    assert len(src.splitlines()) <= 300
    imported = set()
    for node in ast.walk(ast.parse(src)):
        if isinstance(node, ast.Import):
            imported.update(a.name.split(".")[0] for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            imported.add((node.module or "").split(".")[0])
    assert imported <= {"json", "math", "numpy"}, imported


def test_runtime_gaps_silence_and_unknown_phones(tmp_path, tiny_models):
    """A gap is silence and adjacent silences merge, as in dam.Alignment; unseen phones are refused."""
    _, models = tiny_models
    m = models["dam"]
    export_runtime(m, tmp_path / "m.json")
    sys.path.insert(0, os.path.dirname(runtime_source()))
    try:
        import dam_runtime
    finally:
        sys.path.pop(0)
    rt = dam_runtime.load(tmp_path / "m.json")
    # a gap becomes silence and "sp" is silence, as in the toolkit's Alignment
    a = Alignment(["aa", "sp", "m"], [0.05, 0.2, 0.3], [0.2, 0.3, 0.42])
    np.testing.assert_allclose(
        rt.synthesize(["aa", "sp", "m"], [0.2, 0.3, 0.42], [0.05, 0.2, 0.3]), m.predict(a), atol=1e-9
    )
    # adjacent silences (and a gap next to one) are one pause
    a = Alignment(["sil", "pau", "aa", "sil", "m"], [0, 0.1, 0.2, 0.3, 0.45], [0.1, 0.2, 0.3, 0.4, 0.6])
    assert len(a) == 4
    np.testing.assert_allclose(
        rt.synthesize(["sil", "pau", "aa", "sil", "m"], [0.1, 0.2, 0.3, 0.4, 0.6], [0, 0.1, 0.2, 0.3, 0.45]),
        m.predict(a),
        atol=1e-9,
    )
    with pytest.raises(KeyError, match="zz"):
        rt.synthesize(["aa", "zz"], [0.1, 0.2])
    with pytest.raises(ValueError, match="dam-runtime"):
        (tmp_path / "x.json").write_text('{"format": "other"}')
        dam_runtime.load(tmp_path / "x.json")


def test_export_runtime_refuses_what_it_cannot_play(tmp_path, tiny_models):
    tiny, models = tiny_models
    with pytest.raises(DataError, match="tiny runtime"):
        export_runtime(dam.make("target-interpolation").fit(tiny), tmp_path / "p.json")
    with pytest.raises(DataError, match="extension"):
        export_runtime(models["dam"], tmp_path / "p.pkl")
    assert not any(tmp_path.iterdir())
    with pytest.raises(dam.NotFittedError):
        export_runtime(dam.make("dam"), tmp_path / "p.json")
