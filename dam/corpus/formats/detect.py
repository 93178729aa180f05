"""Which corpus layout a path holds, and the loader of each.

:func:`dam.corpus.io.load_corpus` calls :func:`detect_format` unless
``format=`` is given, then :func:`load_formatted` for every layout other than
the toolkit's own corpus directory. Detection looks at file names only (and,
for ``.ema`` files, at the EST header), in this order:

======================  ===================================================
layout                  recognised by
======================  ===================================================
``emu``                 a ``*_DBconfig.json`` in the folder, ``*_bndl.json``
                        files in it, or the path is a ``*_bndl.json`` file
``mview``               ``.mat`` files (Haskins IEEE rate comparison)
``xrmb``                ``.txy`` files (Wisconsin X-ray microbeam)
``mocha``               ``.ema`` files with MOCHA-TIMIT's 20-channel layout
``mngu0``               ``.ema`` files named ``mngu0_*`` (other EST files
                        are read by the generic directory reader)
``directory``           everything else: alignments (TextGrid, ``.lab``, BAS
                        ``.par``) with same-stem trajectories (CSV, NPY, EST)
======================  ===================================================

``bas`` is an alias of ``directory``: BAS Partitur files are alignments there.
"""

from __future__ import annotations

import importlib
import os
from pathlib import Path

from dam.corpus.data import DataError

__all__ = ["CORPUS_FORMATS", "detect_format", "load_formatted"]

#: format name -> "module:function" of its corpus loader (None: the generic directory reader)
CORPUS_FORMATS = {
    "directory": None,
    "bas": None,
    "emu": "dam.corpus.formats.emu:load_emu_corpus",
    "mocha": "dam.corpus.formats.mocha:load_mocha_corpus",
    "mngu0": "dam.corpus.formats.mocha:load_mngu0_corpus",
    "xrmb": "dam.corpus.formats.xrmb:load_xrmb_corpus",
    "mview": "dam.corpus.formats.mview:load_mview_corpus",
}


def detect_format(path) -> str:
    """The name (a key of :data:`CORPUS_FORMATS`) of the layout at ``path``.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> (d / "x_DBconfig.json").write_text("{}")
    2
    >>> detect_format(d)
    'emu'
    """
    p = Path(path)
    if p.is_file():
        if p.name.endswith("_bndl.json"):
            return "emu"
        raise DataError(
            os.fspath(path),
            "path",
            os.fspath(path),
            "not a corpus directory (a single file is read only as an EMU _bndl.json bundle)",
        )
    if not p.is_dir():
        raise DataError(os.fspath(path), "path", os.fspath(path), "not a directory")
    names = [q.name for q in p.iterdir()]
    if any(n.endswith("_DBconfig.json") or n.endswith("_bndl.json") for n in names):
        return "emu"
    suffixes = {Path(n).suffix.lower() for n in names}
    if ".mat" in suffixes:
        return "mview"
    if ".txy" in suffixes or ".xyd" in suffixes:
        return "xrmb"
    if ".ema" in suffixes:
        from dam.corpus.formats.mocha import looks_like_mocha

        emas = sorted(q for q in p.iterdir() if q.suffix.lower() == ".ema")
        if looks_like_mocha(emas[0]):
            return "mocha"
        if emas[0].name.lower().startswith("mngu0"):
            return "mngu0"
    return "directory"


def load_formatted(fmt: str, path, **options):
    """Run the loader of layout ``fmt`` on ``path`` with ``options`` (see each loader)."""
    if fmt not in CORPUS_FORMATS:
        raise DataError(
            os.fspath(path), "format", fmt, "unknown corpus format", f"formats: {', '.join(CORPUS_FORMATS)}"
        )
    spec = CORPUS_FORMATS[fmt]
    if spec is None:
        raise ValueError(f"format {fmt!r} is read by dam.corpus.io.load_corpus itself")
    module, _, func = spec.partition(":")
    return getattr(importlib.import_module(module), func)(path, **options)
