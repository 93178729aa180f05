"""Sensors (x/y(/z) channel groups) and Medina et al.'s (2022) Eq. 1 in evaluate, `dam evaluate` and `dam compare`."""

import json

import numpy as np
import pytest

from dam import make
from dam.cli import main
from dam.corpus import Alignment, Corpus, DataError, Utterance, load_corpus
from dam.corpus.data import infer_sensors, resolve_sensors
from dam.corpus.formats.tables import write_csv
from dam.corpus.formats.textgrid import write_textgrid
from dam.evaluation.compare import compare
from dam.evaluation.metrics import evaluate, medina_error, sensor_distances


def test_sensor_names_of_the_corpora_read():
    assert infer_sensors(["ui_x", "ui_y", "tt_x", "tt_y", "v_x"]) == {"ui": ("ui_x", "ui_y"), "tt": ("tt_x", "tt_y")}
    assert infer_sensors(["TT_px", "TT_py", "TT_pz", "TT_ox", "TT_oy", "TT_oz"]) == {"TT": ("TT_px", "TT_py", "TT_pz")}
    assert infer_sensors(["T1_py", "T1_pz"]) == {"T1": ("T1_py", "T1_pz")}
    assert infer_sensors(["MNI_x", "MNI_y"]) == {"MNI": ("MNI_x", "MNI_y")}
    assert infer_sensors(["HX", "HY", "JX", "JA", "TTX", "TTY", "TS1"]) == {"H": ("HX", "HY"), "TT": ("TTX", "TTY")}
    assert infer_sensors(["a_x", "a_px", "b_y", "b_x"]) == {"b": ("b_x", "b_y")}  # two x's: no sensor
    assert infer_sensors(["jaw_open", "lip_aperture"]) == {}


def test_given_sensors_are_checked():
    ch = ["a", "b", "c", "d"]
    assert resolve_sensors(ch, {"S": ["a", "b"], "T": ["c", "d"]}) == {"S": ("a", "b"), "T": ("c", "d")}
    with pytest.raises(DataError, match=r"corpus.json: field \"sensors\['S'\]\": not a channel.*'q'"):
        resolve_sensors(ch, {"S": ["a", "q"]}, source="corpus.json")
    with pytest.raises(DataError, match="already a channel of sensor 'S'"):
        resolve_sensors(ch, {"S": ["a", "b"], "T": ["b", "c"]})
    with pytest.raises(DataError, match="2 or 3 channels"):
        resolve_sensors(ch, {"S": ["a"]})


def test_medina_eq1_closed_form():
    # prediction = truth + a fixed offset per sensor: the distance is the offset's length at every frame
    rng = np.random.default_rng(0)
    y = rng.normal(size=(30, 5))
    offsets = {(0, 1): (3.0, 4.0), (2, 3, 4): (1.0, 2.0, 2.0)}  # lengths 5 and 3
    p = y.copy()
    for cols, off in offsets.items():
        p[:, list(cols)] += off
    d, valid = sensor_distances(y, p, list(offsets))
    np.testing.assert_allclose(d, np.tile([5.0, 3.0], (30, 1)))
    assert valid.all()
    assert medina_error(y, p, list(offsets)) == pytest.approx(4.0)
    # a frame where one coordinate of a sensor is missing does not count for that sensor
    m = np.ones_like(y, bool)
    m[:10, 0] = False
    p[:10, 0] += 100.0
    assert medina_error(y, p, list(offsets), m) == pytest.approx((20 * 5 + 30 * 3) / 50)


def two_utterance_corpus(offsets, lengths=(40, 120), metadata=None):
    utts, preds = [], []
    for k, (n, off) in enumerate(zip(lengths, offsets)):
        t = np.arange(n) / 100.0
        y = np.column_stack([np.sin(3 * t + k), np.cos(2 * t), 0.5 * t, np.sin(5 * t)])
        a = Alignment(["sil", "a", "sil"], [0, 0.1, n / 100 - 0.1], [0.1, n / 100 - 0.1, n / 100])
        utts.append(Utterance(a, y, 100.0, ["tt_x", "tt_y", "jaw", "ll_y"], name=f"u{k}"))
        preds.append(y + np.array([off[0], off[1], 7.0, 0.0]))
    return Corpus(utts, metadata=metadata), preds


def test_evaluate_reports_eq1_per_sensor_and_overall():
    corpus, preds = two_utterance_corpus([(0.3, 0.4), (0.6, 0.8)], metadata={"length_unit": "mm"})
    ev = evaluate(None, corpus, predictions=preds)
    assert ev.sensors == {"tt": ("tt_x", "tt_y")}  # jaw and ll_y alone are no sensor
    assert [r["sensor_error"] for r in ev.per_utterance] == pytest.approx([0.5, 1.0])
    # overall: the mean of the per-utterance errors (the paper's mean sample error), not frame-weighted
    assert ev.sensor_error == pytest.approx(0.75)
    # per sensor: all frames pooled
    assert ev.sensor_error_per_sensor[0] == pytest.approx((40 * 0.5 + 120 * 1.0) / 160)
    assert "mm" in ev.table() and "Medina" in ev.table()
    given = Corpus(corpus.utterances, metadata={"sensors": {"front": ["tt_x", "ll_y"]}})
    ev2 = evaluate(None, given, predictions=preds)
    assert list(ev2.sensors) == ["front"] and ev2.sensor_error == pytest.approx(np.mean([0.3, 0.6]))


def write_dir(root, corpus, sensors=None):
    root.mkdir()
    meta = {"frame_rate": corpus.frame_rate, "length_unit": "mm"}
    if sensors:
        meta["sensors"] = sensors
    (root / "corpus.json").write_text(json.dumps(meta))
    for u in corpus:
        write_textgrid(u.alignment, root / f"{u.name}.TextGrid")
        write_csv(u.trajectory, u.channels, root / f"{u.name}.csv", decimals=None)


def test_dam_evaluate_and_compare_report_the_sensor_error(tmp_path, capsys):
    corpus, _ = two_utterance_corpus([(0, 0), (0, 0)], lengths=(60, 90))
    corpus = Corpus([u.replace(name=f"u{k}") for k, u in enumerate(corpus.utterances * 3)])
    d = tmp_path / "ema"
    write_dir(d, corpus)
    loaded = load_corpus(d)
    model = make("phone-mean").fit(loaded)
    model.save(tmp_path / "m.dam")
    assert main(["evaluate", str(tmp_path / "m.dam"), str(d), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    ev = evaluate(model, loaded)
    assert out["sensors"]["tt"]["channels"] == ["tt_x", "tt_y"]
    assert out["sensors"]["tt"]["distance"] == pytest.approx(float(ev.sensor_error_per_sensor[0]))
    assert out["sensor_error"] == pytest.approx(ev.sensor_error) and out["length_unit"] == "mm"
    assert main(["evaluate", str(tmp_path / "m.dam"), str(d)]) == 0
    assert "Medina" in capsys.readouterr().out

    res = compare(["phone-mean", "target-interpolation"], loaded, cv=2, verbose=0, out=tmp_path / "out")
    for row in res.summary:
        assert np.isfinite(row["sensor_error"]) and row["sensor_error"] > 0
    assert {r["sensor"] for r in res.per_sensor} == {"tt"}
    assert (tmp_path / "out" / "per_sensor.csv").exists()
    assert "Sensor error (mm)" in res.table()
    assert main(["-q", "compare", "--models", "phone-mean", "--train", str(d), "--cv", "2"]) == 0
    assert "Medina" in capsys.readouterr().out


def test_corpus_json_sensors_are_checked_where_they_enter(tmp_path):
    corpus, _ = two_utterance_corpus([(0, 0), (0, 0)])
    write_dir(tmp_path / "c", corpus, sensors={"tt": ["tt_x", "tt_q"]})
    with pytest.raises(DataError, match=r"corpus.json: field \"sensors\['tt'\]\".*'tt_q'"):
        load_corpus(tmp_path / "c")
    write_dir(tmp_path / "d", corpus, sensors={"lips": ["jaw", "ll_y"]})
    c = load_corpus(tmp_path / "d")
    assert c.sensors == {"lips": ("jaw", "ll_y")}
    assert c.select_channels(["jaw", "tt_x"]).sensors == {}
