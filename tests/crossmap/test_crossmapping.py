"""NNLS cross-mapping (Chen et al. 2012, Appendix A): key shapes, blend weights, bounded controls."""

import numpy as np
import pytest

from dam import Alignment, Corpus, DataError, Utterance
from dam.crossmap.crossmapping import CrossMapper, blend_vertices, blend_weights, find_key_shapes, fit_controls
from dam.crossmap.rig import LinearRig


def _rig(seed=0, n_controls=5, n_dims=30):
    rng = np.random.default_rng(seed)
    return LinearRig(rng.normal(size=n_dims), rng.normal(size=(n_controls, n_dims)))


def _kkt_violation(A, b, c, lo, hi):
    """Largest violation of the optimality conditions of min ||A c - b||^2 on the box."""
    g = A.T @ (A @ c - b)
    at_lo, at_hi = np.isclose(c, lo), np.isclose(c, hi)
    free = ~(at_lo | at_hi)
    return max(np.abs(g[free]).max(initial=0), (-g[at_lo]).max(initial=0), g[at_hi].max(initial=0))


def test_known_blend_weights_recovered_exactly():
    rng = np.random.default_rng(1)
    L = rng.normal(size=(6, 40))
    alpha = rng.uniform(0, 2, size=(200, 6))
    alpha[rng.random(alpha.shape) < 0.4] = 0.0  # many exact zeros: the NNLS active set
    w = blend_weights(alpha @ L, L)
    assert w.shape == (200, 6)
    np.testing.assert_allclose(w, alpha, atol=1e-10)
    assert (w >= 0).all()


def test_blend_weights_are_the_nnls_optimum_for_frames_outside_the_cone():
    rng = np.random.default_rng(2)
    L = rng.normal(size=(4, 12))
    X = rng.normal(size=(30, 12))  # not blends: some weights must hit zero
    w = blend_weights(X, L)
    assert (w >= 0).all() and (w == 0).any()
    for x, wi in zip(X, w):
        assert _kkt_violation(L.T, x, wi, np.zeros(4), np.full(4, np.inf)) < 1e-9


def test_key_shapes_found_by_affinity_propagation():
    rng = np.random.default_rng(3)
    truth = rng.normal(scale=3.0, size=(4, 20))
    frames = np.concatenate([t + 0.05 * rng.normal(size=(40, 20)) for t in truth])
    keys, idx = find_key_shapes(frames, preference="min")
    assert len(keys) == 4
    np.testing.assert_array_equal(keys, frames[idx])  # exemplars are captured frames
    # each key shape is a noisy copy of a different true shape
    nearest = np.argmin(((keys[:, None] - truth[None]) ** 2).sum(-1), axis=1)
    assert sorted(nearest) == [0, 1, 2, 3]
    assert np.abs(keys - truth[nearest]).max() < 0.05 * 5


def test_key_shapes_subsample_keeps_exemplars_real():
    rng = np.random.default_rng(4)
    frames = np.concatenate([t + 0.01 * rng.normal(size=(300, 6)) for t in rng.normal(scale=2, size=(3, 6))])
    keys, idx = find_key_shapes(frames, preference="min", max_frames=100)
    assert len(keys) == 3
    np.testing.assert_array_equal(keys, frames[idx])


def test_affinity_propagation_without_convergence_is_an_error():
    X = np.random.default_rng(5).normal(size=(60, 5))
    with pytest.raises(ValueError, match="did not converge"):
        find_key_shapes(X, max_iter=2)


def test_blend_vertices_is_the_weighted_sum_of_target_key_shapes():
    W = np.array([[1.0, 0.0], [0.25, 0.5]])
    V = np.array([[1.0, 2.0, 3.0], [10.0, 20.0, 30.0]])
    np.testing.assert_allclose(blend_vertices(W, V), [[1, 2, 3], [5.25, 10.5, 15.75]])


def test_bounded_controls_exact_on_a_linear_rig():
    rig = _rig()
    c = np.random.default_rng(6).uniform(0.02, 0.98, size=(100, rig.n_controls))
    np.testing.assert_allclose(fit_controls(rig(c), rig), c, atol=1e-10)


def test_bounded_controls_stay_in_range_when_out_of_reach():
    rig = _rig(seed=7)
    c = np.random.default_rng(8).uniform(-1.0, 2.0, size=(60, rig.n_controls))
    est = fit_controls(rig(c), rig)
    assert est.min() >= 0.0 and est.max() <= 1.0
    assert ((c < 0) | (c > 1)).any()
    A = rig.deltas.T
    for v, ci in zip(rig(c), est):
        assert _kkt_violation(A, v - rig.neutral, ci, 0.0, 1.0) < 1e-8


def test_bounded_controls_of_an_orthogonal_rig_are_the_clipped_solution():
    # With orthonormal blendshapes the box-constrained optimum is the clipped unconstrained one.
    Q, _ = np.linalg.qr(np.random.default_rng(9).normal(size=(20, 4)))
    rig = LinearRig(np.zeros(20), Q.T)
    c = np.random.default_rng(10).uniform(-1, 2, size=(50, 4))
    np.testing.assert_allclose(fit_controls(rig(c), rig), np.clip(c, 0, 1), atol=1e-12)


def test_custom_bounds_and_bare_matrix_rig():
    D = np.random.default_rng(11).normal(size=(3, 9))
    c = np.array([[-0.5, 0.2, 1.5]])
    est = fit_controls(c @ D, D, bounds=([-1, 0, 0], [0, 1, 2]))
    np.testing.assert_allclose(est, c, atol=1e-12)


def test_nonlinear_rig_function_recovers_controls_and_respects_bounds():
    rng = np.random.default_rng(12)
    rig = _rig(seed=13, n_controls=4, n_dims=24)
    E = rng.normal(size=(4, 24))

    def f(c):
        return rig(c) + 0.3 * (np.asarray(c) ** 2) @ E

    c = np.cumsum(rng.normal(scale=0.05, size=(40, 4)), axis=0) % 0.8 + 0.1  # a smooth-ish path in (0, 1)
    est = fit_controls(np.array([f(ci) for ci in c]), f, n_controls=4)
    np.testing.assert_allclose(est, c, atol=1e-6)
    far = np.array([f(ci) for ci in rng.uniform(-1, 2, size=(10, 4))])
    est = fit_controls(far, f, n_controls=4, jacobian=lambda c_: rig.deltas.T + 0.6 * (E * c_[:, None]).T)
    assert est.min() >= 0 and est.max() <= 1


def _corpus(trajs, fr=100.0):
    utts = []
    for k, T in enumerate(trajs):
        n = len(T)
        al = Alignment(
            ["sil", "a", "sil"], [0, n / fr / 3, 2 * n / fr / 3], [n / fr / 3, 2 * n / fr / 3, n / fr], source=f"u{k}"
        )
        utts.append(Utterance(al, T, fr, [f"d{j}" for j in range(T.shape[1])], name=f"u{k}"))
    return Corpus(utts, name="captured")


def test_crossmapper_maps_a_corpus_to_controls_with_alignments_kept():
    rng = np.random.default_rng(14)
    L = rng.normal(size=(3, 16))  # captured key shapes
    rig = _rig(seed=15, n_controls=4, n_dims=20)
    C_k = rng.uniform(0, 1, size=(3, 4))  # the artist's poses of the key shapes
    V_k = rig(C_k)
    alphas = [rng.dirichlet(np.ones(3), size=n) for n in (30, 45)]  # convex blends
    captured = _corpus([a @ L for a in alphas])
    cm = CrossMapper(
        key_shapes=L, target_key_shapes=V_k, rig=LinearRig(rig.neutral, rig.deltas, control_names=list("jklm"))
    )
    out = cm.fit(captured).transform(captured)
    assert isinstance(out, Corpus) and out.channels == tuple("jklm")
    for u_in, u_out, a in zip(captured, out, alphas):
        assert u_out.alignment == u_in.alignment and u_out.name == u_in.name
        # linear rig + convex blends: the controls are the same blend of the artist's poses
        np.testing.assert_allclose(u_out.trajectory, a @ C_k, atol=1e-9)
    np.testing.assert_allclose(cm.weights(captured[0].trajectory), alphas[0], atol=1e-10)


def test_crossmapper_without_target_returns_blend_weights():
    rng = np.random.default_rng(16)
    frames = np.concatenate([t + 0.02 * rng.normal(size=(30, 8)) for t in rng.normal(scale=2, size=(3, 8))])
    cm = CrossMapper(preference="min").fit(frames)
    w = cm.transform(frames)
    assert w.shape == (90, len(cm.key_shapes_)) and (w >= 0).all()
    np.testing.assert_allclose(w @ cm.key_shapes_, frames, atol=0.2)
    assert cm.get_params()["preference"] == "min"
    K = len(cm.key_shapes_)
    named = cm.set_params(control_names=[f"s{k}" for k in range(K)]).transform(_corpus([frames]))
    assert named.channels == tuple(f"s{k}" for k in range(K))
    np.testing.assert_array_equal(named[0].trajectory, w)
    with pytest.raises(DataError, match=f"expected {K} names"):
        cm.set_params(control_names=["only"]).transform(frames)


@pytest.mark.parametrize(
    "bad, field",
    [
        (lambda L: (np.where(np.arange(40).reshape(5, 8) == 11, np.nan, 1.0), L), "frames[1, 3]"),
        (lambda L: (np.ones((5, 7)), L), "frames"),
        (lambda L: (np.ones((5, 8)), np.ones((2, 3, 8))), "key_shapes"),
    ],
)
def test_bad_input_names_the_field(bad, field):
    L = np.eye(8)[:3]
    X, K = bad(L)
    with pytest.raises(DataError) as err:
        blend_weights(X, K)
    assert err.value.field == field


def test_bad_bounds_and_rig_are_errors():
    rig = _rig()
    with pytest.raises(DataError, match="lower bound"):
        fit_controls(rig(np.zeros((1, 5))), rig, bounds=(1.0, 0.0))
    with pytest.raises(DataError, match="n_controls"):
        fit_controls(np.zeros((1, 30)), lambda c: c)
    with pytest.raises(DataError, match="vertices"):
        fit_controls(np.zeros((1, 29)), rig)
    cm = CrossMapper(key_shapes=np.eye(4)[:2], target_key_shapes=np.ones((3, 30)), rig=rig).fit(np.eye(4))
    with pytest.raises(DataError, match="one row per key shape"):
        cm.transform(np.eye(4))
    with pytest.raises(DataError, match="n_dims"):
        CrossMapper(key_shapes=np.eye(5)).fit(np.eye(4))


def test_cli_crossmap_writes_controls_and_names_bad_files(tmp_path, capsys):
    from dam.cli import main
    from dam.corpus.io import load_corpus, save_corpus

    rng = np.random.default_rng(17)
    L = rng.normal(size=(3, 8))
    rig = _rig(seed=18, n_controls=4, n_dims=10)
    C_k = rng.uniform(0, 1, size=(3, 4))
    alphas = [rng.dirichlet(np.ones(3), size=n) for n in (20, 30)]
    save_corpus(_corpus([a @ L for a in alphas]), tmp_path / "captured")
    np.save(tmp_path / "keys.npy", L)
    np.savetxt(tmp_path / "posed.csv", rig(C_k), delimiter=",")
    np.save(tmp_path / "deltas.npy", rig.deltas)
    np.save(tmp_path / "neutral.npy", rig.neutral)
    args = [
        "-q",
        "crossmap",
        str(tmp_path / "captured"),
        "--key-shapes",
        str(tmp_path / "keys.npy"),
        "--target-key-shapes",
        str(tmp_path / "posed.csv"),
        "--rig-deltas",
        str(tmp_path / "deltas.npy"),
        "--rig-neutral",
        str(tmp_path / "neutral.npy"),
        "--control-names",
        "j,k,l,m",
        "-o",
        str(tmp_path / "controls"),
    ]
    assert main(args) == 0
    out = load_corpus(tmp_path / "controls")
    assert out.channels == tuple("jklm")
    for u, a in zip(out, alphas):
        np.testing.assert_allclose(u.trajectory, a @ C_k, atol=1e-5)  # CSV keeps 6 decimals
    # key shapes found and saved for the artist
    assert (
        main(
            [
                "-q",
                "crossmap",
                str(tmp_path / "captured"),
                "--preference",
                "min",
                "--save-key-shapes",
                str(tmp_path / "found.csv"),
            ]
        )
        == 0
    )
    assert np.loadtxt(tmp_path / "found.csv", delimiter=",", ndmin=2).shape[1] == 8
    # a key-shape file of the wrong width: the error names the file and the field
    np.save(tmp_path / "bad.npy", np.ones((3, 7)))
    assert main(["crossmap", str(tmp_path / "captured"), "--key-shapes", str(tmp_path / "bad.npy")]) == 1
    err = capsys.readouterr().err
    assert "bad.npy" in err and "key_shapes" in err and "(3, 7)" in err


def test_transform_before_fit_is_a_not_fitted_error():
    from dam import NotFittedError
    from dam.crossmap.landmarks import LandmarkSolver
    from dam.crossmap.retarget import RigSpaceRetargeter

    for est in (CrossMapper(), RigSpaceRetargeter(), LandmarkSolver(rig=np.eye(2))):
        with pytest.raises(NotFittedError, match=f"{type(est).__name__} is not fitted"):
            est.transform(np.ones((3, 2)))


@pytest.mark.parametrize(
    "cls, bad",
    [
        ("CrossMapper", {"damping": 1.5}),
        ("CrossMapper", {"max_iter": 0}),
        ("RigSpaceRetargeter", {"n_modes": 0}),
        ("LandmarkSolver", {"alpha": -1.0}),
    ],
)
def test_crossmap_estimators_follow_dams_one_contract(cls, bad):
    """One estimator framework: the cross-mapping transformers are dam Estimators (declared
    constraints, get/set_params, dam.clone), not a second, scikit-learn-based one."""
    import dam
    from dam.base import Estimator, InvalidParameterError, Transformer

    klass = getattr(dam.crossmap, cls)
    assert issubclass(klass, Transformer) and issubclass(klass, Estimator)
    assert not any(c.__module__.startswith("sklearn") for c in klass.__mro__)
    est = klass(**bad)
    assert dam.clone(est).get_params() == est.get_params()
    ((name, value),) = bad.items()
    frames = np.random.default_rng(0).normal(size=(30, 6))
    with pytest.raises(InvalidParameterError, match=name):
        est.fit(frames)
