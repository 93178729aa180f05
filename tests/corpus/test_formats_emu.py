"""EMU-SDMS databases and SSFF tracks, written by hand from The EMU-SDMS Manual (ch. 15.1)."""

import base64
import json
import struct

import numpy as np
import pytest

from dam.corpus import DataError, load_corpus
from dam.corpus.formats.emu import annot_alignment, load_emu_corpus, parse_ssff, read_ssff, write_ssff


def ssff_bytes(columns, rate, start="0.0", machine="IBM-PC", extra=(), end="-----------------"):
    """An SSFF file packed with struct, independently of dam's writer.

    columns: list of (name, type, count, rows); rows a list of tuples per record.
    """
    fmt = {"SHORT": "h", "LONG": "i", "FLOAT": "f", "DOUBLE": "d", "BYTE": "B", "CHAR": "b"}
    order = "<" if machine in ("IBM-PC", "VAX") else ">"
    head = ["SSFF -- (c) SHLRC", f"Machine {machine}", f"Record_Freq {rate}", f"Start_Time {start}"]
    head += [f"Column {n} {t} {k}" for n, t, k, _ in columns] + list(extra) + [end]
    n_rec = len(columns[0][3])
    body = b"".join(
        struct.pack(
            order + "".join(fmt[t] * k for _, t, k, _ in columns), *[v for _, _, _, rows in columns for v in rows[i]]
        )
        for i in range(n_rec)
    )
    return ("\n".join(head) + "\n").encode() + body


def test_ssff_reads_the_manuals_fms_example(tmp_path):
    fm = [(500, 1500, 2500, 3500), (510, 1490, 2600, 3400), (520, 1480, 2700, 3300)]
    bw = [(50, 100, 150, 200), (55, 105, 155, 205), (60, 110, 160, 210)]
    p = tmp_path / "msajc003.fms"
    p.write_bytes(
        ssff_bytes(
            [("fm", "SHORT", 4, fm), ("bw", "SHORT", 4, bw)],
            "200.0",
            start="0.0025",
            extra=["Original_Freq DOUBLE 20000.0"],
        )
    )
    f = read_ssff(p)
    assert f.record_freq == 200.0 and f.start_time == 0.0025 and f.machine == "IBM-PC"
    np.testing.assert_array_equal(f.columns["fm"], fm)
    np.testing.assert_array_equal(f.columns["bw"], bw)
    assert list(f.columns) == ["fm", "bw"]
    assert f.extra == {"Original_Freq": ("DOUBLE", "20000.0")}
    values, names = f.channels()
    assert names == [f"fm_T{i}" for i in range(1, 5)] + [f"bw_T{i}" for i in range(1, 5)]
    np.testing.assert_array_equal(values, np.hstack([fm, bw]))


def test_ssff_big_endian_doubles_and_mixed_types(tmp_path):
    rows = [(1.25, -2.5), (3.0, 4.125)]
    p = tmp_path / "a.ema"
    p.write_bytes(
        ssff_bytes(
            [("tt", "DOUBLE", 2, rows), ("q", "LONG", 1, [(7,), (-9,)]), ("b", "BYTE", 1, [(200,), (3,)])],
            "500",
            machine="SPARC",
        )
    )
    f = read_ssff(p)
    np.testing.assert_array_equal(f.columns["tt"], rows)
    np.testing.assert_array_equal(f.columns["q"].ravel(), [7, -9])
    np.testing.assert_array_equal(f.columns["b"].ravel(), [200, 3])
    assert f.channels()[1] == ["tt_T1", "tt_T2", "q", "b"]


@pytest.mark.parametrize("machine", ["IBM-PC", "SPARC"])
def test_write_ssff_round_trip_and_layout(tmp_path, machine):
    rng = np.random.default_rng(0)
    tt = rng.normal(size=(7, 3))
    f0 = rng.integers(-300, 300, size=7)
    p = tmp_path / "r.ssff"
    write_ssff(
        p,
        {"tt": tt, "f0": f0},
        250.0,
        start_time=0.002,
        types={"f0": "SHORT"},
        machine=machine,
        extra={"Original_Freq": ("DOUBLE", 16000.0)},
    )
    back = read_ssff(p)
    np.testing.assert_array_equal(back.columns["tt"], tt)
    np.testing.assert_array_equal(back.columns["f0"].ravel(), f0)
    assert (back.record_freq, back.start_time, back.machine) == (250.0, 0.002, machine)
    # the bytes are what struct packs by hand: the writer follows the documented layout
    expected = ssff_bytes(
        [("tt", "DOUBLE", 3, [tuple(r) for r in tt]), ("f0", "SHORT", 1, [(int(v),) for v in f0])],
        "250.0",
        start="0.002",
        machine=machine,
        extra=["Original_Freq DOUBLE 16000.0"],
    )
    assert p.read_bytes() == expected


@pytest.mark.parametrize(
    "mutate, field, value",
    [
        (lambda b: b.replace(b"SSFF -- (c) SHLRC", b"SSFX -- (c) SHLRC"), "header", "SSFX"),
        (lambda b: b.replace(b"Machine IBM-PC", b"Machine PDP-11"), "Machine", "PDP-11"),
        (lambda b: b.replace(b"Column tt DOUBLE 2", b"Column tt QUAD 2"), "Column tt type", "QUAD"),
        (lambda b: b.replace(b"Record_Freq 100.0\n", b""), "Record_Freq", "None"),
        (lambda b: b.replace(b"Record_Freq 100.0", b"Record_Freq fast"), "Record_Freq", "fast"),
        (lambda b: b.replace(b"Column tt DOUBLE 2", b"Column tt DOUBLE x"), "Column tt count", "x"),
        (lambda b: b[:-3], "data size", "29 bytes"),
        (lambda b: b.replace(b"-----------------\n", b""), "header", "-----------------"),
    ],
)
def test_malformed_ssff_is_refused_naming_file_field_value(tmp_path, mutate, field, value):
    good = ssff_bytes([("tt", "DOUBLE", 2, [(1.0, 2.0), (3.0, 4.0)])], "100.0")
    p = tmp_path / "bad.ema"
    p.write_bytes(mutate(good))
    with pytest.raises(DataError) as err:
        read_ssff(p)
    msg = str(err.value)
    assert "bad.ema" in msg and f"field {field!r}" in msg and value in msg


# -- an emuDB on disk ---------------------------------------------------------
def segment_items(level, segs, start_id=1):
    return [
        {"id": start_id + i, "sampleStart": s, "sampleDur": d, "labels": [{"name": level, "value": lab}]}
        for i, (s, d, lab) in enumerate(segs)
    ]


def make_emudb(root, bundles, *, rate_annot=20000, start="0.0"):
    """bundles: {session: {bundle: (phone segments, syllable segments, tt rows, ul rows)}}"""
    db = root / "test_emuDB"
    db.mkdir()
    config = {
        "name": "test",
        "UUID": "0fc618dc-8980-414d-8c7a-144a649ce199",
        "mediafileExtension": "wav",
        "ssffTrackDefinitions": [
            {"name": "tt", "columnName": "tt", "fileExtension": "pos"},
            {"name": "ul", "columnName": "ul", "fileExtension": "pos"},
        ],
        "levelDefinitions": [
            {"name": "Utterance", "type": "ITEM", "attributeDefinitions": [{"name": "Utterance", "type": "STRING"}]},
            {"name": "Syllable", "type": "SEGMENT", "attributeDefinitions": [{"name": "Syllable", "type": "STRING"}]},
            {"name": "Phonetic", "type": "SEGMENT", "attributeDefinitions": [{"name": "Phonetic", "type": "STRING"}]},
        ],
        "linkDefinitions": [
            {"type": "ONE_TO_MANY", "superlevelName": "Utterance", "sublevelName": "Syllable"},
            {"type": "ONE_TO_MANY", "superlevelName": "Syllable", "sublevelName": "Phonetic"},
        ],
    }
    (db / "test_DBconfig.json").write_text(json.dumps(config))
    for ses, bs in bundles.items():
        for b, (phones, sylls, tt, ul) in bs.items():
            d = db / f"{ses}_ses" / f"{b}_bndl"
            d.mkdir(parents=True)
            annot = {
                "name": b,
                "annotates": f"{b}.wav",
                "sampleRate": rate_annot,
                "levels": [
                    {
                        "name": "Utterance",
                        "type": "ITEM",
                        "items": [{"id": 100, "labels": [{"name": "Utterance", "value": ""}]}],
                    },
                    {"name": "Syllable", "type": "SEGMENT", "items": segment_items("Syllable", sylls, 200)},
                    {"name": "Phonetic", "type": "SEGMENT", "items": segment_items("Phonetic", phones, 300)},
                ],
                "links": [{"fromID": 100, "toID": 200}],
            }
            (d / f"{b}_annot.json").write_text(json.dumps(annot))
            (d / f"{b}.pos").write_bytes(
                ssff_bytes([("tt", "DOUBLE", 2, tt), ("ul", "FLOAT", 2, ul)], "200.0", start=start)
            )
            (d / f"{b}.wav").write_bytes(b"RIFF")
    return db


PHONES = [(0, 1999, "a"), (2000, 2999, "m"), (5000, 999, "")]  # 0.25 s at 20 kHz; last one a pause
SYLLS = [(0, 4999, "am"), (5000, 999, "")]


def rows(n, offset):
    return [(offset + i, offset - 0.5 * i) for i in range(n)]


def test_emudb_reads_phones_tracks_and_times_by_the_manuals_formulas(tmp_path):
    tt, ul = rows(60, 10.0), rows(60, -3.0)
    db = make_emudb(tmp_path, {"0000": {"b1": (PHONES, SYLLS, tt, ul)}, "0001": {"b2": (PHONES, SYLLS, tt, ul)}})
    corpus = load_corpus(db)
    assert corpus.metadata["format"] == "emu"
    assert [u.name for u in corpus] == ["0000_b1", "0001_b2"]
    assert corpus.frame_rate == 200.0
    assert corpus.channels == ("tt_T1", "tt_T2", "ul_T1", "ul_T2")
    u = corpus[0]
    np.testing.assert_array_equal(u.trajectory, np.hstack([tt, ul]))
    # start = (sampleStart - 0.5) / rate (0 for sample 0), end = (sampleStart + sampleDur + 0.5) / rate
    assert u.alignment.labels[:3] == ("a", "m", "sil")
    np.testing.assert_allclose(u.alignment.starts[:3], [0.0, 1999.5 / 20000, 4999.5 / 20000])
    np.testing.assert_allclose(u.alignment.ends[:3], [1999.5 / 20000, 4999.5 / 20000, 5999.5 / 20000])
    assert u.audio.endswith("b1.wav")


def test_emudb_level_choice(tmp_path):
    db = make_emudb(tmp_path, {"0000": {"b1": (PHONES, SYLLS, rows(60, 0.0), rows(60, 1.0))}})
    assert load_corpus(db)[0].alignment.labels[:2] == ("a", "m")  # lowest SEGMENT level
    assert load_corpus(db, tier="Syllable")[0].alignment.labels[0] == "am"
    assert load_emu_corpus(db, level="Syllable")[0].alignment.labels[0] == "am"
    with pytest.raises(DataError, match=r"test_DBconfig.json: field 'level'.*'Word'"):
        load_corpus(db, tier="Word")
    only_ul = load_emu_corpus(db, tracks=["ul"])
    assert only_ul.channels == ("ul_T1", "ul_T2")


def test_ssff_start_time_is_put_on_the_frame_grid(tmp_path):
    # a linear track is reproduced exactly by the linear re-gridding (frame j at j / 200)
    t = 0.0025 + np.arange(60) / 200.0
    tt = [(1 + 4 * ti, 2 - ti) for ti in t]
    db = make_emudb(tmp_path, {"0000": {"b1": (PHONES, SYLLS, tt, tt)}}, start="0.0025")
    u = load_corpus(db)[0]
    grid = np.arange(u.n_frames) / 200.0
    np.testing.assert_allclose(u.trajectory[1:-1, 0], 1 + 4 * grid[1:-1])
    np.testing.assert_allclose(u.trajectory[1:-1, 1], 2 - grid[1:-1])
    assert u.trajectory[0, 0] == pytest.approx(1 + 4 * 0.0025)  # before the first record: held


def test_emu_webapp_bundle_documents(tmp_path):
    tt = rows(50, 5.0)
    blob = ssff_bytes([("tt", "DOUBLE", 2, tt)], "200.0")
    annot = {
        "name": "b1",
        "annotates": "b1.wav",
        "sampleRate": 16000,
        "levels": [
            {
                "name": "Phonetic",
                "type": "SEGMENT",
                "items": segment_items("Phonetic", [(0, 1599, "x"), (1600, 2399, "y")]),
            }
        ],
        "links": [],
    }
    doc = {
        "annotation": annot,
        "ssffFiles": [{"fileExtension": "pos", "encoding": "BASE64", "data": base64.b64encode(blob).decode()}],
        "mediaFile": {"encoding": "BASE64", "data": ""},
    }
    folder = tmp_path / "bundles"
    folder.mkdir()
    (folder / "b1_bndl.json").write_text(json.dumps(doc))
    for c in (load_corpus(folder), load_corpus(folder / "b1_bndl.json")):
        assert c[0].name == "b1"
        np.testing.assert_array_equal(c[0].trajectory, tt)
        assert c[0].alignment.labels == ("x", "y")
        assert c[0].alignment.ends[-1] == pytest.approx(3999.5 / 16000)
    doc["ssffFiles"][0]["data"] = "not base64!"
    (folder / "b1_bndl.json").write_text(json.dumps(doc))
    with pytest.raises(DataError, match=r"b1_bndl.json: field 'ssffFiles\[0\].data'"):
        load_corpus(folder)


@pytest.mark.parametrize(
    "change, field, value",
    [
        (lambda a: a.pop("sampleRate"), "sampleRate", "None"),
        (lambda a: a["levels"][0]["items"][1].update(sampleDur=-5), "level 'Phonetic' item 1 (id 2) sampleDur", "-5"),
        (
            lambda a: a["levels"][0]["items"][0].update(labels=[{"name": "Other", "value": "q"}]),
            "level 'Phonetic' item 0 (id 1) labels",
            "Other",
        ),
        (lambda a: a["levels"][0].update(type="SEGMENTS"), "levels[0] ('Phonetic') type", "SEGMENTS"),
    ],
)
def test_malformed_annotation_is_refused(change, field, value):
    annot = {
        "name": "b",
        "sampleRate": 16000,
        "levels": [
            {"name": "Phonetic", "type": "SEGMENT", "items": segment_items("Phonetic", [(0, 99, "x"), (100, 99, "y")])}
        ],
    }
    change(annot)
    with pytest.raises(DataError) as err:
        annot_alignment(annot, source="b_annot.json")
    msg = str(err.value)
    assert "b_annot.json" in msg and f"field {field!r}" in msg and value in msg


def test_emudb_missing_track_file_is_named(tmp_path):
    db = make_emudb(tmp_path, {"0000": {"b1": (PHONES, SYLLS, rows(60, 0.0), rows(60, 1.0))}})
    (db / "0000_ses" / "b1_bndl" / "b1.pos").unlink()
    with pytest.raises(DataError, match=r"b1: field 'SSFF file .pos'.*tt"):
        load_corpus(db)


def test_parse_ssff_names_its_source():
    with pytest.raises(DataError, match="inline.ssff: field 'Column'"):
        parse_ssff(b"SSFF -- (c) SHLRC\nMachine IBM-PC\nRecord_Freq 1.0\n-----------------\n", "inline.ssff")


def test_format_can_be_forced_and_unknown_formats_are_named(tmp_path):
    db = make_emudb(tmp_path, {"0000": {"b1": (PHONES, SYLLS, rows(60, 0.0), rows(60, 1.0))}})
    assert load_corpus(db, format="emu")[0].name == "0000_b1"
    with pytest.raises(DataError, match=r"field 'format'.*'praat'"):
        load_corpus(db, format="praat")
    with pytest.raises(DataError, match=r"field 'alignments'"):  # forced generic reader: no alignments here
        load_corpus(db, format="directory")
