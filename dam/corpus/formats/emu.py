"""EMU-SDMS databases (emuDB) and their SSFF track files.

The EMU Speech Database Management System of the IPS Munich (used through
the R package emuR) stores a database as a folder (The EMU-SDMS Manual,
chapter "File descriptions")::

    <name>_emuDB/
        <name>_DBconfig.json          levelDefinitions, linkDefinitions, ssffTrackDefinitions
        <session>_ses/
            <bundle>_bndl/
                <bundle>_annot.json   levels, items, links
                <bundle>.wav          the media file ("mediafileExtension")
                <bundle>.<ext>        SSFF tracks ("fileExtension" of each track definition)

``_annot.json``: ``{"name", "annotates", "sampleRate", "levels": [{"name",
"type": "ITEM"|"SEGMENT"|"EVENT", "items": [{"id", "sampleStart",
"sampleDur", "labels": [{"name", "value"}]}]}], "links": [{"fromID",
"toID"}]}``. A SEGMENT covers samples ``sampleStart`` to ``sampleStart +
sampleDur`` inclusive; in seconds it starts at ``(sampleStart - 0.5) /
sampleRate`` (0 for the first sample) and ends at ``(sampleStart + sampleDur
+ 0.5) / sampleRate``, so successive segments meet without a gap. Its label is
the one whose ``name`` is the level's name.

The EMU-webApp serves a bundle as one JSON document, ``{"annotation": {...},
"ssffFiles": [{"fileExtension", "encoding": "BASE64", "data"}], "mediaFile":
{"encoding": "BASE64", "data"}}``; :func:`read_bundle_json` reads those
(``<bundle>_bndl.json`` files in a folder, or one such file).

**SSFF** (Simple Signal File Format, as read and written by wrassp/libassp):
an ASCII header, then binary records::

    SSFF -- (c) SHLRC
    Machine IBM-PC                  (little-endian; SPARC: big-endian)
    Record_Freq 200.0               (records per second)
    Start_Time 0.0025               (time of the first record, seconds)
    Column fm SHORT 4               (name, type CHAR|BYTE|SHORT|LONG|FLOAT|DOUBLE, values per record)
    Column bw SHORT 4
    Original_Freq DOUBLE 20000.0    (optional NAME TYPE VALUE lines, and Comment CHAR ...)
    -----------------

Each record holds every column's values in header order; record ``i`` is at
``Start_Time + i / Record_Freq``. A column of ``k`` values becomes the
channels ``<column>`` (k = 1) or ``<column>_T1 .. <column>_Tk`` (emuR's
``T1 .. Tk`` naming of track columns). Values are kept in the file's unit
(SSFF records none).
"""

from __future__ import annotations

import base64
import binascii
import json
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from dam.corpus.atomic import atomic_write
from dam.corpus.data import SILENCE, Alignment, DataError
from dam.corpus.formats.tracks import Track, build_corpus

__all__ = [
    "SsffFile",
    "read_ssff",
    "parse_ssff",
    "write_ssff",
    "read_annot",
    "annot_alignment",
    "read_bundle_json",
    "load_emu_corpus",
    "SSFF_TYPES",
]

SSFF_MAGIC = "SSFF -- (c) SHLRC"
SSFF_END = "-----------------"
#: SSFF type name -> numpy type (byte order added from the Machine line)
SSFF_TYPES = {"CHAR": "i1", "BYTE": "u1", "SHORT": "i2", "LONG": "i4", "FLOAT": "f4", "DOUBLE": "f8"}
_MACHINES = {"IBM-PC": "<", "VAX": "<", "SPARC": ">"}


@dataclass
class SsffFile:
    """The content of an SSFF file.

    Attributes
    ----------
    columns : dict of str to ndarray
        Column name -> values, shape (n_records, n_values), in header order.
    record_freq : float
        Records per second.
    start_time : float
        Time of the first record in seconds.
    machine : str
        ``IBM-PC`` (little-endian) or ``SPARC`` (big-endian).
    extra : dict of str to (str, str)
        Optional header lines ``NAME TYPE VALUE``, e.g. ``Original_Freq``.
    """

    columns: dict
    record_freq: float
    start_time: float = 0.0
    machine: str = "IBM-PC"
    extra: dict = field(default_factory=dict)

    @property
    def n_records(self) -> int:
        return len(next(iter(self.columns.values()))) if self.columns else 0

    def channels(self) -> tuple[np.ndarray, list[str]]:
        """All columns side by side: ``(values (n_records, n_channels), channel names)``."""
        names, blocks = [], []
        for col, vals in self.columns.items():
            k = vals.shape[1]
            names += [col] if k == 1 else [f"{col}_T{i + 1}" for i in range(k)]
            blocks.append(vals.astype(float))
        return np.hstack(blocks), names


def _number(text: str, source: str, fld: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise DataError(source, fld, text, "not a number") from None
    if not np.isfinite(value):
        raise DataError(source, fld, text, "not a finite number")
    return value


def parse_ssff(raw: bytes, source: str) -> SsffFile:
    """Parse the bytes of an SSFF file (see the module docstring); DataError names ``source``."""
    end = raw.find((SSFF_END + "\n").encode())
    if not raw.startswith(SSFF_MAGIC.encode()):
        raise DataError(
            source, "header", raw[:20].decode("latin-1"), f"not an SSFF file (the first line must be {SSFF_MAGIC!r})"
        )
    if end < 0:
        raise DataError(source, "header", SSFF_END, "the header has no end line")
    body = raw[end + len(SSFF_END) + 1 :]
    machine, rate, start = None, None, 0.0
    cols: list[tuple[str, str, int]] = []
    extra: dict = {}
    for lineno, line in enumerate(raw[:end].decode("latin-1").splitlines()[1:], 2):
        parts = line.split()
        if not parts:
            continue
        key = parts[0]
        if key == "Machine":
            machine = parts[1] if len(parts) > 1 else ""
            if machine not in _MACHINES:
                raise DataError(source, "Machine", machine, "must be IBM-PC (little-endian) or SPARC (big-endian)")
        elif key == "Record_Freq":
            rate = _number(parts[1] if len(parts) > 1 else "", source, "Record_Freq")
            if rate <= 0:
                raise DataError(source, "Record_Freq", rate, "must be positive")
        elif key == "Start_Time":
            start = _number(parts[1] if len(parts) > 1 else "", source, "Start_Time")
            if start < 0:
                raise DataError(source, "Start_Time", start, "must not be negative")
        elif key == "Column":
            if len(parts) != 4:
                raise DataError(source, f"line {lineno} (Column)", line, "expected 'Column NAME TYPE COUNT'")
            name, typ, count = parts[1:]
            if typ not in SSFF_TYPES:
                raise DataError(source, f"Column {name} type", typ, f"must be one of {', '.join(SSFF_TYPES)}")
            try:
                k = int(count)
            except ValueError:
                k = 0
            if k < 1:
                raise DataError(source, f"Column {name} count", count, "must be a whole number >= 1")
            if any(c[0] == name for c in cols):
                raise DataError(source, f"Column {name}", name, "two columns share this name")
            cols.append((name, typ, k))
        elif len(parts) >= 3:
            extra[key] = (parts[1], " ".join(parts[2:]))
    for fld, value in (("Machine", machine), ("Record_Freq", rate)):
        if value is None:
            raise DataError(source, fld, None, "missing from the header")
    if not cols:
        raise DataError(source, "Column", None, "the header declares no column")
    order = _MACHINES[machine]
    dtype = np.dtype([(name, f"{order}{SSFF_TYPES[typ]}", (k,)) for name, typ, k in cols])
    if len(body) % dtype.itemsize:
        raise DataError(
            source,
            "data size",
            f"{len(body)} bytes",
            f"not a whole number of {dtype.itemsize}-byte records ({', '.join(f'{n} {t} x{k}' for n, t, k in cols)})",
        )
    records = np.frombuffer(body, dtype=dtype)
    columns = {name: np.array(records[name]).reshape(len(records), k) for name, _, k in cols}
    return SsffFile(columns=columns, record_freq=float(rate), start_time=float(start), machine=machine, extra=extra)


def read_ssff(path) -> SsffFile:
    """Read an SSFF track file.

    Raises
    ------
    DataError
        Naming the file and the field: a missing magic line or end line, an
        unknown Machine or column type, a missing Record_Freq, or a data
        block that is not a whole number of records.
    """
    path = os.fspath(path)
    with open(path, "rb") as fh:
        return parse_ssff(fh.read(), path)


def _format_number(x: float) -> str:
    text = repr(float(x))
    return text if "e" in text or "." in text else text + ".0"


def write_ssff(
    path, columns, record_freq: float, *, start_time: float = 0.0, types=None, machine: str = "IBM-PC", extra=None
) -> None:
    """Write an SSFF file (atomically: a temporary file, then rename).

    Parameters
    ----------
    path : path-like
    columns : dict of str to array-like, each shape (n_records,) or (n_records, k)
        In the order they are to appear.
    record_freq : float
        Records per second.
    start_time : float, default 0.0
    types : dict of str to str, optional
        SSFF type per column (CHAR, BYTE, SHORT, LONG, FLOAT, DOUBLE); default DOUBLE.
    machine : {"IBM-PC", "SPARC"}, default "IBM-PC"
        Little- or big-endian data.
    extra : dict of str to (str, value), optional
        Further header lines ``NAME TYPE VALUE``.

    Examples
    --------
    >>> import tempfile, os
    >>> p = os.path.join(tempfile.mkdtemp(), "a.ema")
    >>> write_ssff(p, {"tt": [[1.0, 2.0], [3.0, 4.0]]}, 200.0)
    >>> read_ssff(p).columns["tt"].tolist()
    [[1.0, 2.0], [3.0, 4.0]]
    """
    path = os.fspath(path)
    if machine not in _MACHINES:
        raise DataError(path, "machine", machine, "must be IBM-PC or SPARC")
    types = dict(types or {})
    arrays = {}
    n = None
    for name, vals in columns.items():
        if not name or any(ch.isspace() for ch in str(name)):
            raise DataError(path, "columns", name, "SSFF column names cannot be empty or contain white space")
        a = np.asarray(vals)
        a = a[:, None] if a.ndim == 1 else a
        if a.ndim != 2 or (n is not None and len(a) != n):
            raise DataError(path, f"columns[{name!r}]", a.shape, f"must be ({n if n is not None else 'n'}, k)")
        n = len(a)
        typ = types.get(name, "DOUBLE")
        if typ not in SSFF_TYPES:
            raise DataError(path, f"types[{name!r}]", typ, f"must be one of {', '.join(SSFF_TYPES)}")
        arrays[name] = (typ, a)
    if not arrays:
        raise DataError(path, "columns", 0, "need at least one column")
    lines = [
        SSFF_MAGIC,
        f"Machine {machine}",
        f"Record_Freq {_format_number(record_freq)}",
        f"Start_Time {_format_number(start_time)}",
    ]
    lines += [f"Column {name} {typ} {a.shape[1]}" for name, (typ, a) in arrays.items()]
    lines += [f"{k} {t} {v}" for k, (t, v) in (extra or {}).items()]
    lines.append(SSFF_END)
    order = _MACHINES[machine]
    dtype = np.dtype([(name, f"{order}{SSFF_TYPES[typ]}", (a.shape[1],)) for name, (typ, a) in arrays.items()])
    records = np.zeros(n, dtype=dtype)
    for name, (_, a) in arrays.items():
        records[name] = a.reshape(n, -1)
    with atomic_write(path, "wb") as fh:
        fh.write(("\n".join(lines) + "\n").encode("ascii") + records.tobytes())


# -- annotations ------------------------------------------------------------
def _load_json(path: str):
    from dam.corpus.encoding import read_text

    try:
        return json.loads(read_text(path))  # UTF-8 (BOM dropped); other bytes refused with their offset
    except json.JSONDecodeError as exc:
        raise DataError(path, "json", exc.msg, f"invalid JSON at line {exc.lineno}") from None
    except RecursionError:
        raise DataError(path, "json", "nesting", "nested too deeply") from None


def read_annot(path) -> dict:
    """Read and check a ``_annot.json`` file (fields as in the module docstring)."""
    path = os.fspath(path)
    return _check_annot(_load_json(path), path)


def _check_annot(annot, source: str) -> dict:
    if not isinstance(annot, dict):
        raise DataError(source, "annotation", type(annot).__name__, "must be a JSON object")
    for key in ("sampleRate", "levels"):
        if key not in annot:
            raise DataError(source, key, None, "missing")
    rate = annot["sampleRate"]
    if isinstance(rate, bool) or not isinstance(rate, (int, float)) or not rate > 0:
        raise DataError(source, "sampleRate", rate, "must be a positive number")
    if not isinstance(annot["levels"], list):
        raise DataError(source, "levels", type(annot["levels"]).__name__, "must be a list")
    for i, level in enumerate(annot["levels"]):
        if not isinstance(level, dict) or "name" not in level or "items" not in level:
            raise DataError(
                source,
                f"levels[{i}]",
                level if not isinstance(level, dict) else sorted(level),
                "a level needs 'name', 'type' and 'items'",
            )
        if level.get("type") not in ("ITEM", "SEGMENT", "EVENT"):
            raise DataError(
                source, f"levels[{i}] ({level['name']!r}) type", level.get("type"), "must be ITEM, SEGMENT or EVENT"
            )
    return annot


def _lowest_segment_level(annot: dict, link_definitions=None) -> str:
    segs = [lv["name"] for lv in annot["levels"] if lv["type"] == "SEGMENT"]
    if not segs:
        return ""
    if link_definitions:
        supers = {d.get("superlevelName") for d in link_definitions}
        lowest = [s for s in segs if s not in supers]
        if lowest:
            return lowest[-1]
    sizes = {lv["name"]: len(lv["items"]) for lv in annot["levels"] if lv["type"] == "SEGMENT"}
    return max(segs, key=lambda s: (sizes[s], segs.index(s)))


def annot_alignment(
    annot: dict, *, level: str | None = None, source: str | None = None, link_definitions=None, silence: str = SILENCE
) -> Alignment:
    """The phone alignment of one ``_annot.json`` document.

    Parameters
    ----------
    annot : dict
        A parsed ``_annot.json`` (see :func:`read_annot`).
    level : str, optional
        The SEGMENT level holding the phones. Default: the lowest SEGMENT
        level (one that is no super-level in ``link_definitions``), else the
        SEGMENT level with the most items.
    source : str, optional
        Named in errors.
    link_definitions : list of dict, optional
        The ``linkDefinitions`` of the database's DBconfig.
    silence : str, default "sil"

    Returns
    -------
    Alignment
        Times in seconds by the EMU convention of the module docstring; gaps become silence.
    """
    annot = _check_annot(annot, source)
    names = [lv["name"] for lv in annot["levels"]]
    chosen = level or _lowest_segment_level(annot, link_definitions)
    if not chosen:
        raise DataError(source, "levels", names, "no SEGMENT level to read phones from")
    lv = next((lv for lv in annot["levels"] if lv["name"] == chosen), None)
    if lv is None:
        raise DataError(source, "level", chosen, "no level of that name", f"levels: {names}")
    if lv["type"] != "SEGMENT":
        raise DataError(source, f"level {chosen!r} type", lv["type"], "phones must come from a SEGMENT level")
    rate = float(annot["sampleRate"])
    labels, starts, ends = [], [], []
    for k, item in enumerate(lv["items"]):
        where = f"level {chosen!r} item {k}" + (f" (id {item.get('id')})" if isinstance(item, dict) else "")
        if not isinstance(item, dict):
            raise DataError(source, where, item, "an item must be a JSON object")
        s, d = item.get("sampleStart"), item.get("sampleDur")
        for fld, v in (("sampleStart", s), ("sampleDur", d)):
            if isinstance(v, bool) or not isinstance(v, (int, float)) or v < 0 or v != int(v):
                raise DataError(source, f"{where} {fld}", v, "must be a whole number of samples >= 0")
        value = next(
            (
                lab.get("value", "")
                for lab in item.get("labels", [])
                if isinstance(lab, dict) and lab.get("name") == chosen
            ),
            None,
        )
        if value is None:
            raise DataError(source, f"{where} labels", item.get("labels"), f"no label named {chosen!r}")
        labels.append(value)
        starts.append(0.0 if s == 0 else (s - 0.5) / rate)
        ends.append((s + d + 0.5) / rate)
    if not labels:
        raise DataError(source, f"level {chosen!r}", 0, "the level has no items")
    return Alignment(labels, starts, ends, source=source, silence=silence)


def read_bundle_json(path) -> tuple[dict, list[tuple[str, SsffFile]]]:
    """Read an EMU-webApp bundle document: ``(annotation, [(fileExtension, SsffFile), ...])``."""
    path = os.fspath(path)
    doc = _load_json(path)
    if not isinstance(doc, dict) or "annotation" not in doc:
        raise DataError(
            path,
            "annotation",
            None if not isinstance(doc, dict) else sorted(doc),
            "an EMU bundle document holds 'annotation' and 'ssffFiles'",
        )
    files = doc.get("ssffFiles", [])
    if not isinstance(files, list):
        raise DataError(path, "ssffFiles", type(files).__name__, "must be a list")
    out = []
    for i, f in enumerate(files):
        where = f"ssffFiles[{i}]"
        if not isinstance(f, dict) or "data" not in f or "fileExtension" not in f:
            raise DataError(
                path, where, f if not isinstance(f, dict) else sorted(f), "needs 'fileExtension', 'encoding' and 'data'"
            )
        if f.get("encoding", "BASE64") != "BASE64":
            raise DataError(path, f"{where}.encoding", f.get("encoding"), "only BASE64 is defined")
        try:
            raw = base64.b64decode(f["data"], validate=True)
        except (binascii.Error, ValueError, TypeError):
            raise DataError(path, f"{where}.data", str(f["data"])[:20], "not valid base64") from None
        out.append((str(f["fileExtension"]), parse_ssff(raw, f"{path}:{where} (.{f['fileExtension']})")))
    return _check_annot(doc["annotation"], f"{path}:annotation"), out


# -- databases ------------------------------------------------------------------
def _track_definitions(config: dict, source: str) -> list[dict]:
    defs = config.get("ssffTrackDefinitions", [])
    if not isinstance(defs, list):
        raise DataError(source, "ssffTrackDefinitions", type(defs).__name__, "must be a list")
    out = []
    for i, d in enumerate(defs):
        ext = d.get("fileExtension", d.get("fileExtention")) if isinstance(d, dict) else None
        if not isinstance(d, dict) or not d.get("name") or not d.get("columnName") or not ext:
            raise DataError(source, f"ssffTrackDefinitions[{i}]", d, "needs 'name', 'columnName' and 'fileExtension'")
        out.append({"name": d["name"], "columnName": d["columnName"], "fileExtension": ext})
    return out


def _track_channels(name: str, values: np.ndarray) -> list[str]:
    k = values.shape[1]
    return [name] if k == 1 else [f"{name}_T{i + 1}" for i in range(k)]


def _bundle_track(ssff_by_ext: dict, defs: list[dict] | None, wanted, source: str) -> Track:
    """One Track from the SSFF files of a bundle (all tracks of the definitions, or of the files)."""
    blocks, names, ref = [], [], None
    if defs is None:  # no DBconfig: every column of every file, named after the column
        chosen = [(col, ext, col) for ext, f in ssff_by_ext.items() for col in f.columns]
    else:
        chosen = [(d["name"], d["fileExtension"], d["columnName"]) for d in defs]
    if wanted is not None:
        known = [c[0] for c in chosen]
        missing = [w for w in wanted if w not in known]
        if missing:
            raise DataError(source, "tracks", missing, "no such SSFF track", f"tracks: {known}")
        chosen = [c for w in wanted for c in chosen if c[0] == w]
    if not chosen:
        raise DataError(source, "ssffTrackDefinitions", 0, "no SSFF track to read the trajectory from")
    for track_name, ext, column in chosen:
        f = ssff_by_ext.get(ext)
        if f is None:
            raise DataError(source, f"SSFF file .{ext}", track_name, "missing from the bundle")
        if column not in f.columns:
            raise DataError(source, f"SSFF file .{ext} column", column, "no such column", f"columns: {list(f.columns)}")
        if ref is None:
            ref = (f, ext)
        elif (
            abs(f.record_freq - ref[0].record_freq) > 1e-9 * f.record_freq
            or f.n_records != ref[0].n_records
            or abs(f.start_time - ref[0].start_time) > 1e-9
        ):
            raise DataError(
                source,
                f"SSFF file .{ext}",
                f"{f.n_records} records at {f.record_freq:g}/s",
                f"tracks of one bundle must share rate, start and length (.{ref[1]}: "
                f"{ref[0].n_records} records at {ref[0].record_freq:g}/s)",
            )
        vals = f.columns[column].astype(float)
        blocks.append(vals)
        names += _track_channels(track_name, vals)
    return Track(
        np.hstack(blocks), names, ref[0].record_freq, start_time=ref[0].start_time, source=f"{source} (.{ref[1]})"
    )


def load_emu_corpus(
    path,
    *,
    level: str | None = None,
    tracks=None,
    frame_rate: float | None = None,
    silence: str = SILENCE,
    tier: str | None = None,
    **_ignored,
):
    """Read an emuDB folder, a folder of ``_bndl.json`` documents, or one such document.

    Parameters
    ----------
    path : path-like
        The ``<name>_emuDB`` folder (holding ``<name>_DBconfig.json``), a folder of
        ``<bundle>_bndl.json`` files, or one ``_bndl.json`` file.
    level : str, optional
        SEGMENT level with the phones (default: the lowest one). ``tier`` is
        accepted as a synonym so ``load_corpus(path, tier=...)`` works; its
        default ``"phones"`` means the lowest level unless a level has that name.
    tracks : list of str, optional
        SSFF track names (``ssffTrackDefinitions`` names, or column names
        without a DBconfig) forming the trajectory; default all.
    frame_rate : float, optional
        Resample to this rate (see :mod:`dam.corpus.formats.tracks`).
    silence : str, default "sil"

    Returns
    -------
    Corpus
        Utterances named ``<session>_<bundle>`` (or ``<bundle>``: file names that
        :func:`~dam.corpus.io.save_corpus` can write), audio the bundle's media file;
        ``metadata["format"] == "emu"``.
    """
    root = Path(path)
    if level is None and tier not in (None, "phones"):
        level = tier
    configs = sorted(root.glob("*_DBconfig.json")) if root.is_dir() else []
    entries = []
    if root.is_dir() and configs:
        if len(configs) > 1:
            raise DataError(str(root), "DBconfig", [p.name for p in configs], "more than one _DBconfig.json")
        cpath = str(configs[0])
        config = _load_json(cpath)
        if not isinstance(config, dict):
            raise DataError(cpath, "json", type(config).__name__, "must hold a JSON object")
        defs = _track_definitions(config, cpath)
        links = config.get("linkDefinitions") or []
        media = config.get("mediafileExtension", "wav")
        name = config.get("name") or root.name.removesuffix("_emuDB")
        level = _level_for(level, tier, config, cpath)
        sessions = sorted(p for p in root.iterdir() if p.is_dir() and p.name.endswith("_ses"))
        if not sessions:
            raise DataError(cpath, "sessions", 0, "no <session>_ses folder beside the DBconfig")
        for ses in sessions:
            for bndl in sorted(p for p in ses.iterdir() if p.is_dir() and p.name.endswith("_bndl")):
                b = bndl.name[: -len("_bndl")]
                apath = bndl / f"{b}_annot.json"
                if not apath.exists():
                    raise DataError(str(bndl), "annotation", apath.name, "missing from the bundle folder")
                ssff = {}
                for ext in {d["fileExtension"] for d in defs}:
                    fp = bndl / f"{b}.{ext}"
                    if fp.exists():
                        ssff[ext] = read_ssff(fp)
                alignment = annot_alignment(
                    read_annot(apath), level=level, source=str(apath), link_definitions=links, silence=silence
                )
                track = _bundle_track(ssff, defs, tracks, str(bndl / b))
                wav = bndl / f"{b}.{media}"
                entries.append(
                    (f"{ses.name[: -len('_ses')]}_{b}", alignment, track, str(wav) if wav.exists() else None)
                )
    else:
        docs = [root] if root.is_file() else sorted(root.glob("*_bndl.json")) if root.is_dir() else []
        if not docs:
            raise DataError(
                str(root),
                "path",
                str(root),
                "not an emuDB (no <name>_DBconfig.json) nor EMU bundle documents (<bundle>_bndl.json)",
            )
        name = root.stem if root.is_file() else root.name
        for doc in docs:
            annot, files = read_bundle_json(doc)
            alignment = annot_alignment(annot, level=level, source=f"{doc}:annotation", silence=silence)
            track = _bundle_track(dict(files), None, tracks, str(doc))
            entries.append((doc.name.removesuffix("_bndl.json"), alignment, track, None))
    return build_corpus(entries, frame_rate=frame_rate, name=name, source=str(root), metadata={"format": "emu"})


def _level_for(level, tier, config: dict, source: str):
    """The level asked for, checked against the DBconfig's levelDefinitions."""
    defs = config.get("levelDefinitions") or []
    names = [d.get("name") for d in defs if isinstance(d, dict)]
    if level is None and tier == "phones" and "phones" in names:
        level = "phones"
    if level is not None and names and level not in names:
        raise DataError(source, "level", level, "no level of that name in levelDefinitions", f"levels: {names}")
    return level
