"""No spike from a very short segment, in any model that renders segments.

A one-frame segment and a sub-frame one (shorter than a frame, which no frame
falls in) are inserted into held-out alignments. A model may react to them
(a new phone changes its neighbours' contexts, and a Cohen-Massaro phone
dominates by its centre whatever its length), but no frame may leave the
range spanned by the training data and the model's own prediction without
the short segment by more than a quarter of the data's range: the 10 ms
segment of issue 11 rendered 2.33 where the data was 1.17.

``dam-paper`` (the plain sum with quartic animemes) failed here until its
animemes were held outside the local times training evaluated them at
(``extrapolate="trained"``). The short phone was not the spike: inserted
before an inner pause it changed the pause's mode (through ``E_s``, whose
derivatives scale with 1 / duration) to the mode of the utterances' first
silences, which no frame ever preceded in training, so its quartic left tail
was fitted by nothing; 1.2 durations before the pause it was -4.0 on the lip
aperture. The tests below pin that cause and the fix's guarantees.
"""

import math
import warnings

import numpy as np
import pytest

import dam
from dam import Alignment
from dam.datasets.synthetic import insert_segment
from dam.model import animeme as _animeme

MODELS = [
    ("dam", {"max_iter": 5}),
    ("dam-paper", {"max_iter": 5}),
    ("dam-m0", {"max_iter": 5}),
    ("dam-m0", {"max_iter": 5, "normalize": False}),
    ("cohen-massaro", {"max_nfev": 20}),
    ("mmm", {}),
    ("hmm", {}),
]


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
            y = model.predict(insert_segment(a, j, phone, length))
            assert y.shape == base.shape
            assert np.all(y >= lo - 0.25 * span) and np.all(y <= hi + 0.25 * span), (
                f"{name}: a {length * 1e3:.1f} ms segment drives a frame outside the data's range"
            )
        checked += 1
    assert checked


# -- dam-paper: the animeme outside the local times training evaluated it at ----------------


def _plain_sum(tiny, **params):
    train, _ = tiny
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return dam.make("dam-paper", max_iter=5, **params).fit(train)


@pytest.fixture(scope="module")
def paper(tiny):
    return _plain_sum(tiny)


def _eq1(t, sigma, eps):
    """Eq. (1) of the paper, for one local time."""
    if t < 0:
        return math.exp(-t * t / (sigma * sigma + eps))
    if t > 1:
        return math.exp(-((t - 1) ** 2) / (sigma * sigma + eps))
    return 1.0


def test_trained_range_is_where_the_training_frames_reach():
    """``support_`` against a frame-by-frame loop over the training data with Eq. (1).

    One mode per phone, so every occurrence's training mode is its phone's.
    A frame counts where some channel's dominance reaches the truncation
    tolerance; the range always holds [0, 1].
    """
    train = dam.datasets.load("tiny")[:8]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = dam.make("dam-paper", modes="single", max_iter=2).fit(train)
    lo = {p: 0.0 for p in m.phone_modes_}
    hi = {p: 1.0 for p in m.phone_modes_}
    fr, tol = train.frame_rate, m.dominance_tol
    for u in train:
        a = u.alignment
        for p, s, e in zip(a.labels, a.starts, a.ends):
            g = m.phone_modes_[p][0]
            for i in range(u.n_frames):
                t = (i / fr - s) / (e - s)
                if max(_eq1(t, sig, m.eps) for sig in m.sigma_[g]) >= tol:
                    lo[p], hi[p] = min(lo[p], t), max(hi[p], t)
    for p, (g, _) in m.phone_modes_.items():
        np.testing.assert_allclose(m.support_[g], [lo[p], hi[p]], rtol=0, atol=1e-9, err_msg=p)
    assert (m.support_[:, 0] <= 0).all() and (m.support_[:, 1] >= 1).all()


def test_training_utterances_render_the_same_with_the_trained_range():
    """Holding the animeme beyond the trained range changes nothing where training looked.

    One mode per phone, so ``predict`` uses the training modes; the same
    fitted parameters rendered with the polynomial on the whole time line.
    """
    train = dam.datasets.load("tiny")[:10]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = dam.make("dam-paper", modes="single", max_iter=3).fit(train)
    held = m.predict(train.alignments)
    m.set_params(extrapolate="polynomial")
    whole = m.predict(train.alignments)
    for a, b in zip(held, whole):
        np.testing.assert_array_equal(a, b)


def _first_pause_modes(model):
    """Modes whose training range starts at t = 0: only ever fitted with no frame before them."""
    return [int(g) for g in np.flatnonzero(model.support_[:, 0] == 0.0)]


def test_the_spike_was_the_untrained_tail_of_a_first_pause_mode(tiny, paper):
    """The measured cause: an inner pause rendered in a mode trained only as an utterance's first pause.

    With the quartic on the whole time line (the paper's Eq. 2 with nothing
    held) its left tail, which no training frame reached, drives frames far out
    of the data's range; held beyond the trained range it does not.
    """
    train, test = tiny
    sil = train[0].alignment.silence
    first_pause = _first_pause_modes(paper)
    assert first_pause and all(paper.mode_phone_[g] == sil for g in first_pause)
    assert all(u.alignment.labels[0] == sil for u in train)
    Y = np.concatenate(train.trajectories)
    lo, hi = Y.min(axis=0), Y.max(axis=0)
    renders = []  # every inner pause of the held-out data, in every first-pause mode
    for u in test:
        a = u.alignment
        first = np.array([paper.phone_modes_[p][0] for p in a.labels])
        for j in [j for j in range(1, len(a) - 1) if a.labels[j] == sil]:
            for g in first_pause:
                local = paper.select_modes(a)[0] - first
                local[j] = g - first[j]
                renders.append((a, local))
    assert renders
    excess = {}
    try:
        for extrapolate in ("polynomial", "trained"):
            paper.set_params(extrapolate=extrapolate)
            ys = np.concatenate([paper.synthesize(a, modes=local) for a, local in renders])
            excess[extrapolate] = float(np.max(np.maximum(ys - hi, lo - ys) / (hi - lo)))
    finally:
        paper.set_params(extrapolate="trained")
    assert excess["polynomial"] > 0.25, excess  # the spike, as the whole-line quartic renders it
    assert excess["trained"] < 0.25, excess


def test_dam_paper_is_the_plain_sum_with_quartic_animemes_held_beyond_their_trained_range(paper):
    assert (paper.normalize, paper.degree, paper.extrapolate) == (False, 4, "trained")
    g = _first_pause_modes(paper)[0]
    phone, mode = paper.mode_phone_[g], g - paper.phone_modes_[paper.mode_phone_[g]][0]
    t = np.array([-1.5, -0.5, 0.0, 0.5, 1.0, 2.0])
    held = paper.animeme_curve(phone, mode, t)
    np.testing.assert_array_equal(held[0], held[2])  # before the range: A(0)
    np.testing.assert_array_equal(held[1], held[2])
    whole = _animeme.evaluate(paper.coef_[g], t)  # the paper's a^0 + a^1 t + ... + a^4 t^4
    np.testing.assert_allclose(held[2:], whole[2:], rtol=1e-12, atol=1e-12)  # inside it, the polynomial


def test_dam_paper_runtime_stream_and_model_file_render_the_same(tiny, paper, tmp_path):
    """Every other renderer of a fitted DAM holds the animeme where ``predict`` does."""
    from dam.export.runtime import dam_runtime, export_runtime
    from dam.export.streaming import StreamingSynthesizer

    _, test = tiny
    aligns = [insert_segment(u.alignment, 2, "aa", length) for u in list(test)[:3] for length in (0.01, 0.003)]
    paper.save(tmp_path / "p.dam")
    loaded = dam.load(tmp_path / "p.dam")
    np.testing.assert_array_equal(loaded.support_, paper.support_)
    for ext in (".json", ".npz"):
        export_runtime(paper, tmp_path / f"p{ext}")
    runtimes = [dam_runtime.load(tmp_path / f"p{ext}") for ext in (".json", ".npz")]
    for a in aligns:
        ref = paper.predict(a)
        np.testing.assert_array_equal(loaded.predict(a), ref)
        for rt in runtimes:
            np.testing.assert_allclose(rt.synthesize(list(a.labels), ends=a.ends, starts=a.starts), ref, atol=1e-9)
        s = StreamingSynthesizer(paper, max_duration=float(a.durations.max()))
        out = [s.push(lab, end=e) for lab, e in zip(a.labels, a.ends)] + [s.finish()]
        np.testing.assert_allclose(np.concatenate(out), ref, atol=1e-9, rtol=0)


def test_a_model_file_from_before_the_trained_range_still_loads():
    """The bundled default DAM was written before ``support_`` existed: it loads and renders as before."""
    from dam.datasets.default_model import DEFAULT_MODEL_PATH

    m = dam.load(DEFAULT_MODEL_PATH)
    assert m.support_ is None and m.extrapolate == "polynomial"
    phones = [p for p in m.phone_modes_ if p != "sil"][:3]
    a = Alignment(["sil", *phones, "sil"], [0.0, 0.1, 0.2, 0.3, 0.4], [0.1, 0.2, 0.3, 0.4, 0.5])
    assert np.isfinite(m.predict(a)).all()
