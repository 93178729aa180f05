"""One module per file format; :mod:`dam.corpus.io` dispatches to them.

- :mod:`~dam.corpus.formats.textgrid`: Praat TextGrids (alignments).
- :mod:`~dam.corpus.formats.htk`: HTK and ESPS/xwaves ``.lab`` files (alignments).
- :mod:`~dam.corpus.formats.tables`: CSV and ``.npy`` trajectories.
- :mod:`~dam.corpus.formats.est`: Edinburgh Speech Tools tracks (mngu0, MOCHA-TIMIT EMA).

A new format is a module here with ``read_*``/``write_*`` functions that return or take
the data model of :mod:`dam.corpus.data` and raise :class:`~dam.corpus.DataError` naming the
file, the field and the value; register its suffix in :mod:`dam.corpus.io`.
"""
