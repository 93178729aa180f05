"""One module per file format; :mod:`dam.corpus.io` dispatches to them.

- :mod:`~dam.corpus.formats.textgrid`: Praat TextGrids (alignments).
- :mod:`~dam.corpus.formats.htk`: HTK and ESPS/xwaves ``.lab`` files (alignments).
- :mod:`~dam.corpus.formats.tables`: CSV and ``.npy`` trajectories.
- :mod:`~dam.corpus.formats.est`: Edinburgh Speech Tools tracks (mngu0, MOCHA-TIMIT EMA).
- :mod:`~dam.corpus.formats.bas`: BAS Partitur ``.par`` files (WebMAUS alignments).

Corpora as they are distributed (see the README's "Corpora as they come"), each with a
corpus loader that :func:`dam.corpus.io.load_corpus` picks by :mod:`~dam.corpus.formats.detect`:

- :mod:`~dam.corpus.formats.emu`: EMU-SDMS databases, EMU-webApp bundles, SSFF tracks.
- :mod:`~dam.corpus.formats.mocha`: MOCHA-TIMIT and mngu0 EMA directories.
- :mod:`~dam.corpus.formats.xrmb`: Wisconsin X-ray microbeam ``.txy`` pellet files.
- :mod:`~dam.corpus.formats.mview`: Haskins IEEE rate comparison (mview ``.mat``).
- :mod:`~dam.corpus.formats.tracks`: their shared frame grid, missing data and resampling.

A new format is a module here with ``read_*``/``write_*`` functions that return or take
the data model of :mod:`dam.corpus.data` and raise :class:`~dam.corpus.DataError` naming the
file, the field and the value; register its suffix in :mod:`dam.corpus.io`.
"""
