"""CSV, JSON and TextGrid exports: round trips through independent readers; presets and maps."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import dam
import dam.datasets
from dam.corpus import Alignment, DataError
from dam.export import export, read_animation
from dam.export.presets import ARKIT_52, OCULUS_15, LinearMap, preset_names
from dam.export.textgrid import chosen_modes


def sample(n_frames=37, n_channels=3, seed=0):
    rng = np.random.default_rng(seed)
    values = rng.normal(size=(n_frames, n_channels)) * 10 ** rng.uniform(-8, 3, size=n_channels)
    return values, [f"ch{j}" for j in range(n_channels)]


@settings(max_examples=30, deadline=None)
@given(
    n_frames=st.integers(1, 60),
    n_channels=st.integers(1, 50),
    seed=st.integers(0, 10**6),
    fr=st.sampled_from([24.0, 30.0, 100.0, 400.9]),
)
def test_csv_and_json_round_trip_exactly(tmp_path_factory, n_frames, n_channels, seed, fr):
    d = tmp_path_factory.mktemp("rt")
    values, channels = sample(n_frames, n_channels, seed)
    export(values, d / "a.csv", channels=channels, frame_rate=fr)
    export(values, d / "a.json", channels=channels, frame_rate=fr)
    # the standard library's readers, not ours
    rows = list(csv.reader(open(d / "a.csv", newline="")))
    assert rows[0] == ["time", *channels]
    table = np.array(rows[1:], dtype=float)
    np.testing.assert_array_equal(table[:, 0], np.arange(n_frames) / fr)
    np.testing.assert_array_equal(table[:, 1:], values)
    doc = json.load(open(d / "a.json"))
    assert doc["frame_rate"] == fr and doc["channels"] == channels and doc["n_frames"] == n_frames
    np.testing.assert_array_equal(np.array(doc["values"]).reshape(n_frames, n_channels), values)
    for ext in ("csv", "json"):
        back = read_animation(d / f"a.{ext}")
        np.testing.assert_array_equal(back.values, values)
        assert back.channels == tuple(channels)
        if n_frames > 1 or ext == "json":
            assert back.frame_rate == pytest.approx(fr, rel=1e-9)


def test_json_keeps_phones_modes_model_and_version(tmp_path):
    values, channels = sample(31)
    a = Alignment(["sil", "h", "a", "sil"], [0, 0.05, 0.12, 0.25], [0.05, 0.12, 0.25, 0.3])
    export(
        values,
        tmp_path / "a.json",
        channels=channels,
        frame_rate=100,
        alignment=a,
        modes=[0, 1, 2, 0],
        metadata={"model": "dam", "speaker": "JD3"},
    )
    doc = json.load(open(tmp_path / "a.json"))
    assert doc["toolkit"] == {"name": "dam", "version": dam.__version__}
    assert doc["model"] == "dam" and doc["metadata"] == {"speaker": "JD3"}
    assert [p["label"] for p in doc["phones"]] == ["sil", "h", "a", "sil"]
    assert [p["mode"] for p in doc["phones"]] == [0, 1, 2, 0]
    back = read_animation(tmp_path / "a.json")
    assert back.alignment == a and back.modes == (0, 1, 2, 0)


def test_textgrid_of_phones_and_chosen_modes_read_by_praatio(tmp_path):
    from praatio import textgrid as ptg

    corpus = dam.datasets.load("tiny")
    model = dam.make("dam").fit(corpus)
    u = corpus[3]
    y = model.predict(u.alignment)
    modes = chosen_modes(model, u.alignment)
    export(
        y,
        tmp_path / "a.TextGrid",
        channels=corpus.channels,
        frame_rate=corpus.frame_rate,
        alignment=u.alignment,
        modes=modes,
    )
    tg = ptg.openTextgrid(str(tmp_path / "a.TextGrid"), includeEmptyIntervals=True)
    assert list(tg.tierNames) == ["phones", "modes"]
    phones = tg.getTier("phones").entries
    assert [e.label for e in phones] == list(u.alignment.labels)
    np.testing.assert_allclose([e.start for e in phones], u.alignment.starts, atol=1e-9)
    np.testing.assert_allclose([e.end for e in phones], u.alignment.ends, atol=1e-9)
    got = [int(e.label) for e in tg.getTier("modes").entries]
    assert got == modes
    # the modes written are the ones that reproduce the model's own prediction
    np.testing.assert_allclose(model.synthesize(u.alignment, modes=got), y, atol=1e-12)
    assert dam.corpus.read_textgrid(tmp_path / "a.TextGrid") == u.alignment
    assert chosen_modes(dam.make("phone-mean").fit(corpus), u.alignment) is None


def test_bad_input_names_file_field_and_value(tmp_path):
    values, channels = sample(10, 2)
    with pytest.raises(DataError, match=r"a\.xyz.*extension"):
        export(values, tmp_path / "a.xyz", channels=channels, frame_rate=100)
    with pytest.raises(DataError, match="3 channel names"):
        export(values, tmp_path / "a.csv", channels=["a", "b", "c"], frame_rate=100)
    with pytest.raises(DataError, match="duplicate"):
        export(values, tmp_path / "a.csv", channels=["a", "a"], frame_rate=100)
    with pytest.raises(DataError, match="frame_rate"):
        export(values, tmp_path / "a.json", channels=channels, frame_rate=0)
    bad = values.copy()
    bad[4, 1] = np.inf
    with pytest.raises(DataError, match=r"trajectories\[4, 'ch1'\].*not finite"):
        export(bad, tmp_path / "a.json", channels=channels, frame_rate=100)
    with pytest.raises(DataError, match="covers"):
        export(values, tmp_path / "a.json", channels=channels, frame_rate=100, alignment=Alignment(["a"], [0], [1.0]))
    with pytest.raises(DataError, match="one mode per segment"):
        export(
            values,
            tmp_path / "a.json",
            channels=channels,
            frame_rate=100,
            alignment=Alignment(["a"], [0], [0.095]),
            modes=[0, 1],
        )
    with pytest.raises(DataError, match="needs the phones"):
        export(values, tmp_path / "a.TextGrid", channels=channels, frame_rate=100)
    with pytest.raises(DataError, match="not an option of the csv"):
        export(values, tmp_path / "a.csv", channels=channels, frame_rate=100, rig="x.glb")
    with pytest.raises(DataError, match="directory"):
        export(values, tmp_path / "nope" / "a.csv", channels=channels, frame_rate=100)
    assert list(tmp_path.iterdir()) == []
    (tmp_path / "x.json").write_text('{"format": "something-else"}')
    with pytest.raises(DataError, match="x.json.*format"):
        read_animation(tmp_path / "x.json")


# -- presets and linear maps ---------------------------------------------------------------------
def test_presets_have_the_standard_names():
    assert len(ARKIT_52) == len(set(ARKIT_52)) == 52
    assert len(OCULUS_15) == len(set(OCULUS_15)) == 15
    # every ARKit location but the four singles comes as a Left/Right pair
    sides = [n for n in ARKIT_52 if n.endswith(("Left", "Right"))]
    assert {n[:-4] for n in sides if n.endswith("Left")} == {n[:-5] for n in sides if n.endswith("Right")}
    assert set(ARKIT_52) - set(sides) >= {
        "jawOpen",
        "jawForward",
        "mouthClose",
        "mouthFunnel",
        "mouthPucker",
        "cheekPuff",
        "tongueOut",
        "browInnerUp",
    }
    assert preset_names("Oculus")[0] == "viseme_sil" and preset_names("oculus")[10] == "viseme_aa"
    with pytest.raises(DataError, match="unknown preset"):
        preset_names("metahuman")


def test_linear_map_fit_recovers_a_known_map_and_round_trips(tmp_path):
    rng = np.random.default_rng(2)
    X = rng.normal(size=(200, 4))
    M = rng.normal(size=(4, 3))
    b = rng.normal(size=3)
    targets = ["jawOpen", "mouthPucker", "mouthClose"]
    m = LinearMap.fit(X, X @ M + b, ["a", "b", "c", "d"], targets, ridge=0.0, preset="arkit")
    np.testing.assert_allclose(m.matrix, M, atol=1e-10)
    np.testing.assert_allclose(m.offset, b, atol=1e-10)
    m.save(tmp_path / "map.json")
    back = LinearMap.load(tmp_path / "map.json")
    np.testing.assert_array_equal(back.apply(X, ["d", "c", "b", "a"]), m.apply(X, ["d", "c", "b", "a"]))
    (tmp_path / "sparse.json").write_text(json.dumps({"preset": "oculus", "matrix": {"jaw": {"viseme_aa": 2.0}}}))
    sparse = LinearMap.load(tmp_path / "sparse.json")
    assert sparse.targets == OCULUS_15
    np.testing.assert_array_equal(
        sparse.apply(np.array([[0.25]]), ["jaw"])[0], [0.5 if t == "viseme_aa" else 0 for t in OCULUS_15]
    )
    with pytest.raises(DataError, match="not names of the arkit preset"):
        LinearMap(["a"], ["jawOpen", "jaw_open"], np.zeros((1, 2)), preset="arkit")
    with pytest.raises(DataError, match="no such channels"):
        m.apply(X, ["a", "b", "c", "e"])


def test_hand_made_toy_map_drives_an_arkit_named_rig(tmp_path):
    """The toy gestures, mapped to ARKit names, animate a rig with ARKit-named targets."""
    from dam.crossmap.outlines import TOY_CONTROLS

    m = LinearMap.hand_made("toy", "arkit")
    assert m.targets == ARKIT_52
    values = np.zeros((5, len(TOY_CONTROLS)))
    values[:, list(TOY_CONTROLS).index("jaw_open")] = np.linspace(0, 1, 5)
    w = m.apply(values, list(TOY_CONTROLS))
    np.testing.assert_allclose(w[:, ARKIT_52.index("jawOpen")], np.linspace(0, 1, 5))
    assert np.all(w[:, ARKIT_52.index("eyeBlinkLeft")] == 0)


def test_fitted_vtl_viseme_map_finds_the_spoken_viseme_on_held_out_speech():
    """Tract parameters -> Oculus visemes, fitted on one part of vtl, tested on another."""
    from dam.corpus import frame_labels
    from dam.export.presets import OCULUS_TO_ARKIT, SAMPA_TO_OCULUS

    vtl = dam.datasets.load("vtl")
    m = LinearMap.from_phones(vtl[:120], SAMPA_TO_OCULUS, "oculus")
    names = [t.removeprefix("viseme_") for t in OCULUS_15]
    hits = total = 0
    for u in vtl[150:]:
        labels = frame_labels(u.alignment, u.frame_rate, u.n_frames)
        truth = np.array([names.index(SAMPA_TO_OCULUS[lab]) for lab in labels])
        hits += int((m.apply(u.trajectory, vtl.channels).argmax(axis=1) == truth).sum())
        total += len(truth)
    assert hits / total > 0.4  # chance: 1/15; the frames at phone edges are legitimately mixed
    # the ARKit map is that map followed by the viseme table, in closed form
    arkit = LinearMap.vtl("arkit")
    oculus = LinearMap.vtl("oculus")
    x = vtl[150].trajectory[:20]
    v = oculus.apply(x, vtl.channels)
    expect = np.zeros((len(x), len(ARKIT_52)))
    for j, name in enumerate(names):
        for t, g in OCULUS_TO_ARKIT.get(name, {}).items():
            expect[:, ARKIT_52.index(t)] += g * v[:, j]
    np.testing.assert_allclose(arkit.apply(x, vtl.channels), expect, atol=1e-12)
    with pytest.raises(DataError, match="without a viseme"):
        LinearMap.from_phones(vtl[:3], {"sil": "sil"})
