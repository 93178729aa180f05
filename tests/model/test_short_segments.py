"""No spike from a very short segment, in any model that renders segments.

A one-frame segment and a sub-frame one (shorter than a frame, which no frame
falls in) are inserted into held-out alignments. A model may react to them
(a new phone changes its neighbours' contexts, and a Cohen-Massaro phone
dominates by its centre whatever its length), but no frame may leave the
range spanned by the training data and the model's own prediction without
the short segment by more than a quarter of the data's range: the 10 ms
segment of issue 11 rendered 2.33 where the data was 1.17.
"""

import warnings

import numpy as np
import pytest

import dam
from dam import Alignment

PAPER_TAILS = pytest.mark.xfail(
    strict=True,
    reason=(
        "dam-paper, the literal plain sum with quartic animemes evaluated on the whole time line: a phone far "
        "shorter than any in training puts its neighbours' frames at local times of 3-5 durations, where the "
        "quartic is large and the summed (not averaged) dominance still lets it through; `dam` (weighted "
        "average) and the plain sum with constant animemes (dam-m0) do not overshoot"
    ),
)
MODELS = [
    ("dam", {"max_iter": 5}),
    pytest.param("dam-paper", {"max_iter": 5}, marks=PAPER_TAILS),
    ("dam-m0", {"max_iter": 5}),
    ("dam-m0", {"max_iter": 5, "normalize": False}),
    ("cohen-massaro", {"max_nfev": 20}),
    ("mmm", {}),
    ("hmm", {}),
]


def _with_short(a: Alignment, j: int, phone: str, length: float) -> Alignment:
    """``a`` with a segment of ``length`` seconds cut from the start of segment ``j``."""
    s = a.starts[j]
    labels = list(a.labels[:j]) + [phone] + list(a.labels[j:])
    starts = np.r_[a.starts[:j], s, s + length, a.starts[j + 1 :]]
    ends = np.r_[a.ends[:j], s + length, a.ends[j:]]
    return Alignment(labels, starts, ends, source=a.source)


@pytest.fixture(scope="module")
def tiny():
    c = dam.datasets.load("tiny")
    return c.train_test_split(0.25, random_state=0)


@pytest.mark.parametrize(
    "name,params", MODELS, ids=["dam", "dam-paper", "dam-m0", "dam-m0-plain-sum", "cohen-massaro", "mmm", "hmm"]
)
def test_one_frame_and_sub_frame_segments_make_no_spike(tiny, name, params):
    ok, why = dam.registry.available(name)
    if not ok:
        pytest.skip(f"{name}: {why}")
    train, test = tiny
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = dam.make(name, **params).fit(train)
    Y = np.concatenate(train.trajectories)
    span = Y.max(axis=0) - Y.min(axis=0)
    fr = train.frame_rate
    phone = sorted(train.phones - {train[0].alignment.silence})[0]
    checked = 0
    for u in list(test)[:4]:
        a = u.alignment
        j = int(np.argmax(a.durations[1:-1])) + 1  # a long inner segment to cut into
        if a.durations[j] < 4 / fr:
            continue
        base = model.predict(a)
        # the range of the data and of the model's own prediction without the short segment
        lo, hi = np.minimum(Y.min(axis=0), base.min(axis=0)), np.maximum(Y.max(axis=0), base.max(axis=0))
        for length in (1.0 / fr, 0.3 / fr):
            y = model.predict(_with_short(a, j, phone, length))
            assert y.shape == base.shape
            assert np.all(y >= lo - 0.25 * span) and np.all(y <= hi + 0.25 * span), (
                f"{name}: a {length * 1e3:.1f} ms segment drives a frame outside the data's range"
            )
        checked += 1
    assert checked
