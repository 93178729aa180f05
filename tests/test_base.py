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
    code = (
        "import sys, dam; bad = [m for m in ('scipy', 'sklearn', 'matplotlib', 'jax', 'praatio') "
        "if m in sys.modules]; print(','.join(bad))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert out == ""


def test_phone_mean_is_the_mean_of_each_phone():
    a = Alignment(["a", "b", "a"], [0, 0.03, 0.05], [0.03, 0.05, 0.08])
    # frames at 0, 0.01, ..., 0.08 s (an alignment ending at T covers the frame times <= T): 0-2 a, 3-4 b, 5-8 a
    y = np.arange(9, dtype=float)[:, None]
    m = PhoneMean().fit(Corpus([Utterance(a, y, 100, ["x"])]))
    mean_a = (0 + 1 + 2 + 5 + 6 + 7 + 8) / 7
    np.testing.assert_allclose(m.predict(a)[:, 0], [mean_a] * 3 + [3.5] * 2 + [mean_a] * 4)


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
    code = (
        f"import sys, dam, numpy as np; m = dam.load({str(tmp_path / 'm.dam')!r});"
        "a = dam.Alignment(['sil', 'p', 'aa'], [0, .1, .2], [.1, .2, .4]); y = m.predict(a);"
        "print(y.shape, [k for k in ('scipy', 'sklearn') if k in sys.modules])"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "(41, 4) []"  # frames at 0, 0.01, ..., 0.4 s


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
    from dam.testing import all_checks, check_synthesizer

    class StudentMean(PhoneMean):
        """A student's copy of phone-mean, never registered by hand."""

        name = ""
        _tags = {"reference": True}

    registry.names()  # entry points read first
    before = dict(registry._REGISTRY)
    results = check_synthesizer(StudentMean())
    assert registry._REGISTRY == before and "StudentMean" not in registry.names()  # registered for the round trip only
    skipped = {r.check: r.reason for r in results if r.status == "skipped"}
    # what did not apply says so, with a reason; everything else ran
    assert "reference" in skipped.pop("check_beats_phone_mean")
    assert "function" in skipped.pop("check_numpy_runtime")  # a class defined here cannot be imported elsewhere
    assert "random_state" in skipped.pop("check_same_seed_same_model")
    assert not skipped and len(results) == len(all_checks())


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


# -- parameter constraints (dam._params) ------------------------------------------
def test_constraint_vocabulary():
    from dam._params import Interval, InvalidParameterError, Options, TupleOf, make_constraint, validate_params

    deg = Interval(int, 0, None, closed="left")
    assert deg.is_satisfied_by(0) and deg.is_satisfied_by(np.int64(3))
    assert not any(deg.is_satisfied_by(v) for v in (True, np.bool_(False), 1.0, "1", -1, None))
    unit = Interval(float, 0, 1, closed="left")
    assert unit.is_satisfied_by(0) and unit.is_satisfied_by(0.5) and unit.is_satisfied_by(np.float32(0.25))
    assert not any(unit.is_satisfied_by(v) for v in (1.0, -1e-300, float("nan"), True, "0.5"))
    anything = Interval(float, None, None)
    assert anything.is_satisfied_by(-1e300) and not anything.is_satisfied_by(float("inf"))
    opts = Options({"error", "fallback"})
    assert opts.is_satisfied_by("error") and not opts.is_satisfied_by("Error") and not opts.is_satisfied_by(["error"])
    live = {"a": 1}
    grows = Options(live)
    live["b"] = 2  # a registry that grows after the class is declared
    assert grows.is_satisfied_by("b")
    bounds = TupleOf(Interval(float, 0, None, closed="neither"), min_len=2, max_len=2, increasing=True)
    assert bounds.is_satisfied_by((0.25, 4.0)) and bounds.is_satisfied_by([1, 2])
    assert not any(bounds.is_satisfied_by(v) for v in ((2.0, 1.0), (1.0, 1.0), (0.0, 1.0), (1.0,), "ab", 1.0))
    seed = make_constraint("random_state")
    assert seed.is_satisfied_by(None) and seed.is_satisfied_by(2**32 - 1)
    assert not any(seed.is_satisfied_by(v) for v in (-1, 2**32, True, 1.5))
    with pytest.raises(InvalidParameterError) as info:
        validate_params("Model", {"x": [None, Interval(float, 0, None, closed="neither")]}, {"x": 0.0})
    assert str(info.value) == "Model: parameter 'x' is 0.0; it must be None or a finite number in (0, inf)"
    assert isinstance(info.value, ValueError) and isinstance(info.value, TypeError)


@pytest.mark.parametrize(
    "name,params,named",
    [
        ("dam", {"degree": True}, "degree"),
        ("dam", {"degree": "abc"}, "degree"),
        ("dam", {"ridge": "abc"}, "ridge"),
        ("dam", {"dominance_tol": "x"}, "dominance_tol"),
        ("dam", {"ridge": float("nan")}, "ridge"),
        ("dam", {"tol": float("inf")}, "tol"),
        ("dam", {"w_c": -float("inf")}, "w_c"),
        ("dam-m0", {"sigma_init": float("nan")}, "sigma_init"),
        ("mmm", {"smoothness": "x"}, "smoothness"),
        ("mmm", {"smoothness": (1.0, float("nan"))}, "smoothness"),
        ("cohen-massaro", {"max_nfev": -1}, "max_nfev"),
        ("cohen-massaro", {"c_bounds": (2.0, 1.0)}, "c_bounds"),
        ("dtree", {"max_depth": 2.5}, "max_depth"),
        ("transformer", {"d_model": 10, "n_heads": 4}, "d_model"),
    ],
)
def test_bad_values_are_refused_before_any_work(name, params, named, split):
    with pytest.raises(dam.InvalidParameterError) as info:
        dam.make(name, **params).fit(split[0])
    cls = dam.registry.get(name).__name__
    assert str(info.value).startswith(f"{cls}: parameter {named!r} is {params[named]!r}; it must be ")


def test_tag_register_refuses_unknown_tags_and_wrong_types():
    from dam.base import TAGS

    class Typo(PhoneMean):
        _tags = {"deterministc": True}

    class WrongType(PhoneMean):
        _tags = {"requires": "jax"}

    class WrongRead(PhoneMean):
        _tags = {"reads": ("phones", "video")}

    with pytest.raises(TypeError, match="Typo: unknown tag 'deterministc'"):
        Typo.get_tags()
    with pytest.raises(TypeError, match="WrongType: tag 'requires' is 'jax'"):
        WrongType.get_tags()
    with pytest.raises(TypeError, match="WrongRead: tag 'reads'"):
        WrongRead.get_tags()
    tags = PhoneMean.get_tags()
    assert set(tags) == set(TAGS) and tags["reference"] is True and tags["numpy_runtime"] is True
    assert all(t.meaning for t in TAGS.values())


# -- presets ---------------------------------------------------------------------
def test_dam_m0_is_a_preset_of_dam(tmp_path, split):
    import inspect

    from dam.model.estimator import DAM, DAMM0

    assert "__init__" not in vars(DAMM0) or DAMM0.__init__.__signature__  # generated, not written out
    full, m0 = inspect.signature(DAM.__init__).parameters, inspect.signature(DAMM0.__init__).parameters
    assert list(full) == list(m0)
    assert {k for k in full if full[k].default != m0[k].default} == {"degree"} and m0["degree"].default == 0
    m = DAMM0(ridge=1e-3)
    assert repr(m) == "DAMM0(ridge=0.001)" and repr(DAMM0(degree=4)) == "DAMM0(degree=4)"
    assert m.get_params() == {**DAM().get_params(), "degree": 0, "ridge": 1e-3}
    twin = dam.clone(m.set_params(max_iter=2))
    assert type(twin) is DAMM0 and twin.get_params() == m.get_params()
    with pytest.raises(TypeError):
        DAMM0(not_a_parameter=1)
    fitted = DAMM0(max_iter=2, n_resample=8).fit(split[0])
    fitted.save(tmp_path / "m0.dam")
    back = dam.load(tmp_path / "m0.dam")
    assert type(back) is DAMM0 and back.get_params() == fitted.get_params()


def test_model_file_saved_by_dam_0_1_still_loads(split):
    """A dam-m0 model written by dam 0.1 (commit 9ecf8bf, before DAMM0 became a preset)."""
    from pathlib import Path

    here = Path(__file__).parent / "data" / "models"
    m = dam.load(here / "dam-m0_dam-0.1.dam")
    assert repr(m) == "DAMM0(max_iter=3, n_resample=8, ridge=0.0001)" and m.degree == 0
    u = split[1][0]
    assert u.name == "tiny002"
    np.testing.assert_allclose(m.predict(u.alignment), np.load(here / "dam-m0_dam-0.1_tiny002.npy"), atol=1e-10)


def test_a_preset_names_only_parameters_of_its_parent():
    from dam.model.estimator import DAM

    with pytest.raises(TypeError, match="not parameters of DAM"):
        type("Bad", (DAM,), {"_preset": {"degre": 0}})
    with pytest.raises(TypeError, match="no __init__"):
        type("Both", (DAM,), {"_preset": {"degree": 0}, "__init__": lambda self, **kw: None})


# -- the conformance suite's own checks catch what they are for -------------------
class _Seeded(PhoneMean):
    """phone-mean plus noise drawn from ``random_state``: not deterministic, but seeded."""

    _tags = {"deterministic": False, "reference": True}

    def __init__(self, *, unknown_phone="error", random_state=0):
        self.unknown_phone = unknown_phone
        self.random_state = random_state

    def _fit(self, corpus):
        super()._fit(corpus)
        self.table_ = self.table_ + np.random.default_rng(self._seed()).normal(0, 0.1, self.table_.shape)

    def _seed(self):
        return self.random_state


class _Unseeded(_Seeded):
    def _seed(self):
        return None  # ignores random_state


def test_same_seed_check_tells_seeded_from_unseeded(split):
    from dam.testing import check_same_seed_same_model

    check_same_seed_same_model(_Seeded(random_state=3), *split)
    with pytest.raises(AssertionError, match="random_state=3 twice"):
        check_same_seed_same_model(_Unseeded(random_state=3), *split)


def test_predict_must_leave_the_model_unchanged(split):
    from dam.testing import check_predict_leaves_model_unchanged

    class Caching(PhoneMean):
        def _predict(self, alignment, n_frames):
            self._last = alignment  # a cache grown by predict
            return super()._predict(alignment, n_frames)

    class Drifting(PhoneMean):
        def _predict(self, alignment, n_frames):
            self.table_ *= 1.0 + 1e-9  # in place: same object, other values
            return super()._predict(alignment, n_frames)

    check_predict_leaves_model_unchanged(PhoneMean(), *split)
    with pytest.raises(AssertionError, match=r"added \['_last'\]"):
        check_predict_leaves_model_unchanged(Caching(), *split)
    with pytest.raises(AssertionError, match=r"changed \['table_'\]"):
        check_predict_leaves_model_unchanged(Drifting(), *split)


def test_parameter_check_catches_undeclared_and_unrefused_parameters(split):
    from dam.testing import check_parameter_constraints

    class Undeclared(PhoneMean):
        def __init__(self, *, unknown_phone="error", smoothing=1.0):
            self.unknown_phone, self.smoothing = unknown_phone, smoothing

    class Lax(Undeclared):
        _parameter_constraints = {"smoothing": [dam.Interval(float, 0, None, closed="left")]}

        def _validate_params(self):
            pass  # declares, but never checks

    with pytest.raises(AssertionError, match=r"no constraints declared for \['smoothing'\]"):
        check_parameter_constraints(Undeclared(), *split)
    with pytest.raises(AssertionError, match="Lax: fit accepted the wrong type value"):
        check_parameter_constraints(Lax(), *split)


def test_numpy_runtime_check_runs_without_scipy(tmp_path, monkeypatch, split):
    """A model tagged numpy_runtime that needs scipy to predict fails the check."""
    import sys

    from dam.testing import check_numpy_runtime

    (tmp_path / "scipy_mean.py").write_text(
        "from baselines.reference import PhoneMean\n"
        "class ScipyMean(PhoneMean):\n"
        "    name = 'scipy-mean-test'\n"
        "    def _predict(self, alignment, n_frames):\n"
        "        import scipy.special\n"
        "        return super()._predict(alignment, n_frames)\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setenv("PYTHONPATH", str(tmp_path))
    import scipy_mean

    with pytest.raises(AssertionError, match="numpy alone failed"):
        check_numpy_runtime(scipy_mean.ScipyMean(), *split)
    sys.modules.pop("scipy_mean", None)


def test_fit_cache_is_bounded(split):
    from dam import testing

    for k in range(testing.FIT_CACHE_SIZE + 5):
        testing._fitted(_Seeded(random_state=k), split[0])
    assert len(testing._FIT_CACHE) == testing.FIT_CACHE_SIZE
