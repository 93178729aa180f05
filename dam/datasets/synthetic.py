"""Synthetic corpora with known truth, for recovery tests and classroom exercises.

Sample random alignments from a phone set with durations, and render their
trajectories from any parameterized model: a DAM with given coefficients and
sigmas (:meth:`dam.model.DAM.from_parameters`), with the modes chosen by a
rule of the context if you like, any fitted :class:`dam.Synthesizer`, or a
plain function. Deterministic for a seed.

>>> import numpy as np
>>> from dam.model import DAM
>>> from dam.datasets.synthetic import make_corpus
>>> true = DAM.from_parameters({"a": (np.array([[0.5], [1.0]]), 0.4),
...                             "b": (np.array([[-0.5], [0.0]]), 0.2)},
...                            frame_rate=100.0, channels=["x"])
>>> corpus = make_corpus(true, n_utterances=5, random_state=0)
>>> len(corpus)
5
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from dam.corpus.data import Alignment, Corpus, Utterance

__all__ = ["random_alignment", "insert_segment", "make_corpus", "dam_parameters"]


def random_alignment(
    rng: np.random.Generator,
    phones: Sequence[str],
    *,
    n_segments=(8, 16),
    durations=(0.06, 0.18),
    source: str | None = None,
) -> Alignment:
    """A random phone sequence with random durations.

    Parameters
    ----------
    rng : numpy.random.Generator
    phones : sequence of str
        Drawn uniformly, no phone twice in a row (when there are >= 2).
    n_segments : int or (low, high), default (8, 16)
        Number of segments (inclusive range).
    durations : (low, high) or dict str -> (low, high), default (0.06, 0.18)
        Uniform duration range in seconds, overall or per phone.
    source : str, optional
    """
    phones = list(phones)
    n = n_segments if np.isscalar(n_segments) else int(rng.integers(n_segments[0], n_segments[1] + 1))
    labels = []
    for _ in range(n):
        choices = [p for p in phones if not labels or p != labels[-1]] or phones
        labels.append(str(choices[int(rng.integers(len(choices)))]))
    lohi = [durations[p] if isinstance(durations, dict) else durations for p in labels]
    d = np.array([rng.uniform(lo, hi) for lo, hi in lohi])
    ends = np.cumsum(d)
    return Alignment(labels, ends - d, ends, source=source)


def insert_segment(alignment: Alignment, j: int, phone: str, length: float) -> Alignment:
    """``alignment`` with a segment of ``phone``, ``length`` seconds long, cut from the start of segment ``j``.

    How to stress a model with very short phones (a forced aligner's 10 ms
    segment, or one shorter than a frame) in any context.

    Parameters
    ----------
    alignment : Alignment
    j : int
        Segment to cut into; it must be longer than ``length``.
    phone : str
    length : float
        Seconds.

    Examples
    --------
    >>> a = Alignment(["sil", "a", "sil"], [0.0, 0.1, 0.3], [0.1, 0.3, 0.4])
    >>> b = insert_segment(a, 1, "b", 0.01)
    >>> b.labels, b.starts.round(2).tolist(), b.ends.round(2).tolist()
    (('sil', 'b', 'a', 'sil'), [0.0, 0.1, 0.11, 0.3], [0.1, 0.11, 0.3, 0.4])
    """
    s = alignment.starts[j]
    labels = list(alignment.labels[:j]) + [phone] + list(alignment.labels[j:])
    starts = np.r_[alignment.starts[:j], s, s + length, alignment.starts[j + 1 :]]
    ends = np.r_[alignment.ends[:j], s + length, alignment.ends[j:]]
    return Alignment(labels, starts, ends, source=alignment.source, silence=alignment.silence)


def make_corpus(
    model,
    *,
    n_utterances: int = 20,
    phones: Sequence[str] | None = None,
    n_segments=(8, 16),
    durations=(0.06, 0.18),
    mode_rule: Callable[[str, str, str], int] | None = None,
    noise: float = 0.0,
    frame_rate: float | None = None,
    channels: Sequence[str] | None = None,
    random_state=0,
    name: str = "synthetic",
) -> Corpus:
    """Render a corpus from a known model.

    Parameters
    ----------
    model : DAM, Synthesizer or callable
        A fitted synthesizer (``predict`` is used), a DAM (with ``mode_rule``,
        :meth:`dam.model.DAM.synthesize` with the rule's modes), or a function
        ``f(alignment, n_frames) -> (n_frames, n_channels)``.
    n_utterances : int, default 20
    phones : sequence of str, optional
        Default: the model's phones (``phones_``).
    n_segments, durations
        See :func:`random_alignment`.
    mode_rule : callable (phone, left, right) -> int, optional
        The local mode of each segment from its context (neighbours; ``"#"``
        at the utterance edges). Only for DAMs.
    noise : float, default 0.0
        Standard deviation of white Gaussian noise added to the trajectories.
    frame_rate, channels : optional
        Default: the model's (a model's own frame rate is the only one it renders at;
        ``frame_rate`` is required for a function).
    random_state : int, default 0
    name : str, default "synthetic"

    Returns
    -------
    Corpus
        ``metadata["modes"]`` holds the true local modes per utterance when
        ``mode_rule`` was given; ``metadata["noise"]`` the noise level.
    """
    from dam.model.astar import BOUNDARY

    rng = np.random.default_rng(random_state)
    fr = float(frame_rate if frame_rate is not None else model.frame_rate_)
    if hasattr(model, "frame_rate_") and fr != float(model.frame_rate_):
        # a model renders frame i at i / its own frame rate: another rate would mislabel the times
        raise ValueError(
            f"parameter 'frame_rate' is {frame_rate!r} but the model synthesizes at "
            f"{model.frame_rate_:g} Hz; leave it out or give a function"
        )
    chans = list(channels if channels is not None else model.channels_)
    phones = list(phones if phones is not None else model.phones_)
    utts, all_modes = [], []
    for k in range(n_utterances):
        a = random_alignment(rng, phones, n_segments=n_segments, durations=durations, source=f"{name}/utt{k:04d}")
        n = a.n_frames(fr)
        if mode_rule is not None:
            padded = [BOUNDARY, *a.labels, BOUNDARY]
            modes = [int(mode_rule(p, padded[j], padded[j + 2])) for j, p in enumerate(a.labels)]
            all_modes.append(modes)
            y = model.synthesize(a, modes=modes, n_frames=n)
        elif hasattr(model, "predict") and hasattr(model, "frame_rate_"):
            y = model.predict(a)
        else:
            y = np.asarray(model(a, n), dtype=float)
        if noise > 0:
            y = y + rng.normal(0.0, noise, size=y.shape)
        utts.append(Utterance(a, y, fr, chans, name=f"utt{k:04d}"))
    meta = {"generator": "dam.datasets.synthetic.make_corpus", "random_state": random_state, "noise": noise}
    if mode_rule is not None:
        meta["modes"] = all_modes
    return Corpus(utts, name=name, metadata=meta)


def dam_parameters(
    phones: Sequence[str],
    n_channels: int,
    *,
    degree: int = 4,
    n_modes=1,
    sigma_range=(0.2, 0.8),
    scale: float = 1.0,
    random_state=0,
) -> dict:
    """Random DAM parameters for :meth:`dam.model.DAM.from_parameters`.

    Animemes are drawn as shifted-Legendre coefficients decaying with order
    (``scale / (m + 1)``), sigmas uniformly in ``sigma_range``.

    Parameters
    ----------
    phones : sequence of str
    n_channels : int
    degree : int, default 4
    n_modes : int or dict str -> int, default 1
    sigma_range : (low, high), default (0.2, 0.8)
    scale : float, default 1.0
    random_state : int, default 0

    Returns
    -------
    dict str -> (coef, sigma)
        ``coef`` (n_modes, degree + 1, n_channels) shifted-Legendre (pass
        ``basis="legendre"``), ``sigma`` (n_modes, n_channels).
    """
    rng = np.random.default_rng(random_state)
    out = {}
    for p in phones:
        G = n_modes[p] if isinstance(n_modes, dict) else int(n_modes)
        coef = rng.normal(0.0, 1.0, size=(G, degree + 1, n_channels)) * scale / (np.arange(degree + 1) + 1.0)[:, None]
        sigma = rng.uniform(*sigma_range, size=(G, n_channels))
        out[p] = (coef, sigma)
    return out
