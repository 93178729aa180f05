"""HMM-based trajectory synthesis in the HTS tradition (Zen et al. 2007; Tokuda et al. 2000).

What is built, step by step (``HMMSynthesizer.fit``):

1. **Observations.** Channels are standardized; every frame carries the
   static values and their delta and delta-delta (:mod:`.mlpg`).
2. **Phone models.** Each phone is a left-to-right HMM of ``n_states``
   emitting states (5 by default) with one diagonal Gaussian each.
3. **Training within the given phone boundaries.** The alignment's phone
   boundaries are known, so only the state sequence inside each segment is
   hidden. Training is Viterbi EM (segmental k-means, as HTK's ``HInit``):
   states start evenly spread over each segment; then, ``n_iter`` times,
   the Gaussians and self-loop probabilities are re-estimated from the
   current state alignment and every segment is re-aligned by a Viterbi
   pass constrained to start in the first state and end in the last
   (:func:`viterbi_segments`, batched over segments of equal length).
4. **Context clustering.** With the monophone alignment fixed, every state
   position gets a decision tree over quinphone contexts (``context=2``)
   with the MDL stopping rule and a minimum occupancy (:mod:`.tree`); the
   leaves are the tied context-dependent states. The segments are then
   re-aligned with the tied states and the leaf Gaussians re-estimated
   (``n_realign`` times).
5. **State durations.** The state durations of every segment (frames) are
   modelled by diagonal Gaussians tied by one more tree over the same
   questions, as HTS does.

Synthesis (``predict``) honours the alignment's phone boundaries: the
frames of a segment of ``n`` frames are shared among its states by the
duration model under the constraint that they sum to ``n``:
``d_s = mu_s + rho * var_s`` with ``rho = (n - sum mu) / sum var`` (HTS's
rule for a given phone duration, Yoshimura et al. 1998), rounded to whole
frames, one frame at least per state (a segment shorter than ``n_states``
frames visits states evenly, skipping some, as in training). Each frame
takes its tied state's Gaussian and MLPG produces the trajectory, one
banded solve per channel.

What is written here and why
----------------------------
hmmlearn's EM cannot confine the state path to given segment boundaries or
tie states across phone contexts, and HTS/HTK are C toolkits outside the
package index; the constrained Viterbi, the tree clustering and MLPG are
short numpy/scipy code (scipy's ``solveh_banded`` does the banded solve).
Single Gaussians, Viterbi rather than Baum-Welch re-estimation, and
explicit duration Gaussians fitted to the Viterbi state durations (rather
than HSMM re-estimation) are the simplifications; each is exact when the
state path is certain.
"""

from __future__ import annotations

import numpy as np

from dam import Alignment, Corpus, Interval, StateArray, StateNames, Synthesizer

from .mlpg import dynamic_features, mlpg
from .tree import answer_questions, context_indices, context_questions, group_sums, grow_tree, tree_leaves

__all__ = ["HMMSynthesizer", "viterbi_em", "viterbi_segments", "even_states", "durations_for_length", "merge_silences"]

_LOG2PI = float(np.log(2 * np.pi))


def merge_silences(alignment: Alignment) -> Alignment:
    """Adjacent silence segments merged into one (a shifted alignment's new leading gap, say)."""
    labels, starts, ends = list(alignment.labels), alignment.starts, alignment.ends
    keep = [0] + [
        k for k in range(1, len(labels)) if not (labels[k] == alignment.silence and labels[k - 1] == alignment.silence)
    ]
    if len(keep) == len(labels):
        return alignment
    new_ends = [ends[keep[i + 1] - 1] if i + 1 < len(keep) else ends[-1] for i in range(len(keep))]
    return Alignment(
        [labels[k] for k in keep], starts[keep], new_ends, source=alignment.source, silence=alignment.silence
    )


def even_states(n: int, n_states: int) -> np.ndarray:
    """State of each of ``n`` frames when they are spread evenly over ``n_states`` states, shape (n,)."""
    return (np.arange(n) * n_states) // max(n, 1)


def _even_states_all(length, n_states: int) -> np.ndarray:
    """:func:`even_states` of consecutive segments of ``length`` frames, concatenated."""
    length = np.asarray(length)
    first = np.repeat(np.cumsum(length) - length, length)
    n = np.repeat(length, length)
    return ((np.arange(int(length.sum())) - first) * n_states) // np.maximum(n, 1)


def viterbi_segments(loglik: np.ndarray, log_stay: np.ndarray, log_move: np.ndarray) -> np.ndarray:
    """Best left-to-right state path of segments of equal length, entering state 0, leaving from the last.

    Parameters
    ----------
    loglik : ndarray, shape (B, n, S)
        Log-likelihood of frame ``t`` of segment ``b`` in state ``s``; ``n >= S``.
    log_stay, log_move : ndarray, shape (B, S)
        Log self-loop and log forward-transition probabilities.

    Returns
    -------
    ndarray of int, shape (B, n)
        States, non-decreasing by steps of one, from 0 to S-1.
    """
    B, n, S = loglik.shape
    delta = np.full((B, S), -np.inf)
    delta[:, 0] = loglik[:, 0, 0]
    moved = np.zeros((B, n, S), dtype=bool)
    for t in range(1, n):
        stay = delta + log_stay
        move = np.full((B, S), -np.inf)
        move[:, 1:] = delta[:, :-1] + log_move[:, :-1]
        moved[:, t] = move > stay
        delta = np.maximum(stay, move) + loglik[:, t]
    path = np.empty((B, n), dtype=np.int64)
    s = np.full(B, S - 1)
    rows = np.arange(B)
    for t in range(n - 1, -1, -1):
        path[:, t] = s
        s = s - moved[rows, t, s]
    return path


def durations_for_length(mean, var, n: int) -> np.ndarray:
    """Whole-frame state durations summing to ``n``: ``mu + rho var`` rounded (HTS's rule).

    Parameters
    ----------
    mean, var : ndarray, shape (S,)
        Duration Gaussian of each state (frames).
    n : int
        Frames of the segment, ``n >= S``.

    Returns
    -------
    ndarray of int, shape (S,), each >= 1, summing to ``n``.
    """
    mean = np.asarray(mean, dtype=float)
    var = np.maximum(np.asarray(var, dtype=float), 1e-6)
    S = len(mean)
    rho = (n - mean.sum()) / var.sum()
    extra = np.maximum(mean + rho * var, 1.0) - 1.0  # frames beyond the one every state takes
    d = 1.0 + (extra * (n - S) / extra.sum() if extra.sum() > 0 else np.full(S, (n - S) / S))
    # Largest remainders keep the sum exact.
    base = np.floor(d).astype(np.int64)
    short = n - int(base.sum())
    if short > 0:
        base[np.argsort(-(d - base), kind="stable")[:short]] += 1
    elif short < 0:
        for k in np.argsort(d - base, kind="stable"):
            while short < 0 and base[k] > 1:
                base[k] -= 1
                short += 1
    return base


def viterbi_em(obs, start, length, phone, n_phones: int, n_states: int, *, n_iter: int = 5, floor=None):
    """Viterbi EM of left-to-right phone HMMs within known segment boundaries.

    Parameters
    ----------
    obs : ndarray, shape (n_frames, D)
        Observation vectors.
    start, length : ndarray of int, shape (n_segments,)
        First frame and number of frames of every segment; the segments tile
        the frames in order (``start[0] = 0``, ``start[k + 1] = start[k] + length[k]``).
    phone : ndarray of int, shape (n_segments,)
        Phone model of every segment, ``0 .. n_phones - 1``.
    n_phones, n_states : int
    n_iter : int, default 5
        Iterations; stops early when the alignment no longer changes.
    floor : ndarray, shape (D,), optional
        Variance floor (default 1e-4 of the global variance).

    Returns
    -------
    states : ndarray of int, shape (n_frames,)
        State of every frame.
    means, variances : ndarray, shape (n_phones * n_states, D)
        Gaussian of state ``s`` of phone ``p`` in row ``p * n_states + s``.
    """
    obs = np.asarray(obs, dtype=float)
    start, length = np.asarray(start), np.asarray(length)
    if (
        (len(start) and start[0] != 0)
        or np.any(start[1:] != start[:-1] + length[:-1])
        or length.sum() != len(obs)
        or np.any(length < 1)
    ):
        raise ValueError("segments must tile the frames in order: start[0] = 0, start[k+1] = start[k] + length[k]")
    seg = _SegmentFrames(obs, np.asarray(start), np.asarray(length))
    if floor is None:
        floor = 1e-4 * np.maximum(obs.var(axis=0), 1e-12)
    S = int(n_states)
    gauss = np.asarray(phone)[:, None] * S + np.arange(S)[None, :]
    states = _even_states_all(seg.length, S)
    means, variances = _estimate(seg, states, gauss, n_phones * S, floor)
    for _ in range(int(n_iter)):
        stay, move = _transitions(seg, states, gauss, n_phones * S)
        new = _realign(seg, gauss, means, variances, stay, move, S)
        if np.array_equal(new, states):
            break
        states = new
        means, variances = _estimate(seg, states, gauss, n_phones * S, floor, previous=(means, variances))
    return states, means, variances


class _SegmentFrames:
    """Observations and the frame range of every segment (segments tile the frames in order)."""

    def __init__(self, obs, start, length):
        self.obs, self.start, self.length = obs, start, length


class _Segments:
    """Every phone segment of a corpus with frames: label context and frame range in the stacked observations."""

    def __init__(self, corpus: Corpus, vocabulary, context: int, silence: str, mean, scale):
        obs, ctx, start, length = [], [], [], []
        offset = 0
        for u in corpus:
            a = merge_silences(u.alignment)
            z = (u.trajectory - mean) / scale
            obs.append(dynamic_features(z))
            seg = a.segment_index(u.frame_rate, u.n_frames)
            counts = np.bincount(seg, minlength=len(a))
            firsts = np.concatenate([[0], np.cumsum(counts)[:-1]])
            keep = counts > 0
            ctx.append(context_indices(a.labels, vocabulary, context, silence)[keep])
            start.append(firsts[keep] + offset)
            length.append(counts[keep])
            offset += u.n_frames
        self.obs = np.concatenate(obs)
        self.ctx = np.concatenate(ctx)
        self.start = np.concatenate(start)
        self.length = np.concatenate(length)
        self.centre = self.ctx[:, context]


class HMMSynthesizer(Synthesizer):
    """HTS-style HMM synthesis: context-clustered left-to-right phone HMMs and MLPG.

    Parameters
    ----------
    n_states : int, default 5
        Emitting states per phone.
    context : int, default 2
        Phones either side the clustering questions may ask about
        (0 monophone, 1 triphone, 2 quinphone as in Taylor et al.).
    n_iter : int, default 5
        Viterbi EM iterations of the monophone models (stops early when the
        state alignment no longer changes).
    n_realign : int, default 1
        Re-alignments with the clustered states.
    mdl_factor : float, default 1.0
        Scale of the MDL penalty (larger: smaller trees).
    min_occupancy : float, default 50
        Minimum frames in a tied state (Taylor et al.: 50 observations).
    min_segments : int, default 10
        Minimum segments in a tied duration distribution.
    variance_floor : float, default 0.01
        Floor of every variance as a fraction of the feature's global variance.
    unknown_phone : {"error", "fallback"}, default "error"

    Attributes
    ----------
    vocabulary_ : list of str
    silence_ : str
    y_mean_, y_scale_ : ndarray, shape (n_channels,)
    question_offsets_ : ndarray of int, shape (n_questions,)
    question_members_ : ndarray of bool, shape (n_questions, n_phones)
    question_names_ : list of str
    trees_ : list of dict
        One clustering tree per state position (:func:`baselines.hmm.tree.grow_tree`);
        leaf ``k`` of tree ``s`` is Gaussian ``leaf_offset_[s] + k``.
    leaf_offset_ : ndarray of int, shape (n_states,)
    means_, variances_ : ndarray, shape (n_gaussians, 3 * n_channels)
        Tied state Gaussians over standardized static, delta, delta-delta.
    duration_tree_ : dict
    duration_means_, duration_variances_ : ndarray, shape (n_duration_leaves, n_states)
        State durations in frames.
    n_leaves_ : list of int
        Tied states per state position.

    Examples
    --------
    >>> import dam
    >>> train = dam.datasets.load("tiny")
    >>> model = HMMSynthesizer(n_states=3, context=1).fit(train)
    >>> model.predict(train[0].alignment).shape == train[0].trajectory.shape
    True
    """

    name = "hmm"
    _tags = {"deterministic": True, "numpy_runtime": True}
    _parameter_constraints = {
        "n_states": [Interval(int, 1, None, closed="left")],
        "context": [Interval(int, 0, 2, closed="both")],
        **dict.fromkeys(["n_iter", "n_realign"], [Interval(int, 0, None, closed="left")]),
        "min_segments": [Interval(int, 1, None, closed="left")],
        **dict.fromkeys(["mdl_factor", "min_occupancy"], [Interval(float, 0, None, closed="left")]),
        "variance_floor": [Interval(float, 0, 1, closed="neither")],
    }
    _state_schema = {  # checked at save and load (dam.modelfile.check_state)
        "vocabulary_": StateNames("n_vocabulary"),
        "silence_": None,
        "y_mean_": StateArray("float", ("n_channels",)),
        "y_scale_": StateArray("float", ("n_channels",), low=0),
        "question_offsets_": StateArray("int", ("n_questions",)),
        "question_members_": StateArray("bool", ("n_questions", "n_vocabulary")),
        "question_names_": StateNames("n_questions", unique=False),
        "trees_": None,
        "leaf_offset_": StateArray("int", (None,), low=0),
        "n_leaves_": None,
        "means_": StateArray("float", ("n_leaves", "n_features")),
        "variances_": StateArray("float", ("n_leaves", "n_features"), low=0),
        "duration_means_": StateArray("float", ("n_duration_leaves", None)),
        "duration_variances_": StateArray("float", ("n_duration_leaves", None), low=0),
        "duration_tree_": None,
    }

    def __init__(
        self,
        *,
        n_states: int = 5,
        context: int = 2,
        n_iter: int = 5,
        n_realign: int = 1,
        mdl_factor: float = 1.0,
        min_occupancy: float = 50.0,
        min_segments: int = 10,
        variance_floor: float = 0.01,
        unknown_phone: str = "error",
    ):
        self.n_states = n_states
        self.context = context
        self.n_iter = n_iter
        self.n_realign = n_realign
        self.mdl_factor = mdl_factor
        self.min_occupancy = min_occupancy
        self.min_segments = min_segments
        self.variance_floor = variance_floor
        self.unknown_phone = unknown_phone

    @classmethod
    def get_test_params(cls) -> list[dict]:
        return [
            {"n_states": 3, "context": 1, "min_occupancy": 10, "n_iter": 3},
            {"n_states": 2, "context": 0, "n_iter": 1, "n_realign": 0, "unknown_phone": "fallback"},
        ]

    # -- fitting ---------------------------------------------------------------
    def _fit(self, corpus: Corpus) -> None:
        from dam.corpus import phone_vocabulary

        silence = corpus.alignments[0].silence
        S = int(self.n_states)
        self.vocabulary_ = phone_vocabulary(corpus, silence=silence)
        self.silence_ = silence
        Y = np.concatenate(corpus.trajectories)
        self.y_mean_ = Y.mean(axis=0)
        std = Y.std(axis=0)
        self.y_scale_ = np.where(std > 1e-12, std, 1.0)
        seg = _Segments(corpus, self.vocabulary_, int(self.context), silence, self.y_mean_, self.y_scale_)
        floor = self.variance_floor * np.maximum(seg.obs.var(axis=0), 1e-12)
        V = len(self.vocabulary_)

        # 3. monophone Viterbi EM: one Gaussian per (phone, state).
        states, _, _ = viterbi_em(
            seg.obs, seg.start, seg.length, seg.centre, V, S, n_iter=int(self.n_iter), floor=floor
        )
        mono = seg.centre[:, None] * S + np.arange(S)[None, :]  # (n_seg, S) monophone state of each segment

        # 4. context clustering per state position, then re-alignment with the tied states.
        offsets, members, names = context_questions(self.vocabulary_, int(self.context), silence)
        self.question_offsets_, self.question_members_, self.question_names_ = offsets, members, names
        units, unit_of_seg = np.unique(seg.ctx, axis=0, return_inverse=True)
        unit_of_seg = unit_of_seg.ravel()
        columns = offsets + int(self.context)
        frame_unit = np.repeat(unit_of_seg, seg.length)
        self.trees_ = []
        leaf_offset = [0]
        tied = np.empty((len(seg.length), S), dtype=np.int64)
        for s in range(S):
            rows = states == s
            occ, sums, sumsq = _unit_stats(frame_unit[rows], seg.obs[rows], len(units))
            tree = grow_tree(
                occ,
                sums,
                sumsq,
                units,
                columns,
                members,
                floor=floor,
                mdl_factor=float(self.mdl_factor),
                min_occupancy=max(float(self.min_occupancy), 1.0),
            )
            tied[:, s] = leaf_offset[-1] + tree.pop("unit_leaf")[unit_of_seg]
            leaf_offset.append(leaf_offset[-1] + int((tree["question"] < 0).sum()))
            self.trees_.append(tree)
        n_gauss = leaf_offset[-1]
        self.leaf_offset_ = np.asarray(leaf_offset[:-1], dtype=np.int64)
        self.n_leaves_ = [int(b - a) for a, b in zip(leaf_offset[:-1], leaf_offset[1:])]
        means, variances = _estimate(seg, states, tied, n_gauss, floor)
        for _ in range(int(self.n_realign)):
            stay, move = _transitions(seg, states, mono, V * S)
            states = _realign(seg, tied, means, variances, stay, move, S)
            means, variances = _estimate(seg, states, tied, n_gauss, floor, previous=(means, variances))
        self.means_, self.variances_ = means, variances

        # 5. state durations, tied by their own tree.
        dur = np.zeros((len(seg.length), S))
        np.add.at(dur, (np.repeat(np.arange(len(seg.length)), seg.length), states), 1.0)
        full = seg.length >= S
        occ, sums, sumsq = _unit_stats(unit_of_seg[full], dur[full], len(units))
        dfloor = np.full(S, 0.25)
        tree = grow_tree(
            occ,
            sums,
            sumsq,
            units,
            columns,
            members,
            floor=dfloor,
            mdl_factor=float(self.mdl_factor),
            min_occupancy=float(self.min_segments),
        )
        leaf = tree.pop("unit_leaf")
        n_dl = int((tree["question"] < 0).sum())
        lo, ls, lss = (np.zeros(n_dl), np.zeros((n_dl, S)), np.zeros((n_dl, S)))
        np.add.at(lo, leaf, occ)
        np.add.at(ls, leaf, sums)
        np.add.at(lss, leaf, sumsq)
        overall = dur[full].mean(axis=0) if full.any() else np.ones(S)
        n = np.maximum(lo, 1e-12)[:, None]
        self.duration_means_ = np.where(lo[:, None] > 0, ls / n, overall)
        self.duration_variances_ = np.where(lo[:, None] > 0, np.maximum(lss / n - (ls / n) ** 2, dfloor), 1.0)
        self.duration_tree_ = tree

    # -- synthesis -------------------------------------------------------------
    def _predict(self, alignment: Alignment, n_frames: int) -> np.ndarray:
        labels = self._known_labels(alignment, self.unknown_phone)
        if tuple(labels) != alignment.labels:
            alignment = Alignment(
                labels, alignment.starts, alignment.ends, source=alignment.source, silence=alignment.silence
            )
        alignment = merge_silences(alignment)
        S = int(self.n_states)
        counts = np.bincount(alignment.segment_index(self.frame_rate_, n_frames), minlength=len(alignment))
        ctx = context_indices(alignment.labels, self.vocabulary_, int(self.context), alignment.silence)
        answers = answer_questions(ctx, self.question_offsets_, self.question_members_, int(self.context))
        gauss = np.stack([self.leaf_offset_[s] + tree_leaves(self.trees_[s], answers) for s in range(S)], axis=1)
        dleaf = tree_leaves(self.duration_tree_, answers)
        frame_gauss = []
        for k, n in enumerate(counts):
            if n == 0:
                continue
            if n >= S:
                d = durations_for_length(self.duration_means_[dleaf[k]], self.duration_variances_[dleaf[k]], int(n))
                st = np.repeat(np.arange(S), d)
            else:
                st = even_states(int(n), S)
            frame_gauss.append(gauss[k, st])
        g = np.concatenate(frame_gauss)
        z = mlpg(self.means_[g], 1.0 / self.variances_[g])
        return z * self.y_scale_ + self.y_mean_

    def tied_state(self, labels, state: int) -> int:
        """Index into ``means_`` of the tied state ``state`` of the middle phone of ``labels``.

        Parameters
        ----------
        labels : sequence of str
            ``2 * context + 1`` phones centred on the phone asked about
            (silence stands for positions beyond the utterance).
        state : int
        """
        self._check_fitted()
        c = int(self.context)
        if len(labels) != 2 * c + 1:
            raise ValueError(f"labels must hold {2 * c + 1} phones (context {c}), got {len(labels)}")
        if not 0 <= state < int(self.n_states):
            raise ValueError(f"state is {state!r}; the models have {self.n_states} states")
        unknown = [lab for lab in labels if lab not in self.vocabulary_]
        if unknown:
            raise ValueError(f"phones {unknown} were not seen in training; known: {' '.join(self.vocabulary_)}")
        ctx = context_indices(list(labels), self.vocabulary_, c, self.silence_)[c : c + 1]
        answers = answer_questions(ctx, self.question_offsets_, self.question_members_, c)
        return int(self.leaf_offset_[state] + tree_leaves(self.trees_[state], answers)[0])

    def state_gaussian(self, labels, state: int) -> tuple[np.ndarray, np.ndarray]:
        """Mean and variance of the static part of a tied state, in channel units.

        Parameters
        ----------
        labels, state
            As :meth:`tied_state`.

        Returns
        -------
        mean, variance : ndarray, shape (n_channels,)
        """
        g = self.tied_state(labels, state)
        C = len(self.channels_)
        return self.means_[g, :C] * self.y_scale_ + self.y_mean_, self.variances_[g, :C] * self.y_scale_**2

    def state_durations(self, labels) -> np.ndarray:
        """Mean frames of each state of the middle phone of ``labels`` (duration model), shape (n_states,)."""
        self.tied_state(labels, 0)  # checks the labels
        c = int(self.context)
        ctx = context_indices(list(labels), self.vocabulary_, c, self.silence_)[c : c + 1]
        answers = answer_questions(ctx, self.question_offsets_, self.question_members_, c)
        return self.duration_means_[tree_leaves(self.duration_tree_, answers)[0]].copy()


def _unit_stats(unit, obs, n_units):
    """Occupancy (n_units,), sums and sums of squares (n_units, D) of the frames of every unit."""
    S = group_sums(unit, np.concatenate([np.ones((len(obs), 1)), obs, obs * obs], axis=1), n_units)
    D = obs.shape[1]
    return S[:, 0], S[:, 1 : D + 1], S[:, D + 1 :]


def _frame_gaussians(seg, states, gauss_of_seg):
    seg_of_frame = np.repeat(np.arange(len(seg.length)), seg.length)
    return gauss_of_seg[seg_of_frame, states]


def _estimate(seg, states, gauss_of_seg, n_gauss, floor, previous=None):
    """ML Gaussians from the state alignment; one no frame reaches keeps its ``previous`` value."""
    g = _frame_gaussians(seg, states, gauss_of_seg)
    occ, sums, sumsq = _unit_stats(g, seg.obs, n_gauss)
    n = np.maximum(occ, 1e-12)[:, None]
    means = sums / n
    variances = np.maximum(sumsq / n - means * means, floor)
    empty = occ == 0
    if empty.any():
        if previous is not None:
            means[empty], variances[empty] = previous[0][empty], previous[1][empty]
        else:
            means[empty], variances[empty] = seg.obs.mean(axis=0), seg.obs.var(axis=0) + floor
    return means, variances


def _transitions(seg, states, mono, n_mono):
    """Log self-loop and forward probabilities of every segment's states (monophone estimates)."""
    g = _frame_gaussians(seg, states, mono)
    frames = np.bincount(g, minlength=n_mono).astype(float)
    visits = np.zeros(n_mono)
    np.add.at(visits, mono, 1.0)  # each segment leaves each of its states once
    p_move = np.clip(visits / np.maximum(frames, 1.0), 1e-3, 1 - 1e-3)
    p_move = np.where(frames > 0, p_move, 0.5)
    return np.log1p(-p_move)[mono], np.log(p_move)[mono]


def _realign(seg, gauss_of_seg, means, variances, stay, move, S):
    """Viterbi state alignment of every segment with at least S frames (the rest spread evenly)."""
    states = _even_states_all(seg.length, S)
    first = np.concatenate([[0], np.cumsum(seg.length)[:-1]])
    prec = 1.0 / variances
    logdet = np.log(variances).sum(axis=1)
    for n in np.unique(seg.length):
        if n < S:
            continue
        ks = np.flatnonzero(seg.length == n)
        for chunk in np.array_split(ks, max(1, len(ks) * n * S // 200_000)):
            frames = seg.start[chunk][:, None] + np.arange(n)[None, :]
            o = seg.obs[frames]  # (B, n, D)
            g = gauss_of_seg[chunk]  # (B, S)
            m, p = means[g], prec[g]  # (B, S, D)
            ll = -0.5 * (
                np.einsum("bnd,bsd->bns", o * o, p)
                - 2 * np.einsum("bnd,bsd->bns", o, m * p)
                + (m * m * p).sum(-1)[:, None, :]
                + logdet[g][:, None, :]
                + o.shape[-1] * _LOG2PI
            )
            path = viterbi_segments(ll, stay[chunk], move[chunk])
            rows = first[chunk][:, None] + np.arange(n)[None, :]
            states[rows] = path
    return states
