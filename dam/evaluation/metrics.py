"""Accuracy metrics: RMSE, Pearson correlation and Medina et al.'s sensor error.

RMSE is in channel units. Correlations are computed per channel over all
frames of the corpus pooled (the usual convention for EMA and rig channels);
a channel that is constant in the truth or the prediction has no correlation
and reports NaN there (never in the RMSE).

**Sensor error** (Medina et al. 2022, Eq. 1): for EMA-like corpora whose
channels form sensors (``Corpus.sensors``), the Euclidean distance between
predicted and true sensor position, averaged over the sensors and frames of
an utterance (``e_sample``); overall it is the mean of ``e_sample`` over the
utterances, as the paper reports it, and per sensor the mean distance over
all frames. It is in the corpus's length unit (``metadata["length_unit"]``,
millimetres for the corpora of :mod:`dam.corpus.formats`).

**Missing data.** Every metric skips what ``Utterance.mask`` marks as not
observed: RMSE and r use only observed values, a sensor distance only frames
where all the sensor's channels are observed.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = [
    "rmse",
    "rmse_per_channel",
    "pearson_per_channel",
    "sensor_distances",
    "medina_error",
    "Evaluation",
    "evaluate",
]


def _check(y_true, y_pred, where="", mask=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Truth, prediction and observed-mask as 2-D float/bool arrays of one shape."""
    a = np.asarray(y_true, dtype=float)
    b = np.asarray(y_pred, dtype=float)
    if a.shape != b.shape:
        raise ValueError(f"{where}shape mismatch: truth {a.shape} vs prediction {b.shape}")
    if a.ndim == 1:
        a, b = a[:, None], b[:, None]
    m = np.ones(a.shape, bool) if mask is None else np.asarray(mask, dtype=bool).reshape(a.shape)
    return a, b, m


def rmse(y_true, y_pred, mask=None) -> float:
    """Root mean squared error over all (observed) frames and channels.

    Parameters
    ----------
    y_true, y_pred : array-like, shape (n_frames, n_channels)
    mask : array-like of bool, same shape, optional
        True where the truth was observed (default: everywhere).
    """
    a, b, m = _check(y_true, y_pred, mask=mask)
    return float(np.sqrt(np.sum(((a - b) ** 2)[m]) / max(m.sum(), 1)))


def rmse_per_channel(y_true, y_pred, mask=None) -> np.ndarray:
    """RMSE of each channel over its observed frames, shape (n_channels,); NaN for a channel never observed."""
    a, b, m = _check(y_true, y_pred, mask=mask)
    n = m.sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(n > 0, np.sqrt(np.where(m, (a - b) ** 2, 0.0).sum(axis=0) / n), np.nan)


def pearson_per_channel(y_true, y_pred, mask=None) -> np.ndarray:
    """Pearson r of each channel over its observed frames, shape (n_channels,); NaN for a constant channel."""
    a, b, m = _check(y_true, y_pred, mask=mask)
    n = np.maximum(m.sum(axis=0), 1)
    a = np.where(m, a - np.where(m, a, 0.0).sum(axis=0) / n, 0.0)
    b = np.where(m, b - np.where(m, b, 0.0).sum(axis=0) / n, 0.0)
    den = np.sqrt((a * a).sum(axis=0) * (b * b).sum(axis=0))
    with np.errstate(invalid="ignore", divide="ignore"):
        r = (a * b).sum(axis=0) / den
    return np.where(den > 1e-12, r, np.nan)


def sensor_distances(y_true, y_pred, sensor_columns, mask=None) -> tuple[np.ndarray, np.ndarray]:
    """Euclidean distance of every sensor at every frame.

    Parameters
    ----------
    y_true, y_pred : array-like, shape (n_frames, n_channels)
    sensor_columns : sequence of sequence of int
        The column indices (2 or 3) of each sensor.
    mask : array-like of bool, shape (n_frames, n_channels), optional

    Returns
    -------
    distances : ndarray, shape (n_frames, n_sensors)
        ``||y_pred[s, cols] - y_true[s, cols]||_2``.
    valid : ndarray of bool, shape (n_frames, n_sensors)
        True where all of the sensor's channels are observed.
    """
    a, b, m = _check(y_true, y_pred, mask=mask)
    d = (
        np.stack([np.sqrt(((a[:, c] - b[:, c]) ** 2).sum(axis=1)) for c in map(list, sensor_columns)], axis=1)
        if len(sensor_columns)
        else np.zeros((len(a), 0))
    )
    valid = (
        np.stack([m[:, list(c)].all(axis=1) for c in sensor_columns], axis=1)
        if len(sensor_columns)
        else np.zeros((len(a), 0), bool)
    )
    return d, valid


def medina_error(y_true, y_pred, sensor_columns, mask=None) -> float:
    """Medina et al. (2022) Eq. 1 for one utterance: mean Euclidean sensor distance over sensors and frames.

    ``e = 1/S sum_s 1/L sum_l ||y_hat[s, l] - y[s, l]||_2``; with a mask, the
    mean over the (frame, sensor) pairs whose channels are all observed.
    NaN when no sensor is observed at any frame.

    Examples
    --------
    >>> medina_error([[0.0, 0.0, 1.0]], [[3.0, 4.0, 1.0]], [[0, 1]])
    5.0
    """
    d, valid = sensor_distances(y_true, y_pred, sensor_columns, mask)
    return float(d[valid].mean()) if valid.any() else float("nan")


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
        ``{"utterance", "n_frames", "rmse", "pearson_r"}`` for each utterance
        (and ``"sensor_error"``, Eq. 1 of Medina et al., when there are sensors).
    channels : list of str
    sensors : dict of str to tuple of str
        The corpus's sensors (empty when its channels form none).
    sensor_error : float
        Medina et al.'s Eq. 1 averaged over the utterances; NaN without sensors.
    sensor_error_per_sensor : ndarray, shape (n_sensors,)
        Mean Euclidean distance of each sensor over all (observed) frames.
    length_unit : str or None
        Unit of the sensor error (``Corpus.metadata["length_unit"]``).
    """

    rmse: float
    rmse_per_channel: np.ndarray
    pearson_per_channel: np.ndarray
    pearson_r: float
    per_utterance: list = field(default_factory=list)
    channels: list = field(default_factory=list)
    sensors: dict = field(default_factory=dict)
    sensor_error: float = float("nan")
    sensor_error_per_sensor: np.ndarray = field(default_factory=lambda: np.zeros(0))
    length_unit: str | None = None

    def table(self) -> str:
        """A plain-text per-channel table."""
        w = max([7] + [len(c) for c in self.channels])
        lines = [f"{'channel':<{w}}  {'rmse':>10}  {'r':>7}"]
        for c, e, r in zip(self.channels, self.rmse_per_channel, self.pearson_per_channel):
            lines.append(f"{c:<{w}}  {e:>10.4g}  {r:>7.3f}")
        lines.append(f"{'overall':<{w}}  {self.rmse:>10.4g}  {self.pearson_r:>7.3f}")
        if self.sensors:
            unit = f" ({self.length_unit})" if self.length_unit else ""
            ws = max([7] + [len(s) for s in self.sensors])
            lines += ["", f"{'sensor':<{ws}}  {'distance' + unit:>14}  channels"]
            for (s, chans), e in zip(self.sensors.items(), self.sensor_error_per_sensor):
                lines.append(f"{s:<{ws}}  {e:>14.4g}  {' '.join(chans)}")
            lines.append(
                f"{'overall':<{ws}}  {self.sensor_error:>14.4g}  "
                "(Medina et al. 2022, Eq. 1: mean Euclidean distance per sensor and frame)"
            )
        return "\n".join(lines)


def evaluate(model, corpus, predictions=None) -> Evaluation:
    """Score ``model`` on every utterance of ``corpus``.

    Parameters
    ----------
    model : fitted Synthesizer (ignored when ``predictions`` is given)
    corpus : Corpus
    predictions : list of ndarray, optional
        Precomputed predictions, one per utterance.

    Examples
    --------
    >>> import dam
    >>> train, test = dam.datasets.load("tiny").train_test_split(0.25, random_state=0)
    >>> ev = dam.evaluate(dam.make("phone-mean").fit(train), test)
    >>> 0 < ev.rmse < 1, len(ev.rmse_per_channel)
    (True, 4)
    """
    if predictions is None:
        if tuple(model.channels_) != tuple(corpus.channels):
            raise ValueError(
                f"{corpus.source or '<corpus>'}: field 'channels': the corpus has "
                f"{list(corpus.channels)} but the model was trained on {list(model.channels_)}"
            )
        if abs(model.frame_rate_ - corpus.frame_rate) > 1e-9:
            raise ValueError(
                f"{corpus.source or '<corpus>'}: field 'frame_rate': the corpus has "
                f"{corpus.frame_rate:g} but the model was trained at {model.frame_rate_:g}"
            )
        # duck-typed (a Synthesizer's predict_inputs): metrics sits below the interface
        inputs = model.predict_inputs(corpus) if hasattr(model, "predict_inputs") else corpus.alignments
        predictions = model.predict(inputs)
    sensors = corpus.sensors
    names = list(corpus.channels)
    cols = [[names.index(c) for c in chans] for chans in sensors.values()]
    per_utt, dists, valids = [], [], []
    for u, p in zip(corpus, predictions):
        a, b, m = _check(u.trajectory, p, f"{u.name}: ", mask=u.mask)
        r = pearson_per_channel(a, b, m)
        row = {
            "utterance": u.name,
            "n_frames": len(a),
            "rmse": rmse(a, b, m),
            "pearson_r": float(np.nanmean(r)) if np.isfinite(r).any() else float("nan"),
        }
        if cols:
            d, valid = sensor_distances(a, b, cols, m)
            dists.append(d)
            valids.append(valid)
            row["sensor_error"] = float(d[valid].mean()) if valid.any() else float("nan")
        per_utt.append(row)
    Y = np.concatenate(corpus.trajectories)
    P = np.concatenate([np.asarray(p, dtype=float) for p in predictions])
    M = np.concatenate([np.ones(u.trajectory.shape, bool) if u.mask is None else u.mask for u in corpus])
    r = pearson_per_channel(Y, P, M)
    extra = {}
    if cols:
        D, V = np.concatenate(dists), np.concatenate(valids)
        with np.errstate(invalid="ignore", divide="ignore"):
            per_sensor = np.where(V, D, 0.0).sum(axis=0) / V.sum(axis=0)
        utt = [row["sensor_error"] for row in per_utt if np.isfinite(row["sensor_error"])]
        extra = {
            "sensors": dict(sensors),
            "sensor_error_per_sensor": per_sensor,
            "sensor_error": float(np.mean(utt)) if utt else float("nan"),
        }
    return Evaluation(
        rmse=rmse(Y, P, M),
        rmse_per_channel=rmse_per_channel(Y, P, M),
        pearson_per_channel=r,
        pearson_r=float(np.nanmean(r)) if np.isfinite(r).any() else float("nan"),
        per_utterance=per_utt,
        channels=list(corpus.channels),
        length_unit=corpus.metadata.get("length_unit"),
        **extra,
    )
