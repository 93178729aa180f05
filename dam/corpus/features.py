"""Frame-wise phone features for the sliding-window predictors.

Shared by the decision tree (Kim et al. 2015) and the neural predictors
(Taylor et al. 2017; Medina et al. 2022). The pipeline of Taylor et al.,
Fig. 4: the frame-wise phone sequence is cut into overlapping input windows
of ``kx`` frames, a regressor maps each window to an output window of ``ky``
frames, and the overlapping outputs are averaged frame by frame.

Window placement (``align``)
----------------------------
``"center"``
    The window of frame ``i`` covers frames ``i - k//2 .. i - k//2 + k - 1``
    (centred for odd ``k``).
``"causal"``
    The window ends at the frame: ``i - k + 1 .. i``.

Input windows are padded with silence beyond the utterance; target windows
(:func:`window_targets`) are padded by repeating the first/last frame, and
:func:`overlap_average` ignores every window entry outside the utterance.

Feature sets (``features``)
---------------------------
``"raw"``
    The one-hot phone of every window frame, concatenated: ``kx * n_phones``.
``"linguistic"``
    Taylor et al.'s supplementary indicator features (2379 for 41 phones and
    ``kx = 11``), in this order:

    1. phone identity spanning frames ``j .. j+k`` for ``k = 0..3``
       (``n_phones * (4 kx - 6)``; ``k = 0`` is the raw one-hot);
    2. phonetic category of every frame (``kx * 60``,
       :data:`dam.phonetics.TAYLOR_CATEGORIES`), plus one indicator "a consonant
       in frames ``c-h .. c-2`` or ``c+2 .. c+h``" (``c`` the centre,
       ``h = kx // 2``; the paper's ``c-5:c-2, c+2:c+5`` for ``kx = 11``);
    3. transitions between adjacent frames ``j, j+1`` (``(kx - 1) * 16``):
       consonant+vowel pair clusters (2), vowel+consonant (3),
       consonant+consonant (3), consonant then a vowel starting with
       a/e/i/o/u (5), consonant then a vowel ending with h/w/y (3).

    The pair clusters are data-driven in the paper (phone pairs clustered by
    their face parameters; the membership file is not available). By default
    they are approximated phonetically (:func:`phonetic_transition_clusters`:
    CV by whether the vowel is back/rounded; VC and CC by the place of the
    consonant, front/central/back); :func:`fit_transition_clusters` does what
    the paper did on a training corpus (k-means over the mean trajectory of
    each pair type). Categories of German SAMPA phones are those of their
    nearest ARPAbet phone (:func:`dam.phonetics.taylor_categories`). The
    paper's /sp/ is silence here (``dam.data`` merges pause labels), so its
    phone set has 40 entries and 2341 features.

``dilation`` spaces the window frames ``dilation`` frames apart: the paper's
11 frames at 29.97 frames/s span 0.37 s, which at 100 Hz takes dilation 3
(:func:`window_dilation` turns a window frame rate into a dilation).
"""

from __future__ import annotations

import numpy as np

from dam.corpus.data import SILENCE, Alignment, DataError

__all__ = [
    "phone_vocabulary",
    "frame_phone_indices",
    "window_features",
    "window_targets",
    "overlap_average",
    "window_offsets",
    "window_dilation",
    "n_window_features",
    "window_feature_names",
    "phonetic_transition_clusters",
    "fit_transition_clusters",
]

_ALIGNS = ("center", "causal")
# Transition groups of section 1.3 and their number of clusters.
_PAIR_GROUPS = (("CV", 2), ("VC", 3), ("CC", 3))
_VOWEL_START = ("a", "e", "i", "o", "u")
_VOWEL_END = ("h", "w", "y")


def phone_vocabulary(corpus_or_phones, silence: str = SILENCE) -> list[str]:
    """The sorted phone set, silence included.

    Parameters
    ----------
    corpus_or_phones : Corpus, Alignment, or iterable of str / Alignment
    silence : str, default "sil"

    Returns
    -------
    list of str
    """
    phones: set[str] = {silence}
    items = corpus_or_phones.alignments if hasattr(corpus_or_phones, "alignments") else corpus_or_phones
    if isinstance(items, Alignment):
        items = [items]
    for item in items:
        if isinstance(item, Alignment):
            phones.update(item.labels)
        else:
            phones.add(str(item))
    return sorted(phones)


def frame_phone_indices(alignment: Alignment, frame_rate: float, n_frames: int, vocabulary: list[str]) -> np.ndarray:
    """Index into ``vocabulary`` of the phone at every frame.

    Returns
    -------
    ndarray of int, shape (n_frames,)

    Raises
    ------
    DataError
        A label of ``alignment`` is not in ``vocabulary`` (resolve unseen
        phones first, e.g. with ``Synthesizer._known_labels``).
    """
    index = {p: i for i, p in enumerate(vocabulary)}
    rows = np.empty(len(alignment), dtype=np.intp)
    for k, lab in enumerate(alignment.labels):
        if lab not in index:
            raise DataError(
                alignment.source,
                f"segment {k} label",
                lab,
                "phone not in the feature vocabulary",
                f"vocabulary: {' '.join(vocabulary)}",
            )
        rows[k] = index[lab]
    return rows[alignment.segment_index(frame_rate, n_frames)]


def window_offsets(k: int, align: str = "center", dilation: int = 1) -> np.ndarray:
    """Frame offsets of a window of ``k`` frames relative to its frame, shape (k,).

    With ``dilation > 1`` the window frames are ``dilation`` frames apart (a
    window of the same number of frames spanning more time).
    """
    if int(dilation) != dilation or dilation < 1:
        raise ValueError(f"dilation must be a positive integer, got {dilation!r}")
    if align not in _ALIGNS:
        raise ValueError(f"align is {align!r}; use one of {_ALIGNS}")
    if int(k) != k or k < 1:
        raise ValueError(f"window length must be a positive integer, got {k!r}")
    k = int(k)
    start = -(k // 2) if align == "center" else -(k - 1)
    return np.arange(start, start + k) * int(dilation)


def window_dilation(frame_rate: float, window_rate: float | None = 30.0) -> int:
    """Frames between window frames so that windows step at ``window_rate`` Hz: ``round(frame_rate / window_rate)``.

    Parameters
    ----------
    frame_rate : float
        Rate of the data (Hz).
    window_rate : float or None, default 30.0
        Rate of the window frames; Taylor et al.'s video ran at 29.97 Hz, so
        ``kx = 11`` frames spanned 0.37 s. None: every data frame (dilation 1).

    Returns
    -------
    int, at least 1

    Examples
    --------
    >>> from dam.corpus import window_dilation
    >>> window_dilation(100.0), window_dilation(29.97), window_dilation(100.0, None)
    (3, 1, 1)
    >>> 11 * window_dilation(100.0) / 100.0  # seconds spanned by 11 window frames (the paper's: 11 / 29.97 = 0.37)
    0.33
    """
    if window_rate is None:
        return 1
    if not (window_rate > 0 and np.isfinite(window_rate)):
        raise ValueError(f"window_rate must be positive or None, got {window_rate!r}")
    return max(1, int(round(float(frame_rate) / float(window_rate))))


def _windows(idx: np.ndarray, kx: int, align: str, pad: int, dilation: int = 1) -> np.ndarray:
    """(n, kx) phone indices of every input window; ``pad`` outside the utterance."""
    n = len(idx)
    pos = np.arange(n)[:, None] + window_offsets(kx, align, dilation)[None, :]
    inside = (pos >= 0) & (pos < n)
    return np.where(inside, idx[np.clip(pos, 0, max(n - 1, 0))], pad)


def window_features(
    alignment: Alignment,
    frame_rate: float,
    n_frames: int,
    vocabulary: list[str],
    *,
    kx: int = 11,
    features: str = "raw",
    align: str = "center",
    alphabet: str | None = None,
    transition_clusters: dict | None = None,
    dilation: int = 1,
) -> np.ndarray:
    """Indicator features of the ``kx``-frame input window of every frame.

    Parameters
    ----------
    alignment : Alignment
    frame_rate : float
    n_frames : int
    vocabulary : list of str
        From :func:`phone_vocabulary`; must contain the alignment's silence.
    kx : int, default 11
    features : {"raw", "linguistic"}, default "raw"
        See the module docstring.
    align : {"center", "causal"}, default "center"
    alphabet : {"arpabet", "sampa"}, optional
        For the phonetic categories; guessed from ``vocabulary`` by default.
    transition_clusters : dict, optional
        ``{"CV": (V, V) int, "VC": ..., "CC": ...}`` cluster of every phone
        pair (-1: none), from :func:`fit_transition_clusters`; phonetic
        approximation (:func:`phonetic_transition_clusters`) by default.
    dilation : int, default 1
        Window frames are ``dilation`` frames apart (:func:`window_offsets`).

    Returns
    -------
    ndarray of float32, shape (n_frames, n_features)
        ``n_features = n_window_features(len(vocabulary), kx, features)``.
    """
    if features not in ("raw", "linguistic"):
        raise ValueError(f"features is {features!r}; use 'raw' or 'linguistic'")
    if alignment.silence not in vocabulary:
        raise ValueError(f"the vocabulary lacks the silence label {alignment.silence!r} used for padding")
    V = len(vocabulary)
    W = _windows(
        frame_phone_indices(alignment, frame_rate, n_frames, vocabulary),
        kx,
        align,
        vocabulary.index(alignment.silence),
        dilation,
    )
    onehot = np.zeros((len(W), kx, V), dtype=np.float32)
    np.put_along_axis(onehot, W[:, :, None], 1.0, axis=2)
    if features == "raw":
        return onehot.reshape(len(W), kx * V)
    return _linguistic(W, onehot, vocabulary, alphabet, transition_clusters, alignment.silence)


def n_window_features(n_phones: int, kx: int = 11, features: str = "raw") -> int:
    """Length of a feature vector of :func:`window_features`."""
    if features == "raw":
        return n_phones * kx
    spans = sum(kx - k for k in range(min(4, kx)))
    return n_phones * spans + kx * 60 + 1 + (kx - 1) * (2 + 3 + 3 + 5 + 3)


def window_feature_names(vocabulary: list[str], kx: int = 11, features: str = "raw") -> list[str]:
    """A readable name for every column of :func:`window_features` (frames numbered 0..kx-1).

    E.g. ``"phone[3]=s"``, ``"phone[2:4]=s"`` (frames 2..4 all /s/),
    ``"cat[5]=Nasal"``, ``"consonant_away_from_centre"``, ``"CV[4,5]=1"``,
    ``"C+vowel_starting_a[4,5]"``.
    """
    from dam.corpus.phonetics import TAYLOR_CATEGORIES

    if features == "raw":
        return [f"phone[{j}]={p}" for j in range(kx) for p in vocabulary]
    names = [
        f"phone[{j}]={p}" if k == 0 else f"phone[{j}:{j + k}]={p}"
        for k in range(min(4, kx))
        for j in range(kx - k)
        for p in vocabulary
    ]
    names += [f"cat[{j}]={c}" for j in range(kx) for c in TAYLOR_CATEGORIES]
    names.append("consonant_away_from_centre")
    for group, n_clusters in _PAIR_GROUPS:
        names += [f"{group}[{j},{j + 1}]={c}" for j in range(kx - 1) for c in range(n_clusters)]
    names += [f"C+vowel_starting_{v}[{j},{j + 1}]" for j in range(kx - 1) for v in _VOWEL_START]
    names += [f"C+vowel_ending_{v}[{j},{j + 1}]" for j in range(kx - 1) for v in _VOWEL_END]
    return names


def _categories(vocabulary, alphabet, silence):
    """(V, 60) membership, (V,) consonant, (V,) vowel, (V, 5) starts, (V, 3) ends."""
    from dam.corpus.phonetics import TAYLOR_CATEGORIES, is_consonant, taylor_categories

    alphabet = alphabet or _guess(vocabulary)
    names = list(TAYLOR_CATEGORIES)
    cats = [taylor_categories(p, alphabet, silence) for p in vocabulary]
    member = np.array([[n in c for n in names] for c in cats], dtype=bool).reshape(len(vocabulary), len(names))
    cons = np.array([is_consonant(p, alphabet, silence) for p in vocabulary], dtype=bool)
    vowel = member[:, names.index("Vowel")]
    starts = member[:, [names.index(f"Vowel-starting-{s}") for s in _VOWEL_START]]
    ends = member[:, [names.index(f"Vowel-ending-{s}") for s in _VOWEL_END]]
    return member, cons, vowel, starts, ends


def phonetic_transition_clusters(
    vocabulary: list[str], alphabet: str | None = None, silence: str = SILENCE
) -> dict[str, np.ndarray]:
    """A phonetic stand-in for Taylor et al.'s data-driven pair clusters.

    CV pairs: 2 clusters, whether the vowel is back or rounded
    (Vowel-Back, OVowel or ending in /w/). VC pairs: 3 clusters by the place
    of the consonant (Front/Central/Back-Consonant); CC pairs: the same, by
    the second consonant.

    Returns
    -------
    dict with keys "CV", "VC", "CC", each an int array (V, V); -1 where the
    pair is not of that type.
    """
    from dam.corpus.phonetics import TAYLOR_CATEGORIES

    alphabet = alphabet or _guess(vocabulary)
    member, cons, vowel, _, _ = _categories(vocabulary, alphabet, silence)
    names = list(TAYLOR_CATEGORIES)
    rounded = member[:, [names.index(n) for n in ("Vowel-Back", "OVowel", "Vowel-ending-w")]].any(axis=1)
    place = np.full(len(vocabulary), 1)  # central unless the table says front/back
    for k, nm in ((0, "Front-Consonant"), (2, "Back-Consonant")):
        place[member[:, names.index(nm)] & ~member[:, names.index("Central-Consonant")]] = k
    V = len(vocabulary)
    out = {}
    first_c, first_v = cons[:, None], vowel[:, None]
    out["CV"] = np.where(first_c & vowel[None, :], np.broadcast_to(rounded[None, :].astype(int), (V, V)), -1)
    out["VC"] = np.where(first_v & cons[None, :], np.broadcast_to(place[None, :], (V, V)), -1)
    out["CC"] = np.where(first_c & cons[None, :], np.broadcast_to(place[None, :], (V, V)), -1)
    return out


def fit_transition_clusters(
    corpus, vocabulary: list[str], *, alphabet: str | None = None, random_state: int = 0
) -> dict[str, np.ndarray]:
    """Taylor et al.'s data-driven pair clusters, fitted on a training corpus.

    Every adjacent segment pair of type CV, VC or CC is described by the mean
    trajectory over its two segments; pair types are averaged and clustered
    by k-means into 2 (CV) or 3 (VC, CC) clusters. Pairs never seen in
    training get the phonetic cluster (:func:`phonetic_transition_clusters`).

    Returns
    -------
    dict with keys "CV", "VC", "CC" of int arrays (V, V).
    """
    from sklearn.cluster import KMeans

    silence = corpus.alignments[0].silence
    alphabet = alphabet or _guess(vocabulary)
    _, cons, vowel, _, _ = _categories(vocabulary, alphabet, silence)
    out = phonetic_transition_clusters(vocabulary, alphabet, silence)
    index = {p: i for i, p in enumerate(vocabulary)}
    sums: dict[tuple[int, int], np.ndarray] = {}
    counts: dict[tuple[int, int], int] = {}
    for u in corpus:
        a = u.alignment
        seg = a.segment_index(u.frame_rate, u.n_frames)
        for k in range(len(a) - 1):
            i, j = index[a.labels[k]], index[a.labels[k + 1]]
            frames = (seg == k) | (seg == k + 1)
            if not frames.any():
                continue
            sums[(i, j)] = sums.get((i, j), 0) + u.trajectory[frames].mean(axis=0)
            counts[(i, j)] = counts.get((i, j), 0) + 1
    kinds = {"CV": (cons, vowel), "VC": (vowel, cons), "CC": (cons, cons)}
    for group, n_clusters in _PAIR_GROUPS:
        first, second = kinds[group]
        pairs = [p for p in sums if first[p[0]] and second[p[1]]]
        if len(pairs) < n_clusters:
            continue  # too few pair types: keep the phonetic clusters
        X = np.stack([sums[p] / counts[p] for p in pairs])
        labels = KMeans(n_clusters=n_clusters, n_init=10, random_state=random_state).fit_predict(X)
        for (i, j), c in zip(pairs, labels):
            out[group][i, j] = c
    return out


def _guess(vocabulary):
    from dam.corpus.phonetics import guess_alphabet

    return guess_alphabet(vocabulary)


def _linguistic(W, onehot, vocabulary, alphabet, clusters, silence) -> np.ndarray:
    n, kx, V = onehot.shape
    member, cons, vowel, starts, ends = _categories(vocabulary, alphabet, silence)
    clusters = clusters if clusters is not None else phonetic_transition_clusters(vocabulary, alphabet, silence)
    for group, _ in _PAIR_GROUPS:
        if np.shape(clusters.get(group)) != (V, V):
            raise ValueError(
                f"transition_clusters[{group!r}] must have shape {(V, V)}, got {np.shape(clusters.get(group))}"
            )
    blocks = []
    # 1. phone identity spanning frames j..j+k, k = 0..3
    for k in range(min(4, kx)):
        span = onehot[:, : kx - k]
        for d in range(1, k + 1):
            span = span * onehot[:, d : kx - k + d]
        blocks.append(span.reshape(n, -1))
    # 2. category of every frame, and "a consonant away from the centre"
    blocks.append(member[W].reshape(n, -1))
    c, h = kx // 2, kx // 2
    away = np.r_[max(0, c - h) : max(0, c - 1), c + 2 : min(kx, c + h + 1)]
    blocks.append(cons[W[:, away]].any(axis=1, keepdims=True) if away.size else np.zeros((n, 1), bool))
    # 3. transitions between adjacent frames j, j+1
    L, R = W[:, :-1], W[:, 1:]
    for group, n_clusters in _PAIR_GROUPS:
        lab = np.asarray(clusters[group])[L, R]
        blocks.append((lab[:, :, None] == np.arange(n_clusters)).reshape(n, -1))
    cv = cons[L][:, :, None]
    blocks.append((cv & starts[R]).reshape(n, -1))
    blocks.append((cv & ends[R]).reshape(n, -1))
    return np.concatenate([b.astype(np.float32, copy=False) for b in blocks], axis=1)


def window_targets(trajectory, *, ky: int = 5, align: str = "center", dilation: int = 1) -> np.ndarray:
    """The ``ky``-frame output window of every frame, flattened.

    Parameters
    ----------
    trajectory : array-like, shape (n_frames, n_channels)
    ky : int, default 5
    align : {"center", "causal"}, default "center"
    dilation : int, default 1

    Returns
    -------
    ndarray, shape (n_frames, ky * n_channels)
        Row ``i`` holds frames ``i + window_offsets(ky, align, dilation)`` in order,
        channels fastest (entry ``j * n_channels + c``); frames beyond the
        utterance repeat its first/last frame.
    """
    Y = np.asarray(trajectory, dtype=float)
    if Y.ndim == 1:
        Y = Y[:, None]
    n = len(Y)
    pos = np.clip(np.arange(n)[:, None] + window_offsets(ky, align, dilation)[None, :], 0, n - 1)
    return Y[pos].reshape(n, -1)


def overlap_average(
    window_predictions, ky: int, n_channels: int, align: str = "center", dilation: int = 1
) -> np.ndarray:
    """Blend overlapping output windows by the frame-wise mean (Taylor et al., Fig. 4e).

    Parameters
    ----------
    window_predictions : array-like, shape (n_frames, ky * n_channels)
        Row ``i`` is the predicted window of frame ``i`` (layout of
        :func:`window_targets`).
    ky : int
    n_channels : int
    align : {"center", "causal"}, default "center"
    dilation : int, default 1

    Returns
    -------
    ndarray, shape (n_frames, n_channels)
        Frame ``t`` is the mean of every window entry that lands on ``t``;
        near the edges fewer windows cover a frame.
    """
    P = np.asarray(window_predictions, dtype=float)
    n = len(P)
    if P.shape != (n, ky * n_channels):
        raise ValueError(f"window_predictions has shape {P.shape}, expected ({n}, {ky * n_channels})")
    P = P.reshape(n, ky, n_channels)
    total = np.zeros((n, n_channels))
    count = np.zeros(n)
    for j, off in enumerate(window_offsets(ky, align, dilation)):
        lo, hi = max(0, -off), min(n, n - off)  # windows i whose entry j lands inside [0, n)
        if lo < hi:
            total[lo + off : hi + off] += P[lo:hi, j]
            count[lo + off : hi + off] += 1
    return total / count[:, None]
