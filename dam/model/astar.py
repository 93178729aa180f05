"""Mode selection over the animeme graph (Chen et al. 2012, Section VI, Eq. 10).

The graph has one layer per segment and one node per mode of its phone.
A path picks one mode per segment and costs::

    E = sum_j w_c E_c(j, g_j) + sum_{j>0} w_s E_s(g_{j-1}, g_j)

* ``E_c`` (data term): the negative log-likelihood of mode ``g`` given the
  phone and its left and right neighbour phones, estimated from the training
  modes with back-off: the (left, right) trigram context if it was seen in
  training; else the left and the right bigram contexts (the mean of the
  seen ones' distributions); else the phone's unigram mode frequencies. Each
  distribution is smoothed additively (``alpha``). The utterance edges count
  as the neighbour ``BOUNDARY``.
* ``E_s`` (smoothness): the C2 jump between the two *animemes* at their joint:
  the squared differences of value, first and second time derivative of
  ``A_{j-1}`` at its end (t = 1) and ``A_j`` at its start (t = 0), derivatives
  taken per second (local-time derivatives divided by the duration^k) and made
  dimensionless by ``tau^k`` (``tau`` the median training phone duration),
  each channel divided by its training standard deviation, summed over
  channels. (The concatenated signal of Eq. 2 is C1 at every joint by
  construction, so its own jump says little; the animemes' jump says how well
  two modes connect.)

:func:`astar` finds the cheapest path with the admissible and consistent
heuristic ``h(j) = sum_{k>j} min_g (w_c E_c(k, g) + min_g' w_s E_s(g', g))``
(every later layer costs at least its cheapest node plus the cheapest edge into
it); :func:`viterbi` (dynamic programming) and :func:`exhaustive`
(enumeration) are the references the tests hold it to. Synthesis runs
:func:`astar_blocks`: the graph splits at single-mode phones into independent
blocks, short blocks are costed in full for all blocks at once, long ones go
to :func:`astar`.

numpy only: this module is on the load + predict path of a saved model.
"""
from __future__ import annotations

import heapq
import itertools

import numpy as np

__all__ = ["BOUNDARY", "context_counts", "mode_nll", "smoothness_costs", "pad_layers", "astar",
           "astar_blocks", "free_path", "viterbi", "exhaustive", "path_cost"]

BOUNDARY = "#"

# Blocks of free layers with at most this many paths are costed in full at
# once (vectorized); longer ones are searched by A*.
ENUMERATE_MAX_PATHS = 1024


def context_counts(labels_per_utt, modes_per_utt, n_modes: dict) -> dict:
    """Mode counts of every phone in its trigram, left, right and unigram contexts.

    Parameters
    ----------
    labels_per_utt : list of sequence of str
    modes_per_utt : list of sequence of int
        Local mode (0 .. n_modes[phone] - 1) of each segment.
    n_modes : dict str -> int

    Returns
    -------
    dict
        ``{phone: {"unigram": [counts], "left": {L: [counts]}, "right": {R: [counts]},
        "trigram": {L: {R: [counts]}}}}``; JSON-able.
    """
    stats: dict = {}
    for labels, modes in zip(labels_per_utt, modes_per_utt):
        padded = [BOUNDARY, *labels, BOUNDARY]
        for j, (p, g) in enumerate(zip(labels, modes)):
            L, R = padded[j], padded[j + 2]
            G = n_modes[p]
            st = stats.setdefault(p, {"unigram": [0] * G, "left": {}, "right": {}, "trigram": {}})
            st["unigram"][g] += 1
            st["left"].setdefault(L, [0] * G)[g] += 1
            st["right"].setdefault(R, [0] * G)[g] += 1
            st["trigram"].setdefault(L, {}).setdefault(R, [0] * G)[g] += 1
    return stats


def _smoothed(counts, alpha: float) -> np.ndarray:
    c = np.asarray(counts, dtype=float)
    return (c + alpha) / (c.sum() + alpha * c.size)


def mode_nll(stats: dict, phone: str, left: str, right: str, n_modes: int, alpha: float = 0.5):
    """``E_c``: negative log-likelihood of each mode of ``phone`` in context (left, right).

    Returns
    -------
    ndarray, shape (n_modes,)
    level : str
        Which context answered: "trigram", "bigram" or "unigram".
    """
    if n_modes == 1:
        return np.zeros(1), "unigram"
    st = stats.get(phone)
    if st is None:
        return np.full(n_modes, np.log(n_modes)), "unigram"
    tri = st["trigram"].get(left, {}).get(right)
    if tri is not None and sum(tri) > 0:
        return -np.log(_smoothed(tri, alpha)), "trigram"
    seen = [c for c in (st["left"].get(left), st["right"].get(right)) if c is not None and sum(c) > 0]
    if seen:
        return -np.log(np.mean([_smoothed(c, alpha) for c in seen], axis=0)), "bigram"
    return -np.log(_smoothed(st["unigram"], alpha)), "unigram"


def smoothness_costs(edge_prev: np.ndarray, edge_cur: np.ndarray, dur_prev, dur_cur,
                     tau: float, scale: np.ndarray) -> np.ndarray:
    """``E_s`` for every pair (mode of segment j-1, mode of segment j).

    Parameters
    ----------
    edge_prev : ndarray, shape (..., G_prev, 3, n_channels)
        Value, first and second local-time derivative of each previous animeme at t = 1.
    edge_cur : ndarray, shape (..., G_cur, 3, n_channels)
        The same for each current animeme at t = 0.
    dur_prev, dur_cur : float or ndarray, shape (...)
        Durations (seconds) of the two segments.
    tau : float
        Time scale (seconds) that makes the derivatives dimensionless.
    scale : ndarray, shape (n_channels,)
        Channel standard deviations.

    Returns
    -------
    ndarray, shape (..., G_prev, G_cur)
        The leading axes (many joints at once) broadcast.
    """
    k = np.arange(edge_prev.shape[-2])[:, None]
    dp = np.asarray(dur_prev, dtype=float)[..., None, None, None]
    dc = np.asarray(dur_cur, dtype=float)[..., None, None, None]
    p = edge_prev * (tau / dp) ** k / scale
    c = edge_cur * (tau / dc) ** k / scale
    return ((p[..., :, None, :, :] - c[..., None, :, :, :]) ** 2).sum(axis=(-2, -1))


def path_cost(path, node_costs, edge_costs) -> float:
    """Total cost of ``path`` (one mode index per layer)."""
    total = float(node_costs[0][path[0]])
    for j in range(1, len(path)):
        total += float(edge_costs[j - 1][path[j - 1], path[j]] + node_costs[j][path[j]])
    return total


def pad_layers(node_costs, edge_costs):
    """Layers of different sizes as rectangular arrays (missing nodes cost +inf).

    Returns
    -------
    nodes : ndarray, shape (n_layers, G_max)
    edges : ndarray, shape (n_layers - 1, G_max, G_max)
    """
    J = len(node_costs)
    G = max(len(n) for n in node_costs)
    nodes = np.full((J, G), np.inf)
    edges = np.full((max(J - 1, 0), G, G), np.inf)
    for j, n in enumerate(node_costs):
        nodes[j, :len(n)] = n
    for j, e in enumerate(edge_costs):
        e = np.asarray(e, dtype=float)
        edges[j, :e.shape[0], :e.shape[1]] = e
    return nodes, edges


def astar(node_costs, edge_costs):
    """Cheapest path through a layered graph by A*.

    Parameters
    ----------
    node_costs : list of ndarray (layer j has shape (G_j,)), or ndarray (n_layers, G_max)
        Non-negative weighted data costs ``w_c E_c``; in the rectangular form
        a missing node costs +inf (see :func:`pad_layers`).
    edge_costs : list of ndarray (entry j-1 has shape (G_{j-1}, G_j)), or ndarray (n_layers - 1, G_max, G_max)
        Non-negative weighted smoothness costs ``w_s E_s``.

    Returns
    -------
    path : list of int, length n_layers
    cost : float
    """
    if isinstance(node_costs, np.ndarray) and node_costs.ndim == 2:
        nodes_a, edges_a = node_costs, np.asarray(edge_costs)
    else:
        if len(node_costs) == 0:
            return [], 0.0
        nodes_a, edges_a = pad_layers(node_costs, edge_costs)
    J = nodes_a.shape[0]
    if J == 0:
        return [], 0.0
    # h[j]: a lower bound on the cost after layer j: per later layer, its cheapest
    # node plus the cheapest edge into that node (admissible and consistent: every
    # step of a path costs at least its layer's bound)
    step = (nodes_a[1:] + edges_a.min(axis=1)).min(axis=1) if J > 1 else np.zeros(0)
    h = np.concatenate([np.cumsum(step[::-1])[::-1], [0.0]]).tolist()
    nodes, edges = nodes_a.tolist(), edges_a.tolist()   # plain floats: fast in the loop
    inf = float("inf")
    best = {}
    parent = {}
    tie = itertools.count()
    heap = []
    for g, c in enumerate(nodes[0]):
        if c < inf:
            best[(0, g)] = c
            heapq.heappush(heap, (c + h[0], next(tie), 0, g, c))
    closed = set()
    while heap:
        _, _, j, g, cost = heapq.heappop(heap)
        if (j, g) in closed:
            continue
        closed.add((j, g))
        if j == J - 1:
            path = [g]
            while (j, g) in parent:
                g = parent[(j, g)]
                j -= 1
                path.append(g)
            return path[::-1], cost
        nxt, row, hj = nodes[j + 1], edges[j][g], h[j + 1]
        for g2, n2 in enumerate(nxt):
            c2 = cost + row[g2] + n2
            if c2 == inf:
                continue
            key = (j + 1, g2)
            if key not in closed and c2 < best.get(key, inf):
                best[key] = c2
                parent[key] = g
                heapq.heappush(heap, (c2 + hj, next(tie), j + 1, g2, c2))
    raise RuntimeError("A* found no path (empty layer?)")  # pragma: no cover


def astar_blocks(nodes: np.ndarray, edges: np.ndarray):
    """:func:`astar` on the blocks between layers that have a single node.

    A layer with one node lies on every path, so the cheapest path splits
    there into independent searches (exact, and most phones have one mode).
    Short blocks of free layers (at most :data:`ENUMERATE_MAX_PATHS` paths:
    typically one or two multi-mode phones between single-mode ones) are
    solved for all blocks at once by costing every path of each (what A*
    would settle on, without a Python loop per node); longer blocks are
    searched by :func:`astar`.

    Parameters
    ----------
    nodes : ndarray, shape (n_layers, G_max)
    edges : ndarray, shape (n_layers - 1, G_max, G_max)
        Rectangular form, see :func:`pad_layers`.

    Returns
    -------
    path : list of int
    cost : float
    """
    J = nodes.shape[0]
    if J == 0:
        return [], 0.0
    path = free_path(nodes, edges)
    steps = np.arange(J - 1)
    cost = float(nodes[np.arange(J), path].sum() + edges[steps, path[:-1], path[1:]].sum())
    return path.tolist(), cost


def free_path(nodes: np.ndarray, edges: np.ndarray, free=None) -> np.ndarray:
    """The cheapest path of :func:`astar_blocks` as an array, without its cost.

    ``free`` (bool, shape (n_layers,)), if given, marks the layers with more
    than one node; edges between two other layers are never read (the
    caller may leave them unset).
    """
    J = nodes.shape[0]
    path = np.argmin(nodes, axis=1)          # the only node of a forced layer
    if free is None:
        free = np.isfinite(nodes).sum(axis=1) > 1
    idx = np.nonzero(free)[0]
    if idx.size == 0:
        return path
    cut = np.nonzero(np.diff(idx) != 1)[0]
    first = idx[np.concatenate(([0], cut + 1))]
    last = idx[np.concatenate((cut, [idx.size - 1]))]
    L = last - first + 1
    G = nodes.shape[1]
    small = np.power(float(G), L) <= ENUMERATE_MAX_PATHS
    for n in set(L[small].tolist()):
        a = first[small & (L == n)]
        path[a[:, None] + np.arange(n)] = _enumerate_blocks(nodes, edges, path, a, n)
    for a, b in zip(first[~small], last[~small]):
        lo, hi = max(a - 1, 0), min(b + 2, J)   # the forced neighbours anchor the block
        path[lo:hi], _ = astar(nodes[lo:hi], edges[lo:hi - 1])
    return path


def _enumerate_blocks(nodes, edges, path, a, n):
    """Cheapest modes of blocks of ``n`` free layers starting at ``a`` (shape (n_blocks,)),
    each between forced layers (or the graph's ends), by costing all G^n paths at once.

    Returns
    -------
    ndarray of int, shape (n_blocks, n)
    """
    J, G = nodes.shape
    nb = len(a)
    c = nodes[a].copy()                                       # (nb, G)
    before = a > 0
    c[before] += edges[a[before] - 1, path[a[before] - 1], :]
    for k in range(1, n):                                     # c: (nb, G, ..., G), k axes of modes
        shape = (nb,) + (1,) * (k - 1) + (G, G)
        c = c[..., None] + edges[a + k - 1].reshape(shape) + nodes[a + k].reshape((nb,) + (1,) * k + (G,))
    after = a + n < J
    out = edges[a[after] + n - 1, :, path[a[after] + n]]     # (n_after, G)
    c[after] += out.reshape((-1,) + (1,) * (n - 1) + (G,))
    best = np.argmin(c.reshape(nb, -1), axis=1)
    return np.stack(np.unravel_index(best, (G,) * n), axis=1)


def viterbi(node_costs, edge_costs):
    """Cheapest path by dynamic programming (the reference for :func:`astar`)."""
    J = len(node_costs)
    if J == 0:
        return [], 0.0
    acc = np.asarray(node_costs[0], dtype=float)
    back = []
    for j in range(1, J):
        tot = acc[:, None] + np.asarray(edge_costs[j - 1], dtype=float)
        arg = np.argmin(tot, axis=0)
        back.append(arg)
        acc = tot[arg, np.arange(tot.shape[1])] + np.asarray(node_costs[j], dtype=float)
    g = int(np.argmin(acc))
    cost = float(acc[g])
    path = [g]
    for arg in reversed(back):
        g = int(arg[g])
        path.append(g)
    return path[::-1], cost


def exhaustive(node_costs, edge_costs):
    """Cheapest path by enumerating every path (tiny graphs only)."""
    best_path, best_cost = None, np.inf
    for path in itertools.product(*[range(len(n)) for n in node_costs]):
        c = path_cost(path, node_costs, edge_costs)
        if c < best_cost:
            best_path, best_cost = list(path), c
    return best_path, best_cost
