"""Streaming synthesis equals batch, and a frame once returned never changes."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import dam
import dam.datasets
from dam.corpus import Alignment, DataError
from dam.export.streaming import BufferedStream, StreamingSynthesizer, stream


@pytest.fixture(scope="module")
def tiny():
    return dam.datasets.load("tiny")


@pytest.fixture(scope="module")
def model(tiny):
    return dam.make("dam").fit(tiny)


def phones_strategy(phones, max_duration):
    return st.lists(
        st.tuples(st.sampled_from(sorted(phones)), st.floats(0.015, max_duration, allow_nan=False)),
        min_size=1,
        max_size=25,
    )


def run_stream(s, seq):
    chunks, ends = [], 0.0
    for lab, d in seq:
        ends += d
        chunks.append(s.push(lab, end=ends))
    chunks.append(s.finish())
    return chunks


def alignment_of(seq):
    ends = np.cumsum([d for _, d in seq])
    return Alignment([lab for lab, _ in seq], np.concatenate([[0.0], ends[:-1]]), ends)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_stream_equals_batch_on_random_alignments(model, data):
    seq = data.draw(phones_strategy(model.phone_modes_, 0.3))
    # adjacent silences merge (as in dam.Alignment): the longest merged segment bounds the phones
    s = StreamingSynthesizer(model, max_duration=float(alignment_of(seq).durations.max()))
    chunks = run_stream(s, seq)
    a = alignment_of(seq)
    out = np.concatenate(chunks)
    ref = model.predict(a)
    assert out.shape == ref.shape
    np.testing.assert_allclose(out, ref, atol=1e-9, rtol=0)
    assert s.modes == list(model.select_modes(a)[0])


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_emitted_frames_never_change_whatever_comes_next(model, data):
    """Frames returned after a prefix equal batch synthesis of that prefix with any two different futures."""
    phones = model.phone_modes_
    prefix = data.draw(phones_strategy(phones, 0.25))
    futures = [data.draw(phones_strategy(phones, 0.25)) for _ in range(2)]
    longest = max(float(alignment_of(prefix + f).durations.max()) for f in futures)
    s = StreamingSynthesizer(model, max_duration=longest)
    got = []
    end = 0.0
    for lab, d in prefix:
        end += d
        got.append(s.push(lab, end=end))
        # never final before the stated lookahead
        assert s.n_emitted <= math.ceil((end - s.lookahead) * s.frame_rate) + 1 or s.n_emitted == 0
    got = np.concatenate(got)
    assert len(got) == s.n_emitted
    for fut in futures:
        ref = model.predict(alignment_of(prefix + fut))
        np.testing.assert_allclose(got, ref[: len(got)], atol=1e-9, rtol=0)


def test_adjacent_silences_merge_as_in_the_alignment(model):
    seq = [("aa", 0.1), ("sil", 0.05), ("sp", 0.07), ("", 0.03), ("m", 0.1)]
    s = StreamingSynthesizer(model, max_duration=0.2)
    out = np.concatenate(run_stream(s, seq))
    a = alignment_of(seq)
    assert len(a) == 3 and s.alignment() == a
    np.testing.assert_allclose(out, model.predict(a), atol=1e-9)
    s = StreamingSynthesizer(model, max_duration=0.1)
    s.push("sil", duration=0.06)
    with pytest.raises(DataError, match="silences merge"):
        s.push("sil", duration=0.06)


def test_lookahead_is_reach_times_longest_phone(model):
    from dam.model.dominance import reach

    s = StreamingSynthesizer(model, max_duration=0.2)
    r = float(np.sqrt(-(model.sigma_.max() ** 2 + model.eps) * np.log(model.dominance_tol)))
    assert (
        s.reach == pytest.approx(r) == pytest.approx(float(reach(model.sigma_.max(), model.eps, model.dominance_tol)))
    )
    assert s.lookahead == pytest.approx(0.2 * r)
    assert s.lookahead_frames == math.ceil(0.2 * r * model.frame_rate_)
    # frames do come out before the end of a long utterance
    seq = [("sil", 0.2)] + [("aa", 0.1), ("m", 0.08), ("iy", 0.12), ("d", 0.07)] * 20 + [("sil", 0.2)]
    s = StreamingSynthesizer(model, max_duration=0.2)
    first = [len(c) for c in run_stream(s, seq)]
    assert sum(first[:-1]) > 0.6 * sum(first)


def test_durations_and_bad_input(model, tiny):
    s = StreamingSynthesizer(model, max_duration=0.3, source="live")
    a = s.push("sil", duration=0.1)
    b = s.push("aa", duration=0.2)
    with pytest.raises(DataError, match="max_duration"):
        s.push("m", duration=0.31)
    with pytest.raises(DataError, match="live.*after the previous end"):
        s.push("m", end=0.25)
    with pytest.raises(DataError, match="exactly one"):
        s.push("m")
    with pytest.raises(dam.UnknownPhoneError, match="zz"):
        s.push("zz", duration=0.1)
    rest = s.finish()
    ref = model.predict(Alignment(["sil", "aa"], [0, 0.1], [0.1, 0.3]))
    np.testing.assert_allclose(np.concatenate([a, b, rest]), ref, atol=1e-9)
    with pytest.raises(DataError, match="finished"):
        s.push("m", duration=0.1)
    with pytest.raises(DataError, match="max_duration"):
        StreamingSynthesizer(model, max_duration=-1)
    with pytest.raises(DataError, match="no phone"):
        StreamingSynthesizer(model).finish()


def test_dam_m0_streams_and_other_models_buffer(tiny):
    m0 = dam.make("dam-m0").fit(tiny)
    seq = [("sil", 0.1), ("aa", 0.2), ("b", 0.05), ("uw", 0.15), ("sil", 0.1)]
    s = stream(m0, max_duration=0.25)
    assert isinstance(s, StreamingSynthesizer)
    np.testing.assert_allclose(np.concatenate(run_stream(s, seq)), m0.predict(alignment_of(seq)), atol=1e-9)
    pm = dam.make("phone-mean").fit(tiny)
    b = stream(pm, max_duration=0.25)
    assert isinstance(b, BufferedStream) and b.lookahead == math.inf
    chunks = run_stream(b, seq)
    assert all(len(c) == 0 for c in chunks[:-1])
    np.testing.assert_allclose(chunks[-1], pm.predict(alignment_of(seq)))
