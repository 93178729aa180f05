"""Rig-space retargeting (Taylor et al. 2017, Sec. 6, Eqs. 2-3) against the equations by hand."""

import numpy as np
import pytest

from dam import Alignment, Corpus, DataError, Utterance
from dam.crossmap.retarget import (
    RigSpaceRetargeter,
    principal_modes,
    project,
    retarget_weights,
    retargeting_poses,
    rig_space_retarget,
)


def _reference(seed=0, n=400, sds=(2.0, 1.0, 0.5), d=10):
    """Frames with planted orthonormal modes of known standard deviation."""
    rng = np.random.default_rng(seed)
    Q, _ = np.linalg.qr(rng.normal(size=(d, len(sds))))
    coef = rng.normal(size=(n, len(sds)))
    coef = (coef - coef.mean(0)) / coef.std(0, ddof=1) * np.asarray(sds)  # exact sample sds
    mean = rng.normal(size=d)
    return mean + coef @ Q.T, mean, Q.T, np.asarray(sds) ** 2


def test_weights_match_eq2_by_hand():
    lam = np.array([4.0, 1.0])  # sd 2 and 1
    p = np.array([[3.0, -0.5], [-12.0, 0.0], [6.0, 3.0]])
    w = retarget_weights(p, lam)
    # columns: w1^-3, w1^+3, w2^-3, w2^+3 ; w = max(p / (u * sd), 0)
    by_hand = np.array(
        [
            [0.0, 3 / 6, 0.5 / 3, 0.0],
            [12 / 6, 0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0, 1.0],
        ]
    )
    np.testing.assert_allclose(w, by_hand, atol=1e-15)


def test_rig_parameters_match_eq3_by_hand():
    r0 = np.array([0.1, 0.2])
    R = np.array([[0.0, 0.0], [1.0, 0.2], [0.1, 0.9], [0.5, 0.5]])  # r1-, r1+, r2-, r2+
    w = np.array([[0.0, 0.5, 1 / 6, 0.0]])
    # (R - r0) w + r0 = r0 + 0.5 (r1+ - r0) + 1/6 (r2- - r0)
    by_hand = np.array([0.1 + 0.5 * 0.9 + (0.0) / 6, 0.2 + 0.5 * 0.0 + 0.7 / 6])
    np.testing.assert_allclose(rig_space_retarget(w, R, r0)[0], by_hand, atol=1e-15)
    np.testing.assert_allclose(rig_space_retarget(w, R - r0, r0, relative=True), [by_hand], atol=1e-15)


def test_principal_modes_recover_planted_modes():
    X, mean, modes, lam = _reference()
    m, U, ev = principal_modes(X, 3)
    np.testing.assert_allclose(m, X.mean(0), atol=1e-12)
    np.testing.assert_allclose(np.abs(U @ modes.T), np.eye(3), atol=0.05)  # same modes, up to sign
    np.testing.assert_allclose(ev, np.var(project(X, m, U), axis=0, ddof=1), rtol=1e-10)
    np.testing.assert_allclose(ev, lam, rtol=0.1)


def test_posed_reference_shapes_retarget_to_the_artists_poses():
    X, *_ = _reference(seed=1)
    rng = np.random.default_rng(2)
    r0, R = rng.uniform(0, 1, 6), rng.uniform(0, 1, (4, 6))
    rt = RigSpaceRetargeter(n_modes=2, rig_poses=R, rig_neutral=r0).fit(X)
    poses = rt.reference_poses()
    assert poses.shape == (4, X.shape[1])
    # s_k^u = s_0 + s_k u sqrt(lambda_k), rows ordered 1-, 1+, 2-, 2+
    np.testing.assert_allclose(poses[1], rt.mean_ + rt.components_[0] * 3 * np.sqrt(rt.eigenvalues_[0]))
    np.testing.assert_allclose(poses[2], rt.mean_ - rt.components_[1] * 3 * np.sqrt(rt.eigenvalues_[1]))
    # w = 1 at a posed shape: the rig gets exactly the artist's pose; the mean gets r0
    np.testing.assert_allclose(rt.weights(poses), np.eye(4), atol=1e-12)
    np.testing.assert_allclose(rt.transform(poses), R, atol=1e-12)
    np.testing.assert_allclose(rt.transform(rt.mean_[None]), [r0], atol=1e-12)
    # halfway to a pose, halfway in rig space (piece-wise linear)
    half = 0.5 * (rt.mean_ + poses[3])
    np.testing.assert_allclose(rt.transform(half[None])[0], 0.5 * (r0 + R[3]), atol=1e-12)
    assert 0 < rt.explained_variance_ratio_.sum() <= 1


def test_retargeter_keeps_corpus_alignments_and_can_clip():
    X, *_ = _reference(seed=3, n=120)
    al = Alignment(["sil", "a", "b"], [0, 0.4, 0.8], [0.4, 0.8, 1.2])
    corpus = Corpus([Utterance(al, X, 100.0, [f"x{k}" for k in range(X.shape[1])], name="u")])
    R = np.array([[-1.0], [2.0], [0.0], [0.0]])
    rt = RigSpaceRetargeter(n_modes=2, rig_poses=R, rig_neutral=[0.5], rig_names=["jaw"], bounds=(0, 1))
    out = rt.fit(corpus).transform(corpus)
    assert out.channels == ("jaw",) and out[0].alignment == corpus[0].alignment
    assert out[0].trajectory.min() >= 0 and out[0].trajectory.max() <= 1
    raw = rt.set_params(bounds=None).transform(X)
    assert raw.min() < 0 or raw.max() > 1  # the clip did something
    # a list of utterances is the same reference as the corpus holding them
    half = Alignment(["sil", "a"], [0, 0.3], [0.3, 0.6])
    halves = [Utterance(half, X[:60], 100.0, corpus.channels), Utterance(half, X[60:], 100.0, corpus.channels)]
    np.testing.assert_allclose(RigSpaceRetargeter(n_modes=2).fit(halves).components_, rt.components_, atol=1e-12)
    out = rt.transform(halves)
    assert isinstance(out, list) and [u.n_frames for u in out] == [60, 60]


def test_bad_input_is_an_error_naming_the_field():
    X, *_ = _reference(n=50)
    with pytest.raises(DataError, match="n_modes"):
        principal_modes(X, 11)
    with pytest.raises(DataError) as err:
        retarget_weights(np.ones((2, 3)), [1.0, 1.0])
    assert err.value.field == "p"
    with pytest.raises(DataError, match="positive"):
        retarget_weights(np.ones((2, 2)), [1.0, 0.0])
    with pytest.raises(DataError, match="rig_neutral"):
        rig_space_retarget(np.ones((1, 4)), np.ones((4, 3)), [0.0, 0.0])
    with pytest.raises(DataError) as err:
        retarget_weights(np.array([[np.nan, 1.0]]), [1.0, 1.0])
    assert err.value.field == "p[0, 0]"
    rt = RigSpaceRetargeter(n_modes=2, rig_poses=np.ones((3, 2)), rig_neutral=[0, 0]).fit(X)
    with pytest.raises(DataError, match="needs 4 rows"):
        rt.transform(X)
    with pytest.raises(DataError, match="u"):
        retargeting_poses(np.zeros(3), np.eye(3)[:1], [1.0], u=(3, 3))


def test_cli_retarget_saves_poses_and_retargets(tmp_path, capsys):
    from dam.cli import main
    from dam.corpus.io import load_corpus, save_corpus

    X, *_ = _reference(seed=4, n=90, d=6)
    al = Alignment(["sil", "a"], [0, 0.3], [0.3, 0.9])
    save_corpus(Corpus([Utterance(al, X, 100.0, [f"x{k}" for k in range(6)], name="u")]), tmp_path / "ref")
    assert (
        main(["-q", "retarget", str(tmp_path / "ref"), "--n-modes", "2", "--save-poses", str(tmp_path / "poses.csv")])
        == 0
    )
    poses = np.loadtxt(tmp_path / "poses.csv", delimiter=",")
    assert poses.shape == (4, 6)
    R = np.array([[0.0, 1.0], [1.0, 0.0], [0.2, 0.2], [0.9, 0.9]])
    np.savetxt(tmp_path / "R.csv", R, delimiter=",")
    np.savetxt(tmp_path / "r0.csv", [0.5, 0.5], delimiter=",")
    assert (
        main(
            [
                "-q",
                "retarget",
                str(tmp_path / "ref"),
                "--n-modes",
                "2",
                "--rig-poses",
                str(tmp_path / "R.csv"),
                "--rig-neutral",
                str(tmp_path / "r0.csv"),
                "--rig-names",
                "jaw,lip",
                "-o",
                str(tmp_path / "rig"),
            ]
        )
        == 0
    )
    out = load_corpus(tmp_path / "rig")
    rt = RigSpaceRetargeter(n_modes=2, rig_poses=R, rig_neutral=[0.5, 0.5]).fit(X)
    assert out.channels == ("jaw", "lip")
    np.testing.assert_allclose(out[0].trajectory, rt.transform(X), atol=1e-5)
    np.savetxt(tmp_path / "R3.csv", R[:3], delimiter=",")
    assert (
        main(
            [
                "retarget",
                str(tmp_path / "ref"),
                "--n-modes",
                "2",
                "--rig-poses",
                str(tmp_path / "R3.csv"),
                "--rig-neutral",
                str(tmp_path / "r0.csv"),
                "-o",
                str(tmp_path / "x"),
            ]
        )
        == 1
    )
    err = capsys.readouterr().err
    assert "R3.csv" in err and "rig_poses" in err and "needs 4 rows" in err
