"""The ``tiny`` corpus: a few utterances from a small articulatory toy model.

Phone targets for four channels (lip aperture, lip protrusion, jaw opening,
tongue-tip height) are tracked by a critically damped second-order system
whose stiffness depends on the phone, so neighbouring phones coarticulate.
Labels are ARPAbet; pauses are written as empty TextGrid intervals and the
CSVs carry a ``time`` column. It exists so that the demo and the tests run
in seconds; see ``vtl`` for the real reference corpus.

Regenerate (identical for the same seed)::

    dam generate-tiny dam/datasets/data/tiny --overwrite
"""

from __future__ import annotations

import os
import sys

import numpy as np

from dam.corpus.data import SILENCE, Alignment, Corpus, Utterance

CHANNELS = ("lip_aperture", "lip_protrusion", "jaw_open", "tongue_tip")
# phone: (targets per channel, stiffness in 1/s^2 of the tracking system)
PHONES = {
    SILENCE: ((0.10, 0.00, 0.10, 0.20), 150.0),
    "p": ((0.00, 0.20, 0.15, 0.20), 900.0),
    "b": ((0.00, 0.20, 0.15, 0.25), 900.0),
    "m": ((0.00, 0.15, 0.15, 0.25), 800.0),
    "f": ((0.15, 0.00, 0.20, 0.20), 700.0),
    "t": ((0.45, 0.05, 0.25, 1.00), 800.0),
    "d": ((0.45, 0.05, 0.25, 0.95), 800.0),
    "s": ((0.35, 0.00, 0.20, 0.85), 700.0),
    "l": ((0.50, 0.05, 0.30, 0.90), 500.0),
    "k": ((0.50, 0.05, 0.30, 0.20), 600.0),
    "sh": ((0.35, 0.70, 0.20, 0.70), 600.0),
    "aa": ((0.90, 0.10, 0.90, 0.10), 300.0),
    "iy": ((0.50, 0.00, 0.35, 0.60), 300.0),
    "uw": ((0.35, 0.90, 0.35, 0.30), 300.0),
    "eh": ((0.70, 0.05, 0.60, 0.40), 300.0),
    "ao": ((0.75, 0.60, 0.75, 0.15), 300.0),
}
VOWELS = ("aa", "iy", "uw", "eh", "ao")
CONSONANTS = ("p", "b", "m", "f", "t", "d", "s", "l", "k", "sh")
FRAME_RATE = 100.0


def _syllables(rng, n):
    out = []
    for _ in range(n):
        if rng.random() < 0.8:
            out.append((str(rng.choice(CONSONANTS)), rng.uniform(0.05, 0.10)))
        out.append((str(rng.choice(VOWELS)), rng.uniform(0.09, 0.18)))
    return out


def render(labels, starts, ends, frame_rate=FRAME_RATE, substeps=10):
    """Track each phone's targets with a critically damped 2nd-order system."""
    n = int(np.ceil(ends[-1] * frame_rate - 1e-6))
    dt = 1.0 / (frame_rate * substeps)
    y = np.array(PHONES[SILENCE][0])
    v = np.zeros_like(y)
    out = np.empty((n, len(CHANNELS)))
    seg = 0
    for i in range(n):
        for s in range(substeps):
            t = (i * substeps + s) * dt
            while seg < len(labels) - 1 and t >= ends[seg]:
                seg += 1
            # look ahead: the next phone's target pulls during the last 30% of a segment
            target, k = PHONES[labels[seg]]
            target = np.asarray(target)
            frac = (t - starts[seg]) / (ends[seg] - starts[seg])
            if seg + 1 < len(labels) and frac > 0.7:
                w = (frac - 0.7) / 0.3 * 0.5
                target = (1 - w) * target + w * np.asarray(PHONES[labels[seg + 1]][0])
            c = 2.0 * np.sqrt(k)
            if s == 0:
                out[i] = y
            a = k * (target - y) - c * v
            v = v + dt * a
            y = y + dt * v
    return out


def generate(n_utterances=30, seed=0, noise=0.005) -> Corpus:
    """The tiny corpus as a Corpus (deterministic for ``seed``)."""
    rng = np.random.default_rng(seed)
    utts = []
    for k in range(n_utterances):
        labels, starts, ends = [], [], []
        t = rng.uniform(0.15, 0.3)  # leading pause: a gap, written as an empty interval
        for _w in range(int(rng.integers(2, 4))):
            for lab, d in _syllables(rng, int(rng.integers(1, 3))):
                labels.append(lab)
                starts.append(t)
                ends.append(t + d)
                t += d
            if rng.random() < 0.4:
                t += rng.uniform(0.08, 0.2)  # a pause between words
        end = t + rng.uniform(0.15, 0.3)
        a = Alignment(labels, starts, ends, source=f"tiny{k:03d}").with_end(end)
        y = render(a.labels, a.starts, a.ends)
        y = y + noise * rng.standard_normal(y.shape)
        utts.append(Utterance(a, np.round(y, 5), FRAME_RATE, CHANNELS, name=f"tiny{k:03d}"))
    return Corpus(
        utts,
        name="tiny",
        metadata={"generator": "dam.datasets.tiny", "seed": seed, "units": dict.fromkeys(CHANNELS, "a.u.")},
    )  # toy, arbitrary units


def write(directory, *, overwrite: bool = False, seed: int = 0) -> Corpus:
    """Write the tiny corpus to ``directory`` as a whole (:func:`dam.corpus.atomic.atomic_directory`).

    Parameters
    ----------
    directory : path-like
        Must not exist, or be empty; with ``overwrite=True`` an existing
        directory is replaced (never merged with what it held).
    overwrite : bool, default False
    seed : int, default 0

    Returns
    -------
    Corpus
        The corpus written.

    Raises
    ------
    dam.corpus.atomic.OutputPathError
        ``directory`` holds files and ``overwrite`` is False: nothing is written.
    """
    from dam.corpus.atomic import atomic_directory, atomic_write
    from dam.corpus.io import save_corpus

    corpus = generate(seed=seed)
    with atomic_directory(directory, overwrite=overwrite) as tmp:
        save_corpus(corpus, tmp, decimals=5)
        # Pauses as empty intervals, as MFA writes them.
        for name in sorted(os.listdir(tmp)):
            if name.endswith(".TextGrid"):
                path = os.path.join(tmp, name)
                with open(path, encoding="utf-8") as fh:
                    txt = fh.read().replace(f'text = "{SILENCE}"', 'text = ""')
                with atomic_write(path) as fh:
                    fh.write(txt)
    return corpus


def main(argv=None) -> int:
    """``python -m dam.datasets.tiny DIR [--overwrite]`` (also ``dam generate-tiny``)."""
    args = list(sys.argv[1:] if argv is None else argv)
    overwrite = "--overwrite" in args
    rest = [a for a in args if a != "--overwrite"]
    if len(rest) != 1 or rest[0].startswith("-"):
        print("usage: python -m dam.datasets.tiny DIR [--overwrite]", file=sys.stderr)
        return 2
    try:
        corpus = write(rest[0], overwrite=overwrite)
    except ValueError as exc:  # DataError / OutputPathError: one line, no traceback
        print(f"dam: error: {exc}", file=sys.stderr)
        return 1
    print(f"wrote {corpus!r} to {rest[0]}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
