"""Phone durations from context: the model that turns text into timed phones.

A log-linear model (as in Klatt's multiplicative duration rules and the
sum-of-products models of van Santen, reduced to its first-order terms): the
log duration of a phone is a sum of effects of

* its identity,
* the broad class of its left and right neighbours (silence counts),
* its position in the word (initial, medial, final, a one-phone word,
  unknown when no word boundaries are given),
* its position in the phrase (in the last word before a pause or the end,
  phrase-final lengthening; phrase-initial),
* lexical stress (ARPAbet digits 0/1/2; none for phone sets without stress),
* a vowel in the phrase-final word (lengthening falls mostly on the rhyme).

Fitted by ridge regression on log durations (closed form), with the
log-normal mean correction ``exp(sigma^2 / 2)`` so predictions are means in
seconds. ``rate`` divides every duration (``rate=1.2``: 20% faster speech).
Saved in the toolkit's model-file format (``dam.modelfile``), numpy only.
"""

from __future__ import annotations

import re

import numpy as np

from dam.corpus import SILENCE, Alignment, Corpus, DataError
from dam.corpus.phonetics import base_phone, guess_alphabet, phone_class

__all__ = ["DurationModel", "context_features", "phone_mean_baseline"]

_STRESS = re.compile(r"([012])$")


def _stress(label: str) -> str:
    m = _STRESS.search(label) if len(label) > 1 else None
    return m.group(1) if m else "none"


def _cls(label: str, silence: str, alphabet: str | None) -> str:
    if label == silence:
        return "silence"
    return phone_class(label, alphabet) or "other"


def context_features(labels, word_ids=None, *, silence: str = SILENCE, alphabet: str | None = None) -> list[list[str]]:
    """The categorical features of each phone of an utterance.

    Parameters
    ----------
    labels : sequence of str, length n
        Phones (ARPAbet stress digits are read as stress) and silences.
    word_ids : sequence of int, length n, optional
        The word each phone belongs to (any integers, equal within a word;
        ignored for silences). Without them, word position is ``unknown``.
    silence : str, default "sil"
    alphabet : {"arpabet", "sampa"}, optional
        How to read upper-case symbols for the neighbour classes (ARPAbet
        ``T`` is /t/, SAMPA ``T`` is /θ/); guessed from ``labels`` if omitted.

    Returns
    -------
    list of list of str, length n
        ``"name=value"`` strings, the one-hot feature names of each phone.

    Examples
    --------
    >>> from dam.speech import context_features
    >>> context_features(["sil", "K", "AE1", "T", "sil"], [0, 1, 1, 1, 2])[2]
    ['phone=AE', 'left=velar', 'right=alveolar', 'word=medial', 'phrase=final_word', 'stress=1', 'final_vowel=1']
    """
    labels = list(labels)
    n = len(labels)
    if alphabet is None:
        alphabet = guess_alphabet(labels)
    if word_ids is not None and len(word_ids) != n:
        raise ValueError(f"word_ids has {len(word_ids)} entries for {n} phones")
    feats: list[list[str]] = []
    # the phrase-final word: the last word before a silence or the end
    final_word = [False] * n
    initial_word = [False] * n
    i = 0
    while i < n:
        if labels[i] == silence:
            i += 1
            continue
        j = i
        while j < n and labels[j] != silence:
            j += 1
        # phones i..j-1 form a phrase
        if word_ids is not None:
            last, first = word_ids[j - 1], word_ids[i]
            for k in range(i, j):
                final_word[k] = word_ids[k] == last
                initial_word[k] = word_ids[k] == first
        else:
            final_word[j - 1] = True
            initial_word[i] = True
        i = j
    for k, lab in enumerate(labels):
        left = _cls(labels[k - 1], silence, alphabet) if k > 0 else "silence"
        right = _cls(labels[k + 1], silence, alphabet) if k < n - 1 else "silence"
        if lab == silence:
            pos = "initial" if k == 0 else "final" if k == n - 1 else "medial"
            feats.append([f"phone={silence}", f"pause={pos}"])
            continue
        if word_ids is None:
            wpos = "unknown"
        else:
            w = word_ids[k]
            first = k == 0 or labels[k - 1] == silence or word_ids[k - 1] != w
            last = k == n - 1 or labels[k + 1] == silence or word_ids[k + 1] != w
            wpos = "single" if first and last else "initial" if first else "final" if last else "medial"
        ph = base_phone(lab)
        f = [
            f"phone={ph}",
            f"left={left}",
            f"right={right}",
            f"word={wpos}",
            "phrase=final_word" if final_word[k] else "phrase=initial_word" if initial_word[k] else "phrase=medial",
            f"stress={_stress(lab)}",
        ]
        if final_word[k] and _cls(lab, silence, alphabet).endswith("vowel"):
            f.append("final_vowel=1")
        feats.append(f)
    return feats


def _examples(data, word_ids, silence):
    """(labels, word_ids or None, durations) per utterance, from the accepted inputs."""
    if isinstance(data, Corpus):
        aligns = list(data.alignments)
    elif isinstance(data, Alignment):
        aligns = [data]
    else:
        aligns = list(data)
    if word_ids is not None and len(word_ids) != len(aligns):
        raise ValueError(f"word_ids has {len(word_ids)} entries for {len(aligns)} alignments")
    out = []
    for i, a in enumerate(aligns):
        if not isinstance(a, Alignment):
            raise TypeError(f"expected dam.Alignment objects, got {type(a).__name__}")
        wid = None if word_ids is None else word_ids[i]  # None: this utterance has no word boundaries
        out.append((list(a.labels), wid, a.ends - a.starts, a.silence))
    return out


class DurationModel:
    """Context-dependent phone durations (log-linear, ridge), with a speaking-rate factor.

    Parameters
    ----------
    alpha : float, default 1.0
        Ridge penalty on the feature weights (not on the intercept).
    min_count : int, default 2
        Feature values seen fewer times in training are dropped (they fall
        back to the intercept).

    Attributes
    ----------
    alphabet_ : str
        ``"arpabet"`` or ``"sampa"``: how the training phones were read.
    features_ : list of str
        The one-hot feature names, in coefficient order.
    coef_ : ndarray, shape (n_features,)
        Effects on log duration: ``exp(coef)`` is the factor.
    intercept_ : float
    sigma2_ : float
        Residual variance of log durations (the log-normal mean correction).
    phone_means_ : dict of str to float
        Mean duration per phone in seconds (the baseline, and the
        fallback's reference).

    Examples
    --------
    >>> from dam.speech import DurationModel
    >>> model = DurationModel().fit(dam.datasets.load("tiny"))
    >>> durations = model.predict(["sil", "a", "b", "a", "sil"])
    >>> durations.shape
    (5,)
    """

    name = "duration"

    def __init__(self, *, alpha: float = 1.0, min_count: int = 2):
        self.alpha = alpha
        self.min_count = min_count

    def get_params(self, deep: bool = True) -> dict:
        return {"alpha": self.alpha, "min_count": self.min_count}

    def fit(self, data, word_ids=None) -> DurationModel:
        """Fit on aligned speech.

        Parameters
        ----------
        data : Corpus, Alignment or list of Alignment
        word_ids : list of (int sequence or None), optional
            Per alignment, the word index of every segment (see
            :func:`context_features`); None for an alignment without words.

        Returns
        -------
        self
        """
        if not (np.isfinite(self.alpha) and self.alpha >= 0):
            raise ValueError(f"DurationModel: parameter 'alpha' is {self.alpha!r}; use a number >= 0")
        rows, y, phones = [], [], []
        examples = _examples(data, word_ids, SILENCE)
        alphabet = guess_alphabet({lab for labels, _, _, _ in examples for lab in labels})
        for labels, wid, dur, silence in examples:
            for f, d in zip(context_features(labels, wid, silence=silence, alphabet=alphabet), dur):
                rows.append(f)
                y.append(np.log(d))
                phones.append(f[0][len("phone=") :])
        if not rows:
            raise DataError(None, "data", 0, "no phones to fit durations on")
        counts: dict[str, int] = {}
        for f in rows:
            for name in f:
                counts[name] = counts.get(name, 0) + 1
        vocab = sorted(k for k, c in counts.items() if c >= self.min_count)
        index = {k: i for i, k in enumerate(vocab)}
        X = np.zeros((len(rows), len(vocab)))
        for r, f in enumerate(rows):
            for name in f:
                if name in index:
                    X[r, index[name]] = 1.0
        y = np.asarray(y)
        mean_y, mean_x = y.mean(), X.mean(axis=0)
        Xc = X - mean_x
        A = Xc.T @ Xc + self.alpha * np.eye(len(vocab))
        coef = np.linalg.solve(A, Xc.T @ (y - mean_y))
        resid = y - mean_y - Xc @ coef
        self.alphabet_ = alphabet
        self.features_ = vocab
        self.coef_ = coef
        self.intercept_ = float(mean_y - mean_x @ coef)
        self.sigma2_ = float(resid.var())
        sums: dict[str, list[float]] = {}
        for p, v in zip(phones, np.exp(y)):
            sums.setdefault(p, []).append(float(v))
        self.phone_means_ = {p: float(np.mean(v)) for p, v in sorted(sums.items())}
        return self

    def _check_fitted(self):
        if not hasattr(self, "coef_"):
            from dam.base import NotFittedError

            raise NotFittedError("this DurationModel is not fitted yet; call fit(corpus) first")

    def effect(self, feature: str) -> float:
        """The multiplicative effect ``exp(coef)`` of one feature (1.0 if unknown)."""
        self._check_fitted()
        return float(np.exp(self.coef_[self.features_.index(feature)])) if feature in self.features_ else 1.0

    def predict(self, labels, word_ids=None, *, rate: float = 1.0, silence: str = SILENCE) -> np.ndarray:
        """Durations in seconds for a phone sequence.

        Parameters
        ----------
        labels : sequence of str, length n
        word_ids : sequence of int, length n, optional
        rate : float, default 1.0
            Speaking-rate factor: every duration is divided by it.
        silence : str, default "sil"

        Returns
        -------
        ndarray of float, shape (n,)
            Positive and finite.
        """
        self._check_fitted()
        if not (np.isfinite(rate) and rate > 0):
            raise ValueError(f"rate is {rate!r}; use a positive number (1.0 = the training speed)")
        index = {k: i for i, k in enumerate(self.features_)}
        out = np.empty(len(labels))
        for r, f in enumerate(context_features(labels, word_ids, silence=silence, alphabet=self.alphabet_)):
            out[r] = self.intercept_ + sum(self.coef_[index[name]] for name in f if name in index)
        return np.exp(out + self.sigma2_ / 2) / rate

    def predict_alignment(
        self, labels, word_ids=None, *, rate: float = 1.0, start: float = 0.0, silence: str = SILENCE, source=None
    ) -> Alignment:
        """An :class:`~dam.Alignment` with predicted durations, starting at ``start`` seconds."""
        d = self.predict(labels, word_ids, rate=rate, silence=silence)
        ends = start + np.cumsum(d)
        return Alignment(list(labels), ends - d, ends, source=source, silence=silence)

    # -- the model file format ----------------------------------------------
    def _get_state(self) -> dict:
        return {
            "alphabet_": self.alphabet_,
            "features_": list(self.features_),
            "coef_": np.asarray(self.coef_),
            "intercept_": self.intercept_,
            "sigma2_": self.sigma2_,
            "phone_means_": dict(self.phone_means_),
        }

    def _set_state(self, state: dict) -> None:
        for k, v in state.items():
            setattr(self, k, v)

    def save(self, path) -> None:
        """Write the fitted model (npz + JSON, see :mod:`dam.modelfile`); atomic."""
        from dam.modelfile import write_model_file

        self._check_fitted()
        write_model_file(self, path)  # atomic (dam.corpus.atomic)

    @classmethod
    def load(cls, path) -> DurationModel:
        """Read a model written by :meth:`save` (numpy only).

        Raises
        ------
        ModelFileError
            Missing, corrupt or foreign file, or a model that is not a duration model.
        """
        from dam.modelfile import ModelFileError, _decode, check_state, read_model_file

        meta, arrays = read_model_file(path)
        if meta["model"] != cls.name:
            raise ModelFileError(
                f"{path}: field 'model' is {meta['model']!r}, expected {cls.name!r} (a duration model)"
            )
        try:
            state = _decode(meta["state"], arrays)
            check_state(cls, state, path)  # learned-attribute names only (dam.modelfile)
            model = cls(**_decode(meta["params"], arrays))
            model._set_state(state)
            model.coef_ = np.asarray(model.coef_, dtype=float)
            if model.coef_.shape != (len(model.features_),):
                raise ValueError("coef_ and features_ differ in length")
        except (KeyError, TypeError, ValueError) as exc:
            raise ModelFileError(f"{path}: the stored duration model is damaged ({exc})") from None
        return model


def phone_mean_baseline(train, test) -> np.ndarray:
    """Predicted durations of every segment of ``test``: the mean duration of its phone in ``train``.

    Unseen phones get the overall mean. Returns shape (n_test_segments,) in seconds.
    """
    sums: dict[str, list[float]] = {}
    for labels, _, dur, _ in _examples(train, None, SILENCE):
        for lab, d in zip(labels, dur):
            sums.setdefault(base_phone(lab), []).append(float(d))
    means = {p: float(np.mean(v)) for p, v in sums.items()}
    overall = float(np.mean([d for v in sums.values() for d in v]))
    return np.array(
        [means.get(base_phone(lab), overall) for labels, _, _, _ in _examples(test, None, SILENCE) for lab in labels]
    )
