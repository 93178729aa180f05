"""The data model: alignments, utterances, corpora and their validation."""
import numpy as np
import pytest

from dam import SILENCE, Alignment, Corpus, DataError, Utterance
from dam.corpus.data import frame_labels


def test_silence_spellings_and_gaps_become_silence():
    a = Alignment(["", "p", "SP", "aa", "pau"], [0.0, 0.1, 0.2, 0.35, 0.5], [0.1, 0.2, 0.3, 0.5, 0.6])
    # the gap 0.3-0.35 becomes its own silence segment
    assert a.labels == (SILENCE, "p", SILENCE, SILENCE, "aa", SILENCE)
    np.testing.assert_allclose(a.starts, [0, 0.1, 0.2, 0.3, 0.35, 0.5])
    assert a.n_frames(100) == 60


def test_leading_gap_is_silence_and_custom_silence_label():
    a = Alignment(["p"], [0.2], [0.3], silence="SIL")
    assert a.labels == ("SIL", "p") and a.starts[0] == 0.0


def test_frame_convention():
    a = Alignment(["a", "b"], [0.0, 0.025], [0.025, 0.05])
    # frames at 0, .01, .02 | .03, .04 -> 5 frames; frame 2 (t=.02) in "a", frame 3 (t=.03) in "b"
    assert frame_labels(a, 100) == ["a", "a", "a", "b", "b"]


@pytest.mark.parametrize("labels,starts,ends,field,problem", [
    (["a", "b"], [0, 0.1], [0.1, 0.1], "segment 1 ('b')", "zero-length"),
    (["a", "b"], [0, 0.05], [0.1, 0.2], "segment 1 ('b') start", "overlaps"),
    (["a", "b"], [0.1, 0.0], [0.2, 0.05], "segment 1 ('b') start", "not sorted"),
    (["a", "b"], [0, np.nan], [0.1, 0.2], "segment 1 ('b') start", "not finite"),
    ([], [], [], "segments", "no segments"),
])
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
    u = _utt(n=29)  # one frame short: the last segment is trimmed
    assert u.alignment.n_frames(100) == 29 and u.alignment.labels[-1] == "aa"


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
