"""Frame-wise window features and output-window blending (dam.features)."""

import numpy as np
import pytest

from dam.corpus.data import Alignment, DataError
from dam.corpus.features import (
    fit_transition_clusters,
    frame_phone_indices,
    n_window_features,
    overlap_average,
    phone_vocabulary,
    window_feature_names,
    window_features,
    window_targets,
)

# Taylor et al. (2017) supplementary: 40 phones plus silence ("sp" kept apart here).
TAYLOR_PHONES = (
    "sil dh ih s z uh p r aa b l m th ae d g ow k n er iy y w eh ch v t sh f ah sp hh aw oy uw ey ao zh ay jh ng"
).split()


def _hand_alignment():
    # 10 frames/s: frames 0,1 sil | 2 p | 3,4 aa
    return Alignment(["sil", "p", "aa"], [0.0, 0.2, 0.3], [0.2, 0.3, 0.5])


def test_overlap_average_hand_computation_center():
    # n = 3 frames, ky = 3, one channel; row i predicts frames i-1, i, i+1.
    P = np.array([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [7.0, 8.0, 9.0]])
    # frame 0: window 0 entry 1 (2), window 1 entry 0 (4)            -> 3
    # frame 1: window 0 entry 2 (3), window 1 entry 1 (5), window 2 entry 0 (7) -> 5
    # frame 2: window 1 entry 2 (6), window 2 entry 1 (8)            -> 7
    out = overlap_average(P, ky=3, n_channels=1)
    np.testing.assert_allclose(out[:, 0], [3.0, 5.0, 7.0])


def test_overlap_average_hand_computation_causal_two_channels():
    # ky = 2 causal: row i predicts frames i-1, i; layout frame-major, channels fastest.
    P = np.array([[10.0, -1.0, 1.0, -2.0], [2.0, -3.0, 3.0, -4.0], [4.0, -5.0, 5.0, -6.0]])
    out = overlap_average(P, ky=2, n_channels=2, align="causal")
    # frame 0: window 0 entry 1 (1,-2), window 1 entry 0 (2,-3)
    # frame 1: window 1 entry 1 (3,-4), window 2 entry 0 (4,-5); frame 2: window 2 entry 1 (5,-6)
    np.testing.assert_allclose(out, [[1.5, -2.5], [3.5, -4.5], [5.0, -6.0]])


def test_window_targets_rows_and_round_trip():
    Y = np.arange(12.0).reshape(6, 2)
    T = window_targets(Y, ky=3)
    np.testing.assert_allclose(T[0], [0, 1, 0, 1, 2, 3])  # frame -1 repeats frame 0
    np.testing.assert_allclose(T[3], [4, 5, 6, 7, 8, 9])
    np.testing.assert_allclose(T[5], [8, 9, 10, 11, 10, 11])  # frame 6 repeats frame 5
    for ky, align in [(5, "center"), (4, "center"), (3, "causal")]:
        np.testing.assert_allclose(overlap_average(window_targets(Y, ky=ky, align=align), ky, 2, align), Y)


def test_phone_vocabulary_sorted_with_silence():
    a = Alignment(["b", "a"], [0.1, 0.2], [0.2, 0.3])  # the leading gap becomes silence
    assert phone_vocabulary([a]) == ["a", "b", "sil"]
    assert phone_vocabulary(["x", "y"]) == ["sil", "x", "y"]


def test_frame_phone_indices_and_unknown_phone():
    voc = ["aa", "p", "sil"]
    np.testing.assert_array_equal(frame_phone_indices(_hand_alignment(), 10, 5, voc), [2, 2, 1, 0, 0])
    with pytest.raises(DataError, match="'p'"):
        frame_phone_indices(_hand_alignment(), 10, 5, ["aa", "sil"])


def test_raw_features_of_hand_alignment():
    voc = ["aa", "p", "sil"]
    X = window_features(_hand_alignment(), 10, 5, voc, kx=3)
    assert X.shape == (5, 9)
    onehot = {"aa": [1, 0, 0], "p": [0, 1, 0], "sil": [0, 0, 1]}
    expect = {0: ["sil", "sil", "sil"], 2: ["sil", "p", "aa"], 4: ["aa", "aa", "sil"]}  # edges padded with sil
    for i, phones in expect.items():
        np.testing.assert_array_equal(X[i], sum((onehot[p] for p in phones), []))
    Xc = window_features(_hand_alignment(), 10, 5, voc, kx=3, align="causal")
    np.testing.assert_array_equal(Xc[2], onehot["sil"] + onehot["sil"] + onehot["p"])  # frames 0..2
    np.testing.assert_array_equal(Xc[4], onehot["p"] + onehot["aa"] + onehot["aa"])


def test_linguistic_features_of_hand_alignment():
    voc = ["aa", "p", "sil"]
    X = window_features(_hand_alignment(), 10, 5, voc, kx=3, features="linguistic", alphabet="arpabet")
    names = window_feature_names(voc, 3, "linguistic")
    assert X.shape == (5, len(names)) == (5, n_window_features(3, 3, "linguistic"))
    on = {i: {n for n, v in zip(names, X[i]) if v} for i in range(5)}
    # frame 2: window sil | p | aa
    assert {"phone[0]=sil", "phone[1]=p", "phone[2]=aa"} <= on[2]
    assert not any(n.startswith("phone[") and ":" in n for n in on[2])  # no phone spans 2+ frames
    assert {
        "cat[1]=Plosive",
        "cat[1]=Bilabial",
        "cat[1]=Unvoiced-Plosive",
        "cat[2]=Vowel",
        "cat[2]=Vowel-starting-a",
        "cat[2]=Long-Vowel",
        "cat[0]=silences",
    } <= on[2]
    assert "cat[1]=Nasal" not in on[2] and "cat[2]=Vowel-ending-h" not in on[2]
    # p -> aa is consonant + vowel starting with /a/; aa is a back vowel: phonetic CV cluster 1
    assert {"C+vowel_starting_a[1,2]", "CV[1,2]=1"} <= on[2]
    assert not any(n.startswith(("VC", "CC", "C+vowel_ending")) for n in on[2])
    # frame 4: window aa | aa | sil: /aa/ spans frames 0..1
    assert {"phone[0:1]=aa", "cat[2]=silences"} <= on[4]
    assert "phone[1:2]=aa" not in on[4]
    # frame 1: window sil | sil | p: silence spans 0..1, no transitions into a vowel
    assert {"phone[0:1]=sil", "cat[2]=Plosive"} <= on[1]
    assert not any(n.startswith(("CV", "C+vowel")) for n in on[1])


def test_linguistic_feature_count_matches_taylor():
    # 2379 indicator features for 41 phones and Kx = 11 (supplementary, section 1).
    assert n_window_features(len(TAYLOR_PHONES), 11, "linguistic") == 2379
    voc = phone_vocabulary(TAYLOR_PHONES)
    a = Alignment(["dh", "ih", "s", "z", "ae"], [0.0, 0.1, 0.2, 0.3, 0.4], [0.1, 0.2, 0.3, 0.4, 0.5])
    X = window_features(a, 30, a.n_frames(30), voc, features="linguistic")
    assert X.shape == (a.n_frames(30), 2379)
    assert len(window_feature_names(voc, 11, "linguistic")) == 2379


def test_sampa_categories_and_consonant_away_from_centre():
    voc = ["S", "a:", "sil"]  # SAMPA: /S/ is ARPAbet /sh/
    a = Alignment(["S", "a:"], [0.0, 0.1], [0.1, 0.9])
    X = window_features(a, 10, 9, voc, kx=11, features="linguistic")
    names = window_feature_names(voc, 11, "linguistic")
    f = dict(zip(names, X[6]))  # frame 6: window covers frames 1..11, all a: or padding silence
    assert f["cat[5]=Vowel"] == 1 and f["consonant_away_from_centre"] == 0
    g = dict(zip(names, X[3]))  # frame 3: window frame 0 is frame -2 (sil), frame 2 is /S/ (c-3)
    assert g["cat[2]=Sibilant-Fricative"] == 1 and g["consonant_away_from_centre"] == 1


def test_fit_transition_clusters_separates_pair_types(tiny_pair_corpus):
    voc = phone_vocabulary(tiny_pair_corpus)
    cl = fit_transition_clusters(tiny_pair_corpus, voc, alphabet="arpabet")
    i = {p: k for k, p in enumerate(voc)}
    # CV pairs p+aa and b+aa have trajectories near 0, m+uw and p+uw near 10: two clusters
    assert cl["CV"][i["p"], i["aa"]] == cl["CV"][i["b"], i["aa"]]
    assert cl["CV"][i["m"], i["uw"]] == cl["CV"][i["p"], i["uw"]]
    assert cl["CV"][i["p"], i["aa"]] != cl["CV"][i["p"], i["uw"]]
    assert cl["CV"][i["aa"], i["p"]] == -1  # a VC pair is no CV pair


@pytest.fixture
def tiny_pair_corpus():
    from dam.corpus.data import Corpus, Utterance

    utts = []
    for k, (c, v, level) in enumerate([("p", "aa", 0.0), ("b", "aa", 0.5), ("m", "uw", 10.0), ("p", "uw", 10.5)]):
        a = Alignment(["sil", c, v, "sil"], [0, 0.1, 0.2, 0.4], [0.1, 0.2, 0.4, 0.5])
        y = np.zeros((50, 1))
        y[10:40] = level
        utts.append(Utterance(a, y, 100, ["x"], name=f"u{k}"))
    return Corpus(utts)


def test_dilated_windows_hand_computation():
    # ky = 3, dilation 2: row i predicts frames i-2, i, i+2
    P = np.array([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [7.0, 8.0, 9.0], [10.0, 11.0, 12.0]])
    # frame 0: w0 entry 1 (2), w2 entry 0 (7); frame 1: w1 e1 (5), w3 e0 (10);
    # frame 2: w0 e2 (3), w2 e1 (8); frame 3: w1 e2 (6), w3 e1 (11)
    np.testing.assert_allclose(overlap_average(P, 3, 1, dilation=2)[:, 0], [4.5, 7.5, 5.5, 8.5])
    X = window_features(_hand_alignment(), 10, 5, ["aa", "p", "sil"], kx=3, dilation=2)
    np.testing.assert_array_equal(X[2], [0, 0, 1, 0, 1, 0, 1, 0, 0])  # frames 0, 2, 4: sil, p, aa
    Y = np.arange(7.0)[:, None]
    np.testing.assert_allclose(overlap_average(window_targets(Y, ky=5, dilation=3), 5, 1, dilation=3), Y)


def test_guess_alphabet():
    from dam.corpus.phonetics import guess_alphabet

    assert guess_alphabet(["a:", "OY", "aI", "S", "sil"]) == "sampa"  # OY is SAMPA too
    assert guess_alphabet(["AH0", "S", "N"]) == "arpabet"
    assert guess_alphabet(["iy", "sh", "sil"]) == "arpabet"


def test_fallback_reads_upper_case_arpabet_as_arpabet():
    from dam.corpus.phonetics import fallback_phone, phone_class

    # ARPAbet T, S, N are alveolar /t s n/; the same letters in SAMPA are /θ ʃ ŋ/.
    assert [phone_class(p, "arpabet") for p in ("T", "S", "N")] == ["alveolar"] * 3
    assert [phone_class(p, "sampa") for p in ("T", "S", "N")] == ["dental", "postalveolar", "velar"]
    mfa = {"D": 3, "DH": 9, "AH0": 5, "NG": 4, "sil": 1}  # an MFA phone set that never saw T or N
    assert fallback_phone("T", mfa) == "D" and fallback_phone("N", mfa) == "D"
    vtl = {"Z": 1, "s": 4, "a:": 3, "N": 2}  # German SAMPA: S is /ʃ/
    assert fallback_phone("S", vtl) == "Z" and fallback_phone("g", vtl) == "N"
