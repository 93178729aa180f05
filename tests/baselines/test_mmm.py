"""MMM (Ezzat et al. 2002): banded solves, the adjoint gradient, recovery of known Gaussians."""

import numpy as np
import pytest

from baselines.mmm import MMM, banded_cholesky_solve, difference_gram_banded, mmm_system, synthesis_loss_and_gradient
from dam.corpus.data import Alignment, Corpus, Utterance

PHONES = ["aa", "m", "s", "sil"]
TRUE_MEAN = np.array([[1.0, -0.5], [0.0, 0.8], [0.5, 0.2], [0.2, 0.0]])
TRUE_VAR = np.array([[0.5, 0.2], [0.01, 0.05], [0.1, 0.4], [0.3, 0.3]])
TRUE_LAMBDA = 20.0


def _dense(ab):
    n = ab.shape[-1]
    M = np.zeros((n, n))
    for k in range(ab.shape[0]):
        idx = np.arange(n - k)
        M[idx + k, idx] = M[idx, idx + k] = ab[k, : n - k]
    return M


@pytest.mark.parametrize("order", [1, 2])
def test_difference_gram_is_WtW(order):
    n = 9
    W = np.diff(np.eye(n), n=order, axis=0)
    np.testing.assert_allclose(_dense(difference_gram_banded(n, order)), W.T @ W)


@pytest.mark.parametrize("order", [1, 2])
def test_banded_solves_equal_dense_solve(order):
    from scipy.linalg import solveh_banded

    rng = np.random.default_rng(order)
    n = 40
    prec = rng.uniform(0.1, 5.0, size=(3, n))  # a batch of three channels
    b = rng.normal(size=(3, n))
    M = mmm_system(prec, difference_gram_banded(n, order), 7.0)
    ours = banded_cholesky_solve(M, b)
    for c in range(3):
        dense = np.linalg.solve(_dense(M[c]), b[c])
        np.testing.assert_allclose(ours[c], dense, rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(solveh_banded(M[c], b[c], lower=True), dense, rtol=1e-10, atol=1e-12)


def test_solution_minimises_the_mmm_energy():
    # y* minimises (y-mu)^T A (y-mu) + lam y^T W^T W y: any perturbation raises the energy
    rng = np.random.default_rng(0)
    n, lam = 25, 3.0
    A, mu = rng.uniform(0.5, 2, n), rng.normal(size=n)
    W = np.diff(np.eye(n), n=2, axis=0)
    y = banded_cholesky_solve(mmm_system(A, difference_gram_banded(n, 2), lam), A * mu)
    energy = lambda v: (v - mu) @ (A * (v - mu)) + lam * np.sum((W @ v) ** 2)  # noqa: E731
    for _ in range(5):
        assert energy(y + 1e-3 * rng.normal(size=n)) > energy(y)


def test_banded_cholesky_refuses_indefinite():
    ab = np.array([[1.0, -1.0, 1.0], [2.0, 0.0, 0.0]])
    with pytest.raises(np.linalg.LinAlgError):
        banded_cholesky_solve(ab, np.ones(3))


def _random_alignment(rng, n_segments=9):
    labels = ["sil"] + list(rng.choice(PHONES[:3], size=n_segments - 2)) + ["sil"]
    for k in range(1, len(labels)):
        if labels[k] == labels[k - 1]:
            labels[k] = "aa" if labels[k] != "aa" else "m"
    ends = np.cumsum(rng.uniform(0.05, 0.2, size=len(labels)))
    return Alignment(labels, np.r_[0.0, ends[:-1]], ends)


def _generated_corpus(n_utts=14, seed=0):
    """A corpus synthesised by the MMM itself (standardisation undone below)."""
    rng = np.random.default_rng(seed)
    utts = []
    for k in range(n_utts):
        a = _random_alignment(rng)
        n = a.n_frames(100)
        seg = a.segment_index(100, n)
        rows = np.array([PHONES.index(lab) for lab in a.labels])[seg]
        dw = 1.0 / np.bincount(seg)[seg]
        A = (dw[:, None] / TRUE_VAR[rows]).T
        y = banded_cholesky_solve(mmm_system(A, difference_gram_banded(n, 2), TRUE_LAMBDA), A * TRUE_MEAN[rows].T).T
        utts.append(Utterance(a, y, 100, ["x", "y"], name=f"u{k}"))
    return Corpus(utts)


def test_adjoint_gradient_matches_finite_differences():
    corpus = _generated_corpus(n_utts=3, seed=4)
    utts = []
    for u in corpus:
        seg = u.alignment.segment_index(100, u.n_frames)
        rows = np.array([PHONES.index(lab) for lab in u.alignment.labels])[seg]
        utts.append((rows, 1.0 / np.bincount(seg)[seg], difference_gram_banded(u.n_frames, 2), u.trajectory[:, 0]))
    rng = np.random.default_rng(1)
    mu, lv = rng.normal(size=4), rng.normal(-1, 0.5, size=4)
    _, gm, gl = synthesis_loss_and_gradient(mu, lv, utts, 5.0)
    h = 1e-6
    for k in range(4):
        e = np.zeros(4)
        e[k] = h
        fd_mu = (
            synthesis_loss_and_gradient(mu + e, lv, utts, 5.0)[0]
            - synthesis_loss_and_gradient(mu - e, lv, utts, 5.0)[0]
        ) / (2 * h)
        fd_lv = (
            synthesis_loss_and_gradient(mu, lv + e, utts, 5.0)[0]
            - synthesis_loss_and_gradient(mu, lv - e, utts, 5.0)[0]
        ) / (2 * h)
        np.testing.assert_allclose([gm[k], gl[k]], [fd_mu, fd_lv], rtol=1e-5, atol=1e-8)


def test_recovers_known_means_and_variances():
    corpus = _generated_corpus()
    scale = np.concatenate(corpus.trajectories).std(axis=0)
    # lambda is per standardised channel: give the generating value in those units
    model = MMM(smoothness=(TRUE_LAMBDA * scale[0] ** 2,), max_iter=500).fit(_only_channel(corpus, 0))
    assert model.phones_ == PHONES
    np.testing.assert_allclose(model.mean_[:, 0], TRUE_MEAN[:, 0], atol=1e-3)
    np.testing.assert_allclose(model.var_[:, 0], TRUE_VAR[:, 0], rtol=2e-2)
    for u in _generated_corpus(n_utts=2, seed=7):
        np.testing.assert_allclose(model.predict(u.alignment)[:, 0], u.trajectory[:, 0], atol=1e-3)


def test_validation_chooses_the_generating_smoothness_among_far_candidates():
    corpus = _only_channel(_generated_corpus(), 1)
    scale = np.concatenate(corpus.trajectories).std()
    right = TRUE_LAMBDA * scale**2
    # with the variances fixed at their starting values (max_iter=0) only lambda differs
    model = MMM(smoothness=(right / 1000, right, right * 1000), max_iter=0).fit(corpus)
    assert model.smoothness_ == right, model.validation_rmse_


def _only_channel(corpus, c):
    return Corpus([u.replace(trajectory=u.trajectory[:, [c]], channels=[u.channels[c]]) for u in corpus])


def test_synthesis_without_scipy_equals_with_scipy(monkeypatch):
    import builtins

    model = MMM(smoothness=(10.0,), max_iter=5).fit(_generated_corpus(n_utts=4))
    a = _generated_corpus(n_utts=1, seed=3)[0].alignment
    with_scipy = model.predict(a)
    real_import = builtins.__import__

    def no_scipy(name, *args, **kwargs):
        if name.startswith("scipy"):
            raise ImportError("scipy hidden by the test")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_scipy)
    np.testing.assert_allclose(model.predict(a), with_scipy, rtol=1e-10, atol=1e-12)


def test_concatenated_utterances_solve_as_separate_ones():
    from baselines.mmm import _concatenated

    rng = np.random.default_rng(2)
    parts = []
    for n in (7, 12, 5):
        A = rng.uniform(0.5, 2, n)
        parts.append((A, difference_gram_banded(n, 2), rng.normal(size=n)))
    separate = np.concatenate([banded_cholesky_solve(mmm_system(A, g, 3.0), A * m) for A, g, m in parts])
    ((_, A, g, m),) = _concatenated([(np.zeros(len(A), int), A, g, m) for A, g, m in parts])
    np.testing.assert_allclose(banded_cholesky_solve(mmm_system(A, g, 3.0), A * m), separate, rtol=1e-12)


def test_training_start_uses_only_the_given_utterances():
    from baselines.mmm import _phone_start

    # two "utterances": phone 0 in both, phone 1 only in the second, phone 2 in neither
    part1 = (np.array([0, 0]), None, None, np.array([[1.0], [3.0]]))
    part2 = (np.array([0, 1, 1]), None, None, np.array([[5.0], [-1.0], [1.0]]))
    mu0, lv0 = _phone_start([part1], 3, 1e-4)
    # phones without frames in the given part start at the standardised mean 0, variance 1
    np.testing.assert_allclose(mu0[:, 0], [2.0, 0.0, 0.0])
    np.testing.assert_allclose(np.exp(lv0[:, 0]), [1.0, 1.0, 1.0])
    mu0, lv0 = _phone_start([part1, part2], 3, 1e-4)
    np.testing.assert_allclose(mu0[:, 0], [3.0, 0.0, 0.0])
    np.testing.assert_allclose(np.exp(lv0[:, 0]), [8 / 3, 1.0, 1.0])
