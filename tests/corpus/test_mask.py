"""Missing data: the per-frame, per-channel mask of an Utterance, through fitting and scoring."""

import numpy as np
import pytest

from dam import make
from dam.corpus import Corpus, DataError, Utterance
from dam.datasets.tiny import generate
from dam.evaluation.metrics import evaluate, pearson_per_channel, rmse, rmse_per_channel
from dam.registry import get, names


def masked_corpus(garbage: float | None, seed=0):
    """The tiny corpus with dropouts; masked values set to ``garbage`` (None: NaN)."""
    base = generate(8, seed=seed)
    rng = np.random.default_rng(5)
    utts = []
    for u in base:
        mask = np.ones(u.trajectory.shape, bool)
        for _ in range(3):  # three dropouts of 2-6 frames in random channels
            j, i0 = rng.integers(u.n_channels), rng.integers(1, u.n_frames - 8)
            mask[i0 : i0 + rng.integers(2, 7), j] = False
        y = np.array(u.trajectory)
        y[~mask] = np.nan if garbage is None else garbage
        utts.append(Utterance(u.alignment, y, u.frame_rate, u.channels, name=u.name, mask=mask))
    return Corpus(utts, name="masked")


def test_masked_values_are_interpolated_whatever_was_there():
    a, b = masked_corpus(1e6), masked_corpus(None)
    for ua, ub in zip(a, b):
        np.testing.assert_array_equal(ua.trajectory, ub.trajectory)
        assert np.isfinite(ua.trajectory).all()
        for j in range(ua.n_channels):
            ok = ua.mask[:, j]
            frames = np.arange(ua.n_frames)
            np.testing.assert_allclose(ua.trajectory[~ok, j], np.interp(frames[~ok], frames[ok], ua.trajectory[ok, j]))


def test_mask_validation():
    u = generate(1)[0]
    with pytest.raises(DataError, match="field 'mask'.*must have the trajectory's shape"):
        Utterance(u.alignment, u.trajectory, u.frame_rate, u.channels, mask=np.ones((3, 3), bool))
    y = np.array(u.trajectory)
    y[4, 1] = np.nan
    with pytest.raises(DataError, match=r"trajectory\[4, 'lip_protrusion'\]"):  # NaN where observed
        Utterance(u.alignment, y, u.frame_rate, u.channels)
    m = np.ones(y.shape, bool)
    m[4, 1] = False
    v = Utterance(u.alignment, y, u.frame_rate, u.channels, mask=m)
    assert v.trajectory[4, 1] == pytest.approx(0.5 * (y[3, 1] + y[5, 1]))
    assert Utterance(u.alignment, u.trajectory, u.frame_rate, u.channels, mask=np.ones(y.shape, bool)).mask is None
    assert v.replace(name="x").mask is not None
    c = Corpus([v]).select_channels(["lip_protrusion", "jaw_open"])
    assert c[0].mask.shape == (v.n_frames, 2) and not c[0].mask[4, 0]


def test_a_channel_never_observed_is_zero_and_masked():
    u = generate(1)[0]
    m = np.ones(u.trajectory.shape, bool)
    m[:, 2] = False
    v = Utterance(u.alignment, u.trajectory, u.frame_rate, u.channels, mask=m)
    assert (v.trajectory[:, 2] == 0).all()


def test_metrics_skip_masked_values():
    rng = np.random.default_rng(0)
    y, p = rng.normal(size=(50, 3)), rng.normal(size=(50, 3))
    m = rng.random((50, 3)) > 0.3
    assert rmse(y, p, m) == pytest.approx(np.sqrt(np.mean((y - p)[m] ** 2)))
    for j in range(3):
        assert rmse_per_channel(y, p, m)[j] == pytest.approx(np.sqrt(np.mean((y - p)[m[:, j], j] ** 2)))
        assert pearson_per_channel(y, p, m)[j] == pytest.approx(np.corrcoef(y[m[:, j], j], p[m[:, j], j])[0, 1])
    q = np.where(m, p, 1e9)  # garbage in the prediction where the truth is missing
    assert rmse(y, q, m) == rmse(y, p, m)


# Every registered model that needs no optional extra (the neural ones were checked by hand: same result).
MODELS = [n for n in names() if not get(n).get_tags()["requires"]]


@pytest.mark.filterwarnings("ignore::UserWarning")
@pytest.mark.parametrize("name", MODELS)
def test_garbage_in_masked_frames_changes_neither_fit_nor_score(name):
    params = get(name).get_test_params()[0]
    clean, dirty = masked_corpus(0.0), masked_corpus(1e6)
    ma = make(name, **params).fit(clean)
    mb = make(name, **params).fit(dirty)
    for pa, pb in zip(ma.predict(clean.alignments), mb.predict(dirty.alignments)):
        np.testing.assert_array_equal(pa, pb)
        assert np.isfinite(pa).all()
    ea, eb = evaluate(ma, clean), evaluate(mb, dirty)
    assert ea.rmse == eb.rmse
    # and the score is over observed values only
    Y = np.concatenate(clean.trajectories)
    P = np.concatenate(ma.predict(clean.alignments))
    M = np.concatenate([u.mask for u in clean])
    assert ea.rmse == pytest.approx(np.sqrt(np.mean((Y - P)[M] ** 2)))


def test_phone_mean_averages_observed_values_only():
    c = masked_corpus(None)
    model = make("phone-mean").fit(c)
    for p in model.phones_:
        vals = [[] for _ in c.channels]
        for u in c:
            seg = u.alignment.segment_index(u.frame_rate, u.n_frames)
            rows = np.array(u.alignment.labels)[seg] == p
            for j in range(u.n_channels):
                vals[j] += list(u.trajectory[rows & u.mask[:, j], j])
        np.testing.assert_allclose(model.table_[model.phones_.index(p)], [np.mean(v) for v in vals])


def test_dam_estep_weights_equal_dropping_the_rows():
    """The weighted E-step solves the least squares with the masked rows deleted (dense closed form)."""
    from dam.model.estep import Occurrences, design_matrix, normal_equations, solve_normal_equations

    c = masked_corpus(0.0)
    glob = []
    phones = sorted(c.phones)
    for u in c:
        glob.append(np.array([phones.index(p) for p in u.alignment.labels]))
    occ = Occurrences.from_corpus(c, glob, len(phones), degree=2)
    sigma = np.full(len(phones), 0.8)
    Y = np.concatenate(c.trajectories)
    W = np.concatenate([u.mask for u in c]).astype(float)
    X = design_matrix(occ, sigma).toarray()
    lam = 1e-3
    for j in range(c.n_channels):
        keep = W[:, j] > 0
        Xk = X[keep]
        truth = np.linalg.solve(Xk.T @ Xk + lam * np.eye(X.shape[1]), Xk.T @ Y[keep, j])
        G, Xty = normal_equations(occ, sigma, Y[:, j], weights=W[:, j])
        np.testing.assert_allclose(solve_normal_equations(G, Xty, lam)[0][:, 0], truth, rtol=1e-6, atol=1e-8)


@pytest.mark.filterwarnings("ignore:DAM EM stopped")
def test_dam_fit_skips_masked_frames():
    """The DAM's EM uses the mask as weights: the same values with and without the mask fit differently."""
    c = masked_corpus(0.0)
    unmasked = Corpus([Utterance(u.alignment, u.trajectory, u.frame_rate, u.channels, name=u.name) for u in c])
    params = {"degree": 2, "max_iter": 3, "n_resample": 8}
    a = make("dam", **params).fit(c)
    b = make("dam", **params).fit(unmasked)
    assert not np.allclose(a.coef_, b.coef_)  # skipping is not the same as fitting the interpolated values


def test_save_corpus_keeps_the_mask(tmp_path):
    from dam.corpus import load_corpus, save_corpus

    c = masked_corpus(None)
    save_corpus(c, tmp_path / "c", decimals=None)
    back = load_corpus(tmp_path / "c")
    for u, v in zip(c, back):
        np.testing.assert_array_equal(u.mask, v.mask)
        np.testing.assert_allclose(u.trajectory, v.trajectory)
    np.save(tmp_path / "c" / f"{c[0].name}.mask.npy", np.zeros((3, 3)))
    with pytest.raises(DataError, match=r"mask.npy: field 'mask'.*float64"):
        load_corpus(tmp_path / "c")
