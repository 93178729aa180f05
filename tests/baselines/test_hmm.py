"""HMM synthesis: MLPG against the dense closed form, EM against a known generating HMM, tree tying."""

import itertools

import numpy as np
import pytest

import dam
from baselines.hmm import (
    HMMSynthesizer,
    durations_for_length,
    dynamic_features,
    grow_tree,
    mlpg,
    tree_leaves,
    viterbi_em,
    viterbi_segments,
)
from baselines.hmm.mlpg import solveh_banded_numpy

FR = 100.0


def _dense_window_matrix(T):
    """W built entry by entry from the HTS windows, edge taps reading the edge frame."""
    windows = [{0: 1.0}, {-1: -0.5, 1: 0.5}, {-1: 1.0, 0: -2.0, 1: 1.0}]
    W = np.zeros((3 * T, T))
    for k, win in enumerate(windows):
        for t in range(T):
            for off, w in win.items():
                W[k * T + t, min(max(t + off, 0), T - 1)] += w
    return W


@pytest.mark.parametrize("T", [1, 2, 3, 12])
def test_mlpg_equals_dense_closed_form(T):
    rng = np.random.default_rng(T)
    C = 3
    mu = rng.normal(size=(T, 3 * C))
    prec = rng.uniform(0.2, 5.0, size=(T, 3 * C))
    got = mlpg(mu, prec)
    W = _dense_window_matrix(T)
    for c in range(C):
        cols = [k * C + c for k in range(3)]
        m = mu[:, cols].T.ravel()  # window-major, as the rows of W
        P = np.diag(prec[:, cols].T.ravel())
        want = np.linalg.solve(W.T @ P @ W, W.T @ P @ m)
        np.testing.assert_allclose(got[:, c], want, rtol=1e-9, atol=1e-10)


def test_numpy_banded_solver_equals_dense_solve():
    rng = np.random.default_rng(7)
    T, C, u = 15, 3, 2
    mats = []
    ab = np.zeros((u + 1, T, C))
    for c in range(C):
        M = rng.normal(size=(T, T)) * (np.abs(np.subtract.outer(range(T), range(T))) <= u)
        A = M @ M.T * (np.abs(np.subtract.outer(range(T), range(T))) <= u) + T * np.eye(T)
        mats.append(A)
        for i in range(T):
            for j in range(i, min(i + u, T - 1) + 1):
                ab[u + i - j, j, c] = A[i, j]
    b = rng.normal(size=(T, C))
    x = solveh_banded_numpy(ab, b)
    for c in range(C):
        np.testing.assert_allclose(x[:, c], np.linalg.solve(mats[c], b[:, c]), rtol=1e-10, atol=1e-12)


def test_dynamic_features_are_the_window_matrix_rows():
    x = np.random.default_rng(1).normal(size=(7, 2))
    W = _dense_window_matrix(7)
    want = np.concatenate([(W @ x)[k * 7 : (k + 1) * 7] for k in range(3)], axis=1)
    np.testing.assert_allclose(dynamic_features(x), want, atol=1e-12)


def test_mlpg_returns_a_trajectory_whose_own_features_are_the_means():
    """If the means are the features of some trajectory, that trajectory is the ML solution."""
    x = np.cumsum(np.random.default_rng(2).normal(size=(20, 2)), axis=0)
    np.testing.assert_allclose(mlpg(dynamic_features(x), np.ones((20, 6))), x, atol=1e-9)


def test_viterbi_matches_exhaustive_search():
    rng = np.random.default_rng(3)
    B, n, S = 4, 7, 3
    ll = rng.normal(size=(B, n, S))
    stay, move = np.log(rng.uniform(0.2, 0.8, (B, S))), np.log(rng.uniform(0.2, 0.8, (B, S)))
    got = viterbi_segments(ll, stay, move)
    for b in range(B):
        best, best_path = -np.inf, None
        for cuts in itertools.combinations(range(1, n), S - 1):  # frames where a new state starts
            path = np.searchsorted(np.array(cuts), np.arange(n), side="right")
            score = ll[b, 0, 0] + sum(
                ll[b, t, path[t]] + (move[b, path[t - 1]] if path[t] != path[t - 1] else stay[b, path[t]])
                for t in range(1, n)
            )
            if score > best:
                best, best_path = score, path
        np.testing.assert_array_equal(got[b], best_path)


@pytest.mark.parametrize("n", [3, 5, 17, 40])
def test_durations_sum_to_segment_and_follow_the_model(n):
    mean, var = np.array([2.0, 6.0, 4.0]), np.array([1.0, 4.0, 1.0])
    d = durations_for_length(mean, var, n)
    assert d.sum() == n and d.min() >= 1
    if n == 12:  # exactly the mean length: the means themselves
        np.testing.assert_array_equal(d, mean)
    if n == 40:  # stretched: the state with the largest variance takes most of the extra frames
        assert np.argmax(d - mean) == 1
    np.testing.assert_array_equal(durations_for_length(mean, var, 12), [2, 6, 4])


# -- data from a known HMM ----------------------------------------------------
TRUE_MEANS = {
    "aa": [[0.0, 1.0], [2.0, -1.0], [1.0, 0.5]],
    "iy": [[-2.0, 0.0], [0.5, 2.0], [-1.0, -1.5]],
    "uw": [[2.5, 2.5], [-0.5, -2.0], [0.0, 3.0]],
}
TRUE_DURATIONS = {"aa": [4, 10, 6], "iy": [8, 5, 9], "uw": [5, 6, 12]}


def _hmm_corpus(means, durations, n_utts=30, noise=0.05, seed=0):
    """Phones in random order; each state holds its mean (plus noise) for its known number of frames."""
    rng = np.random.default_rng(seed)
    phones = sorted(means)
    utts = []
    for i in range(n_utts):
        labels = list(rng.choice(phones, size=8))
        frames, starts, ends, t = [], [], [], 0
        for p in labels:
            for s, d in enumerate(durations[p]):
                frames.append(np.tile(means[p][s], (d, 1)))
            n = sum(durations[p])
            starts.append(t / FR)
            ends.append((t + n) / FR)
            t += n
        y = np.concatenate(frames) + noise * rng.normal(size=(t, 2))
        utts.append(dam.Utterance(dam.Alignment(labels, starts, ends), y, FR, channels=("a", "b"), name=f"u{i}"))
    return dam.Corpus(utts)


def test_viterbi_em_recovers_a_known_hmm():
    """Observation vectors drawn from known state Gaussians for known state durations: EM finds both."""
    rng = np.random.default_rng(6)
    P, S, D = 3, 3, 4
    true_means = rng.normal(scale=2.0, size=(P * S, D))
    true_sd = rng.uniform(0.3, 0.6, size=(P * S, D))
    phone = rng.integers(0, P, size=300)
    dur = rng.integers(2, 9, size=(300, S))  # known, varying state durations
    obs, truth = [], []
    for p, d in zip(phone, dur):
        for s in range(S):
            g = p * S + s
            obs.append(true_means[g] + true_sd[g] * rng.normal(size=(d[s], D)))
            truth += [s] * d[s]
    length = dur.sum(axis=1)
    start = np.concatenate([[0], np.cumsum(length)[:-1]])
    states, means, variances = viterbi_em(np.concatenate(obs), start, length, phone, P, S, n_iter=20)
    assert np.mean(states == np.array(truth)) > 0.97
    np.testing.assert_allclose(means, true_means, atol=0.15)
    np.testing.assert_allclose(np.sqrt(variances), true_sd, rtol=0.2)


def test_hmm_fits_trajectories_of_a_known_hmm():
    """Trajectories holding each state's mean for its known duration: plateaus and durations come back.

    The two frames at a step have outlying deltas, and the static+delta Gaussians may put both in
    either neighbouring state: durations are checked to two frames and means to two frames' weight.
    """
    corpus = _hmm_corpus(TRUE_MEANS, TRUE_DURATIONS)
    model = HMMSynthesizer(n_states=3, context=0, min_occupancy=5, n_iter=10).fit(corpus)
    for p in TRUE_MEANS:
        np.testing.assert_allclose(model.state_durations([p]), TRUE_DURATIONS[p], atol=2.01)
        for s in range(3):
            mean, _ = model.state_gaussian([p], s)
            step = np.abs(np.diff(np.asarray(TRUE_MEANS[p]), axis=0)).max()
            np.testing.assert_allclose(
                mean, TRUE_MEANS[p][s], atol=0.03 + 2 * step / TRUE_DURATIONS[p][s], err_msg=f"{p} state {s}"
            )
    # Synthesis with the training durations reproduces the state plateaus away from the joins.
    u = corpus[0]
    y = model.predict(u.alignment)
    t = 0
    for p in u.alignment.labels:
        for s, d in enumerate(TRUE_DURATIONS[p]):
            if d >= 8:
                np.testing.assert_allclose(y[t + d // 2], TRUE_MEANS[p][s], atol=0.2)
            t += d


def test_tree_ties_identical_states_and_splits_different_ones():
    # "aa" and "iy" are generated by the same HMM; "uw" by another.
    means = {"aa": TRUE_MEANS["aa"], "iy": TRUE_MEANS["aa"], "uw": TRUE_MEANS["uw"]}
    durations = {"aa": TRUE_DURATIONS["aa"], "iy": TRUE_DURATIONS["aa"], "uw": TRUE_DURATIONS["uw"]}
    model = HMMSynthesizer(n_states=3, context=1, min_occupancy=5).fit(_hmm_corpus(means, durations, seed=4))
    for s in range(3):
        for left, right in [("aa", "uw"), ("uw", "iy"), ("sil", "aa")]:
            a = model.tied_state([left, "aa", right], s)
            assert model.tied_state([left, "iy", right], s) == a, f"state {s}: identical aa/iy not tied"
            assert model.tied_state([left, "uw", right], s) != a, f"state {s}: different uw tied with aa"
    # The middle state never sees a neighbour (edge states do, through their deltas): no context leaf.
    assert model.n_leaves_[1] == 2


def test_grow_tree_on_sufficient_statistics():
    """Units of three groups, two with one distribution: two leaves, split exactly between the groups."""
    rng = np.random.default_rng(5)
    group = np.repeat([0, 1, 2], 20)
    loc = np.array([[0.0, 0.0], [0.0, 0.0], [1.0, -1.0]])[group]
    occ = rng.integers(20, 40, size=len(group)).astype(float)
    sums, sumsq = np.zeros((len(group), 2)), np.zeros((len(group), 2))
    for u in range(len(group)):
        x = loc[u] + 0.3 * rng.normal(size=(int(occ[u]), 2))
        sums[u], sumsq[u] = x.sum(0), (x * x).sum(0)
    # Two context positions: the group, and a random bit; questions on each.
    ctx = np.stack([group, (rng.random(len(group)) < 0.5).astype(int)], axis=1)
    columns = np.array([0, 0, 0, 0, 1])
    members = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [0, 1, 1], [0, 1, 0]], dtype=bool)
    answers = members[np.arange(5)[None, :], ctx[:, columns]]
    tree = grow_tree(occ, sums, sumsq, ctx, columns, members, floor=np.full(2, 1e-4))
    leaves = tree_leaves(tree, answers)
    np.testing.assert_array_equal(leaves, tree["unit_leaf"])
    assert len(set(leaves)) == 2
    assert len(set(leaves[group < 2])) == 1 and set(leaves[group == 2]).isdisjoint(leaves[group < 2])
    # Without the MDL penalty and occupancy limit the same data splits much further.
    loose = grow_tree(occ, sums, sumsq, ctx, columns, members, floor=np.full(2, 1e-4), mdl_factor=0.0, min_occupancy=1)
    assert len(set(tree_leaves(loose, answers))) > 2


def test_phone_boundaries_are_honoured():
    """A phone's frames come from its own states: changing one phone leaves far frames untouched."""
    corpus = _hmm_corpus(TRUE_MEANS, TRUE_DURATIONS, n_utts=10)
    model = HMMSynthesizer(n_states=3, context=0, min_occupancy=5).fit(corpus)
    a = corpus[0].alignment
    other = "uw" if a.labels[-1] != "uw" else "aa"
    b = dam.Alignment(a.labels[:-1] + (other,), a.starts, a.ends)
    ya, yb = model.predict(a), model.predict(b)
    last = int(round(a.starts[-1] * FR))
    np.testing.assert_allclose(ya[: last - 10], yb[: last - 10], atol=1e-6)
    assert np.abs(ya[last + 5 :] - yb[last + 5 :]).max() > 0.5


@pytest.mark.parametrize(
    "bad", [{"n_states": 0}, {"context": 3}, {"variance_floor": 0.0}, {"mdl_factor": -1.0}, {"unknown_phone": "guess"}]
)
def test_bad_parameters_are_refused(bad):
    with pytest.raises(ValueError, match=next(iter(bad))):
        HMMSynthesizer(**bad).fit(_hmm_corpus(TRUE_MEANS, TRUE_DURATIONS, n_utts=2))


def test_inspection_names_unknown_phones():
    model = HMMSynthesizer(n_states=3, context=0, min_occupancy=5).fit(
        _hmm_corpus(TRUE_MEANS, TRUE_DURATIONS, n_utts=3)
    )
    with pytest.raises(ValueError, match="zz"):
        model.state_gaussian(["zz"], 0)
    with pytest.raises(ValueError, match="3 states"):
        model.tied_state(["aa"], 3)


def test_merge_silences_joins_only_adjacent_silences():
    from baselines.hmm import merge_silences

    a = dam.Alignment(["aa", "p", "sil", "aa"], [0.07, 0.1, 0.2, 0.3], [0.1, 0.2, 0.3, 0.4])  # gap -> silence
    assert a.labels == ("sil", "aa", "p", "sil", "aa")
    b = merge_silences(a.shifted(0.05))  # the new leading gap joins the first silence
    assert b.labels == a.labels and b.starts[1] == pytest.approx(0.12) and b.ends[0] == pytest.approx(0.12)
    assert merge_silences(a) is a


def test_registered():
    assert dam.registry.get("hmm") is HMMSynthesizer
