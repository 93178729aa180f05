"""The Synthesizer interface, the model file format and the reference synthesizers."""
import json
import subprocess
import sys
import zipfile

import numpy as np
import pytest

import dam
from baselines.reference import PhoneMean, TargetInterpolation, hermite_catmull_rom
from dam import Alignment, Corpus, ModelFileError, Utterance


@pytest.fixture(scope="module")
def split():
    return dam.datasets.load("tiny").train_test_split(0.25, random_state=0)


def test_import_dam_is_light():
    code = ("import sys, dam; bad = [m for m in ('scipy', 'sklearn', 'matplotlib', 'jax', 'praatio') "
            "if m in sys.modules]; print(','.join(bad))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert out == ""


def test_phone_mean_is_the_mean_of_each_phone():
    a = Alignment(["a", "b", "a"], [0, 0.03, 0.05], [0.03, 0.05, 0.08])
    y = np.arange(8, dtype=float)[:, None]  # frames 0-2 a, 3-4 b, 5-7 a
    m = PhoneMean().fit(Corpus([Utterance(a, y, 100, ["x"])]))
    np.testing.assert_allclose(m.predict(a)[:, 0], [(0 + 1 + 2 + 5 + 6 + 7) / 6] * 3 + [3.5] * 2 + [3.5] * 3)


def test_target_interpolation_passes_through_midpoint_targets():
    kt = np.array([0.05, 0.2, 0.3])
    ky = np.array([[0.0], [1.0], [-1.0]])
    t = np.array([0.0, 0.05, 0.2, 0.3, 0.4])
    np.testing.assert_allclose(hermite_catmull_rom(kt, ky, t)[:, 0], [0, 0, 1, -1, -1])
    # a linear key sequence is reproduced exactly between keys
    kt = np.array([0.0, 0.1, 0.3, 0.4])
    y = hermite_catmull_rom(kt, 2 * kt[:, None], np.linspace(0.1, 0.3, 7))
    np.testing.assert_allclose(y[:, 0], 2 * np.linspace(0.1, 0.3, 7))


def test_save_format_is_npz_with_json_and_no_pickle(tmp_path, split):
    m = TargetInterpolation().fit(split[0])
    m.save(tmp_path / "m.dam")
    with zipfile.ZipFile(tmp_path / "m.dam") as z:
        names = z.namelist()
    assert "__dam__.npy" in names
    with np.load(tmp_path / "m.dam", allow_pickle=False) as f:
        meta = json.loads(bytes(f["__dam__"]).decode())
    assert meta["format"] == "dam-model" and meta["version"] == 1 and meta["model"] == "target-interpolation"


def test_corrupt_and_foreign_model_files_are_refused(tmp_path, split):
    bad = tmp_path / "bad.dam"
    bad.write_bytes(b"hello")
    with pytest.raises(ModelFileError, match="bad.dam: not a dam model file"):
        dam.load(bad)
    np.savez(tmp_path / "foreign.npz", x=np.zeros(3))
    with pytest.raises(ModelFileError, match="field '__dam__' missing"):
        dam.load(tmp_path / "foreign.npz")
    m = PhoneMean().fit(split[0])
    m.save(tmp_path / "m.dam")
    raw = (tmp_path / "m.dam").read_bytes()
    (tmp_path / "trunc.dam").write_bytes(raw[: len(raw) // 2])
    with pytest.raises(ModelFileError, match="trunc.dam"):
        dam.load(tmp_path / "trunc.dam")
    with np.load(tmp_path / "m.dam") as f:
        arrays = dict(f)
    meta = json.loads(bytes(arrays["__dam__"]).decode())
    meta["version"] = 99
    arrays["__dam__"] = np.frombuffer(json.dumps(meta).encode(), dtype=np.uint8)
    np.savez(tmp_path / "future.dam.npz", **arrays)
    with pytest.raises(ModelFileError, match="field 'version' is 99"):
        dam.load(tmp_path / "future.dam.npz")


def test_saved_reference_model_predicts_with_numpy_alone(tmp_path, split):
    m = TargetInterpolation().fit(split[0])
    m.save(tmp_path / "m.dam")
    code = (f"import sys, dam, numpy as np; m = dam.load({str(tmp_path / 'm.dam')!r});"
            "a = dam.Alignment(['sil', 'p', 'aa'], [0, .1, .2], [.1, .2, .4]); y = m.predict(a);"
            "print(y.shape, [k for k in ('scipy', 'sklearn') if k in sys.modules])")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "(40, 4) []"


def test_fallback_chain_for_unseen_phones(split):
    m = PhoneMean(unknown_phone="fallback").fit(split[0])
    a = Alignment(["sil", "b", "AA1", "zz"], [0, 0.1, 0.2, 0.3], [0.1, 0.2, 0.3, 0.4])
    labels = m._known_labels(a, "fallback")
    assert labels[0] == "sil"
    assert labels[1] == "b"  # seen
    assert labels[2] == "aa"  # stress and case dropped
    assert labels[3] == "sil"  # no class: silence
    with pytest.raises(dam.UnknownPhoneError, match="segment 2 label.*'AA1'"):
        m._known_labels(a, "error")


def test_get_set_params_and_repr():
    m = PhoneMean()
    assert m.get_params() == {"unknown_phone": "error"}
    assert repr(m.set_params(unknown_phone="fallback")) == "PhoneMean(unknown_phone='fallback')"
    with pytest.raises(ValueError, match="unknown parameter 'degree'"):
        m.set_params(degree=3)
    with pytest.raises(ValueError, match="unknown_phone"):
        PhoneMean(unknown_phone="maybe").fit(dam.datasets.load("tiny"))


def test_evaluate_matches_hand_computation(split):
    train, test = split
    m = PhoneMean().fit(train)
    ev = dam.evaluate(m, test)
    Y = np.concatenate(test.trajectories)
    P = np.concatenate(m.predict(test.alignments))
    assert ev.rmse == pytest.approx(np.sqrt(np.mean((Y - P) ** 2)))
    for c in range(Y.shape[1]):
        assert ev.pearson_per_channel[c] == pytest.approx(np.corrcoef(Y[:, c], P[:, c])[0, 1])
    assert len(ev.per_utterance) == len(test)


def test_failed_fit_leaves_an_unfitted_model(split):
    train, test = split

    class Fails(PhoneMean):
        def _fit(self, corpus):
            super()._fit(corpus)
            if getattr(self, "fail", False):
                raise FloatingPointError("diverged")

    m = Fails().fit(train)
    m.fail = True
    with pytest.raises(FloatingPointError):
        m.fit(train)
    assert not m.is_fitted() and not [k for k in vars(m) if k.endswith("_")]
    with pytest.raises(dam.base.NotFittedError):
        m.predict(test[0].alignment)


def test_conformance_suite_runs_on_an_unregistered_model():
    from dam import registry
    from dam.testing import check_synthesizer

    class StudentMean(PhoneMean):
        """A student's copy of phone-mean, never registered by hand."""
        name = ""
        _tags = {"reference": True}

    check_synthesizer(StudentMean())
    assert registry.get("StudentMean") is StudentMean
    registry._REGISTRY.pop("StudentMean")
    registry._LOADED.pop("StudentMean")


def test_conformance_suite_catches_a_model_that_ignores_timing():
    from dam.testing import check_time_shift_equivariance, default_corpora

    class Clock(PhoneMean):
        """Predicts from absolute frame index: not time-shift equivariant."""
        name = "clock-test"

        def _predict(self, alignment, n_frames):
            y = super()._predict(alignment, n_frames)
            return y + np.sin(np.arange(n_frames) / 3.0)[:, None] * y.std(axis=0)

    train, test = default_corpora()
    with pytest.raises(AssertionError, match="does not shift"):
        check_time_shift_equivariance(Clock(), train, test)
