"""Accuracy metrics: RMSE and Pearson correlation, overall, per channel and per utterance.

RMSE is in channel units. Correlations are computed per channel over all
frames of the corpus pooled (the usual convention for EMA and rig channels);
a channel that is constant in the truth or the prediction has no correlation
and reports NaN there (never in the RMSE).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["rmse", "rmse_per_channel", "pearson_per_channel", "Evaluation", "evaluate"]


def _check(y_true, y_pred, where="") -> tuple[np.ndarray, np.ndarray]:
    a = np.asarray(y_true, dtype=float)
    b = np.asarray(y_pred, dtype=float)
    if a.shape != b.shape:
        raise ValueError(f"{where}shape mismatch: truth {a.shape} vs prediction {b.shape}")
    if a.ndim == 1:
        a, b = a[:, None], b[:, None]
    return a, b


def rmse(y_true, y_pred) -> float:
    """Root mean squared error over all frames and channels."""
    a, b = _check(y_true, y_pred)
    return float(np.sqrt(np.mean((a - b) ** 2)))


def rmse_per_channel(y_true, y_pred) -> np.ndarray:
    """RMSE of each channel, shape (n_channels,)."""
    a, b = _check(y_true, y_pred)
    return np.sqrt(np.mean((a - b) ** 2, axis=0))


def pearson_per_channel(y_true, y_pred) -> np.ndarray:
    """Pearson r of each channel, shape (n_channels,); NaN for a constant channel."""
    a, b = _check(y_true, y_pred)
    a = a - a.mean(axis=0)
    b = b - b.mean(axis=0)
    den = np.sqrt((a * a).sum(axis=0) * (b * b).sum(axis=0))
    with np.errstate(invalid="ignore", divide="ignore"):
        r = (a * b).sum(axis=0) / den
    return np.where(den > 1e-12, r, np.nan)


@dataclass
class Evaluation:
    """Scores of one model on one corpus.

    Attributes
    ----------
    rmse : float
        Over all frames and channels.
    rmse_per_channel, pearson_per_channel : ndarray, shape (n_channels,)
    pearson_r : float
        Mean of the per-channel correlations (NaN channels ignored).
    per_utterance : list of dict
        ``{"utterance", "n_frames", "rmse", "pearson_r"}`` for each utterance.
    channels : list of str
    """

    rmse: float
    rmse_per_channel: np.ndarray
    pearson_per_channel: np.ndarray
    pearson_r: float
    per_utterance: list = field(default_factory=list)
    channels: list = field(default_factory=list)

    def table(self) -> str:
        """A plain-text per-channel table."""
        w = max([7] + [len(c) for c in self.channels])
        lines = [f"{'channel':<{w}}  {'rmse':>10}  {'r':>7}"]
        for c, e, r in zip(self.channels, self.rmse_per_channel, self.pearson_per_channel):
            lines.append(f"{c:<{w}}  {e:>10.4g}  {r:>7.3f}")
        lines.append(f"{'overall':<{w}}  {self.rmse:>10.4g}  {self.pearson_r:>7.3f}")
        return "\n".join(lines)


def evaluate(model, corpus, predictions=None) -> Evaluation:
    """Score ``model`` on every utterance of ``corpus``.

    Parameters
    ----------
    model : fitted Synthesizer (ignored when ``predictions`` is given)
    corpus : Corpus
    predictions : list of ndarray, optional
        Precomputed predictions, one per utterance.
    """
    if predictions is None:
        if tuple(model.channels_) != tuple(corpus.channels):
            raise ValueError(f"{corpus.source or '<corpus>'}: field 'channels': the corpus has "
                             f"{list(corpus.channels)} but the model was trained on {list(model.channels_)}")
        if abs(model.frame_rate_ - corpus.frame_rate) > 1e-9:
            raise ValueError(f"{corpus.source or '<corpus>'}: field 'frame_rate': the corpus has "
                             f"{corpus.frame_rate:g} but the model was trained at {model.frame_rate_:g}")
        predictions = model.predict(corpus.alignments)
    truth = corpus.trajectories
    per_utt = []
    for u, y, p in zip(corpus, truth, predictions):
        a, b = _check(y, p, f"{u.name}: ")
        r = pearson_per_channel(a, b)
        per_utt.append({"utterance": u.name, "n_frames": len(a), "rmse": rmse(a, b),
                        "pearson_r": float(np.nanmean(r)) if np.isfinite(r).any() else float("nan")})
    Y = np.concatenate(truth)
    P = np.concatenate([np.asarray(p, dtype=float) for p in predictions])
    r = pearson_per_channel(Y, P)
    return Evaluation(rmse=rmse(Y, P), rmse_per_channel=rmse_per_channel(Y, P), pearson_per_channel=r,
                      pearson_r=float(np.nanmean(r)) if np.isfinite(r).any() else float("nan"),
                      per_utterance=per_utt, channels=list(corpus.channels))
