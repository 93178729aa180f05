"""The DAM's pieces against the paper's equations: dominance (Eq. 1), animemes,
Eq. (2) by hand, the E-step (Eqs. 3-7) against a dense solve, the M-step's
Jacobian against finite differences, and a non-increasing training error."""

import numpy as np
import pytest

from dam.base import ConvergenceWarning
from dam.corpus.data import Alignment, Corpus, Utterance
from dam.model import animeme, synthesis
from dam.model.dominance import dominance, dominance_dsigma, reach
from dam.model.em import fit_em
from dam.model.estep import Occurrences, design_matrix, fitted_values, normal_equations, pairs, solve_normal_equations
from dam.model.mstep import gauss_newton_sigma, jacobian
from dam.model.synthesis import concatenate


# -- Eq. (1) ------------------------------------------------------------------
def test_dominance_matches_eq1_by_hand():
    s, eps = 0.5, 1e-8
    t = np.array([-1.0, -0.25, 0.0, 0.4, 1.0, 1.5, 2.0])
    want = [
        np.exp(-1.0 / (s * s + eps)),
        np.exp(-0.0625 / (s * s + eps)),
        1,
        1,
        1,
        np.exp(-0.25 / (s * s + eps)),
        np.exp(-1.0 / (s * s + eps)),
    ]
    np.testing.assert_allclose(dominance(t, s, eps), want, rtol=1e-14)


def test_dominance_truncation_and_reach():
    s, tol = 0.3, 1e-3
    r = reach(s, 1e-8, tol)
    assert dominance(-r * 0.999, s, 1e-8, tol) > 0.0
    assert dominance(1 + r * 1.001, s, 1e-8, tol) == 0.0
    assert dominance(-r * 1.001, s, 1e-8, tol) == 0.0
    # the jump left by truncation is at most tol
    assert dominance(-r * 0.9999, s, 1e-8, tol) < tol * 1.01


def test_dominance_derivative_matches_finite_differences():
    t = np.linspace(-2.5, 3.5, 61)
    for s in (0.1, 0.4, 1.3):
        h = 1e-6 * s
        fd = (dominance(t, s + h) - dominance(t, s - h)) / (2 * h)
        np.testing.assert_allclose(dominance_dsigma(t, s), fd, rtol=1e-6, atol=1e-9)
    assert np.all(dominance_dsigma(np.array([0.0, 0.5, 1.0]), 0.7) == 0.0)


# -- animemes -------------------------------------------------------------------
def test_legendre_basis_is_the_same_polynomial_as_the_monomials():
    rng = np.random.default_rng(0)
    mono = rng.normal(size=(5, 3))
    leg = animeme.monomial_to_legendre(mono)
    np.testing.assert_allclose(animeme.legendre_to_monomial(leg), mono, atol=1e-12)
    t = np.linspace(-1.5, 2.5, 41)  # outside [0, 1] too: "polynomial" extrapolation
    direct = np.stack([np.polyval(mono[::-1, c], t) for c in range(3)], axis=1)
    np.testing.assert_allclose(animeme.evaluate(leg, t), direct, atol=1e-10)


def test_hold_extrapolation_holds_the_edge_values():
    leg = np.array([0.3, -1.0, 0.5])
    t = np.array([-2.0, -0.1, 0.0, 1.0, 1.7])
    v = animeme.evaluate(leg, t, "hold")
    assert v[0] == v[1] == v[2] and v[3] == v[4]
    assert v[0] == pytest.approx(0.3 + 1.0 + 0.5)  # P0=1, P1(-1)=-1, P2(-1)=1
    with pytest.raises(ValueError, match="extrapolate"):
        animeme.basis(t, 2, "zero")


def test_boundary_derivatives_match_the_monomial_form():
    mono = np.array([[1.0], [2.0], [-3.0], [0.5]])  # 1 + 2t - 3t^2 + 0.5t^3
    e = animeme.boundary_derivatives(animeme.monomial_to_legendre(mono))
    np.testing.assert_allclose(e[0, :, 0], [1.0, 2.0, -6.0], atol=1e-12)
    np.testing.assert_allclose(e[1, :, 0], [0.5, -2.5, -3.0], atol=1e-12)


# -- Eq. (2) by hand ----------------------------------------------------------------
def test_eq2_plain_sum_and_weighted_average_by_hand():
    # two segments [0, 0.1) and [0.1, 0.3) at 20 frames/s: frames at 0, .05, ..., .25
    starts, ends = np.array([0.0, 0.1]), np.array([0.1, 0.3])
    mono = np.array([[[1.0], [2.0]], [[-1.0], [0.0]]])  # A1 = 1 + 2t, A2 = -1
    coef = np.stack([animeme.monomial_to_legendre(m) for m in mono])
    sigma = np.array([[0.5], [0.25]])
    eps = 1e-8
    got_sum = concatenate(starts, ends, coef, sigma, 20.0, 6, tol=0.0, eps=eps)
    got_avg = concatenate(starts, ends, coef, sigma, 20.0, 6, normalize=True, tol=0.0, eps=eps)
    for i in range(6):
        t1 = (i / 20 - 0.0) / 0.1
        t2 = (i / 20 - 0.1) / 0.2
        d1 = 1.0 if t1 <= 1 else np.exp(-((t1 - 1) ** 2) / (0.25 + eps))
        d2 = 1.0 if t2 >= 0 else np.exp(-(t2**2) / (0.0625 + eps))
        a1, a2 = 1 + 2 * t1, -1.0
        assert got_sum[i, 0] == pytest.approx(d1 * a1 + d2 * a2, abs=1e-12)
        assert got_avg[i, 0] == pytest.approx((d1 * a1 + d2 * a2) / (d1 + d2), abs=1e-12)


@pytest.mark.parametrize("normalize,extrapolate", [(False, "polynomial"), (True, "polynomial"), (True, "hold")])
@pytest.mark.parametrize("n_seg", [1, 2, 9])
@pytest.mark.parametrize("pairs", ["windowed", "dense"])
def test_eq2_with_truncation_matches_a_frame_by_frame_reference(normalize, extrapolate, n_seg, pairs, monkeypatch):
    # Eq. (1) and (2) written out frame by frame and segment by segment, with the
    # monomial animemes of the paper: three channels, overlapping tails, truncation;
    # both ways synthesis enumerates (frame, segment) pairs: within the dominance
    # windows, and all of them (what it does for a few phones)
    monkeypatch.setattr(synthesis, "DENSE_PAIRS", 0 if pairs == "windowed" else 10**9)
    rng = np.random.default_rng(7 + n_seg)
    d = rng.uniform(0.04, 0.2, n_seg)
    ends = np.cumsum(d)
    starts = ends - d
    fr, n = 100.0, int(np.ceil(ends[-1] * 100.0))
    mono = rng.normal(size=(n_seg, 5, 3))  # a^0 .. a^4 per segment and channel
    sigma = rng.uniform(0.05, 0.9, (n_seg, 3))
    eps, tol = 1e-8, 1e-3
    coef = np.stack([animeme.monomial_to_legendre(m) for m in mono])
    got = concatenate(starts, ends, coef, sigma, fr, n, normalize=normalize, extrapolate=extrapolate, eps=eps, tol=tol)
    want = np.zeros((n, 3))
    for i in range(n):
        for c in range(3):
            num = den = 0.0
            for j in range(n_seg):
                t = (i / fr - starts[j]) / d[j]
                u = max(-t, 0.0, t - 1.0)
                D = np.exp(-u * u / (sigma[j, c] ** 2 + eps))
                D = 0.0 if D < tol else D
                tt = min(max(t, 0.0), 1.0) if extrapolate == "hold" else t
                A = sum(mono[j, m, c] * tt**m for m in range(5))
                num += D * A
                den += D
            want[i, c] = num / den if normalize else num
    np.testing.assert_allclose(got, want, rtol=1e-11, atol=1e-11)


# -- a small training problem -----------------------------------------------------------
def _small_problem(normalize=False, extrapolate="polynomial", seed=0, n_utt=4, degree=2):
    rng = np.random.default_rng(seed)
    utts, modes = [], []
    for _k in range(n_utt):
        n = 7
        d = rng.uniform(0.05, 0.15, n)
        e = np.cumsum(d)
        labels = rng.integers(0, 3, n)
        a = Alignment([f"p{m}" for m in labels], e - d, e)
        nf = a.n_frames(100.0)
        utts.append(Utterance(a, rng.normal(size=(nf, 2)), 100.0, ["x", "y"]))
        modes.append(labels)
    corpus = Corpus(utts)
    occ = Occurrences.from_corpus(
        corpus, modes, 3, degree=degree, normalize=normalize, extrapolate=extrapolate, tol=1e-4
    )
    Y = np.concatenate(corpus.trajectories)
    return occ, Y


@pytest.mark.parametrize("normalize", [False, True])
def test_estep_equals_dense_least_squares(normalize):
    occ, Y = _small_problem(normalize=normalize)
    sigma = np.array([0.3, 0.7, 0.5])
    X = design_matrix(occ, sigma).toarray()
    # Eq. (7): the dense design built occurrence by occurrence, repeated modes summed
    k, row, t, D = pairs(occ, sigma)
    Xd = np.zeros_like(X)
    B = animeme.basis(t, occ.degree)
    S = np.bincount(row, weights=D, minlength=occ.n_rows) if normalize else np.ones(occ.n_rows)
    for p in range(len(k)):
        m = occ.mode[k[p]]
        Xd[row[p], m * 3 : (m + 1) * 3] += D[p] * B[p] / S[row[p]]
    np.testing.assert_allclose(X, Xd, atol=1e-13)
    ref = np.linalg.lstsq(Xd, Y, rcond=None)[0]
    G, XtY = normal_equations(occ, sigma, Y)
    np.testing.assert_allclose(G, Xd.T @ Xd, rtol=1e-10, atol=1e-10)
    got, _ = solve_normal_equations(G, XtY, 0.0)
    np.testing.assert_allclose(got, ref, rtol=1e-7, atol=1e-9)
    # and the model evaluated with those coefficients is X a
    pred, _ = fitted_values(occ, got[:, 0].reshape(3, 3), sigma)
    np.testing.assert_allclose(pred, Xd @ got[:, 0], atol=1e-10)


@pytest.mark.parametrize("normalize,extrapolate", [(False, "polynomial"), (True, "polynomial"), (False, "hold")])
def test_jacobian_matches_finite_differences(normalize, extrapolate):
    occ, Y = _small_problem(normalize=normalize, extrapolate=extrapolate, seed=1)
    occ.tol = 0.0  # no truncation: the model is smooth in sigma
    rng = np.random.default_rng(2)
    coef = rng.normal(size=(3, 3))
    sigma = np.array([0.35, 0.6, 0.9])
    J = jacobian(occ, coef, sigma).toarray()  # d pred / d log sigma
    for b in range(3):
        h = 1e-6
        up, dn = sigma.copy(), sigma.copy()
        up[b] *= np.exp(h)
        dn[b] *= np.exp(-h)
        fd = (fitted_values(occ, coef, up)[0] - fitted_values(occ, coef, dn)[0]) / (2 * h)
        np.testing.assert_allclose(J[:, b], fd, rtol=1e-5, atol=1e-8)


@pytest.mark.parametrize("normalize", [False, True])
def test_mstep_products_are_those_of_the_jacobian(normalize):
    # the M-step never forms J: its J^T J, J^T f and X^T J must be the checked Jacobian's
    from dam.model.mstep import _products

    occ, Y = _small_problem(normalize=normalize, seed=5)
    rng = np.random.default_rng(6)
    coef, sigma, y = rng.normal(size=(3, 3)), np.array([0.3, 0.5, 0.8]), Y[:, 0]
    cur = fitted_values(occ, coef, sigma)
    J = jacobian(occ, coef, sigma, cur).toarray()
    X = design_matrix(occ, sigma).toarray()
    f = y - cur[0]
    H, g, K = _products(occ, y, cur, coef, sigma, projected=True)
    np.testing.assert_allclose(H, J.T @ J, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(g, J.T @ f, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(K, X.T @ J, rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("projected", [True, False])
def test_training_error_never_increases(projected):
    occ, Y = _small_problem(seed=3, n_utt=6)
    with pytest.warns(ConvergenceWarning, match="max_iter=12"):  # tol=0 is never met
        coef, sigma, curves, n_iter, conv = fit_em(occ, Y, sigma_init=1.0, tol=0.0, max_iter=12, projected=projected)
    for c in curves:
        assert len(c) >= 3
        assert np.all(np.diff(c) <= 1e-12 * c[0]), np.diff(c)
        assert c[-1] < c[0]
    assert np.all(sigma > 0)


def test_mstep_returns_no_worse_objective_and_positive_sigma():
    occ, Y = _small_problem(seed=4)
    y = Y[:, 0]
    G, Xty = normal_equations(occ, np.ones(3), y)
    a, _ = solve_normal_equations(G, Xty[:, 0], 1e-6)
    a = a.reshape(3, 3)
    r = y - fitted_values(occ, a, np.ones(3))[0]
    before = r @ r + 1e-6 * np.sum(a * a)
    s, a2, after, _ = gauss_newton_sigma(occ, y, a, np.ones(3), lam=1e-6, projected=True, n_steps=3)
    assert after <= before and np.all(s > 0)
    r2 = y - fitted_values(occ, a2, s)[0]
    assert after == pytest.approx(r2 @ r2 + 1e-6 * np.sum(a2 * a2), rel=1e-10)


# -- modes (Section V-A) -------------------------------------------------------------
def test_resampling_reproduces_a_cubic_exactly():
    from dam.model.modes import resample_occurrences

    fr = 100.0
    t = np.arange(60) / fr
    traj = np.stack([1 + 2 * t - 3 * t**2 + 4 * t**3, -t], axis=1)
    starts, ends = np.array([0.05, 0.213]), np.array([0.213, 0.4])
    out = resample_occurrences(traj, fr, starts, ends, 7)
    u = np.linspace(0, 1, 7)
    for j in range(2):
        tt = starts[j] + u * (ends[j] - starts[j])
        np.testing.assert_allclose(out[j, :, 0], 1 + 2 * tt - 3 * tt**2 + 4 * tt**3, atol=1e-10)
        np.testing.assert_allclose(out[j, :, 1], -tt, atol=1e-12)


def test_cluster_modes_finds_separated_shapes_and_records_single_modes():
    from dam.model.modes import cluster_modes

    rng = np.random.default_rng(0)
    up, down = np.linspace(0, 1, 10), np.linspace(1, 0, 10)
    X = np.vstack([up + 0.01 * rng.normal(size=(12, 10)), down + 0.01 * rng.normal(size=(9, 10))])
    res = cluster_modes(X, random_state=0)
    assert res.n_modes == 2 and res.reason == ""
    assert len(set(res.labels[:12])) == 1 and len(set(res.labels[12:])) == 1 and res.labels[0] != res.labels[12]
    assert res.labels[0] == 0  # modes ordered by size: the larger cluster is mode 0
    few = cluster_modes(X[:4], min_occurrences=6)
    assert few.n_modes == 1 and "too few occurrences (4 < 6)" in few.reason
    same = cluster_modes(np.ones((8, 10)))
    assert same.n_modes == 1 and "identical" in same.reason
    stuck = cluster_modes(rng.normal(size=(30, 10)), preference="median", max_iter=2, damping=0.99)
    assert stuck.n_modes == 1 and "did not converge" in stuck.reason
    single = cluster_modes(X, method="single")
    assert single.n_modes == 1 and "single" in single.reason
    # a tiny cluster is merged into its nearest neighbour
    X3 = np.vstack([X, np.full((2, 10), 5.0)])
    merged = cluster_modes(X3, min_mode_size=3, preference="median", random_state=0)
    assert merged.labels[-1] == merged.labels[-2] and np.bincount(merged.labels).min() >= 3
