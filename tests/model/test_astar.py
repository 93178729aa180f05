"""Mode selection: A* against exhaustive enumeration and dynamic programming; E_c back-off; E_s by hand."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dam.model.astar import (
    BOUNDARY,
    ModeGraph,
    astar,
    astar_blocks,
    chain_dp,
    context_counts,
    exhaustive,
    free_path,
    mode_nll,
    pad_layers,
    path_cost,
    smoothness_costs,
    viterbi,
)


def _graph(seed, n_layers, max_modes, scale_edges=1.0):
    rng = np.random.default_rng(seed)
    G = rng.integers(1, max_modes + 1, n_layers)
    nodes = [rng.uniform(0, 10, g) for g in G]
    edges = [rng.uniform(0, 10 * scale_edges, (G[j - 1], G[j])) for j in range(1, n_layers)]
    return nodes, edges


@settings(max_examples=150, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), n_layers=st.integers(1, 6), max_modes=st.integers(1, 4))
def test_astar_equals_exhaustive_on_small_random_graphs(seed, n_layers, max_modes):
    nodes, edges = _graph(seed, n_layers, max_modes)
    p1, c1 = astar(nodes, edges)
    p2, c2 = exhaustive(nodes, edges)
    assert c1 == pytest.approx(c2, rel=1e-12)
    assert p1 == p2  # continuous random costs: the optimum is unique
    assert path_cost(p1, nodes, edges) == pytest.approx(c1, rel=1e-12)


@settings(max_examples=60, deadline=None)
@given(
    seed=st.integers(0, 2**31 - 1),
    n_layers=st.integers(2, 60),
    max_modes=st.integers(1, 6),
    scale=st.sampled_from([0.01, 1.0, 100.0]),
)
def test_astar_equals_dynamic_programming_on_long_random_graphs(seed, n_layers, max_modes, scale):
    nodes, edges = _graph(seed, n_layers, max_modes, scale)
    p1, c1 = astar(nodes, edges)
    p2, c2 = viterbi(nodes, edges)
    assert c1 == pytest.approx(c2, rel=1e-12)
    assert p1 == p2
    # split at single-mode layers (what the DAM runs), on the rectangular form
    p3, c3 = astar_blocks(*pad_layers(nodes, edges))
    assert c3 == pytest.approx(c2, rel=1e-12)
    assert p3 == p2


@pytest.mark.parametrize("max_modes", [2, 4, 7])
def test_block_dynamic_program_equals_astar_and_dynamic_programming(max_modes):
    """free_path (what synthesis runs: all blocks advance together) against A* and viterbi, many shapes."""
    rng = np.random.default_rng(max_modes)
    for seed in range(40):
        n_layers = int(rng.integers(1, 60))
        nodes, edges = _graph(seed, n_layers, max_modes)
        n_pad, e_pad = pad_layers(nodes, edges)
        p1, c1 = astar_blocks(n_pad, e_pad)
        p2, c2 = viterbi(nodes, edges)
        p3, c3 = astar(nodes, edges)
        assert p1 == p2 == p3 and c1 == pytest.approx(c2, rel=1e-12) and c3 == pytest.approx(c2, rel=1e-12)
        assert chain_dp(n_pad, e_pad).tolist() == p2
        # edges between two single-node layers are never read
        free = np.array([len(n) > 1 for n in nodes])
        both_forced = ~free[:-1] & ~free[1:]
        e_nan = e_pad.copy()
        e_nan[both_forced] = np.nan
        assert free_path(n_pad, e_nan, free).tolist() == p2


def test_astar_prefers_smoothness_when_data_terms_tie():
    nodes = [np.zeros(2), np.zeros(2), np.zeros(2)]
    edges = [np.array([[0.0, 5.0], [5.0, 1.0]]), np.array([[3.0, 0.5], [0.0, 9.0]])]
    path, cost = astar(nodes, edges)
    assert path == [0, 0, 1] and cost == pytest.approx(0.5)


def test_context_counts_and_backoff_levels():
    labels = [["a", "x", "b"], ["a", "x", "c"], ["b", "x", "c"], ["b", "x", "c"]]
    modes = [[0, 0, 0], [0, 1, 0], [0, 1, 0], [0, 0, 0]]
    stats = context_counts(labels, modes, {"a": 1, "b": 1, "c": 1, "x": 2})
    assert stats["x"]["trigram"]["a"]["b"] == [1, 0]
    assert stats["x"]["trigram"]["b"]["c"] == [1, 1]
    assert stats["a"]["left"][BOUNDARY] == [2]
    alpha = 0.5
    nll, level = mode_nll(stats, "x", "a", "b", 2, alpha)  # seen trigram
    assert level == "trigram"
    np.testing.assert_allclose(nll, -np.log(np.array([1.5, 0.5]) / 2.0))
    nll, level = mode_nll(stats, "x", "a", "a", 2, alpha)  # unseen trigram: left bigram only
    assert level == "bigram"
    np.testing.assert_allclose(nll, -np.log(np.array([1.5, 1.5]) / 3.0))
    nll, level = mode_nll(stats, "x", "b", "b", 2, alpha)  # left "b" and right "b" both seen
    p_left = (np.array([1, 1]) + alpha) / (2 + 2 * alpha)
    p_right = (np.array([1, 0]) + alpha) / (1 + 2 * alpha)
    np.testing.assert_allclose(nll, -np.log((p_left + p_right) / 2))
    nll, level = mode_nll(stats, "x", "z", "z", 2, alpha)  # nothing: unigram
    assert level == "unigram"
    np.testing.assert_allclose(nll, -np.log((np.array([2, 2]) + alpha) / (4 + 2 * alpha)))


def test_smoothness_cost_by_hand():
    # one channel; previous animeme ends with (value, slope, curvature) = (1, 2, 3) per local time
    prev = np.array([[[1.0], [2.0], [3.0]]])
    cur = np.array([[[1.0], [1.0], [0.0]], [[0.0], [2.0], [3.0]]])
    E = smoothness_costs(prev, cur, dur_prev=0.1, dur_cur=0.2, tau=0.1, scale=np.array([2.0]))
    # per-second derivatives times tau^k: prev (1, 2, 3), cur0 (1, .5, 0), cur1 (0, 1, .75)
    want0 = ((1 - 1) ** 2 + (2 - 0.5) ** 2 + (3 - 0) ** 2) / 4
    want1 = ((1 - 0) ** 2 + (2 - 1) ** 2 + (3 - 0.75) ** 2) / 4
    np.testing.assert_allclose(E, [[want0, want1]])


@pytest.mark.parametrize("alpha", [0.5, 0.01, 2.0])
def test_mode_graph_node_costs_equal_mode_nll_in_every_context(alpha):
    """The vectorised E_c of ModeGraph against the reference back-off of mode_nll, every (left, right)."""
    rng = np.random.default_rng(int(alpha * 100))
    phones = ["a", "b", "c", "d"]
    n_modes = {"a": 3, "b": 1, "c": 2, "d": 2}
    labels = [list(rng.choice(phones, size=int(rng.integers(2, 7)))) for _ in range(25)]
    modes = [[int(rng.integers(n_modes[p])) for p in lab] for lab in labels]
    stats = context_counts(labels, modes, n_modes)
    first, phone_modes = 0, {}
    for p in phones:
        phone_modes[p] = [first, n_modes[p]]
        first += n_modes[p]
    graph = ModeGraph(phone_modes, stats)
    levels = {"trigram": 0, "bigram": 1, "unigram": 2}
    for left in phones + [None]:
        for p in phones:
            for right in phones + [None]:
                seq = [q for q in (left, p, right) if q is not None]
                j = 0 if left is None else 1
                pid, _, count = graph.layers(seq)
                nll, level = graph.node_costs(pid, count, alpha)
                want, lev = mode_nll(stats, p, left or BOUNDARY, right or BOUNDARY, n_modes[p], alpha)
                np.testing.assert_allclose(nll[j, : n_modes[p]], want, rtol=1e-12)
                assert np.all(np.isinf(nll[j, n_modes[p] :]))
                assert level[j] == levels[lev]
