"""The models ``dam animate`` uses when none is given, and the script that makes them.

Two small files ship in ``dam/datasets/data/``:

* ``default_dam.npz``: a DAM (:class:`dam.model.DAM`, the paper's defaults
  except ``modes="single"``, one animeme per phone, which keeps the file
  small) fitted on the bundled ``vtl`` training split: 19 VocalTractLab
  tract parameters at 100 Hz, German SAMPA phones;
* ``default_durations.npz``: a :class:`dam.speech.DurationModel` fitted on
  the same split (phone durations measured in real German speech), with
  the word boundaries the corpus records (:func:`vtl_word_ids`).

Both are in the toolkit's model-file format and load with numpy alone.
English input reaches them through the phone-set tables of
:mod:`dam.corpus.phonetics`, with every approximation reported.

Both are fitted to the vtl corpus and so share its licence terms (see
``LICENCE_NOTE`` in :mod:`dam.datasets.vtl`: treat them as derived from
GPL-3.0-or-later data).

Regenerate (deterministic; about a minute on 2 cores)::

    python -m dam.datasets.default_model
"""

from __future__ import annotations

import sys
from pathlib import Path

__all__ = ["DEFAULT_MODEL_PATH", "DEFAULT_DURATIONS_PATH", "DEFAULT_ALPHABET", "build_default_models", "vtl_word_ids"]

_DATA = Path(__file__).parent / "data"
#: The default animation model (a DAM on the vtl corpus).
DEFAULT_MODEL_PATH = _DATA / "default_dam.npz"
#: The default duration model (fitted on the vtl corpus).
DEFAULT_DURATIONS_PATH = _DATA / "default_durations.npz"
#: The phone set of both default models.
DEFAULT_ALPHABET = "german-sampa"
#: Hyperparameters of the default DAM (recorded in the file too).
DEFAULT_DAM_PARAMS = {"modes": "single", "unknown_phone": "fallback"}


def vtl_word_ids(split: str) -> tuple[list, list]:
    """The vtl corpus split and, per utterance, the word index of every segment (-1 for silence).

    The corpus records each phrase's words (``corpus.json``); their phones
    come from the word list it was generated from, so the word boundaries are
    exact. An utterance whose phones do not match its words gets None.
    """
    import json

    from dam.datasets import load, path
    from dam.datasets.vtl import SYMBOL_MAP, load_lexicon

    lexicon = {w.word: w.phones for w in load_lexicon()}
    corpus = load("vtl", split)
    meta = json.loads((path("vtl", split) / "corpus.json").read_text())["utterances"]
    out = []
    for utt in corpus:
        words = meta[utt.name]["words"]
        phones = [SYMBOL_MAP.get(p, p) for w in words for p in lexicon[w]]
        owner = iter([i for i, w in enumerate(words) for _ in lexicon[w]])
        labels = utt.alignment.labels
        if phones != [lab for lab in labels if lab != utt.alignment.silence]:
            out.append(None)
            continue
        out.append([-1 if lab == utt.alignment.silence else next(owner) for lab in labels])
    return corpus, out


def build_default_models(out_dir=_DATA, *, verbose: bool = True) -> tuple[Path, Path]:
    """Fit the default DAM and duration model on the bundled vtl training split and save them.

    Returns the two paths written.
    """
    import time

    from dam.datasets import load
    from dam.model import DAM
    from dam.speech.durations import DurationModel

    out_dir = Path(out_dir)
    corpus = load("vtl", "train")
    t0 = time.perf_counter()
    dam_model = DAM(**DEFAULT_DAM_PARAMS).fit(corpus)
    t1 = time.perf_counter()
    _, word_ids = vtl_word_ids("train")
    durations = DurationModel().fit(corpus, word_ids)
    model_path, dur_path = out_dir / DEFAULT_MODEL_PATH.name, out_dir / DEFAULT_DURATIONS_PATH.name
    dam_model.save(model_path)
    durations.save(dur_path)
    if verbose:
        print(
            f"DAM fitted in {t1 - t0:.1f} s -> {model_path} ({model_path.stat().st_size / 1024:.0f} KiB)",
            file=sys.stderr,
        )
        print(f"durations -> {dur_path} ({dur_path.stat().st_size / 1024:.0f} KiB)", file=sys.stderr)
    return model_path, dur_path


if __name__ == "__main__":  # pragma: no cover - the regeneration script
    build_default_models(Path(sys.argv[1]) if len(sys.argv) > 1 else _DATA)
