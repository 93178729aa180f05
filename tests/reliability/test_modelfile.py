"""Model files that are not what they claim (issue 12): every value checked at load against
the class's declared state, archive sizes checked before allocation, and every byte flip or
truncation of a real file a ModelFileError naming the path (or the same predictions)."""

import io
import json
import struct
import zipfile

import numpy as np
import pytest

import dam
from dam.modelfile import META_KEY, ModelFileError, read_model_file


def _rewrite(src, dst, edit_meta=None, arrays=None):
    """Write ``dst`` as ``src`` with its JSON record and arrays edited: a crafted model file."""
    meta, arr = read_model_file(src)
    if edit_meta is not None:
        edit_meta(meta)
    arr.update(arrays or {})
    arr[META_KEY] = np.frombuffer(json.dumps(meta).encode(), dtype=np.uint8)
    with open(dst, "wb") as fh:
        np.savez_compressed(fh, **arr)
    return dst


def _table_key(path):
    meta, _ = read_model_file(path)
    return meta["state"]["table_"]["__array__"]


def _refused(path, *words):
    with pytest.raises(ModelFileError) as info:
        dam.load(path)
    msg = str(info.value)
    assert str(path) in msg, msg
    for w in words:
        assert w in msg, msg
    return msg


def test_an_int8_table_is_refused(phone_mean_file, tmp_path):
    src, _ = phone_mean_file
    key = _table_key(src)
    table = read_model_file(src)[1][key]
    bad = _rewrite(src, tmp_path / "int8.dam", arrays={key: (table * 100).astype(np.int8)})
    _refused(bad, "state.table_", "int8")


@pytest.mark.parametrize("rate", [1e9, 0.0, -100.0, "100"])
def test_frame_rates_out_of_range_are_refused(phone_mean_file, tmp_path, rate):
    src, _ = phone_mean_file
    bad = _rewrite(src, tmp_path / "rate.dam", lambda m: m["state"].__setitem__("frame_rate_", rate))
    _refused(bad, "state.frame_rate_")


def test_a_phone_mean_record_relabelled_dam_is_refused(phone_mean_file, tmp_path):
    src, _ = phone_mean_file
    bad = _rewrite(src, tmp_path / "relabel.dam", lambda m: m.update(model="dam", params={}))
    _refused(bad, "not a complete DAM")


@pytest.mark.parametrize(
    "edit, words",
    [
        (lambda m: m["state"].__setitem__("phone_counts_", {"a": 0}), ["state.phone_counts_"]),
        (lambda m: m["state"].__setitem__("channels_", ["x", "x", "y", "z"]), ["state.channels_", "repeats"]),
        (lambda m: m["state"].__setitem__("channels_", ["x"]), ["state.table_", "n_channels"]),
        (lambda m: m["state"].__setitem__("predict_", 1), ["predict_"]),
        (lambda m: m["state"].__setitem__("phones_", ["a"]), ["phones_"]),
        (lambda m: m["state"].__setitem__("__class__", "x"), ["__class__"]),
        (lambda m: m["state"].pop("table_"), ["state.table_", "missing"]),
        (lambda m: m["state"].__setitem__("table_", {"__array__": "nope"}), ["nope"]),
        (lambda m: m["params"].__setitem__("unknown_phone", "guess"), ["unknown_phone"]),
        (lambda m: m["params"].__setitem__("colour", "red"), ["params"]),
        (lambda m: m.__setitem__("model", ["phone-mean"]), ["model"]),
        (lambda m: m.__setitem__("version", True), ["version"]),
    ],
    ids=[
        "zero-count",
        "duplicate-channels",
        "shape-mismatch",
        "extra-attribute",
        "property",
        "dunder",
        "missing",
        "dangling-array",
        "bad-param",
        "unknown-param",
        "model-not-str",
        "version-bool",
    ],
)
def test_crafted_records_name_the_field(phone_mean_file, tmp_path, edit, words):
    src, _ = phone_mean_file
    _refused(_rewrite(src, tmp_path / "crafted.dam", edit), *words)


def test_non_finite_state_is_refused(phone_mean_file, tmp_path):
    src, _ = phone_mean_file
    key = _table_key(src)
    table = read_model_file(src)[1][key].copy()
    table[1, 2] = np.nan
    _refused(_rewrite(src, tmp_path / "nan.dam", arrays={key: table}), "state.table_", "non-finite")


def test_deeply_nested_json_is_refused(phone_mean_file, tmp_path):
    src, _ = phone_mean_file
    deep = [[]]
    for _ in range(200):
        deep = [deep]
    _refused(_rewrite(src, tmp_path / "deep.dam", lambda m: m["state"].__setitem__("x_", deep)), "nested")
    raw = ("[" * 200000 + "]" * 200000).encode()
    bad = tmp_path / "deeper.dam"
    with open(bad, "wb") as fh:
        np.savez(fh, **{META_KEY: np.frombuffer(raw, dtype=np.uint8)})
    _refused(bad, "nested")


def test_a_directory_is_not_a_model_file(tmp_path):
    _refused(tmp_path, "directory")


def test_an_npy_header_declaring_1e11_elements_is_refused_before_allocation(phone_mean_file, tmp_path):
    src, _ = phone_mean_file
    key = _table_key(src)
    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(buf, {"descr": "<f8", "fortran_order": False, "shape": (10**11,)})
    member = buf.getvalue() + b"\0" * 64
    bad = tmp_path / "huge.dam"
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(bad, "w", zipfile.ZIP_DEFLATED) as zout:
        for info in zin.infolist():
            zout.writestr(info.filename, member if info.filename == key + ".npy" else zin.read(info))
    _refused(bad, key, "declares shape (100000000000,)")


def test_a_zip_bomb_is_refused_from_its_declared_sizes(phone_mean_file, tmp_path):
    """A member whose central-directory entry declares 1 GiB: refused before reading it."""
    src, _ = phone_mean_file
    raw = bytearray(src.read_bytes())
    pos = raw.index(b"PK\x01\x02")  # first central-directory entry; uncompressed size at +24
    raw[pos + 24 : pos + 28] = struct.pack("<I", 2**30)
    bad = tmp_path / "bomb.dam"
    bad.write_bytes(bytes(raw))
    _refused(bad, "declares", "refused before reading")


def test_a_real_zip_bomb_is_refused(tmp_path):
    """64 MiB of zeros compress to ~64 kB: over the limit of 64 MiB + 50x the file size."""
    bad = tmp_path / "zeros.dam"
    with open(bad, "wb") as fh:
        np.savez_compressed(fh, a0=np.zeros(2**23 + 2**20))
    assert bad.stat().st_size < 200_000
    _refused(bad, "refused before reading")


def test_every_single_byte_flip_is_an_error_or_changes_nothing(micro_model_file, tmp_path):
    src, alignment, expected = micro_model_file
    raw = src.read_bytes()
    bad = tmp_path / "flip.dam"
    outcomes = {"error": 0, "same": 0}
    for i in range(len(raw)):
        for mask in (0x01, 0xFF):
            b = bytearray(raw)
            b[i] ^= mask
            bad.write_bytes(bytes(b))
            try:
                y = dam.load(bad).predict(alignment)
            except ModelFileError as exc:
                assert str(bad) in str(exc), (i, mask, exc)
                outcomes["error"] += 1
            else:
                np.testing.assert_array_equal(y, expected, err_msg=f"byte {i} ^ {mask:#x}")
                outcomes["same"] += 1
    assert outcomes["error"] > len(raw)  # most flips matter; none escaped as another error type


def test_every_truncation_is_a_model_file_error(micro_model_file, tmp_path):
    src, _, _ = micro_model_file
    raw = src.read_bytes()
    bad = tmp_path / "short.dam"
    for n in range(len(raw)):
        bad.write_bytes(raw[:n])
        _refused(bad)


def test_every_registered_classical_model_round_trips_through_its_schema(tiny_train, tmp_path):
    """Saving checks the state against the same schema as loading: what is written loads."""
    alignment = tiny_train[0].alignment
    for name in ("dam", "dam-m0", "cohen-massaro", "mmm", "dtree", "phone-mean", "target-interpolation"):
        cls = dam.registry.get(name)
        model = cls(**cls.get_test_params()[0]).fit(tiny_train)
        model.save(tmp_path / f"{name}.dam")
        back = dam.load(tmp_path / f"{name}.dam")
        np.testing.assert_array_equal(back.predict(alignment), model.predict(alignment))


def test_a_model_whose_state_breaks_its_schema_is_not_written(tiny_train, tmp_path):
    model = dam.make("phone-mean").fit(tiny_train)
    model.table_ = model.table_.astype(np.float32)
    model.table_[0, 0] = np.inf
    with pytest.raises(ModelFileError, match="state.table_"):
        model.save(tmp_path / "m.dam")
    assert not (tmp_path / "m.dam").exists()


def test_every_numpy_runtime_model_declares_its_state():
    """A model a runtime loads with numpy alone must say what its file holds."""
    from dam.modelfile import _declares_schema

    for name in dam.registry.names():
        ok, _ = dam.registry.available(name)
        if ok and dam.registry.get(name).get_tags()["numpy_runtime"]:
            assert _declares_schema(dam.registry.get(name)), f"{name} declares no _state_schema"
