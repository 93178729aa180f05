"""Property-based fuzzing (issue 12) of alignments, trajectories, corpus files, model files and
command lines. Whatever goes in: only dam's own error types come out, every message names the
file or the parameter, no output is left half-written, and no NaN reaches an output.

Bounded: a fixed number of examples per property, derandomized, the whole file in well under a
minute."""

import contextlib
import hashlib
import io
import json
import os
import shutil
import tempfile

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

import dam
from dam.corpus.atomic import TEMP_PREFIX
from dam.corpus.data import MAX_DURATION, TIME_TOL
from dam.datasets import DATA
from dam.modelfile import META_KEY, ModelFileError, read_model_file

FUZZ = settings(
    max_examples=150,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)

times = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.floats(0, 5),
    st.integers(-10, 10**12),
    st.sampled_from([1e-7, 6e-7, 1e10, -0.0, 1e308]),
)
labels = st.one_of(
    st.text(max_size=4), st.sampled_from(["sil", "", " sp ", "a", "b", "é", "\ufeffa"]), st.integers(), st.none()
)


# -- alignments and trajectories ---------------------------------------------------------------
@FUZZ
@given(st.lists(st.tuples(labels, times, times), min_size=0, max_size=6))
def test_alignment_is_valid_or_a_data_error(segments):
    labs = [s[0] for s in segments]
    try:
        a = dam.Alignment(labs, [s[1] for s in segments], [s[2] for s in segments], source="fuzz.lab")
    except dam.DataError as exc:
        assert "fuzz.lab" in str(exc)
        return
    # what is accepted tiles [0, duration] with positive, finite, bounded segments
    assert np.all(np.isfinite(a.starts)) and np.all(np.isfinite(a.ends))
    assert abs(a.starts[0]) <= TIME_TOL and np.all(a.durations > TIME_TOL) and a.duration <= MAX_DURATION
    np.testing.assert_array_equal(a.starts[1:], a.ends[:-1])


ragged = st.recursive(
    st.one_of(st.floats(), st.integers(-5, 5), st.text(max_size=2), st.none(), st.complex_numbers(max_magnitude=10)),
    lambda inner: st.lists(inner, max_size=4),
    max_leaves=12,
)
arrays = hnp.arrays(
    dtype=st.sampled_from([np.float64, np.float32, np.int8, np.bool_, np.complex128, np.uint16]),
    shape=hnp.array_shapes(min_dims=0, max_dims=3, max_side=5),
)


@FUZZ
@given(st.one_of(ragged, arrays), st.sampled_from([["x"], ["x", "y"], "x", 5, None]))
def test_utterance_is_valid_or_a_data_error(trajectory, channels):
    a = dam.Alignment(["a", "b"], [0.0, 0.01], [0.01, 0.02])
    try:
        u = dam.Utterance(a, trajectory, 100.0, channels, source="fuzz.csv")
    except dam.DataError as exc:
        assert "fuzz.csv" in str(exc)
        return
    assert u.trajectory.dtype == np.float64 and u.trajectory.ndim == 2
    assert np.all(np.isfinite(u.trajectory))


# -- corpus files -----------------------------------------------------------------------------------
FILES = ["corpus.json", "tiny000.TextGrid", "tiny000.csv", "tiny001.TextGrid", "tiny001.csv"]
json_values = st.recursive(
    st.one_of(st.none(), st.booleans(), st.floats(), st.integers(), st.text(max_size=5)),
    lambda inner: st.one_of(st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=5), inner, max_size=4)),
    max_leaves=10,
)


def _mutate(raw: bytes, kind: str, pos: int, value) -> bytes:
    pos = pos % (len(raw) + 1)
    if kind == "flip":
        mask = (value if isinstance(value, int) else len(value)) % 255 + 1
        return raw[:pos] + bytes([raw[pos] ^ mask]) + raw[pos + 1 :] if pos < len(raw) else raw
    if kind == "truncate":
        return raw[:pos]
    if kind == "bom":
        return b"\xef\xbb\xbf" + raw
    if kind == "latin1":
        return raw[:pos] + b"\xe9" + raw[pos:]
    if kind == "number":
        text = raw.decode("utf-8", errors="replace")
        digits = [i for i, ch in enumerate(text) if ch.isdigit()]
        if not digits:
            return raw
        i = digits[pos % len(digits)]
        repl = str(value) if not isinstance(value, str) else value
        return (text[:i] + repl + text[i + 1 :]).encode("utf-8")
    raise AssertionError(kind)


@FUZZ
@given(
    st.sampled_from(FILES),
    st.sampled_from(["flip", "truncate", "bom", "latin1", "number"]),
    st.integers(0, 10**6),
    st.one_of(st.integers(0, 255), st.sampled_from(["9" * 400, "inf", "nan", "1e10", "-", "1e400", "é"])),
)
def test_mutated_corpus_loads_or_names_the_file(name, kind, pos, value):
    with tempfile.TemporaryDirectory() as tmp:
        d = os.path.join(tmp, "corpus")
        os.mkdir(d)
        for f in FILES:
            shutil.copy(DATA / "tiny" / f, os.path.join(d, f))
        path = os.path.join(d, name)
        with open(path, "rb") as fh:
            raw = fh.read()
        with open(path, "wb") as fh:
            fh.write(_mutate(raw, kind, pos, value))
        try:
            corpus = dam.load_corpus(d)
        except dam.DataError as exc:
            assert d in str(exc), str(exc)  # names a file of the corpus (or the directory)
            return
        for u in corpus:
            assert np.all(np.isfinite(u.trajectory))
            assert np.all(u.alignment.durations > TIME_TOL)


@FUZZ
@given(json_values)
def test_any_corpus_json_loads_or_names_the_file(meta):
    with tempfile.TemporaryDirectory() as tmp:
        for f in FILES[1:]:
            shutil.copy(DATA / "tiny" / f, os.path.join(tmp, f))
        with open(os.path.join(tmp, "corpus.json"), "w") as fh:
            json.dump(meta, fh)
        try:
            corpus = dam.load_corpus(tmp)
        except dam.DataError as exc:
            assert "corpus.json" in str(exc) or tmp in str(exc)
            return
        assert corpus.frame_rate > 0 and len(corpus.channels) == 4


# -- model files: crafted records --------------------------------------------------------------
state_values = st.one_of(
    json_values,
    hnp.arrays(
        dtype=st.sampled_from([np.float64, np.int8, np.bool_, np.float32]),
        shape=hnp.array_shapes(min_dims=0, max_dims=3, max_side=4),
    ),
)


@FUZZ
@given(
    st.sampled_from(["frame_rate_", "channels_", "phone_counts_", "table_", "extra_", "model", "params"]), state_values
)
def test_crafted_model_records_load_or_raise_model_file_error(micro_model_file, key, value):
    src, alignment, _ = micro_model_file
    meta, arrays = read_model_file(src)
    if isinstance(value, np.ndarray):
        arrays["crafted"] = value
        value = {"__array__": "crafted"}
    if key in ("model", "params"):
        meta[key] = value
    else:
        meta["state"][key] = value
    arrays[META_KEY] = np.frombuffer(json.dumps(meta).encode(), dtype=np.uint8)
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "crafted.dam")
        with open(path, "wb") as fh:
            np.savez(fh, **arrays)
        try:
            model = dam.load(path)
        except ModelFileError as exc:
            assert path in str(exc)
            return
        y = model.predict(alignment)  # what loads synthesizes finite values
        assert np.all(np.isfinite(y))


@FUZZ
@given(st.lists(st.tuples(st.integers(0, 10**6), st.integers(1, 255)), min_size=1, max_size=4))
def test_model_file_with_random_byte_damage(phone_mean_file, flips):
    src, expected = phone_mean_file
    raw = bytearray(open(src, "rb").read())
    for pos, mask in flips:
        raw[pos % len(raw)] ^= mask
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "damaged.dam")
        with open(path, "wb") as fh:
            fh.write(bytes(raw))
        try:
            model = dam.load(path)
        except ModelFileError as exc:
            assert path in str(exc)
            return
        first = dam.datasets.load("tiny")[0]
        np.testing.assert_array_equal(model.predict(first.alignment), expected)


# -- command lines --------------------------------------------------------------------------------------
def _digest(path):
    if os.path.isdir(path):
        return {n: _digest(os.path.join(path, n)) for n in sorted(os.listdir(path))}
    with open(path, "rb") as fh:
        return hashlib.sha256(fh.read()).hexdigest()


def _run_cli(argv):
    from dam.cli import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(argv)
        except SystemExit as exc:  # argparse: usage errors
            code = exc.code
    return code, out.getvalue(), err.getvalue()


PATHS = ["MODEL", "ALIGN", "CORPUS", "CSV", "MISSING", "NODIR/x.out", "-", "", "DIR", "OUT.csv", "OUT.dam"]


@settings(
    max_examples=80,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(
    st.sampled_from(
        [
            ["predict", "MODEL", "ALIGN", "-o", "P"],
            ["predict", "P", "ALIGN"],
            ["predict", "MODEL", "P", "-o", "P"],
            ["evaluate", "P", "CORPUS"],
            ["evaluate", "MODEL", "P"],
            ["fit", "phone-mean", "CORPUS", "-o", "P"],
            ["fit", "phone-mean", "P", "-o", "OUT.dam"],
            ["inspect", "P"],
            ["generate-tiny", "P"],
            ["fit", "phone-mean", "CORPUS", "-o", "OUT.dam", "--param", "P"],
        ]
    ),
    st.sampled_from(PATHS + ["unknown_phone=guess", "colour=red", "unknown_phone=error", "x"]),
)
def test_command_lines_never_trace_back_or_damage_inputs(micro_model_file, small_corpus_dir, argv, pick):
    root = str(small_corpus_dir.parent)
    src = os.path.join(root, "m.dam")
    shutil.copy(micro_model_file[0], src)
    names = {
        "MODEL": str(src),
        "ALIGN": str(small_corpus_dir / "tiny000.TextGrid"),
        "CORPUS": str(small_corpus_dir),
        "CSV": str(small_corpus_dir / "tiny000.csv"),
        "MISSING": os.path.join(root, "missing.TextGrid"),
        "NODIR/x.out": os.path.join(root, "nodir", "x.out"),
        "DIR": root,
        "OUT.csv": os.path.join(root, "out.csv"),
        "OUT.dam": os.path.join(root, "out.dam"),
    }
    argv = [names.get(a, a) for a in argv]
    argv = [names.get(pick, pick) if a == "P" else a for a in argv]
    # the inputs: every existing path on the command line but the output (a file after -o may be replaced)
    output = argv[argv.index("-o") + 1] if "-o" in argv[:-1] else None
    inputs = {a for a in argv if a != output and a and os.path.exists(a) and a != root}
    inputs.add(str(small_corpus_dir))  # never an output of anything
    before = {p: _digest(p) for p in inputs}
    here = os.getcwd()
    os.chdir(root)  # relative outputs ("x", "colour=red") land in the test's folder, not the checkout
    try:
        code, out, err = _run_cli(["-q"] + argv)
    finally:
        os.chdir(here)
    assert code in (0, 1, 2), (argv, code, err)
    assert "Traceback" not in err
    if code == 1:
        lines = err.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("dam: error: "), err
    # inputs untouched, no temporary files left, no NaN written
    assert {p: _digest(p) for p in inputs} == before, argv
    for _dirpath, _, files in os.walk(root):
        assert not [f for f in files if f.startswith(TEMP_PREFIX)], (argv, files)
    assert "nan" not in out.lower()
    for written in (names["OUT.csv"], names["OUT.dam"]):
        if os.path.isdir(written):  # generate-tiny made a directory of that name
            shutil.rmtree(written)
        elif os.path.exists(written):
            with open(written, "rb") as fh:
                data = fh.read()
            if argv[0] == "predict":
                assert b"nan" not in data.lower() and b"inf" not in data.lower()
            else:  # a model file: complete, and it loads
                dam.load(written)
            os.unlink(written)
