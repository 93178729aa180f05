"""The conformance suite every synthesizer passes (scikit-learn's ``check_estimator`` for dam).

Run it on your own model::

    from dam.testing import check_synthesizer
    check_synthesizer(MyModel())            # raises AssertionError on the first failure

or one check at a time (the project's tests make one pytest case per check
and model)::

    for check in all_checks():
        check(MyModel(), train, test)

Model files name their model, so ``check_save_load_roundtrip`` registers an
unregistered model under its ``name`` (or class name) for the round trip only.

Every check is a small function ``check_<what>(estimator, train, test)``
that fits clones of ``estimator`` (never ``estimator`` itself) on the
``train`` corpus and raises ``AssertionError`` with a readable message. A
check that does not apply raises :class:`SkipCheck` with the reason (pytest
shows it as a skip; :func:`check_synthesizer` returns it): none passes
silently. The project's tests run every setting of ``get_test_params``
(:func:`each_test_setting`).

The checks that only read a fitted model share one fit of a clone per
estimator and corpus (the last :data:`FIT_CACHE_SIZE` are kept), recorded
with what ``fit`` returned, the hyperparameters and training data before it
and the model's attributes right after it, so that "fit returns self",
"inputs not mutated", "parameters not overwritten" and "predict leaves the
model unchanged" need no fit of their own.
"""

from __future__ import annotations

import collections
import copy
import json
import os
import subprocess
import sys
import tempfile
import unittest
from dataclasses import dataclass

import numpy as np

from dam._params import InvalidParameterError, invalid_values
from dam.base import TAGS, NotFittedError, Synthesizer, UnknownPhoneError, clone, predict_inputs
from dam.corpus.data import Alignment, Corpus, DataError

__all__ = [
    "check_synthesizer",
    "all_checks",
    "clone",
    "default_corpora",
    "audio_corpora",
    "corpora_for",
    "each_test_setting",
    "assert_refused",
    "SkipCheck",
    "CheckResult",
]


class SkipCheck(unittest.SkipTest):
    """A check that does not apply to this model, with the reason.

    pytest reports it as a skip (it is a ``unittest.SkipTest``);
    :func:`check_synthesizer` records it in its results. A check never passes
    silently where it did not look.
    """


@dataclass(frozen=True)
class CheckResult:
    """What one check said: ``status`` is ``"passed"`` or ``"skipped"`` (with ``reason``)."""

    check: str
    status: str
    reason: str = ""


#: Fitted models the read-only checks share, least recently used dropped first.
FIT_CACHE_SIZE = 8
_FIT_CACHE: collections.OrderedDict = collections.OrderedDict()
_CORPORA: dict = {}


def default_corpora() -> tuple[Corpus, Corpus]:
    """The bundled ``tiny`` corpus split into train and test (fixed seed)."""
    if "tiny" not in _CORPORA:
        import dam.datasets as datasets

        _CORPORA["tiny"] = datasets.load("tiny").train_test_split(0.25, random_state=0)
    return _CORPORA["tiny"]


def audio_corpora() -> tuple[Corpus, Corpus]:
    """The ``tiny`` corpus with toy audio (:func:`dam.datasets.tones.tiny_with_audio`: every phone a
    chord of its own), split as :func:`default_corpora`: small and fast, and it does not change when
    more of the ``vtl`` corpus gets audio."""
    if "tiny-audio" not in _CORPORA:
        from dam.datasets.tones import tiny_with_audio

        _CORPORA["tiny-audio"] = tiny_with_audio().train_test_split(0.25, random_state=0)
    return _CORPORA["tiny-audio"]


def corpora_for(estimator: Synthesizer) -> tuple[Corpus, Corpus]:
    """The corpora the suite runs ``estimator`` on: :func:`default_corpora`, or
    :func:`audio_corpora` for a model that reads audio."""
    return audio_corpora() if "audio" in estimator.reads() else default_corpora()


def _inputs(est, corpus: Corpus) -> list:
    """What ``est.predict`` takes for every utterance of ``corpus`` (alignments, or utterances with audio)."""
    return predict_inputs(est, corpus)


@dataclass
class _Fit:
    """One fit of a fresh clone, with what the checks compare against: what ``fit`` returned,
    the hyperparameters and the training trajectories before it, the model's attributes right
    after it (before any prediction)."""

    train: Corpus  # held, so that its id cannot be reused by another corpus while the entry lives
    model: Synthesizer
    returned: object
    params_before: dict
    trajectories_before: list
    state_after_fit: dict


def _fit_record(estimator: Synthesizer, train: Corpus) -> _Fit:
    """The shared fit of a clone of ``estimator`` on ``train`` (at most :data:`FIT_CACHE_SIZE` are kept):
    one fit serves every check that does not need a fit of its own."""
    key = (type(estimator), repr(sorted(estimator.get_params().items(), key=lambda kv: kv[0])), id(train))
    if key in _FIT_CACHE:
        _FIT_CACHE.move_to_end(key)
        return _FIT_CACHE[key]
    model = clone(estimator)
    params_before = copy.deepcopy(model.get_params())
    trajectories_before = [u.trajectory.copy() for u in train]
    returned = model.fit(train)
    _FIT_CACHE[key] = _Fit(
        train, model, returned, params_before, trajectories_before, {k: _snapshot(v) for k, v in vars(model).items()}
    )
    while len(_FIT_CACHE) > FIT_CACHE_SIZE:
        _FIT_CACHE.popitem(last=False)
    return _FIT_CACHE[key]


def _fitted(estimator: Synthesizer, train: Corpus) -> Synthesizer:
    """A fitted clone, shared between the checks that only read it."""
    return _fit_record(estimator, train).model


def each_test_setting(cls: type) -> list[Synthesizer]:
    """One unfitted ``cls`` per setting of ``cls.get_test_params()`` (the suite runs them all)."""
    return [cls(**params) for params in cls.get_test_params()]


def _name(est) -> str:
    return est.name or type(est).__name__


# -- the checks -----------------------------------------------------------
def check_init_stores_params(estimator, train, test):
    """``__init__`` only stores hyperparameters; get_params/set_params round trip."""
    params = estimator.get_params()
    twin = type(estimator)(**params)
    assert _equal(twin.get_params(), params), f"{_name(estimator)}: get_params differs after re-construction"
    learned = [k for k in vars(twin) if k.endswith("_") and not k.startswith("_")]
    assert not learned, f"{_name(estimator)}: __init__ sets learned attributes {learned}"
    twin.set_params(**params)
    assert _equal(twin.get_params(), params), f"{_name(estimator)}: set_params does not round-trip"
    try:
        twin.set_params(not_a_parameter_xyz=1)
    except ValueError:
        pass
    else:
        raise AssertionError(f"{_name(estimator)}: set_params accepted an unknown parameter")
    tps = type(estimator).get_test_params()
    assert isinstance(tps, list) and len(tps) >= 2, f"{_name(estimator)}: get_test_params must give two settings"


def check_tags(estimator, train, test):
    """Every tag the class sets is in the register (:data:`dam.base.TAGS`) with a value of its type,
    and ``requires`` names extras dam declares."""
    try:
        tags = type(estimator).get_tags()
    except TypeError as exc:
        raise AssertionError(str(exc)) from None
    assert set(tags) == set(TAGS), f"{_name(estimator)}: tags {sorted(tags)} differ from the register {sorted(TAGS)}"
    extras = _dam_extras()
    if extras:
        unknown = [e for e in tags["requires"] if e not in extras]
        assert not unknown, f"{_name(estimator)}: tag 'requires' names {unknown}, not extras of dam ({sorted(extras)})"


def _dam_extras() -> set:
    try:
        from importlib.metadata import metadata

        return set(metadata("dam").get_all("Provides-Extra") or [])
    except Exception:  # not installed as a distribution: nothing to compare with
        return set()


def check_parameter_constraints(estimator, train, test):
    """Every parameter declares its constraints; the defaults and every ``get_test_params``
    setting satisfy them; and every wrong-typed or out-of-range value the declarations
    imply is refused by ``fit`` with an :class:`~dam.InvalidParameterError` that names the
    class, the parameter and the value."""
    cls = type(estimator)
    names = set(cls._param_names())
    declared = cls.get_parameter_constraints()
    missing = sorted(names - set(declared))
    assert not missing, (
        f"{cls.__name__}: no constraints declared for {missing}; add them to _parameter_constraints (see dam._params)"
    )
    for klass in cls.__mro__:  # Synthesizer's own declarations are conventions for whoever has the parameter
        if klass is Synthesizer or not issubclass(klass, Synthesizer):
            continue
        stray = sorted(set(klass.__dict__.get("_parameter_constraints") or {}) - names)
        assert not stray, (
            f"{klass.__name__}: _parameter_constraints declares {stray}, which are not parameters of {cls.__name__}"
        )
    for params in [{}] + cls.get_test_params():
        try:
            cls(**params)._validate_params()
        except InvalidParameterError as exc:
            raise AssertionError(f"{cls.__name__}: the setting {params} breaks its own constraints: {exc}") from None
    for name, specs in declared.items():
        bad = invalid_values(specs)
        assert bad, f"{cls.__name__}: the constraints of {name!r} refuse nothing"
        for kind, value in bad:
            assert_refused(estimator, name, value, train, f"{kind} value")


def assert_refused(estimator, name: str, value, train: Corpus, what: str = "value") -> None:
    """``fit`` with ``name=value`` raises an InvalidParameterError naming the class, ``name`` and ``value``."""
    cls = type(estimator)
    est = clone(estimator).set_params(**{name: value})
    try:
        est.fit(train)
    except InvalidParameterError as exc:
        msg = str(exc)
        assert cls.__name__ in msg and repr(name) in msg and repr(value) in msg, (
            f"{cls.__name__}: the error for {name}={value!r} must name the class, the parameter and the value: {msg}"
        )
    else:
        raise AssertionError(f"{cls.__name__}: fit accepted the {what} {name}={value!r}")


def check_fit_returns_self(estimator, train, test):
    fit = _fit_record(estimator, train)
    assert fit.returned is fit.model, f"{_name(estimator)}: fit must return self"


def check_not_fitted(estimator, train, test):
    est = clone(estimator)
    try:
        est.predict(_inputs(est, test)[0])
    except NotFittedError:
        return
    raise AssertionError(f"{_name(estimator)}: predict before fit must raise NotFittedError")


def check_predict_shapes_finite(estimator, train, test):
    est = _fitted(estimator, train)
    inputs = _inputs(est, test)
    out = est.predict(inputs)
    assert isinstance(out, list) and len(out) == len(inputs), "a list in must give a list out"
    for u, y in zip(test, out):
        n = u.alignment.n_frames(est.frame_rate_)
        assert y.shape == (n, train.n_channels), (
            f"{_name(estimator)}: shape {y.shape}, expected {(n, train.n_channels)}"
        )
        assert n == u.n_frames, f"alignment of {u.name} covers {n} frames, the utterance has {u.n_frames}"
        assert np.all(np.isfinite(y)), f"{_name(estimator)}: non-finite prediction for {u.name}"
    single = est.predict(inputs[0])
    assert isinstance(single, np.ndarray), "one alignment in must give one array out"
    np.testing.assert_allclose(
        single,
        out[0],
        rtol=1e-6,
        atol=1e-9,
        err_msg=f"{_name(estimator)}: predict of one differs from predict of a list",
    )


def check_inputs_not_mutated(estimator, train, test):
    """``fit`` leaves the training trajectories alone and ``predict`` the alignments."""
    fit = _fit_record(estimator, train)
    for u, y in zip(fit.train, fit.trajectories_before):
        assert np.array_equal(u.trajectory, y), f"{_name(estimator)}: fit changed the trajectory of {u.name}"
    before_align = [(a.labels, a.starts.copy(), a.ends.copy()) for a in test.alignments]
    fit.model.predict(_inputs(fit.model, test))
    for a, (lab, s, e) in zip(test.alignments, before_align):
        assert a.labels == lab and np.array_equal(a.starts, s) and np.array_equal(a.ends, e), (
            f"{_name(estimator)}: predict changed an alignment"
        )


def check_params_not_overwritten(estimator, train, test):
    fit = _fit_record(estimator, train)
    assert _equal(fit.model.get_params(), fit.params_before), (
        f"{_name(estimator)}: fit changed hyperparameters: {fit.params_before} -> {fit.model.get_params()}"
    )


def check_refit_idempotent(estimator, train, test):
    if not type(estimator).get_tags()["deterministic"]:
        raise SkipCheck("not tagged deterministic: check_same_seed_same_model applies instead")
    est = clone(estimator)
    inputs = _inputs(est, test)
    first = est.fit(train).predict(inputs)
    second = est.fit(train).predict(inputs)
    third = _fitted(estimator, train).predict(inputs)  # a fresh clone's fit, shared
    for a, b, c in zip(first, second, third):
        np.testing.assert_allclose(
            a, b, rtol=1e-6, atol=1e-8, err_msg=f"{_name(estimator)}: refitting the same object changed predictions"
        )
        np.testing.assert_allclose(
            a, c, rtol=1e-6, atol=1e-8, err_msg=f"{_name(estimator)}: a fresh fit gave other predictions"
        )


def check_save_load_roundtrip(estimator, train, test):
    from dam.base import load
    from dam.registry import names, register, registered_name, unregister

    # a student's model: files name their model, so it is registered for the round trip only
    temporary = None if registered_name(type(estimator)) else (estimator.name or type(estimator).__name__)
    if temporary in names():  # the name belongs to another class: do not shadow it
        temporary = f"conformance-{type(estimator).__module__}.{type(estimator).__qualname__}"
    if temporary:
        register(temporary, type(estimator))
    est = _fitted(estimator, train)
    try:
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "model.dam")
            est.save(path)
            back = load(path)
    finally:
        if temporary:
            unregister(temporary)
    assert type(back) is type(est), f"loaded a {type(back).__name__}, saved a {type(est).__name__}"
    assert _equal(back.get_params(), est.get_params()), f"{_name(estimator)}: params changed by save/load"
    for a in _inputs(est, test):
        np.testing.assert_allclose(
            back.predict(a),
            est.predict(a),
            rtol=1e-6,
            atol=1e-9,
            err_msg=f"{_name(estimator)}: predictions changed by save/load",
        )


def check_time_shift_equivariance(estimator, train, test):
    """Shifting an alignment by k frames shifts the prediction by k frames.

    The shifted alignment starts with a new silence segment of k frames, which
    a model with context may legitimately react to; so the comparison skips
    the first two original segments and asks that the median absolute
    difference stay below 2% of each channel's spread, and below the
    difference to the unshifted prediction. (The data model merges adjacent
    silences: where the alignment starts with one, the shift lengthens it.)
    """
    if "phones" not in estimator.reads():
        raise SkipCheck("reads audio, not phones: shifting an alignment does not shift the audio")
    est = _fitted(estimator, train)
    k = 7
    scale = np.concatenate(train.trajectories).std(axis=0) + 1e-12
    compared = 0
    for a in test.alignments[:3]:
        base = est.predict(a)
        moved = est.predict(a.shifted(k / est.frame_rate_))
        start = int(np.ceil(a.ends[min(1, len(a) - 1)] * est.frame_rate_))
        if len(base) - start < 10:
            continue
        compared += 1
        same = np.median(np.abs(moved[k + start :] - base[start:]), axis=0) / scale
        wrong = np.median(np.abs(moved[start : len(base)] - base[start:]), axis=0) / scale
        assert np.all(same <= 0.02), (
            f"{_name(estimator)}: prediction does not shift with the alignment "
            f"(median |diff| / std per channel: {np.round(same, 4)})"
        )
        assert same.mean() <= wrong.mean() + 1e-12, f"{_name(estimator)}: shift makes predictions closer unshifted"
    assert compared, "time-shift check: no test utterance has 10 frames after its first two segments"


def check_bad_input(estimator, train, test):
    est = _fitted(estimator, train)
    try:
        est.predict(np.zeros((3, 2)))
    except TypeError:
        pass
    else:
        raise AssertionError(f"{_name(estimator)}: predict accepted an array instead of an Alignment")
    try:
        clone(estimator).fit(train.trajectories)
    except TypeError:
        pass
    else:
        raise AssertionError(f"{_name(estimator)}: fit accepted a list of arrays instead of a Corpus")
    if "phones" not in estimator.reads():
        return  # an unknown phone cannot reach a model that reads no phones
    a = test[0].alignment
    unknown = Alignment(("zzunknown",) + a.labels[1:], a.starts, a.ends, source="check.TextGrid")
    params = est.get_params()
    if "unknown_phone" in params:
        strict = clone(estimator).set_params(unknown_phone="error")
        strict = _fitted(strict, train)
        try:
            strict.predict(unknown)
        except UnknownPhoneError as exc:
            assert "zzunknown" in str(exc) and "check.TextGrid" in str(exc), (
                f"{_name(estimator)}: the unknown-phone error must name the file and the phone: {exc}"
            )
        else:
            raise AssertionError(f"{_name(estimator)}: unknown phone accepted with unknown_phone='error'")
        lenient = _fitted(clone(estimator).set_params(unknown_phone="fallback"), train)
        y = lenient.predict(unknown)
        assert np.all(np.isfinite(y)), f"{_name(estimator)}: fallback gave non-finite values"
    else:
        try:
            y = est.predict(unknown)
        except UnknownPhoneError:
            pass
        else:
            assert np.all(np.isfinite(y)), f"{_name(estimator)}: non-finite output for an unknown phone"


def check_beats_phone_mean(estimator, train, test):
    """Held-out RMSE below the per-phone-mean baseline on the bundled corpus."""
    if type(estimator).get_tags().get("reference"):
        raise SkipCheck("tagged reference: it is the baseline the others must beat")
    from dam.evaluation.metrics import evaluate
    from dam.registry import make

    ours = evaluate(_fitted(estimator, train), test).rmse
    ref = evaluate(_fitted(make("phone-mean"), train), test).rmse
    assert ours < ref, f"{_name(estimator)}: held-out RMSE {ours:.4g} does not beat phone-mean {ref:.4g}"


def check_predict_leaves_model_unchanged(estimator, train, test):
    """``predict`` changes no attribute of the model, adds none and removes none: the attributes
    after predicting are those recorded right after the fit, before any prediction.

    Arrays and containers are compared by value; other objects (a compiled
    network, say) by identity.
    """
    fit = _fit_record(estimator, train)
    est, before = fit.model, fit.state_after_fit
    est.predict(_inputs(est, test))
    est.predict(_inputs(est, test)[0])
    after = vars(est)
    added = sorted(set(after) - set(before))
    removed = sorted(set(before) - set(after))
    changed = sorted(k for k in set(before) & set(after) if not _same_state(before[k], after[k]))
    assert not (added or removed or changed), (
        f"{_name(estimator)}: predict changed the model (added {added}, removed {removed}, changed {changed}); "
        "prediction must be stateless"
    )


class _Opaque:
    """An object the snapshot does not copy: compared by identity."""

    def __init__(self, obj):
        self.obj = obj


def _snapshot(v):
    if isinstance(v, np.ndarray):
        return v.copy()
    if isinstance(v, dict):
        return {k: _snapshot(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return type(v)(_snapshot(x) for x in v) if type(v) in (list, tuple) else _Opaque(v)
    if v is None or isinstance(v, (str, bytes, int, float, complex, bool, np.generic)):
        return v
    return _Opaque(v)


def _same_state(before, now) -> bool:
    if isinstance(before, _Opaque):
        return before.obj is now
    if isinstance(before, np.ndarray):
        return (
            isinstance(now, np.ndarray)
            and before.dtype == now.dtype
            and np.array_equal(before, now, equal_nan=before.dtype.kind in "fc")
        )
    if isinstance(before, dict):
        return (
            isinstance(now, dict)
            and before.keys() == now.keys()
            and all(_same_state(before[k], now[k]) for k in before)
        )
    if isinstance(before, (list, tuple)):
        return (
            type(now) is type(before)
            and len(now) == len(before)
            and all(_same_state(a, b) for a, b in zip(before, now))
        )
    return type(before) is type(now) and (before == now or (before != before and now != now))


def check_empty_corpus(estimator, train, test):
    """An empty corpus is refused with a DataError where it is built, so ``fit`` never sees one;
    ``fit`` of an empty list is a TypeError."""
    try:
        Corpus([], source="empty-corpus")
    except DataError as exc:
        assert "empty" in str(exc), f"the empty-corpus error must say so: {exc}"
    else:
        raise AssertionError("dam.Corpus([]) was accepted")
    try:
        clone(estimator).fit([])
    except TypeError:
        pass
    else:
        raise AssertionError(f"{_name(estimator)}: fit accepted an empty list instead of a Corpus")


def check_one_utterance_corpus(estimator, train, test):
    """A corpus of one utterance: a valid fit (finite predictions of the right shape) or a
    DataError / InvalidParameterError that says what is missing, leaving the model unfitted."""
    one = Corpus([train[0]], name="one-utterance")
    est = clone(estimator)
    try:
        est.fit(one)
    except (DataError, InvalidParameterError) as exc:
        assert str(exc), f"{_name(estimator)}: an empty error message for a one-utterance corpus"
        assert not est.is_fitted(), f"{_name(estimator)}: a failed fit left the model fitted"
        return
    y = est.predict(_inputs(est, one)[0])
    assert y.shape == one[0].trajectory.shape, f"{_name(estimator)}: shape {y.shape} on a one-utterance corpus"
    assert np.all(np.isfinite(y)), f"{_name(estimator)}: non-finite prediction after a one-utterance fit"


def check_same_seed_same_model(estimator, train, test):
    """Two fits with the same ``random_state`` predict the same (models not tagged deterministic)."""
    params = estimator.get_params()
    if "random_state" not in params:
        raise SkipCheck("no random_state parameter")
    if type(estimator).get_tags()["deterministic"]:
        raise SkipCheck("tagged deterministic: check_refit_idempotent compares refits")
    seed = 0 if params["random_state"] is None else params["random_state"]
    inputs = _inputs(estimator, test)
    first = clone(estimator).set_params(random_state=seed).fit(train).predict(inputs)
    second = clone(estimator).set_params(random_state=seed).fit(train).predict(inputs)
    for a, b in zip(first, second):
        np.testing.assert_allclose(
            a, b, rtol=1e-6, atol=1e-8, err_msg=f"{_name(estimator)}: random_state={seed} twice gave other predictions"
        )


_NUMPY_RUNTIME = """
import json, sys
for blocked in ("scipy", "sklearn", "jax", "matplotlib", "pandas", "torch"):
    sys.modules[blocked] = None  # importing any of them now fails
import numpy as np
import dam
from dam import registry
from dam.modelfile import read_model_file
args = json.loads(sys.argv[1])
name = read_model_file(args["path"])[0]["model"]
if name not in registry.names():
    registry.register(name, args["class"])
model = dam.load(args["path"])
a = dam.Alignment(args["labels"], args["starts"], args["ends"])
from dam.corpus.atomic import atomic_write
with atomic_write(args["out"], "wb") as fh:
    np.save(fh, model.predict(a))
"""


def check_numpy_runtime(estimator, train, test):
    """A model tagged ``numpy_runtime`` loads and predicts in a fresh Python where scipy,
    scikit-learn, jax, matplotlib and pandas cannot be imported, and predicts the same."""
    cls = type(estimator)
    if not cls.get_tags()["numpy_runtime"]:
        raise SkipCheck("not tagged numpy_runtime")
    if "<locals>" in cls.__qualname__ or cls.__module__ == "__main__":
        raise SkipCheck(f"{cls.__qualname__} cannot be imported by another Python (defined in a function or __main__)")
    est = _fitted(estimator, train)
    a = test[0].alignment
    with tempfile.TemporaryDirectory() as d:
        path, out = os.path.join(d, "model.dam"), os.path.join(d, "y.npy")
        est.save(path)
        args = {
            "path": path,
            "out": out,
            "class": f"{cls.__module__}:{cls.__qualname__}",
            "labels": list(a.labels),
            "starts": a.starts.tolist(),
            "ends": a.ends.tolist(),
        }
        proc = subprocess.run([sys.executable, "-c", _NUMPY_RUNTIME, json.dumps(args)], capture_output=True, text=True)
        assert proc.returncode == 0, (
            f"{_name(estimator)}: tagged numpy_runtime, but loading and predicting "
            f"with numpy alone failed:\n{proc.stderr[-2000:]}"
        )
        y = np.load(out)
    np.testing.assert_allclose(
        y, est.predict(a), rtol=1e-6, atol=1e-9, err_msg=f"{_name(estimator)}: the numpy-only prediction differs"
    )


def _equal(a, b) -> bool:
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_equal(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return len(a) == len(b) and all(_equal(x, y) for x, y in zip(a, b))
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return np.array_equal(np.asarray(a), np.asarray(b))
    return a == b or (a != a and b != b)


_CHECKS = [
    check_init_stores_params,
    check_tags,
    check_parameter_constraints,
    check_fit_returns_self,
    check_not_fitted,
    check_predict_shapes_finite,
    check_inputs_not_mutated,
    check_params_not_overwritten,
    check_predict_leaves_model_unchanged,
    check_refit_idempotent,
    check_same_seed_same_model,
    check_save_load_roundtrip,
    check_numpy_runtime,
    check_time_shift_equivariance,
    check_bad_input,
    check_empty_corpus,
    check_one_utterance_corpus,
    check_beats_phone_mean,
]


def all_checks() -> list:
    """Every check, in order."""
    return list(_CHECKS)


def check_synthesizer(
    estimator: Synthesizer, train: Corpus | None = None, test: Corpus | None = None
) -> list[CheckResult]:
    """Run every check on ``estimator``; raise AssertionError on the first failure.

    Parameters
    ----------
    estimator : Synthesizer
        Unfitted; it is cloned, never fitted itself. To run every setting of
        ``get_test_params`` as the project's tests do, call this on each of
        :func:`each_test_setting`.
    train, test : Corpus, optional
        Defaults to :func:`corpora_for` the estimator: the bundled ``tiny``
        corpus split 75/25, or the ``vtl`` utterances with audio for a model
        that reads audio.

    Returns
    -------
    list of CheckResult
        One per check: ``"passed"``, or ``"skipped"`` with the reason (a
        check that does not apply says so; none passes silently).
    """
    if train is None or test is None:
        train, test = corpora_for(estimator)
    results = []
    for check in _CHECKS:
        try:
            check(estimator, train, test)
        except SkipCheck as exc:
            results.append(CheckResult(check.__name__, "skipped", str(exc)))
        else:
            results.append(CheckResult(check.__name__, "passed"))
    return results
