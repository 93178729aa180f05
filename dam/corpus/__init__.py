"""The ground floor: the data model, readers and writers of every format, phone sets, features.

Nothing in :mod:`dam.corpus` imports the rest of dam. Data is validated once, here, where
it enters; errors (:class:`DataError`) name the file, the field and the value.

- :mod:`dam.corpus.data`: :class:`Alignment`, :class:`Utterance`, :class:`Corpus`.
- :mod:`dam.corpus.io`: :func:`load_corpus`, :func:`save_corpus`, :func:`read_alignment`.
- :mod:`dam.corpus.formats`: one module per file format.
- :mod:`dam.corpus.phonetics`: phone sets and classes; :mod:`dam.corpus.features`: the
  linguistic window features of Taylor et al. (2017).
"""

from __future__ import annotations

from dam._lazy import lazy_exports
from dam.corpus.data import SILENCE, Alignment, Corpus, DataError, Utterance, frame_labels, frame_times

_EXPORTS = {
    **dict.fromkeys(
        ["load_corpus", "save_corpus", "read_alignment", "read_trajectory", "write_utterance", "frame_rate_from_times"],
        ".io",
    ),
    **dict.fromkeys(["read_textgrid", "write_textgrid"], ".formats.textgrid"),
    **dict.fromkeys(["atomic_write", "atomic_path", "atomic_directory", "check_output", "OutputPathError"], ".atomic"),
    **dict.fromkeys(["read_lab", "write_lab"], ".formats.htk"),
    **dict.fromkeys(["write_csv", "write_npy"], ".formats.tables"),
    **dict.fromkeys(["EstTrack", "read_est", "write_est"], ".formats.est"),
    **dict.fromkeys(["read_ssff", "write_ssff"], ".formats.emu"),
    **dict.fromkeys(["read_par", "write_par"], ".formats.bas"),
    **dict.fromkeys(["read_txy", "write_txy"], ".formats.xrmb"),
    **dict.fromkeys(["detect_format", "CORPUS_FORMATS"], ".formats.detect"),
    **dict.fromkeys(["AudioClip", "audio_header", "AUDIO_SUFFIXES"], ".formats.audio"),
    **dict.fromkeys(["fill_masked", "infer_sensors", "resolve_sensors"], ".data"),
    **dict.fromkeys(
        [
            "phone_class",
            "base_phone",
            "fallback_phone",
            "guess_alphabet",
            "is_vowel",
            "is_consonant",
            "taylor_categories",
            "TAYLOR_CATEGORIES",
        ],
        ".phonetics",
    ),
    **dict.fromkeys(
        [
            "phone_vocabulary",
            "frame_phone_indices",
            "window_offsets",
            "window_dilation",
            "window_features",
            "n_window_features",
            "window_feature_names",
            "phonetic_transition_clusters",
            "fit_transition_clusters",
            "window_targets",
            "overlap_average",
        ],
        ".features",
    ),
}
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, ("io", "formats", "phonetics", "features", "atomic"))

__all__ = ["SILENCE", "Alignment", "Utterance", "Corpus", "DataError", "frame_labels", "frame_times", *_EXPORTS]
