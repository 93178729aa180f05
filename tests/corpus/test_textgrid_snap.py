"""TextGrids written by other tools with float noise at the boundaries (an interval starting
1e-16 s before its neighbour ends) are read with the overlap snapped; real overlaps stay errors."""

import pytest
from praatio import textgrid as ptg

import dam

TEMPLATE = """File type = "ooTextFile"
Object class = "TextGrid"

xmin = 0
xmax = 0.6
tiers? <exists>
size = 1
item []:
    item [1]:
        class = "IntervalTier"
        name = "phones"
        xmin = 0
        xmax = 0.6
        intervals: size = 3
        intervals [1]:
            xmin = 0
            xmax = {end1}
            text = "a"
        intervals [2]:
            xmin = 0.3
            xmax = 0.45
            text = "b"
        intervals [3]:
            xmin = {start3}
            xmax = 0.6
            text = "c"
"""


def _write(tmp_path, end1, start3):
    path = tmp_path / "other_tool.TextGrid"
    path.write_text(TEMPLATE.format(end1=end1, start3=start3), encoding="utf-8")
    return path


def test_praatio_itself_refuses_the_float_noise(tmp_path):
    # independent truth that the file overlaps: the reference reader refuses it
    path = _write(tmp_path, "0.30000000000000004", "0.45")
    with pytest.raises(Exception, match="overlap"):
        ptg.openTextgrid(str(path), includeEmptyIntervals=True)


@pytest.mark.parametrize(
    "end1, start3",
    [("0.30000000000000004", "0.45"), ("0.3", "0.4499995"), ("0.30000000000000004", "0.44999999999999996")],
)
def test_sub_microsecond_overlaps_are_snapped(tmp_path, end1, start3):
    a = dam.read_alignment(_write(tmp_path, end1, start3))
    assert list(a.labels) == ["a", "b", "c"]
    # every start is exactly the previous end: no overlap, no gap
    assert list(a.starts[1:]) == list(a.ends[:-1])
    assert a.ends[1] == pytest.approx(0.45, abs=1e-12) and a.ends[0] == pytest.approx(0.3, abs=1e-12)


def test_a_real_overlap_is_an_error_naming_the_interval(tmp_path):
    with pytest.raises(dam.DataError, match=r"interval 3 xmin.*'b'.*0\.001 s"):
        dam.read_alignment(_write(tmp_path, "0.3", "0.449"))


def test_a_corpus_of_such_files_loads(tmp_path):
    import numpy as np

    _write(tmp_path, "0.30000000000000004", "0.4499999")
    np.savetxt(tmp_path / "other_tool.csv", np.zeros((61, 1)), header="x", comments="", delimiter=",")
    corpus = dam.load_corpus(tmp_path, frame_rate=100)
    assert list(corpus[0].alignment.labels) == ["a", "b", "c"]
