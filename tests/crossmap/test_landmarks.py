"""Landmark-to-rig solve (Medina et al. 2022, Sec. 7, Eqs. 2-4)."""

import numpy as np
import pytest

from dam import Alignment, Corpus, DataError, Utterance
from dam.crossmap.landmarks import (
    LandmarkSolver,
    landmark_targets,
    similarity_transform,
    solve_landmarks,
    tied_parameters,
)
from dam.crossmap.rig import LinearRig


def _rig(seed=0, n_params=5, n_coords=12):
    rng = np.random.default_rng(seed)
    return LinearRig(rng.normal(size=n_coords), rng.normal(size=(n_params, n_coords)))


def _path(seed, n, p):
    """A smooth parameter trajectory inside (0, 1)."""
    t = np.linspace(0, 1, n)[:, None]
    phase = np.random.default_rng(seed).uniform(0, 2 * np.pi, p)
    return 0.5 + 0.4 * np.sin(2 * np.pi * t + phase)


def test_known_parameters_are_recovered_from_their_landmarks():
    rig = _rig()
    theta = _path(1, 40, 5)
    est = solve_landmarks(rig(theta), rig, alpha=0.0)
    np.testing.assert_allclose(est, theta, atol=1e-6)
    # the paper's prior weight biases the solution only slightly
    est = solve_landmarks(rig(theta), rig, alpha=0.01)
    assert np.abs(est - theta).max() < 0.01


def test_nonlinear_rig_with_jacobian_recovers_parameters():
    rig = _rig(seed=2, n_params=3, n_coords=10)
    E = np.random.default_rng(3).normal(size=(3, 10))

    def f(th):
        return rig(th) + 0.5 * np.sin(th) @ E

    def jac(th):
        return rig.deltas.T + 0.5 * (E * np.cos(th)[:, None]).T

    theta = _path(4, 25, 3)
    Y = np.array([f(t) for t in theta])
    np.testing.assert_allclose(solve_landmarks(Y, f, alpha=0.0, n_params=3, jacobian=jac), theta, atol=1e-6)
    # finite-difference gradient when no Jacobian is given
    np.testing.assert_allclose(solve_landmarks(Y[:5], f, alpha=0.0, n_params=3), theta[:5], atol=1e-4)


def test_l1_prior_gives_sparser_solutions_than_none():
    rng = np.random.default_rng(5)
    rig = LinearRig(np.zeros(4), rng.normal(size=(10, 4)))  # 10 parameters, 4 coordinates: redundant
    theta = np.zeros((30, 10))
    for t in range(30):
        theta[t, rng.choice(10, 2, replace=False)] = rng.uniform(0.3, 0.8, 2)
    dense, info0 = solve_landmarks(rig(theta), rig, alpha=0.0, return_info=True)
    sparse, info1 = solve_landmarks(rig(theta), rig, alpha=0.01, return_info=True)
    nnz0, nnz1 = (dense > 1e-4).sum(1), (sparse > 1e-4).sum(1)
    assert nnz1.mean() < nnz0.mean() - 1
    assert nnz1.max() <= 4 < nnz0.max()  # an L1 optimum is a vertex: at most n_coords non-zeros
    assert np.abs(sparse).sum(1).mean() < np.abs(dense).sum(1).mean()  # smaller L1 norm
    assert info0["pose_error"].max() < 1e-10 and info1["pose_error"].max() < 1e-2  # both fit the landmarks


def test_symmetric_tying_fills_in_the_unseen_side():
    # parameters: left_open, right_open, tongue; the landmarks see only the right side (as the paper's sensors)
    rng = np.random.default_rng(6)
    deltas = rng.normal(size=(3, 8))
    deltas[0] = 0.0  # left_open moves no observed landmark
    rig = LinearRig(np.zeros(8), deltas)
    theta = _path(7, 20, 3)
    theta[:, 0] = theta[:, 1]  # a symmetric face
    free = solve_landmarks(rig(theta), rig, alpha=0.01)
    tied = solve_landmarks(rig(theta), rig, alpha=0.01, symmetric_pairs=[(0, 1)])
    assert np.abs(free[:, 0]).max() < 1e-8  # the prior keeps the unseen side shut
    np.testing.assert_array_equal(tied[:, 0], tied[:, 1])
    np.testing.assert_allclose(tied, theta, atol=0.01)


def test_signed_parameters_are_split_exactly():
    rig = _rig(seed=8)
    theta = _path(9, 20, 5) * 2 - 1  # in (-0.8, 0.8)
    np.testing.assert_allclose(solve_landmarks(rig(theta), rig, alpha=0.0, bounds=(-1, 1)), theta, atol=1e-6)
    M, lo, hi, cost = tied_parameters(2, ([-1, 0], [1, 1]))
    assert M.shape == (2, 3) and list(cost) == [1, 1, 1]
    np.testing.assert_array_equal(M, [[1, -1, 0], [0, 0, 1]])


def test_frames_are_warm_started_from_the_previous_frame():
    rig = _rig(seed=10)
    theta = np.repeat(_path(11, 1, 5), 3, axis=0)  # the same pose three times
    _, info = solve_landmarks(rig(theta), rig, alpha=0.0, return_info=True)
    assert info["n_iter"][0] > 3 and info["n_iter"][1:].max() <= 1


def test_similarity_transform_and_targets():
    rng = np.random.default_rng(12)
    a = 0.4
    Rot = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    P = rng.normal(size=(6, 2))
    s, R_hat, t = similarity_transform(P, 2.5 * P @ Rot.T + [1.0, -2.0])
    assert s == pytest.approx(2.5) and np.allclose(R_hat, Rot) and np.allclose(t, [1, -2])
    # captured landmarks in another frame (scaled, rotated, shifted) map to the rig's targets
    rig = _rig(seed=13, n_coords=12)
    theta = _path(14, 15, 5)
    to_capture = lambda X: (X.reshape(len(X), -1, 2) @ (0.5 * Rot.T) + [3.0, 4.0]).reshape(len(X), -1)
    Y = landmark_targets(to_capture(rig(theta)), to_capture(rig(np.zeros((1, 5))))[0], rig.neutral)
    np.testing.assert_allclose(Y, rig(theta), atol=1e-10)
    solver = LandmarkSolver(rig=rig, alpha=0.0).fit(to_capture(rig(np.zeros((1, 5)))))
    np.testing.assert_allclose(solver.transform(to_capture(rig(theta))), theta, atol=1e-6)


def test_solver_keeps_corpus_alignments():
    rig = LinearRig(np.zeros(6), np.random.default_rng(15).normal(size=(2, 6)), control_names=["jaw", "lip"])
    theta = _path(16, 50, 2)
    al = Alignment(["sil", "a"], [0, 0.2], [0.2, 0.5])
    corpus = Corpus([Utterance(al, rig(theta), 100.0, [f"l{k}" for k in range(6)], name="u0")])
    out = LandmarkSolver(rig=rig, alpha=0.0).fit().transform(corpus)
    assert out.channels == ("jaw", "lip") and out[0].alignment == corpus[0].alignment
    np.testing.assert_allclose(out[0].trajectory, theta, atol=1e-6)


def test_bad_input_is_an_error_naming_the_field():
    rig = _rig()
    Y = rig(np.full((2, 5), 0.5))
    Y[1, 3] = np.nan
    with pytest.raises(DataError) as err:
        solve_landmarks(Y, rig)
    assert err.value.field == "targets[1, 3]"
    with pytest.raises(DataError, match="targets"):
        solve_landmarks(np.zeros((2, 11)), rig)
    with pytest.raises(DataError, match="alpha"):
        solve_landmarks(Y[:1], rig, alpha=-1)
    with pytest.raises(DataError, match="symmetric_pairs"):
        solve_landmarks(Y[:1], rig, symmetric_pairs=[(0, 9)])
    with pytest.raises(DataError, match="do not overlap"):
        solve_landmarks(Y[:1], rig, bounds=([0, 2, 0, 0, 0], [1, 3, 1, 1, 1]), symmetric_pairs=[(0, 1)])
    with pytest.raises(DataError, match="n_params"):
        solve_landmarks(Y[:1], lambda th: th)


def test_cli_rigsolve(tmp_path):
    from dam.cli import main
    from dam.corpus.io import load_corpus, save_corpus

    rig = LinearRig(np.random.default_rng(17).normal(size=8), np.random.default_rng(18).normal(size=(3, 8)))
    theta = _path(19, 30, 3)
    al = Alignment(["sil", "a"], [0, 0.1], [0.1, 0.3])
    save_corpus(Corpus([Utterance(al, rig(theta), 100.0, [f"l{k}" for k in range(8)], name="u")]), tmp_path / "lm")
    np.save(tmp_path / "d.npy", rig.deltas)
    np.save(tmp_path / "n.npy", rig.neutral)
    assert (
        main(
            [
                "-q",
                "rigsolve",
                str(tmp_path / "lm"),
                "--rig-deltas",
                str(tmp_path / "d.npy"),
                "--rig-neutral",
                str(tmp_path / "n.npy"),
                "--alpha",
                "0",
                "-o",
                str(tmp_path / "out"),
            ]
        )
        == 0
    )
    np.testing.assert_allclose(load_corpus(tmp_path / "out")[0].trajectory, theta, atol=1e-5)
