"""The conformance suite every synthesizer passes (scikit-learn's ``check_estimator`` for dam).

Run it on your own model::

    from dam.testing import check_synthesizer
    check_synthesizer(MyModel())            # raises AssertionError on the first failure

or one check at a time (the project's tests make one pytest case per check
and model)::

    for check in all_checks():
        check(MyModel(), train, test)

Model files name their model, so ``check_save_load_roundtrip`` registers an
unregistered model under its ``name`` (or class name) before saving it.

Every check is a small function ``check_<what>(estimator, train, test)``
that fits clones of ``estimator`` (never ``estimator`` itself) on the
``train`` corpus and raises ``AssertionError`` with a readable message.
"""
from __future__ import annotations

import copy
import os
import tempfile

import numpy as np

from dam.base import NotFittedError, Synthesizer, UnknownPhoneError, clone
from dam.corpus.data import Alignment, Corpus

__all__ = ["check_synthesizer", "all_checks", "clone", "default_corpora"]

_FIT_CACHE: dict = {}


def default_corpora() -> tuple[Corpus, Corpus]:
    """The bundled ``tiny`` corpus split into train and test (fixed seed)."""
    if "tiny" not in _FIT_CACHE:
        import dam.datasets as datasets
        _FIT_CACHE["tiny"] = datasets.load("tiny").train_test_split(0.25, random_state=0)
    return _FIT_CACHE["tiny"]


def _fitted(estimator: Synthesizer, train: Corpus) -> Synthesizer:
    """A fitted clone, shared between the checks that only read it."""
    key = (type(estimator), repr(sorted(estimator.get_params().items(), key=lambda kv: kv[0])), id(train))
    if key not in _FIT_CACHE:
        # The entry holds ``train`` too: while it lives, its id cannot be reused by another corpus.
        _FIT_CACHE[key] = (train, clone(estimator).fit(train))
    return _FIT_CACHE[key][1]


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
    tags = type(estimator).get_tags()
    assert set(tags["reads"]) <= {"phones", "audio"}, f"{_name(estimator)}: bad 'reads' tag {tags['reads']}"
    tps = type(estimator).get_test_params()
    assert isinstance(tps, list) and len(tps) >= 2, f"{_name(estimator)}: get_test_params must give two settings"


def check_fit_returns_self(estimator, train, test):
    est = clone(estimator)
    assert est.fit(train) is est, f"{_name(estimator)}: fit must return self"


def check_not_fitted(estimator, train, test):
    est = clone(estimator)
    try:
        est.predict(test[0].alignment)
    except NotFittedError:
        return
    raise AssertionError(f"{_name(estimator)}: predict before fit must raise NotFittedError")


def check_predict_shapes_finite(estimator, train, test):
    est = _fitted(estimator, train)
    alignments = test.alignments
    out = est.predict(alignments)
    assert isinstance(out, list) and len(out) == len(alignments), "a list in must give a list out"
    for a, u, y in zip(alignments, test, out):
        n = a.n_frames(est.frame_rate_)
        assert y.shape == (n, train.n_channels), f"{_name(estimator)}: shape {y.shape}, expected {(n, train.n_channels)}"
        assert n == u.n_frames, f"alignment of {u.name} covers {n} frames, the utterance has {u.n_frames}"
        assert np.all(np.isfinite(y)), f"{_name(estimator)}: non-finite prediction for {u.name}"
    single = est.predict(alignments[0])
    assert isinstance(single, np.ndarray), "one alignment in must give one array out"
    np.testing.assert_allclose(single, out[0], rtol=1e-6, atol=1e-9,
                               err_msg=f"{_name(estimator)}: predict of one differs from predict of a list")


def check_inputs_not_mutated(estimator, train, test):
    before_train = [u.trajectory.copy() for u in train]
    before_align = [(a.labels, a.starts.copy(), a.ends.copy()) for a in test.alignments]
    est = clone(estimator).fit(train)
    est.predict(test.alignments)
    for u, y in zip(train, before_train):
        assert np.array_equal(u.trajectory, y), f"{_name(estimator)}: fit changed the trajectory of {u.name}"
    for a, (lab, s, e) in zip(test.alignments, before_align):
        assert a.labels == lab and np.array_equal(a.starts, s) and np.array_equal(a.ends, e), \
            f"{_name(estimator)}: predict changed an alignment"


def check_params_not_overwritten(estimator, train, test):
    est = clone(estimator)
    before = copy.deepcopy(est.get_params())
    est.fit(train)
    assert _equal(est.get_params(), before), \
        f"{_name(estimator)}: fit changed hyperparameters: {before} -> {est.get_params()}"


def check_refit_idempotent(estimator, train, test):
    if not type(estimator).get_tags()["deterministic"]:
        return
    est = clone(estimator)
    first = est.fit(train).predict(test.alignments)
    second = est.fit(train).predict(test.alignments)
    third = clone(estimator).fit(train).predict(test.alignments)
    for a, b, c in zip(first, second, third):
        np.testing.assert_allclose(a, b, rtol=1e-6, atol=1e-8,
                                   err_msg=f"{_name(estimator)}: refitting the same object changed predictions")
        np.testing.assert_allclose(a, c, rtol=1e-6, atol=1e-8,
                                   err_msg=f"{_name(estimator)}: a fresh fit gave other predictions")


def check_save_load_roundtrip(estimator, train, test):
    from dam.base import load
    from dam.registry import _REGISTRY, register
    name = estimator.name or type(estimator).__name__
    if name not in _REGISTRY:  # a student's model: files name their model, so it must be registered
        register(name, type(estimator))
    est = _fitted(estimator, train)
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "model.dam")
        est.save(path)
        back = load(path)
    assert type(back) is type(est), f"loaded a {type(back).__name__}, saved a {type(est).__name__}"
    assert _equal(back.get_params(), est.get_params()), f"{_name(estimator)}: params changed by save/load"
    for a in test.alignments:
        np.testing.assert_allclose(back.predict(a), est.predict(a), rtol=1e-6, atol=1e-9,
                                   err_msg=f"{_name(estimator)}: predictions changed by save/load")


def check_time_shift_equivariance(estimator, train, test):
    """Shifting an alignment by k frames shifts the prediction by k frames.

    The shifted alignment starts with a new silence segment of k frames, which
    a model with context may legitimately react to; so the comparison skips
    the first two original segments and asks that the median absolute
    difference stay below 2% of each channel's spread, and below the
    difference to the unshifted prediction.
    """
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
        same = np.median(np.abs(moved[k + start:] - base[start:]), axis=0) / scale
        wrong = np.median(np.abs(moved[start:len(base)] - base[start:]), axis=0) / scale
        assert np.all(same <= 0.02), (f"{_name(estimator)}: prediction does not shift with the alignment "
                                      f"(median |diff| / std per channel: {np.round(same, 4)})")
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
    a = test[0].alignment
    unknown = Alignment(("zzunknown",) + a.labels[1:], a.starts, a.ends, source="check.TextGrid")
    params = est.get_params()
    if "unknown_phone" in params:
        strict = clone(estimator).set_params(unknown_phone="error")
        strict = _fitted(strict, train)
        try:
            strict.predict(unknown)
        except UnknownPhoneError as exc:
            assert "zzunknown" in str(exc) and "check.TextGrid" in str(exc), \
                f"{_name(estimator)}: the unknown-phone error must name the file and the phone: {exc}"
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
        return
    from dam.evaluation.metrics import evaluate
    from dam.registry import make
    ours = evaluate(_fitted(estimator, train), test).rmse
    ref = evaluate(_fitted(make("phone-mean"), train), test).rmse
    assert ours < ref, f"{_name(estimator)}: held-out RMSE {ours:.4g} does not beat phone-mean {ref:.4g}"


def _equal(a, b) -> bool:
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_equal(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return len(a) == len(b) and all(_equal(x, y) for x, y in zip(a, b))
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return np.array_equal(np.asarray(a), np.asarray(b))
    return a == b or (a != a and b != b)


_CHECKS = [check_init_stores_params, check_fit_returns_self, check_not_fitted, check_predict_shapes_finite,
           check_inputs_not_mutated, check_params_not_overwritten, check_refit_idempotent,
           check_save_load_roundtrip, check_time_shift_equivariance, check_bad_input, check_beats_phone_mean]


def all_checks() -> list:
    """Every check, in order."""
    return list(_CHECKS)


def check_synthesizer(estimator: Synthesizer, train: Corpus | None = None, test: Corpus | None = None) -> None:
    """Run every check on ``estimator``; raise AssertionError on the first failure.

    Parameters
    ----------
    estimator : Synthesizer
        Unfitted; it is cloned, never fitted itself.
    train, test : Corpus, optional
        Defaults to the bundled ``tiny`` corpus split 75/25.
    """
    if train is None or test is None:
        train, test = default_corpora()
    for check in _CHECKS:
        check(estimator, train, test)
