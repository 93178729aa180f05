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
:func:`free_path`, the same optimum by exact dynamic programming: the graph
splits at single-mode phones into independent blocks, and all blocks advance
together, one min-plus product per layer (:func:`chain_dp` is the plain
one-chain form). :class:`ModeGraph` holds the fixed part of a fitted model's
graph, built once at the end of fit and at load.

numpy only: this module is on the load + predict path of a saved model.
"""

from __future__ import annotations

import heapq
import itertools

import numpy as np

__all__ = [
    "BOUNDARY",
    "context_counts",
    "mode_nll",
    "smoothness_costs",
    "pad_layers",
    "astar",
    "astar_blocks",
    "free_path",
    "chain_dp",
    "viterbi",
    "exhaustive",
    "path_cost",
    "ModeGraph",
]

BOUNDARY = "#"


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
    if seen:  # (sum / len: np.mean's overhead is most of a one-phone call's selection)
        return -np.log(sum(_smoothed(c, alpha) for c in seen) / len(seen)), "bigram"
    return -np.log(_smoothed(st["unigram"], alpha)), "unigram"


def smoothness_costs(
    edge_prev: np.ndarray, edge_cur: np.ndarray, dur_prev, dur_cur, tau: float, scale: np.ndarray
) -> np.ndarray:
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
    p = edge_prev * ((tau / dp) ** k / scale)
    c = edge_cur * ((tau / dc) ** k / scale)
    p = p.reshape(p.shape[:-2] + (-1,))  # (..., G_prev, 3 C)
    c = c.reshape(c.shape[:-2] + (-1,))
    # |p - c|^2 = |p|^2 + |c|^2 - 2 p.c: one matrix product instead of a (G, G, 3, C) difference
    cost = (p * p).sum(axis=-1)[..., :, None] + (c * c).sum(axis=-1)[..., None, :] - 2.0 * (p @ np.swapaxes(c, -1, -2))
    return np.maximum(cost, 0.0)


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
        nodes[j, : len(n)] = n
    for j, e in enumerate(edge_costs):
        e = np.asarray(e, dtype=float)
        edges[j, : e.shape[0], : e.shape[1]] = e
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
    nodes, edges = nodes_a.tolist(), edges_a.tolist()  # plain floats: fast in the loop
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
    """The cheapest path and its cost, split at the layers that have a single node.

    A layer with one node lies on every path, so the cheapest path splits
    there into independent blocks (exact, and most phones have one mode);
    :func:`free_path` solves all blocks together by dynamic programming.
    Same optimum as :func:`astar` (the tests hold them to each other).

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

    Exact dynamic programming over the chain, vectorised across blocks: the
    graph splits at single-node layers into independent blocks of free
    layers, each anchored by its forced neighbours; all blocks advance one
    layer per step together (a min-plus product each), so an utterance costs
    as many numpy steps as its longest block has layers (typically 1-3),
    not one Python step per node as A* does.

    ``free`` (bool, shape (n_layers,)), if given, marks the layers with more
    than one node; edges between two other layers are never read (the
    caller may leave them unset).
    """
    J = nodes.shape[0]
    path = np.argmin(nodes, axis=1)  # the only node of a forced layer
    if free is None:
        free = np.isfinite(nodes).sum(axis=1) > 1
    idx = np.flatnonzero(free)
    if idx.size == 0:
        return path
    cut = (np.diff(idx) != 1).nonzero()[0]
    first = idx[np.concatenate(([0], cut + 1))]
    last = idx[np.concatenate((cut, [idx.size - 1]))]
    # longest block first: the blocks still running at step k are the first n_run[k] (slices, not gathers)
    order = np.argsort(first - last, kind="stable")
    first, last = first[order], last[order]
    L = last - first + 1
    n_max = int(L[0])
    n_run = np.searchsorted(-L, -np.arange(n_max), side="left").tolist()  # blocks with L > k
    acc = nodes[first]  # (n_blocks, G): fancy indexing copies
    before = first > 0
    acc[before] += edges[first[before] - 1, path[first[before] - 1], :]
    back = []
    for k in range(1, n_max):
        n = n_run[k]
        j = first[:n] + k
        tot = acc[:n, :, None] + edges[j - 1]  # (n, G_prev, G)
        back.append(tot.argmin(axis=1))
        acc[:n] = tot.min(axis=1) + nodes[j]  # the value at the argmin, without gathering it
    after = last + 1 < J
    acc[after] += edges[last[after], :, path[last[after] + 1]]
    path[last] = acc.argmin(axis=1)
    rows = np.arange(len(first))
    for k in range(n_max - 1, 0, -1):
        arg = back[k - 1]
        n = len(arg)
        j = first[:n] + k
        path[j - 1] = arg[rows[:n], path[j]]
    return path


def chain_dp(nodes: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """Cheapest path through a chain of layers by exact dynamic programming, vectorised over modes.

    The same optimum as :func:`astar` (the tests hold them to each other and
    to :func:`exhaustive`): the graph is a chain, so the cheapest cost of
    reaching every node of layer ``j`` is a min-plus product of layer
    ``j - 1``'s with the ``(G, G)`` edge costs; one numpy step per layer, no
    priority queue.

    Parameters
    ----------
    nodes : ndarray, shape (n_layers, G_max)
        Node costs, +inf for missing nodes.
    edges : ndarray, shape (n_layers - 1, G_max, G_max)

    Returns
    -------
    ndarray of int, shape (n_layers,)
    """
    J, G = nodes.shape
    if J == 0:
        return np.zeros(0, dtype=np.int64)
    back = np.empty((max(J - 1, 0), G), dtype=np.int64)
    acc = nodes[0]
    cols = np.arange(G)
    for j in range(1, J):
        tot = acc[:, None] + edges[j - 1]
        arg = tot.argmin(axis=0)
        back[j - 1] = arg
        acc = tot[arg, cols] + nodes[j]
    path = np.empty(J, dtype=np.int64)
    path[-1] = int(np.argmin(acc))
    for j in range(J - 2, -1, -1):
        path[j] = back[j, path[j + 1]]
    return path


class ModeGraph:
    """The fixed part of a fitted DAM's animeme graph, built once (at the end of fit and at load).

    Holds what does not change between utterances: the phone index, every
    phone's global mode range, and the training context counts behind
    ``E_c`` as dense arrays (unigram, left and right bigram; seen trigram
    contexts sorted by code), so the data term of a whole utterance is a few
    array lookups. It holds no animeme: ``E_s`` is computed from the model's
    current ``coef_`` on every call, and ``w_c``, ``w_s`` and the smoothing
    are arguments, so changing them (or ``coef_`` in place) never leaves
    anything stale. Rebuild it (:meth:`dam.model.DAM.select_modes` does not)
    after editing ``phone_modes_`` or ``context_counts_`` by hand.

    Parameters
    ----------
    phone_modes : dict str -> (first global mode, number of modes)
    context_counts : dict
        As :func:`context_counts` returns.

    Examples
    --------
    >>> g = ModeGraph({"a": [0, 2], "b": [2, 1]}, context_counts([["a", "b", "a"]], [[0, 0, 1]], {"a": 2, "b": 1}))
    >>> pid, first, count = g.layers(["a", "b", "a"])
    >>> nll, level = g.node_costs(pid, count, alpha=0.5)
    >>> nll.shape, level.tolist()          # both "a"s were seen in their trigram contexts
    ((3, 2), [0, 2, 0])
    """

    LEVELS = ("trigram", "bigram", "unigram")

    def __init__(self, phone_modes: dict, context_counts: dict):
        names = list(phone_modes)
        self.names = names
        self.index = {p: i for i, p in enumerate(names)}
        fc = np.array([phone_modes[p] for p in names], dtype=np.int64).reshape(-1, 2)
        self.first, self.count = fc[:, 0].copy(), fc[:, 1].copy()
        P, B = len(names), len(names)  # context index B: the utterance edge
        G = int(self.count.max()) if P else 1
        self.G = G
        ctx = {**self.index, BOUNDARY: B}
        self.unigram = np.zeros((P, G))
        self.left = np.zeros((P, B + 1, G))
        self.right = np.zeros((P, B + 1, G))
        codes, rows = [], []
        for p, st in (context_counts or {}).items():
            i = self.index.get(p)
            if i is None or self.count[i] < 2:
                continue
            g = self.count[i]
            self.unigram[i, :g] = st["unigram"][:g]
            for side, arr in (("left", self.left), ("right", self.right)):
                for q, c in st[side].items():
                    if q in ctx:
                        arr[i, ctx[q], :g] = c[:g]
            for L, byR in st["trigram"].items():
                for R, c in byR.items():
                    if L in ctx and R in ctx and sum(c) > 0:
                        codes.append((i * (B + 1) + ctx[L]) * (B + 1) + ctx[R])
                        row = np.zeros(G)
                        row[:g] = c[:g]
                        rows.append(row)
        order = np.argsort(codes, kind="stable") if codes else np.zeros(0, dtype=np.int64)
        # a last code above every real one (with zero counts): a lookup always lands on a row
        self.tri_codes = np.append(np.asarray(codes, dtype=np.int64)[order], np.iinfo(np.int64).max)
        self.tri_counts = np.vstack([np.asarray(rows, dtype=float).reshape(-1, G)[order], np.zeros((1, G))])
        # rows by (phone, context) code, and whether that context was seen (1.0) or not (0.0)
        self.left_rows, self.right_rows = self.left.reshape(-1, G), self.right.reshape(-1, G)
        self.left_seen = (self.left_rows.sum(axis=1) > 0).astype(float)
        self.right_seen = (self.right_rows.sum(axis=1) > 0).astype(float)
        # all four tables in one, so the counts behind every level are one gather
        self._rows = np.vstack((self.unigram, self.left_rows, self.right_rows, self.tri_counts))
        self._offsets = np.cumsum([0, P, P * (B + 1), P * (B + 1)])

    def layers(self, labels):
        """Phone index, first global mode and number of modes of every segment (labels must be known)."""
        pid = np.fromiter((self.index[p] for p in labels), dtype=np.int64, count=len(labels))
        return pid, self.first[pid], self.count[pid]

    def node_costs(self, pid: np.ndarray, count: np.ndarray, alpha: float):
        """``E_c`` of every mode of every segment, and its back-off level.

        Returns
        -------
        nll : ndarray, shape (n_segments, G_max)
            Negative log-likelihoods as :func:`mode_nll` gives them (0 for a
            single-mode phone), +inf for modes a phone does not have.
        level : ndarray of int, shape (n_segments,)
            Index into :attr:`LEVELS`.
        """
        # One pass over every level at once (few numpy steps: a one-phone call pays them all).
        J, G = len(pid), self.G
        nll = np.zeros((J, G))
        level = np.full(J, 2)
        multi = (count > 1).nonzero()[0]
        if multi.size:
            B1 = len(self.names) + 1  # context B1 - 1: the utterance edge
            ctx = np.concatenate(([B1 - 1], pid, [B1 - 1]))
            p = pid[multi]
            kl = p * B1 + ctx[multi]  # (phone, left) and (phone, right) rows
            kr = p * B1 + ctx[multi + 2]
            code = kl * B1 + ctx[multi + 2]
            pos = self.tri_codes.searchsorted(code)
            hit = self.tri_codes[pos] == code
            # counts behind each level: unigram, left and right bigram, trigram; smoothed
            c = self._rows.take(np.concatenate((p, kl, kr, pos)) + self._offsets.repeat(len(p)), axis=0)
            c = c.reshape(4, len(p), G)
            prob = (c + alpha) / (np.add.reduce(c, axis=2, keepdims=True) + alpha * count[multi][:, None])
            # bigram: the mean over the sides seen in training
            ls, rs = self.left_seen[kl], self.right_seen[kr]
            n_seen = ls + rs
            both = (ls[:, None] * prob[1] + rs[:, None] * prob[2]) / np.maximum(n_seen, 1.0)[:, None]
            bi = n_seen > 0
            prob = np.where(hit[:, None], prob[3], np.where(bi[:, None], both, prob[0]))
            level[multi] = np.where(hit, 0, np.where(bi, 1, 2))
            if alpha > 0:  # every probability positive
                nll[multi] = -np.log(prob)
            else:
                with np.errstate(divide="ignore"):
                    nll[multi] = -np.log(prob)
        nll[np.arange(G) >= count[:, None]] = np.inf
        return nll, level

    def edge_costs(self, first, count, durations, coef, joints, tau: float, scale) -> np.ndarray:
        """``E_s`` at ``joints`` (joint j: segment j to j + 1), shape (len(joints), G_max, G_max),
        +inf to or from a missing mode; the animemes' edges from ``coef`` (n_modes, M + 1, C)."""
        from dam.model.animeme import boundary_derivatives

        G = self.G
        if len(joints) == 0:  # a one-phone utterance has no joint
            return np.zeros((0, G, G))
        idx = first[:, None] + np.minimum(np.arange(G), count[:, None] - 1)
        d = np.asarray(durations, dtype=float)
        prev = boundary_derivatives(coef[idx[joints]], order=2)[:, :, 1]  # (n_joints, G, 3, C) at t = 1
        cur = boundary_derivatives(coef[idx[joints + 1]], order=2)[:, :, 0]  # at t = 0
        cost = smoothness_costs(prev, cur, d[joints], d[joints + 1], tau, scale)
        missing = np.arange(G) >= count[:, None]
        cost[missing[joints]] = np.inf
        cost.transpose(0, 2, 1)[missing[joints + 1]] = np.inf
        return cost


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
