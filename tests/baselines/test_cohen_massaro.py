"""Cohen–Massaro (1993): exact Jacobian, and recovery of known parameters."""

import numpy as np
import pytest

from baselines.cohen_massaro import (
    BLOCKS,
    CohenMassaro,
    _Design,
    cohen_massaro_trajectory,
    dominance,
    residuals_and_jacobian,
)
from dam.corpus.data import Alignment, Corpus, Utterance

PHONES = ["aa", "m", "s", "sil"]  # sorted, the order of phones_
TRUE = {  # per phone, for channels (0, 1)
    "target": np.array([[1.0, -0.5], [0.0, 0.8], [0.5, 0.2], [0.2, 0.0]]),
    "alpha": np.array([[1.0, 0.6], [2.5, 1.5], [0.5, 1.0], [0.3, 0.4]]),
    "theta_left": np.array([[15.0, 10.0], [40.0, 25.0], [8.0, 20.0], [12.0, 6.0]]),
    "theta_right": np.array([[10.0, 20.0], [30.0, 12.0], [25.0, 10.0], [8.0, 9.0]]),
    "c": np.array([[1.0, 1.2], [1.5, 0.8], [0.9, 1.0], [1.0, 1.0]]),
}


def _random_alignment(rng, n_segments=9):
    labels = ["sil"] + list(rng.choice(PHONES[:3], size=n_segments - 2)) + ["sil"]
    for k in range(1, len(labels)):  # no repeated neighbours
        if labels[k] == labels[k - 1]:
            labels[k] = "aa" if labels[k] != "aa" else "m"
    ends = np.cumsum(rng.uniform(0.06, 0.2, size=len(labels)))
    return Alignment(labels, np.r_[0.0, ends[:-1]], ends)


def _cm_1993(alignment, frame_rate, n_frames, par, ch):
    """Cohen & Massaro (1993) written out from the paper, independently of the module:
    F(t) = sum_s D_s(t) T_s / sum_s D_s(t), D_s(t) = alpha exp(-theta |m_s - t|^c), theta
    the left rate before the centre m_s and the right rate after it (plain exp, no log domain)."""
    t = np.arange(n_frames) / frame_rate
    num = np.zeros(n_frames)
    den = np.zeros(n_frames)
    for lab, s0, s1 in zip(alignment.labels, alignment.starts, alignment.ends):
        i = PHONES.index(lab)
        tau = 0.5 * (s0 + s1) - t
        theta = np.where(tau > 0, par["theta_left"][i, ch], par["theta_right"][i, ch])
        D = par["alpha"][i, ch] * np.exp(-theta * np.abs(tau) ** par["c"][i, ch])
        num += D * par["target"][i, ch]
        den += D
    return num / den


def _generated_corpus(n_utts=16, seed=0, frame_rate=100.0):
    """A corpus synthesised from TRUE by the 1993 formula (:func:`_cm_1993`)."""
    rng = np.random.default_rng(seed)
    utts = []
    for k in range(n_utts):
        a = _random_alignment(rng)
        n = a.n_frames(frame_rate)
        y = np.stack([_cm_1993(a, frame_rate, n, TRUE, ch) for ch in range(2)], axis=1)
        utts.append(Utterance(a, y, frame_rate, ["x", "y"], name=f"u{k}"))
    return Corpus(utts, name="cm-generated")


def test_dominance_is_the_1993_equation():
    tau = np.array([-0.2, -0.05, 0.0, 0.05, 0.2])  # centre minus time: positive before the centre
    got = dominance(tau, 2.0, 10.0, 30.0, 1.5)
    theta = np.array([30.0, 30.0, 30.0, 10.0, 10.0])
    np.testing.assert_allclose(got, 2.0 * np.exp(-theta * np.abs(tau) ** 1.5))
    assert got[2] == 2.0


def test_trajectory_is_weighted_average_of_targets():
    a = Alignment(["aa", "m"], [0.0, 0.1], [0.1, 0.3])
    d = _Design(a, np.array([0, 1]), 100.0, 30)
    P = 4
    T, al, tl, tr, c = (TRUE[k][:, 0] for k in ("target", "alpha", "theta_left", "theta_right", "c"))
    F = cohen_massaro_trajectory(d, T, np.log(al), tl, tr, c)
    t = np.arange(30) / 100.0
    D0 = dominance(0.05 - t, al[0], tl[0], tr[0], c[0])
    D1 = dominance(0.2 - t, al[1], tl[1], tr[1], c[1])
    np.testing.assert_allclose(F, (D0 * T[0] + D1 * T[1]) / (D0 + D1), rtol=1e-12)
    assert P == len(PHONES)


def test_jacobian_matches_finite_differences():
    corpus = _generated_corpus(n_utts=3, seed=1)
    idx = {p: i for i, p in enumerate(PHONES)}
    designs = [
        _Design(u.alignment, np.array([idx[lab] for lab in u.alignment.labels]), 100.0, u.n_frames) for u in corpus
    ]
    ys = [u.trajectory[:, 0] + 0.1 for u in corpus]
    rng = np.random.default_rng(3)
    x = np.concatenate(
        [rng.normal(size=4), rng.normal(0, 0.3, 4), np.log(rng.uniform(5, 30, 8)), np.log(rng.uniform(0.7, 1.5, 4))]
    )
    _, J = residuals_and_jacobian(x, designs, ys, 4)
    h = 1e-6
    num = np.empty_like(J)
    for j in range(len(x)):
        e = np.zeros_like(x)
        e[j] = h
        num[:, j] = (
            residuals_and_jacobian(x + e, designs, ys, 4)[0] - residuals_and_jacobian(x - e, designs, ys, 4)[0]
        ) / (2 * h)
    assert len(x) == len(BLOCKS) * 4
    np.testing.assert_allclose(J, num, atol=1e-7 * np.abs(num).max() + 1e-9, rtol=1e-5)


def test_recovers_known_parameters_from_generated_corpus():
    corpus = _generated_corpus()
    model = CohenMassaro(ridge=1e-9, max_nfev=300, tol=1e-10).fit(corpus)
    assert model.phones_ == PHONES
    np.testing.assert_allclose(model.target_, TRUE["target"], atol=1e-4)
    # alpha only matters up to a common scale per channel: compare ratios to the geometric mean
    norm = lambda a: a / np.exp(np.log(a).mean(axis=0))  # noqa: E731
    np.testing.assert_allclose(norm(model.alpha_), norm(TRUE["alpha"]), rtol=1e-3)
    for k in ("theta_left", "theta_right", "c"):
        np.testing.assert_allclose(getattr(model, k + "_"), TRUE[k], rtol=1e-3, err_msg=k)
    assert np.all(model.cost_ < 1e-10)
    # and it synthesizes the generating model's trajectory on a new alignment
    test = _generated_corpus(n_utts=2, seed=9)
    for u in test:
        np.testing.assert_allclose(model.predict(u.alignment), u.trajectory, atol=1e-4)


def test_bad_params_are_refused():
    corpus = _generated_corpus(n_utts=2)
    with pytest.raises(ValueError, match="c_bounds"):
        CohenMassaro(c_bounds=(2.0, 1.0)).fit(corpus)
    with pytest.raises(ValueError, match="unknown_phone"):
        CohenMassaro(unknown_phone="guess").fit(corpus)


def test_fit_rate_thins_the_fitted_frames_without_bias():
    # a 400 Hz corpus from the model: fitting every 4th frame still recovers the targets
    corpus = _generated_corpus(n_utts=10, seed=2, frame_rate=400.0)
    model = CohenMassaro(ridge=1e-9, tol=1e-10, fit_rate=100.0).fit(corpus)
    assert model._stride(400.0) == 4
    np.testing.assert_allclose(model.target_, TRUE["target"], atol=1e-3)


def test_normal_equations_equal_dense_products():
    from baselines.cohen_massaro import normal_equations

    corpus = _generated_corpus(n_utts=3, seed=5)
    idx = {p: i for i, p in enumerate(PHONES)}
    designs = [
        _Design(u.alignment, np.array([idx[lab] for lab in u.alignment.labels]), 100.0, u.n_frames) for u in corpus
    ]
    ys = [u.trajectory[:, 1] for u in corpus]
    x = np.random.default_rng(0).normal(0, 0.5, size=20)
    r, J = residuals_and_jacobian(x, designs, ys, 4)
    cost, g, H = normal_equations(x, designs, ys, 4)
    assert cost == pytest.approx(r @ r, rel=1e-12)
    np.testing.assert_allclose(g, J.T @ r, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(H, J.T @ J, rtol=1e-10, atol=1e-12)


def test_levenberg_marquardt_matches_scipy_on_a_bounded_problem():
    from scipy.optimize import least_squares

    from baselines.cohen_massaro import levenberg_marquardt

    t = np.linspace(0, 3, 40)
    y = 2.0 * np.exp(-1.3 * t) + 0.5

    def resid(x):
        return x[0] * np.exp(-x[1] * t) + x[2] - y

    def jac(x):
        e = np.exp(-x[1] * t)
        return np.stack([e, -x[0] * t * e, np.ones_like(t)], axis=1)

    def normal_eq(x):
        r, J = resid(x), jac(x)
        return float(r @ r), J.T @ r, J.T @ J

    lo, hi = np.array([0.0, 0.0, 0.6]), np.array([10.0, 10.0, 10.0])  # the offset bound is active
    ours, cost, _ = levenberg_marquardt(normal_eq, np.array([1.0, 0.5, 1.0]), lo, hi, tol=1e-12)
    ref = least_squares(resid, [1.0, 0.5, 1.0], jac=jac, bounds=(lo, hi), ftol=1e-14, xtol=1e-14, gtol=1e-14)
    np.testing.assert_allclose(ours, ref.x, rtol=1e-5)
    assert ours[2] == pytest.approx(0.6)
    assert cost == pytest.approx(2 * ref.cost, rel=1e-8)


def test_long_recordings_are_synthesised_in_blocks_identically(monkeypatch):
    import baselines.cohen_massaro as cm

    model = CohenMassaro(max_nfev=5).fit(_generated_corpus(n_utts=3))
    a = _generated_corpus(n_utts=1, seed=4)[0].alignment
    whole = model.predict(a)
    monkeypatch.setattr(cm, "BLOCK_FRAMES", 5)  # blocks of 5 frames, each with every segment within 30
    np.testing.assert_allclose(model.predict(a), whole, rtol=1e-12)


def test_long_utterance_in_windowed_blocks_matches_the_dense_model(monkeypatch):
    """Linear memory: blocks of frames see only nearby segments; the dense (frames x all segments)
    weighted average, with every segment, gives the same trajectory."""
    import baselines.cohen_massaro as cm

    model = CohenMassaro(max_nfev=5).fit(_generated_corpus(n_utts=3))
    parts = [u.alignment for u in _generated_corpus(n_utts=12, seed=5)]
    labels, starts, ends, t = [], [], [], 0.0
    for a in parts:  # one long utterance of ~12 phrases
        labels += list(a.labels)
        starts += list(a.starts + t)
        ends += list(a.ends + t)
        t += a.duration
    long = Alignment(labels, starts, ends)
    windowed = model.predict(long)
    monkeypatch.setattr(cm, "BLOCK_FRAMES", 10**9)
    monkeypatch.setattr(cm, "NEIGHBOURS", 10**9)
    dense = model.predict(long)
    assert len(long) > 60  # many more segments than one block sees
    err = np.abs(windowed - dense).max() / np.ptp(dense, axis=0).max()
    assert err < 1e-4, err


def _with_parameters(par):
    """A CohenMassaro holding the parameters ``par`` (fitted briefly, then overwritten)."""
    model = CohenMassaro(max_nfev=2).fit(_generated_corpus(n_utts=2))
    assert model.phones_ == PHONES
    model.target_, model.alpha_ = par["target"].copy(), par["alpha"].copy()
    model.theta_left_, model.theta_right_, model.c_ = (par[k].copy() for k in ("theta_left", "theta_right", "c"))
    return model


def test_predict_is_the_1993_formula():
    # the weights are formed in the log domain, the smallest clipped at e^-100 of the largest:
    # the plain formula agrees to rounding, at every frame of every utterance
    model = _with_parameters(TRUE)
    for u in _generated_corpus(n_utts=5, seed=11):
        np.testing.assert_allclose(model.predict(u.alignment), u.trajectory, rtol=0, atol=1e-12)


def test_one_phone_is_its_target_throughout():
    # one segment, or a pause cut in two (one segment once merged): the weighted average of one target
    model = _with_parameters(TRUE)
    for a in (Alignment(["m"], [0.0], [0.37]), Alignment(["sil", "sil"], [0.0, 0.2], [0.2, 0.5])):
        row = PHONES.index(a.labels[0])
        out = model.predict(a)
        assert out.shape == (a.n_frames(100.0), 2)
        np.testing.assert_array_equal(out, np.broadcast_to(TRUE["target"][row], out.shape))
        np.testing.assert_allclose(
            _cm_1993(Alignment(a.labels[:1], [0.0], [a.duration]), 100.0, len(out), TRUE, 1), out[:, 1]
        )


def test_far_frames_do_not_divide_zero_by_zero():
    # 2 s after the last centre every dominance underflows to 0 in the plain formula (0/0);
    # the model takes the ratio in the log domain
    par = {k: v.copy() for k, v in TRUE.items()}
    par["theta_right"][:] = 2000.0
    par["theta_right"][PHONES.index("m")] = 1000.0  # falls slowest after its centre
    model = _with_parameters(par)
    a = Alignment(["aa", "m", "s"], [0.0, 0.1, 0.2], [0.1, 0.2, 5.0])
    with np.errstate(all="ignore"):
        plain = _cm_1993(a, 100.0, a.n_frames(100.0), par, 0)
    assert np.isnan(plain).any()  # the plain formula fails there
    out = model.predict(a)
    assert np.isfinite(out).all()
    centres = 0.5 * (a.starts + a.ends)
    for f in np.flatnonzero(np.isnan(plain)):
        for ch in range(2):
            rows = [PHONES.index(lab) for lab in a.labels]
            tau = centres - f / 100.0
            theta = np.where(tau > 0, par["theta_left"][rows, ch], par["theta_right"][rows, ch])
            log_d = np.log(par["alpha"][rows, ch]) - theta * np.abs(tau) ** par["c"][rows, ch]
            w = np.exp(log_d - log_d.max())  # the same ratio, scaled by a common factor
            assert out[f, ch] == pytest.approx(w @ par["target"][rows, ch] / w.sum(), abs=1e-12)


@pytest.mark.parametrize("work_size", [1, 1 << 17])  # one channel per pass, or all three at once
def test_channels_evaluated_together_equal_one_at_a_time(monkeypatch, work_size):
    import baselines.cohen_massaro as cm
    from baselines.cohen_massaro import normal_equations

    monkeypatch.setattr(cm, "WORK_SIZE", work_size)

    corpus = _generated_corpus(n_utts=3, seed=6)
    idx = {p: i for i, p in enumerate(PHONES)}
    designs = [
        _Design(u.alignment, np.array([idx[lab] for lab in u.alignment.labels]), 100.0, u.n_frames) for u in corpus
    ]
    X = np.random.default_rng(2).normal(0, 0.5, size=(3, 20))
    ys = [np.stack([u.trajectory[:, 0], u.trajectory[:, 1], -u.trajectory[:, 0]]) for u in corpus]
    cost, g, H = normal_equations(X, designs, ys, 4)
    for i in range(3):
        c1, g1, H1 = normal_equations(X[i], designs, [y[i] for y in ys], 4)
        assert cost[i] == pytest.approx(c1, rel=1e-12)
        np.testing.assert_allclose(g[i], g1, rtol=1e-12, atol=1e-14)
        np.testing.assert_allclose(H[i], H1, rtol=1e-12, atol=1e-14)


def test_levenberg_marquardt_runs_problems_in_lockstep_as_alone():
    from baselines.cohen_massaro import levenberg_marquardt

    t = np.linspace(0, 3, 40)
    ys = np.stack([2.0 * np.exp(-1.3 * t) + 0.5, 0.7 * np.exp(-4.0 * t) - 0.2, 3.0 * np.exp(-0.2 * t)])

    def one(x, y):
        e = np.exp(-x[1] * t)
        r, J = x[0] * e + x[2] - y, np.stack([e, -x[0] * t * e, np.ones_like(t)], axis=1)
        return float(r @ r), J.T @ r, J.T @ J

    def batched(X, rows):
        out = [one(x, ys[i]) for x, i in zip(X, rows)]
        return np.array([o[0] for o in out]), np.stack([o[1] for o in out]), np.stack([o[2] for o in out])

    lo, hi = np.array([0.0, 0.0, -1.0]), np.array([10.0, 10.0, 10.0])
    x0 = np.array([1.0, 0.5, 1.0])
    stops = []
    X, cost, nfev = levenberg_marquardt(batched, np.tile(x0, (3, 1)), lo, hi, tol=1e-12, on_stop=stops.append)
    assert sorted(stops) == [0, 1, 2]  # each problem reported once, when it stops
    assert [int(nfev[i]) for i in stops] == sorted(int(v) for v in nfev)
    for i in range(3):
        xi, ci, ni = levenberg_marquardt(lambda x, i=i: one(x, ys[i]), x0, lo, hi, tol=1e-12)
        np.testing.assert_array_equal(X[i], xi)
        assert (cost[i], nfev[i]) == (ci, ni)
    np.testing.assert_allclose(X, [[2.0, 1.3, 0.5], [0.7, 4.0, -0.2], [3.0, 0.2, 0.0]], atol=1e-6)


def test_model_file_saved_before_the_fast_fit_still_loads():
    """A model written by the per-channel fit of commit before issue 11's speed-up
    (fitted on tiny's training split, max_nfev=5): same parameters, same predictions."""
    from pathlib import Path

    import dam

    here = Path(__file__).parents[1] / "data" / "models"
    m = dam.load(here / "cohen-massaro_before-issue11.dam")
    assert type(m) is CohenMassaro and m.max_nfev == 5
    train, test = dam.datasets.load("tiny").train_test_split(0.25, random_state=0)
    u = test[0]
    np.testing.assert_allclose(m.predict(u.alignment), np.load(here / "cohen-massaro_before-issue11.npy"), atol=1e-12)
