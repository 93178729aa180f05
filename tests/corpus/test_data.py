"""The data model: alignments, utterances, corpora and their validation."""

import numpy as np
import pytest

from dam import SILENCE, Alignment, Corpus, DataError, Utterance
from dam.corpus.data import frame_labels


def test_silence_spellings_and_gaps_become_silence_merged():
    a = Alignment(["", "p", "SP", "aa", "pau"], [0.0, 0.1, 0.2, 0.35, 0.5], [0.1, 0.2, 0.3, 0.5, 0.6])
    # the gap 0.3-0.35 is silence, merged with the "SP" before it into one pause
    assert a.labels == (SILENCE, "p", SILENCE, "aa", SILENCE)
    np.testing.assert_allclose(a.starts, [0, 0.1, 0.2, 0.35, 0.5])
    np.testing.assert_allclose(a.ends, [0.1, 0.2, 0.35, 0.5, 0.6])
    # frames at 0.00 .. 0.60 inclusive
    assert a.n_frames(100) == 61


def test_adjacent_silences_from_file_merge_into_one():
    a = Alignment(["sil", "sp", "a", "pau", "", "sil"], [0, 0.1, 0.2, 0.3, 0.4, 0.45], [0.1, 0.2, 0.3, 0.4, 0.45, 0.5])
    assert a.labels == (SILENCE, "a", SILENCE)
    np.testing.assert_allclose(np.c_[a.starts, a.ends], [[0, 0.2], [0.2, 0.3], [0.3, 0.5]])


def test_leading_gap_is_silence_and_custom_silence_label():
    a = Alignment(["p"], [0.2], [0.3], silence="SIL")
    assert a.labels == ("SIL", "p") and a.starts[0] == 0.0


def test_frame_convention():
    a = Alignment(["a", "b"], [0.0, 0.025], [0.025, 0.05])
    # frames at 0, .01, .02 | .03, .04, .05 -> 6 frames (t <= end); frame 2 (t=.02) in "a", 3 in "b"
    assert frame_labels(a, 100) == ["a", "a", "a", "b", "b", "b"]
    # n_frames counts frames at times <= end, robust to decimals
    for fr in (100.0, 200.0, 400.9, 60.0):
        for n in (2, 7, 123):
            end = (n - 1) / fr
            assert Alignment(["a"], [0], [end]).n_frames(fr) == n
            assert Alignment(["a"], [0], [round(end, 6)]).n_frames(fr) == n  # as a TextGrid stores it
            assert Alignment(["a"], [0], [end + 0.99 / fr]).n_frames(fr) == n


@pytest.mark.parametrize(
    "labels,starts,ends,field,problem",
    [
        (["a", "b"], [0, 0.1], [0.1, 0.1], "segment 1 ('b')", "zero-length"),
        (["a", "b"], [0, 0.05], [0.1, 0.2], "segment 1 ('b') start", "overlaps"),
        (["a", "b"], [0.1, 0.0], [0.2, 0.05], "segment 1 ('b') start", "not sorted"),
        (["a", "b"], [0, np.nan], [0.1, 0.2], "segment 1 ('b') start", "not finite"),
        ([], [], [], "segments", "no segments"),
    ],
)
def test_bad_alignments_name_file_field_value(labels, starts, ends, field, problem):
    with pytest.raises(DataError) as err:
        Alignment(labels, starts, ends, source="x.TextGrid")
    msg = str(err.value)
    assert "x.TextGrid" in msg and field in msg and problem in msg


def _utt(n=30, channels=("a", "b"), end=0.3, **kw):
    a = Alignment(["p", "aa"], [0, 0.1], [0.1, end], source="u.TextGrid")
    return Utterance(a, np.zeros((n, len(channels))), 100, channels, **kw)


def test_utterance_pads_alignment_with_trailing_silence_and_trims_one_frame():
    u = _utt(n=35)
    assert u.alignment.labels[-1] == SILENCE and u.alignment.n_frames(100) == 35
    assert u.alignment.ends[-1] == pytest.approx(0.34)  # the last frame time
    u = _utt(n=29)  # two frames short: the last segment is trimmed to the last frame time
    assert u.alignment.n_frames(100) == 29 and u.alignment.labels[-1] == "aa"
    assert u.alignment.ends[-1] == pytest.approx(0.28)


@pytest.mark.parametrize("fr", [100.0, 400.9, 60.0])
@pytest.mark.parametrize("n", [12, 30, 517])
def test_alignment_ending_at_last_frame_time_is_kept_unpadded(fr, n):
    """The issue's case: the alignment ends exactly at the last frame's time (i / frame_rate)."""
    last = (n - 1) / fr
    a = Alignment(["sil", "a", "sil"], [0, last / 3, 2 * last / 3], [last / 3, 2 * last / 3, last])
    u = Utterance(a, np.zeros((n, 1)), fr, ["x"])
    assert u.alignment is a and u.alignment.n_frames(fr) == n
    # within one frame after it (e.g. the old convention, end = n / frame_rate - a bit): kept too
    b = Alignment(a.labels, a.starts, np.r_[a.ends[:-1], last + 0.6 / fr])
    assert Utterance(b, np.zeros((n, 1)), fr, ["x"]).alignment is b


def test_sub_frame_gaps_and_overhangs_are_absorbed_not_segments():
    fr = 100.0
    # a trailing gap of 0.4 frame: the last segment grows to the last frame time
    a = Alignment(["sil", "a"], [0, 0.1], [0.1, 0.286])
    u = Utterance(a, np.zeros((30, 1)), fr, ["x"])
    assert u.alignment.labels == ("sil", "a") and u.alignment.ends[-1] == pytest.approx(0.29)
    # an overhang of exactly one frame (end = n / frame_rate, a writer's habit): trimmed, no new segment
    a = Alignment(["sil", "a", "sil"], [0, 0.1, 0.29], [0.1, 0.29, 0.30])
    u = Utterance(a, np.zeros((30, 1)), fr, ["x"])
    assert u.alignment.labels == ("sil", "a") and u.alignment.ends[-1] == pytest.approx(0.29)
    # a sub-frame pause between phones (and a leading one) is absorbed into the neighbour
    a = Alignment(["a", "b", "c"], [0.004, 0.1, 0.205], [0.096, 0.2, 0.29])
    assert a.labels == ("sil", "a", "sil", "b", "sil", "c")
    u = Utterance(a, np.zeros((30, 1)), fr, ["x"])
    assert u.alignment.labels == ("a", "b", "c")
    np.testing.assert_allclose(np.c_[u.alignment.starts, u.alignment.ends], [[0, 0.1], [0.1, 0.205], [0.205, 0.29]])
    # a real pause at the end (3 frames) extends the trailing silence instead of adding a second one
    a = Alignment(["sil", "a", "sil"], [0, 0.1, 0.2], [0.1, 0.2, 0.26])
    u = Utterance(a, np.zeros((30, 1)), fr, ["x"])
    assert u.alignment.labels == ("sil", "a", "sil") and u.alignment.ends[-1] == pytest.approx(0.29)
    assert u.alignment.n_frames(fr) == u.n_frames


def test_edge_convention_round_trips_through_files(tmp_path):
    from dam.corpus.io import load_corpus, save_corpus

    fr = 100.0
    a = Alignment(["sil", "a", "sil"], [0, 0.1, 0.2], [0.1, 0.2, 0.29])
    c = Corpus([Utterance(a, np.arange(30.0)[:, None], fr, ["x"], name="u")])
    save_corpus(c, tmp_path / "c")
    back = load_corpus(tmp_path / "c")
    assert back[0].alignment == a and back[0].n_frames == 30


def test_utterance_errors():
    with pytest.raises(DataError, match=r"u.TextGrid.*trajectory.*shorter than its alignment"):
        _utt(n=20)
    a = Alignment(["p"], [0], [0.05], source="u.TextGrid")
    y = np.zeros((5, 2))
    y[3, 1] = np.nan
    with pytest.raises(DataError, match=r"trajectory\[3, 'b'\].*nan"):
        Utterance(a, y, 100, ["a", "b"])
    with pytest.raises(DataError, match="channels.*2 columns but 3"):
        Utterance(a, np.zeros((5, 2)), 100, ["a", "b", "c"])
    with pytest.raises(DataError, match="frame_rate"):
        Utterance(a, np.zeros((5, 2)), -100, ["a", "b"])


def test_corpus_checks_shared_channels_and_rate():
    with pytest.raises(DataError, match="empty"):
        Corpus([])
    with pytest.raises(DataError, match="channel count differs"):
        Corpus([_utt(), _utt(channels=("a", "b", "c"))])
    with pytest.raises(DataError, match="channel names differ"):
        Corpus([_utt(), _utt(channels=("a", "c"))])


def test_splits_are_disjoint_and_cover():
    c = Corpus([_utt(name=f"u{i}") for i in range(10)])
    tr, te = c.train_test_split(0.3, random_state=1)
    names = [u.name for u in tr] + [u.name for u in te]
    assert sorted(names) == sorted(u.name for u in c) and len(te) == 3
    folds = list(c.kfold(5))
    tests = [u.name for _, te in folds for u in te]
    assert sorted(tests) == sorted(u.name for u in c)
    for tr, te in folds:
        assert not {u.name for u in tr} & {u.name for u in te}


def test_trajectories_are_read_only_copies():
    y = np.zeros((30, 2))
    u = Utterance(Alignment(["a"], [0], [0.3]), y, 100, ["x", "y"])
    y[0, 0] = 5
    assert u.trajectory[0, 0] == 0
    with pytest.raises(ValueError):
        u.trajectory[0, 0] = 1
