"""Decision-tree state clustering (Odell 1995; Young, Odell and Woodland 1994) with the MDL stopping rule.

Every *unit* (a distinct phone context, for one state position) carries the
sufficient statistics of the frames aligned to it: occupancy ``N``, sums and
sums of squares (diagonal Gaussian). Starting from one cluster holding every
unit, a node is split by the yes/no question about the context that gains
the most log-likelihood,

    L(cluster) = -N/2 * (D log(2 pi) + sum_d log var_d + D),

and the split is kept only when the gain exceeds the minimum description
length penalty of one more Gaussian (Shinoda and Watanabe 2000):
``mdl_factor * D * log(N_root)`` (2D more parameters, each costing
``log(N_root) / 2``), and when both children hold at least
``min_occupancy`` frames. Leaves are the tied states.

Questions ask whether the phone at a context position (``-2 .. 2``:
left-left, left, centre, right, right-right) is a given phone or belongs to
a phone class: the classes of :func:`dam.corpus.taylor_categories` (Taylor
et al.'s 60 categories, largely Odell's questions) and of
:func:`dam.corpus.phone_class`. Positions beyond the utterance read silence.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "context_questions",
    "context_indices",
    "answer_questions",
    "grow_tree",
    "tree_leaves",
    "gaussian_loglik",
    "group_sums",
]

_LOG2PI = float(np.log(2 * np.pi))


def context_questions(vocabulary, context: int = 2, silence: str = "sil"):
    """The question set: every phone and every phone class, at every context position.

    Parameters
    ----------
    vocabulary : list of str
        The phone set, silence included.
    context : int, default 2
        Positions ``-context .. context`` (0: monophone, 1: triphone, 2: quinphone).
    silence : str, default "sil"

    Returns
    -------
    offsets : ndarray of int, shape (n_questions,)
    members : ndarray of bool, shape (n_questions, len(vocabulary))
        ``members[q, v]``: phone ``v`` at position ``offsets[q]`` answers yes.
    names : list of str
        Readable names, e.g. ``"L-Nasal"``, ``"C-is-a:"``, ``"RR-Vowel"``.
        Identical phone sets at one position are asked once.
    """
    from dam.corpus import TAYLOR_CATEGORIES, guess_alphabet, phone_class, taylor_categories

    vocabulary = list(vocabulary)
    alphabet = guess_alphabet(vocabulary)
    sets: list[tuple[str, frozenset]] = [(f"is-{p}", frozenset({p})) for p in vocabulary]
    cats = {p: taylor_categories(p, alphabet, silence) for p in vocabulary}
    for name in TAYLOR_CATEGORIES:
        sets.append((name, frozenset(p for p in vocabulary if name in cats[p])))
    classes = {p: phone_class(p, alphabet if alphabet == "arpabet" else None) for p in vocabulary}
    for name in sorted({c for c in classes.values() if c}):
        sets.append((name, frozenset(p for p in vocabulary if classes[p] == name)))
    pos_name = {-2: "LL", -1: "L", 0: "C", 1: "R", 2: "RR"}
    offsets, members, names = [], [], []
    for off in range(-context, context + 1):
        seen = set()
        for name, s in sets:
            if not s or len(s) == len(vocabulary) or s in seen:
                continue  # a question everyone (or no one) answers yes cannot split
            seen.add(s)
            offsets.append(off)
            members.append([p in s for p in vocabulary])
            names.append(f"{pos_name.get(off, str(off))}-{name}")
    return (
        np.asarray(offsets, dtype=np.int64),
        np.asarray(members, dtype=bool).reshape(len(offsets), len(vocabulary)),
        names,
    )


def context_indices(labels, vocabulary, context: int, silence: str) -> np.ndarray:
    """Vocabulary index of the phone at every context position of every segment.

    Returns
    -------
    ndarray of int, shape (len(labels), 2 * context + 1)
        Column ``context + o`` holds the phone ``o`` segments away; silence beyond the ends.
    """
    index = {p: i for i, p in enumerate(vocabulary)}
    idx = np.array([index[lab] for lab in labels], dtype=np.int64)
    n = len(idx)
    pos = np.arange(n)[:, None] + np.arange(-context, context + 1)[None, :]
    inside = (pos >= 0) & (pos < n)
    return np.where(inside, idx[np.clip(pos, 0, n - 1)], index[silence])


def answer_questions(ctx: np.ndarray, offsets: np.ndarray, members: np.ndarray, context: int) -> np.ndarray:
    """Answers of every question for every context row: bool (n_rows, n_questions)."""
    cols = ctx[:, offsets + context]  # (n, Q): the phone each question looks at
    return members[np.arange(len(offsets))[None, :], cols]


def gaussian_loglik(occ, sums, sumsq, floor) -> np.ndarray:
    """Log-likelihood of the frames of each cluster under its own ML diagonal Gaussian.

    ``occ`` (...,), ``sums``/``sumsq`` (..., D), ``floor`` (D,) variance floor.
    """
    occ = np.asarray(occ, dtype=float)
    n = np.maximum(occ, 1e-12)[..., None]
    mean = sums / n
    var = np.maximum(sumsq / n - mean * mean, floor)
    D = sums.shape[-1]
    return -0.5 * occ * (D * (_LOG2PI + 1.0) + np.log(var).sum(axis=-1))


def grow_tree(
    occ,
    sums,
    sumsq,
    ctx,
    columns,
    members,
    *,
    floor,
    mdl_factor: float = 1.0,
    min_occupancy: float = 50.0,
    max_leaves: int | None = None,
) -> dict:
    """Grow one clustering tree over units.

    Parameters
    ----------
    occ : ndarray, shape (U,)
        Occupancy (frames) of every unit.
    sums, sumsq : ndarray, shape (U, D)
    ctx : ndarray of int, shape (U, P)
        The unit's phone (vocabulary index) at each context position.
    columns : ndarray of int, shape (Q,)
        The position (column of ``ctx``) question ``q`` asks about.
    members : ndarray of bool, shape (Q, V)
        ``members[q, v]``: phone ``v`` there answers question ``q`` with yes.
    floor : ndarray, shape (D,)
        Variance floor.
    mdl_factor : float, default 1.0
        Scales the MDL penalty; 0 splits whenever the occupancy allows.
    min_occupancy : float, default 50
        Minimum frames in each child (Taylor et al. used 50 observations).
    max_leaves : int, optional

    Returns
    -------
    dict of ndarray, each of shape (n_nodes,)
        ``question`` (-1 at leaves), ``yes``, ``no`` (child nodes, -1 at
        leaves), ``leaf`` (leaf number, -1 at inner nodes); and
        ``unit_leaf`` (U,): the leaf of every unit.

    Notes
    -----
    A question reads one position, so the statistics of its yes-branch are
    those of the phones it names there: a node sums its units' statistics
    by phone once per position (``P`` sorts of ``U`` rows) and every
    question's split follows by a ``(Q, V) @ (V, 2D + 1)`` product, instead of
    summing the units once per question.
    """
    occ = np.asarray(occ, dtype=float)
    X = np.concatenate([occ[:, None], np.asarray(sums, dtype=float), np.asarray(sumsq, dtype=float)], axis=1)
    ctx = np.asarray(ctx)
    columns = np.asarray(columns)
    M = np.asarray(members, dtype=float)
    V = M.shape[1]
    D = (X.shape[1] - 1) // 2
    threshold = mdl_factor * D * np.log(max(occ.sum(), 2.0))
    by_col = [np.flatnonzero(columns == c) for c in range(ctx.shape[1])]
    question, yes, no = [-1], [-1], [-1]
    members_of = {0: np.arange(len(occ))}
    stack = [0]
    n_leaves = 1
    while stack:
        node = stack.pop()
        idx = members_of[node]
        if max_leaves is not None and n_leaves >= max_leaves:
            break
        if len(idx) < 2:
            continue
        total = X[idx].sum(axis=0)
        Y = np.zeros((len(columns), X.shape[1]))  # yes-branch statistics of every question
        for c, qs in enumerate(by_col):
            if len(qs):
                Y[qs] = M[qs] @ group_sums(ctx[idx, c], X[idx], V)
        Nn = total - Y
        gain = (
            gaussian_loglik(Y[:, 0], Y[:, 1 : D + 1], Y[:, D + 1 :], floor)
            + gaussian_loglik(Nn[:, 0], Nn[:, 1 : D + 1], Nn[:, D + 1 :], floor)
            - gaussian_loglik(total[0], total[1 : D + 1], total[D + 1 :], floor)
        )
        ok = (Y[:, 0] >= min_occupancy) & (Nn[:, 0] >= min_occupancy)
        if not ok.any():
            continue
        gain = np.where(ok, gain, -np.inf)
        q = int(np.argmax(gain))  # ties: the first question in the list
        if not gain[q] > threshold:
            continue
        go = M[q, ctx[idx, columns[q]]] > 0
        for part in (idx[go], idx[~go]):
            members_of[len(question)] = part
            stack.append(len(question))
            question.append(-1)
            yes.append(-1)
            no.append(-1)
        question[node], yes[node], no[node] = q, len(question) - 2, len(question) - 1
        n_leaves += 1
        del members_of[node]
    question = np.asarray(question, dtype=np.int64)
    leaf = np.full(len(question), -1, dtype=np.int64)
    leaf[question < 0] = np.arange(int((question < 0).sum()))
    tree = {
        "question": question,
        "yes": np.asarray(yes, dtype=np.int64),
        "no": np.asarray(no, dtype=np.int64),
        "leaf": leaf,
    }
    answers = np.asarray(members, dtype=bool)[np.arange(len(columns))[None, :], ctx[:, columns]]
    tree["unit_leaf"] = tree_leaves(tree, answers)
    return tree


def group_sums(group, X, n_groups: int) -> np.ndarray:
    """Rows of ``X`` (n, K) summed by ``group`` (n ints in ``0 .. n_groups-1``): shape (n_groups, K)."""
    out = np.zeros((n_groups, X.shape[1]))
    if len(group) == 0:
        return out
    order = np.argsort(group, kind="stable")
    g = group[order]
    first = np.flatnonzero(np.r_[True, g[1:] != g[:-1]])
    out[g[first]] = np.add.reduceat(X[order], first, axis=0)
    return out


def tree_leaves(tree: dict, answers) -> np.ndarray:
    """Leaf number of every row of ``answers`` (bool, (n, Q)): shape (n,)."""
    answers = np.asarray(answers, dtype=bool)
    q, yes, no = tree["question"], tree["yes"], tree["no"]
    node = np.zeros(len(answers), dtype=np.int64)
    rows = np.arange(len(answers))
    active = q[node] >= 0
    while active.any():
        r, nd = rows[active], node[active]
        node[r] = np.where(answers[r, q[nd]], yes[nd], no[nd])
        active[r] = q[node[r]] >= 0
    return tree["leaf"][node]
