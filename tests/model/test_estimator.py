"""The DAM as a whole: parameter recovery from corpora generated with known
parameters, modes tied to context found and chosen, inspection, the file
format and the numpy-only runtime."""

import json
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from dam import registry
from dam.base import UnknownPhoneError
from dam.corpus.data import Alignment
from dam.datasets.synthetic import dam_parameters, make_corpus, random_alignment
from dam.model import DAM, DAMM0, inspect_report

PHONES = ["a", "b", "c", "d", "e"]


def _truth(extrapolate="polynomial", seed=0, sigma_range=(0.2, 0.6), degree=4, normalize=False):
    """A known DAM; the plain sum (Eq. 2 as printed) unless ``normalize``."""
    par = dam_parameters(PHONES, 2, degree=degree, random_state=seed, sigma_range=sigma_range)
    return DAM.from_parameters(
        par, frame_rate=100.0, channels=["x", "y"], basis="legendre", extrapolate=extrapolate, normalize=normalize
    )


@pytest.mark.parametrize("extrapolate,seed", [("polynomial", 2), ("polynomial", 4), ("hold", 0)])
def test_recovers_known_parameters_noise_free(extrapolate, seed):
    # sigma up to 0.6 durations: neighbouring dominances overlap over most of each phone
    true = _truth(extrapolate, seed)
    corpus = make_corpus(true, n_utterances=25, random_state=seed)
    m = DAM(
        modes="single", extrapolate=extrapolate, degree=4, tol=1e-10, max_iter=40, ridge=1e-10, normalize=False
    ).fit(corpus)
    np.testing.assert_allclose(m.sigma_, true.sigma_, atol=1e-5)
    np.testing.assert_allclose(m.coef_, true.coef_, atol=1e-4)
    pred = m.predict(corpus.alignments[:3])
    for p, u in zip(pred, corpus):
        np.testing.assert_allclose(p, u.trajectory, atol=1e-4)


def test_recovers_known_parameters_with_noise():
    true = _truth("hold", 1, degree=2)
    noise = 0.05
    corpus = make_corpus(true, n_utterances=40, noise=noise, random_state=1)
    m = DAM(modes="single", extrapolate="hold", degree=2, normalize=False).fit(corpus)
    np.testing.assert_allclose(m.sigma_, true.sigma_, atol=0.03)
    np.testing.assert_allclose(m.coef_, true.coef_, atol=0.06)
    # the fit explains everything but the noise
    mse = m.loss_curve_[0][-1]
    assert noise**2 * 0.9 < mse < noise**2 * 1.1


def test_recovers_weighted_average_model():
    true = _truth("hold", 3, degree=2, normalize=True)
    corpus = make_corpus(true, n_utterances=25, random_state=3)
    m = DAM(modes="single", extrapolate="hold", degree=2, normalize=True, tol=1e-10, ridge=1e-10).fit(corpus)
    np.testing.assert_allclose(m.sigma_, true.sigma_, atol=1e-4)
    np.testing.assert_allclose(m.coef_, true.coef_, atol=1e-4)


def _two_mode_truth():
    """Phone "a" rises after "b" and falls after "c": two shapes tied to the left context."""
    C = 2
    flat = np.zeros((3, C))
    phones = {
        p: (np.array([[[v, 0.0], [0.0, 0.0], [0.0, 0.0]]]), 0.3) for p, v in [("b", 0.5), ("c", -0.5), ("d", 0.0)]
    }
    up = np.array([[-1.0, 1.0], [2.0, -2.0], [0.0, 0.0]])
    down = -up
    phones["a"] = (np.stack([up, down]), np.array([[0.3, 0.3], [0.2, 0.2]]))
    del flat
    return DAM.from_parameters(phones, frame_rate=100.0, channels=["x", "y"], basis="monomial", extrapolate="hold")


def _rule(phone, left, right):
    return int(phone == "a" and left == "c")


def test_two_shapes_tied_to_context_are_found_as_two_modes_and_chosen():
    true = _two_mode_truth()
    kw = dict(phones=["a", "b", "c", "d"], durations=(0.08, 0.16))
    corpus = make_corpus(true, n_utterances=40, mode_rule=_rule, noise=0.01, random_state=0, **kw)
    m = DAM(extrapolate="hold", degree=2).fit(corpus)
    assert m.phone_modes_["a"][1] == 2
    # (other phones may get extra modes: their shapes vary with the neighbouring "a")
    # the two modes' animemes are the true "up" and "down" shapes (in some order)
    t = np.linspace(0, 1, 11)
    got = [m.animeme_curve("a", g, t) for g in range(2)]
    want = [true.animeme_curve("a", g, t) for g in range(2)]
    order = [0, 1] if np.abs(got[0] - want[0]).max() < np.abs(got[0] - want[1]).max() else [1, 0]
    for g in range(2):
        np.testing.assert_allclose(got[order[g]], want[g], atol=0.05)
    # new utterances: A* picks the mode the context calls for, and the output follows
    test = make_corpus(true, n_utterances=10, mode_rule=_rule, random_state=99, **kw)
    n_a = 0
    for u, modes in zip(test, test.metadata["modes"]):
        chosen = m.select_modes(u.alignment)[0]
        for j, p in enumerate(u.alignment.labels):
            if p == "a" and u.alignment.labels[j - 1] in ("b", "c") and j > 0:
                n_a += 1
                assert chosen[j] - m.phone_modes_["a"][0] == order[modes[j]]
        assert np.sqrt(np.mean((m.predict(u.alignment) - u.trajectory) ** 2)) < 0.05
    assert n_a >= 5
    # a single-mode DAM cannot do this
    single = DAM(extrapolate="hold", degree=2, modes="single").fit(corpus)
    err = [np.sqrt(np.mean((single.predict(u.alignment) - u.trajectory) ** 2)) for u in test]
    assert np.mean(err) > 0.1


def test_explain_and_inspection():
    true = _two_mode_truth()
    corpus = make_corpus(true, n_utterances=30, mode_rule=_rule, random_state=0, phones=["a", "b", "c", "d"])
    m = DAM(extrapolate="hold", degree=2, max_iter=5).fit(corpus)
    a = corpus[0].alignment
    rows = m.explain(a)
    assert [r["phone"] for r in rows] == list(a.labels)
    glob, cost = m.select_modes(a)
    assert rows[-1]["total"] == pytest.approx(cost, rel=1e-9, abs=1e-9)
    for r in rows:
        assert r["cost"] == pytest.approx(m.w_c * r["E_c"] + m.w_s * r["E_s"])
        assert r["context"] in ("trigram", "bigram", "unigram")
    info = m.modes_of("a")
    assert info["n_modes"] == 2 and info["sigma"].shape == (2, 2)
    # the monomial coefficients are the same polynomial
    t = np.linspace(-0.5, 1.5, 9)
    mono = info["coef_monomial"][1]
    direct = np.stack([np.polyval(mono[::-1, c], np.clip(t, 0, 1)) for c in range(2)], axis=1)
    np.testing.assert_allclose(m.animeme_curve("a", 1, t), direct, atol=1e-10)
    d = m.dominance_curve("a", 0, np.array([-1.0, 0.5, 2.0]))
    assert d.shape == (3, 2) and np.all(d[1] == 1.0) and np.all(d[[0, 2]] < 1)
    report = inspect_report(m)
    for word in ("phones", "modes", "channel", "x", "a "):
        assert word in report
    with pytest.raises(KeyError, match="phone 'zz'"):
        m.modes_of("zz")
    with pytest.raises(ValueError, match="modes 0..1"):
        m.animeme_curve("a", 2, t)


def test_select_modes_equals_dynamic_programming_on_the_model_graph():
    # a model with 1-3 modes per phone and random context counts, so that multi-mode
    # phones form blocks of every length; the fast path must find the optimum
    rng = np.random.default_rng(0)
    phones, counts = {}, {}
    for i, p in enumerate("abcdefgh"):
        G = [1, 2, 3][i % 3]
        phones[p] = (rng.normal(size=(G, 3, 2)), rng.uniform(0.1, 0.5, (G, 2)))
    names = [*phones, "#"]
    for p, (coef, _) in phones.items():
        G = coef.shape[0]
        tri = {L: {R: rng.integers(0, 5, G).tolist() for R in names} for L in names}
        counts[p] = {"unigram": rng.integers(1, 9, G).tolist(), "left": {}, "right": {}, "trigram": tri}
    m = DAM.from_parameters(phones, frame_rate=100.0, channels=["x", "y"], context_counts=counts, w_c=1.0, w_s=0.3)
    from dam.model.astar import viterbi

    for seed in range(5):
        a = random_alignment(np.random.default_rng(seed), list(phones), n_segments=60)
        glob, cost = m.select_modes(a)
        nodes, edges, _ = m._graph(a.labels, a.durations)
        path, want = viterbi(list(nodes), list(edges))
        first = np.array([m.phone_modes_[p][0] for p in a.labels])
        assert (glob - first).tolist() == path
        assert cost == pytest.approx(want, rel=1e-10)
        assert m.explain(a)[-1]["total"] == pytest.approx(want, rel=1e-10)
    # a one-phone call reads E_c from the counts directly: the same choice as the graph's
    for p in phones:
        a = Alignment([p], [0.0], [0.12])
        nodes, edges, _ = m._graph(a.labels, a.durations)
        assert m.select_modes(a)[0][0] - m.phone_modes_[p][0] == int(np.argmin(nodes[0]))
        assert m.select_modes(a)[1] == pytest.approx(float(nodes[0].min()), rel=1e-12)
        assert m.explain(a)[-1]["total"] == pytest.approx(float(nodes[0].min()), rel=1e-12)


def test_em_that_stops_at_max_iter_warns_naming_the_channels():
    from dam.base import ConvergenceWarning

    corpus = make_corpus(_truth("hold", 0, degree=1), n_utterances=6, noise=0.05, random_state=0)
    with pytest.warns(
        ConvergenceWarning,
        match=r"max_iter=1 .*tol=1e-12.*x \(last relative improvement "
        r".*y \(.*Raise max_iter, or raise tol",
    ):
        m = DAM(modes="single", degree=1, max_iter=1, tol=1e-12).fit(corpus)
    assert not m.converged_.any() and np.all(m.n_iter_ == 1)
    # converged: no warning
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error", ConvergenceWarning)
        m = DAM(modes="single", degree=1, max_iter=30, tol=0.5).fit(corpus)
    assert m.converged_.all()


def test_unknown_phone_errors_or_falls_back():
    true = _truth("hold", 0, degree=1)
    corpus = make_corpus(true, n_utterances=8, random_state=0)
    m = DAM(modes="single", degree=1, max_iter=2).fit(corpus)
    a = Alignment(["a", "p", "c"], [0, 0.1, 0.2], [0.1, 0.2, 0.3])
    with pytest.raises(UnknownPhoneError, match="'p'"):
        m.predict(a)
    m.set_params(unknown_phone="fallback")  # "p" -> the seen bilabial "b"
    np.testing.assert_array_equal(m.predict(a), m.predict(a.relabel({"p": "b"})))


def test_bad_hyperparameters_are_refused_by_name():
    corpus = make_corpus(_truth("hold", 0, degree=1), n_utterances=3, random_state=0)
    for kw in (
        {"degree": -1},
        {"extrapolate": "zero"},
        {"modes": "kmeans"},
        {"sigma_init": -1.0},
        {"dominance_tol": 1.5},
        {"gn_steps": 0},
    ):
        with pytest.raises(ValueError, match=list(kw)[0]):
            DAM(**kw).fit(corpus)


def test_registry_and_m0_variant():
    assert registry.get("dam") is DAM and registry.get("dam-m0") is DAMM0
    assert DAMM0().degree == 0 and DAMM0().get_params()["modes"] == DAM().modes
    # the weighted average is the default of both (see the DAM's Notes)
    assert DAM().normalize is True and DAMM0().normalize is True
    corpus = make_corpus(_truth("hold", 0, degree=1), n_utterances=6, random_state=0)
    m = DAMM0(max_iter=2).fit(corpus)
    assert m.coef_.shape[1] == 1


def test_saved_model_loads_and_synthesizes_with_numpy_only(tmp_path):
    true = _two_mode_truth()
    corpus = make_corpus(true, n_utterances=20, mode_rule=_rule, random_state=0, phones=["a", "b", "c", "d"])
    m = DAM(extrapolate="hold", degree=2, max_iter=3).fit(corpus)
    path = tmp_path / "m.dam"
    m.save(path)
    a = corpus[1].alignment
    np.save(tmp_path / "want.npy", m.predict(a))
    code = textwrap.dedent(f"""
        import json, sys
        import numpy as np
        import dam
        from dam.corpus.data import Alignment
        m = dam.load({str(path)!r})
        a = Alignment({list(a.labels)!r}, {a.starts.tolist()!r}, {a.ends.tolist()!r})
        y = m.predict(a)
        m.explain(a)
        ok = np.array_equal(y, np.load({str(tmp_path / "want.npy")!r}))
        heavy = sorted(k for k in sys.modules if k.split('.')[0] in ('scipy', 'sklearn', 'matplotlib', 'jax'))
        print(json.dumps({{"equal": ok, "heavy": heavy}}))
    """)
    out = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        check=True,
        cwd=str(tmp_path),
        env={
            "PYTHONPATH": str(__import__("pathlib").Path(__file__).parents[1]),
            "OPENBLAS_NUM_THREADS": "1",
            "PATH": "",
        },
    )
    res = json.loads(out.stdout.strip().splitlines()[-1])
    assert res["heavy"] == []
    assert res["equal"]
    # and the round trip keeps every learned attribute
    m2 = DAM.load(path)
    for k in ("coef_", "sigma_", "mode_counts_", "n_iter_"):
        np.testing.assert_array_equal(getattr(m2, k), getattr(m, k))
    assert m2.context_counts_ == m.context_counts_ and m2.phone_modes_ == m.phone_modes_
    assert m2.single_mode_ == m.single_mode_
    assert all(np.array_equal(x, y) for x, y in zip(m2.loss_curve_, m.loss_curve_))


def test_synthetic_generator_is_deterministic_and_renders_the_model():
    true = _truth("polynomial", 0)
    c1 = make_corpus(true, n_utterances=3, noise=0.1, random_state=5)
    c2 = make_corpus(true, n_utterances=3, noise=0.1, random_state=5)
    for u1, u2 in zip(c1, c2):
        assert u1.alignment == u2.alignment
        np.testing.assert_array_equal(u1.trajectory, u2.trajectory)
    clean = make_corpus(true, n_utterances=3, random_state=5)
    for u in clean:
        np.testing.assert_array_equal(u.trajectory, true.predict(u.alignment))
    a = random_alignment(
        np.random.default_rng(0), ["a", "b"], n_segments=5, durations={"a": (0.1, 0.1), "b": (0.2, 0.2)}
    )
    assert len(a) == 5 and all(abs(d - {"a": 0.1, "b": 0.2}[p]) < 1e-12 for p, d in zip(a.labels, a.durations))
    # a model renders only at its own frame rate: another one would mislabel every frame's time
    with pytest.raises(ValueError, match="frame_rate.*50.*100 Hz"):
        make_corpus(true, n_utterances=1, frame_rate=50.0, mode_rule=lambda p, left, right: 0)


def test_cli_inspect_prints_the_report(tmp_path, capsys):
    from dam.cli import main

    m = _two_mode_truth()
    m.save(tmp_path / "m.dam")
    assert main(["inspect", str(tmp_path / "m.dam"), "--phone", "a"]) == 0
    out = capsys.readouterr().out
    assert "4 phones, 5 modes, 2 channels" in out
    assert "phone 'a': 2 mode(s)" in out and "a^0..a^M=[-1.  2.  0.]" in out
    assert main(["inspect", str(tmp_path / "missing.dam")]) == 1


@pytest.mark.filterwarnings("ignore::dam.base.ConvergenceWarning")
def test_zero_weights_of_the_search_are_an_ablation_not_a_crash():
    """w_s = 0 (context only) or w_c = 0 (smoothness only): missing modes stay impossible (0 * inf is
    not a cost), every chosen mode belongs to its phone, and the weights act without refitting."""
    import dam
    from dam.model.estimator import DAM

    train = dam.datasets.load("tiny")
    model = DAM(max_iter=2, n_resample=8, min_occurrences=4, min_mode_size=2, mode_preference="median").fit(train)
    assert max(g for _, g in model.phone_modes_.values()) > 1
    for params in ({"w_s": 0.0}, {"w_c": 0.0}, {"w_c": 0.0, "w_s": 0.0}):
        model.set_params(**params)
        for u in train:
            modes, cost = model.select_modes(u.alignment)
            for p, g in zip(u.alignment.labels, modes):
                first, n = model.phone_modes_[p]
                assert first <= g < first + n
            assert np.isfinite(cost)
            assert np.isfinite(model.predict(u.alignment)).all()
        model.set_params(w_c=1000.0, w_s=1.0)


@pytest.mark.filterwarnings("ignore::dam.base.ConvergenceWarning")
def test_predict_is_stateless_and_sees_coefficients_changed_in_place(tmp_path):
    """Issue 11: predict kept caches keyed by id(coef_), stale after an in-place change."""
    import dam
    from dam.model.estimator import DAM

    train = dam.datasets.load("tiny")
    model = DAM(max_iter=2, n_resample=8, min_occurrences=4, min_mode_size=2, mode_preference="median").fit(train)
    a = train[1].alignment
    names = set(vars(model))
    y0 = model.predict(a)
    assert set(vars(model)) == names  # predict adds nothing
    model.coef_ *= 2.0  # in place: same object, same id
    model.sigma_[:] = model.sigma_ * 0.5
    y1 = model.predict(a)
    assert set(vars(model)) == names
    model.save(tmp_path / "m.dam")
    fresh = dam.load(tmp_path / "m.dam")  # the graph rebuilt at load, from the changed state
    np.testing.assert_allclose(y1, fresh.predict(a), rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(model.select_modes(a)[0], fresh.select_modes(a)[0])
    assert not np.allclose(y0, y1)
