"""VisemeNet (Zhou et al. 2018): audio to phone groups, landmarks and viseme activations (``visemenet``).

The paper's network (Sec. 4, Fig. 3), three LSTM stages:

1. **phone-group stage**: the audio features of a window of frames around the
   current one (past, current and future frames concatenated) go through three
   unidirectional LSTM layers; two fully connected layers (ReLU between)
   decode the top layer into phone-group probabilities (softmax);
2. **landmark stage**: the *same* three LSTM layers (shared, multi-task),
   decoded by two fully connected layers of its own into landmark
   displacements from a neutral face;
3. **viseme stage**: the phone-group activations (before the softmax), the
   landmarks and the current frame's audio features, concatenated, go through
   separate three-layer LSTMs per output type: rig parameter *values*, and
   rig parameter *activations* (probability that a control is active; sigmoid).
   At test time a control takes its predicted value where its activation
   probability is above a threshold chosen per control on held-out data
   (the paper: "dense grid search ... best precision and recall"), else its
   rest value.

Training (Sec. 5): pre-training of stages 1-2 (cross-entropy on phone
groups + L1 on landmarks + L1 on their time derivative), then joint training
of everything with, added, a binary cross-entropy on activations, an L1 on the
values *where the control is active* (Eq. 7) and an L1 on their time
derivative (central differences).

Adapted to this toolkit (what differs from the paper):

* **targets**: the paper's landmarks (2D face landmarks tracked in video) and
  rig values (JALI viseme and co-articulation controls keyed by an animator)
  do not exist in an articulatory corpus. Both the landmark stage and the
  viseme-value stage predict the corpus's own channels (standardized); the
  JALI viseme-field output (JA/LI style parameters) is dropped: nothing in
  the corpus supervises it;
* **activations**: a control is *active* at a frame when it is more than
  ``activation_threshold`` standard deviations away from its rest value (its
  mean over the training corpus's silence frames); JALI's sparse controls are
  active when non-zero, which is the same rule with the rest at 0. Precision
  and recall of activations (the paper's Table 1 measures) come from
  :meth:`VisemeNet.activation_scores`;
* **phone groups**: the paper's 20 JALI viseme groups are English-specific;
  here the groups are the broad articulatory classes of
  :func:`dam.corpus.phone_class` (bilabial, labiodental, ..., front/central/back
  vowel, silence) of the phones seen in training (German SAMPA and ARPAbet
  alike), read from the training alignments; prediction needs no transcript;
* **data**: no separate audiovisual corpus for pre-training: both steps use
  the training corpus (``pretrain_epochs`` then ``max_epochs``);
* **sizes and optimiser**: the paper's LSTMs have 256 units, its loss
  weights and batch sizes are not in our copy of the paper; defaults here are
  64 units, Adam, loss weights 1 (0.1 for the smoothness terms), so that it
  trains in minutes on a CPU. Input: the paper's 65 features (13 MFCC, 26
  mel filterbank, 26 subband centroids: encoder ``"mfcc-mfb-ssc"``).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from dam import Interval

from .base import NeuralSynthesizer
from .rnn import run_recurrent_layer, sequence_windows
from .train import predict_padded

__all__ = ["VisemeNetwork", "VisemeNet", "LOSS_WEIGHTS"]

#: Weights of the multi-task loss terms (ours: the paper's values are not in our copy).
LOSS_WEIGHTS = {
    "phone_group": 1.0,
    "landmark": 1.0,
    "landmark_smooth": 0.1,
    "activation": 1.0,
    "value": 1.0,
    "value_smooth": 0.1,
}


def _lstm_stack(n_in: int, hidden: int, n_layers: int, key) -> list:
    keys = jax.random.split(key, n_layers)
    return [eqx.nn.LSTMCell(n_in if i == 0 else hidden, hidden, key=k) for i, k in enumerate(keys)]


def _run_stack(cells, h, mask, dropout, keys, inference):
    for cell, k in zip(cells, keys):
        h = dropout(run_recurrent_layer(cell, h, mask), key=k, inference=inference)
    return h


class _Head(eqx.Module):
    """Two fully connected layers with a ReLU between (the paper's decoders)."""

    fc1: eqx.nn.Linear
    fc2: eqx.nn.Linear

    def __init__(self, n_in: int, n_hidden: int, n_out: int, *, key):
        k1, k2 = jax.random.split(key)
        self.fc1 = eqx.nn.Linear(n_in, n_hidden, key=k1)
        self.fc2 = eqx.nn.Linear(n_hidden, n_out, key=k2)

    def __call__(self, h):
        return jax.vmap(self.fc2)(jax.nn.relu(jax.vmap(self.fc1)(h)))


class VisemeNetwork(eqx.Module):
    """The three stages on one sequence.

    Called on ``x (length, window * n_features)`` (every frame's feature window,
    the current frame at position ``n_past``) with ``mask (length,)``; returns
    ``(length, n_groups + 3 * n_channels)``: phone-group logits, landmarks
    (channels), activation logits, values (standardized channels).
    """

    shared: list
    group_head: _Head
    landmark_head: _Head
    value_lstm: list
    value_head: _Head
    activation_lstm: list
    activation_head: _Head
    dropout: eqx.nn.Dropout
    n_features: int = eqx.field(static=True)
    n_past: int = eqx.field(static=True)
    n_groups: int = eqx.field(static=True)

    def __init__(
        self,
        n_inputs: int,
        n_outputs: int,
        n_features: int,
        n_past: int,
        n_groups: int,
        hidden_size: int,
        n_layers: int,
        fc_size: int,
        dropout: float,
        *,
        key,
    ):
        n_channels = (n_outputs - n_groups) // 3
        ks = jax.random.split(key, 7)
        self.shared = _lstm_stack(n_inputs, hidden_size, n_layers, ks[0])
        self.group_head = _Head(hidden_size, fc_size, n_groups, key=ks[1])
        self.landmark_head = _Head(hidden_size, fc_size, n_channels, key=ks[2])
        n_vis = n_groups + n_channels + n_features
        self.value_lstm = _lstm_stack(n_vis, hidden_size, n_layers, ks[3])
        self.value_head = _Head(hidden_size, fc_size, n_channels, key=ks[4])
        self.activation_lstm = _lstm_stack(n_vis, hidden_size, n_layers, ks[5])
        self.activation_head = _Head(hidden_size, fc_size, n_channels, key=ks[6])
        self.dropout = eqx.nn.Dropout(dropout)
        self.n_features, self.n_past, self.n_groups = n_features, n_past, n_groups

    def __call__(self, x, mask, *, key=None):
        x = x.astype(jnp.float32)
        mask = mask > 0
        n = len(self.shared) + len(self.value_lstm) + len(self.activation_lstm)
        keys = [None] * n if key is None else list(jax.random.split(key, n))
        off = key is None
        k1, k2, k3 = (
            keys[: len(self.shared)],
            keys[len(self.shared) : -len(self.activation_lstm)],
            keys[-len(self.activation_lstm) :],
        )
        h = _run_stack(self.shared, x, mask, self.dropout, k1, off)
        groups = self.group_head(h)
        landmarks = self.landmark_head(h)
        current = x[:, self.n_past * self.n_features : (self.n_past + 1) * self.n_features]
        v_in = jnp.concatenate([groups, landmarks, current], axis=-1)
        values = self.value_head(_run_stack(self.value_lstm, v_in, mask, self.dropout, k2, off))
        act = self.activation_head(_run_stack(self.activation_lstm, v_in, mask, self.dropout, k3, off))
        return jnp.concatenate([groups, landmarks, act, values], axis=-1)


def _split_output(out, n_groups):
    c = (out.shape[-1] - n_groups) // 3
    g = out[..., :n_groups]
    return g, out[..., n_groups : n_groups + c], out[..., n_groups + c : n_groups + 2 * c], out[..., n_groups + 2 * c :]


def _smooth_l1(z, w):
    """Mean |central difference over time| of ``z (B, L, C)`` where both neighbours are real frames."""
    d = 0.5 * (z[:, 2:] - z[:, :-2])
    ok = w[:, 2:] * w[:, :-2]
    return jnp.sum(jnp.mean(jnp.abs(d), axis=-1) * ok) / jnp.maximum(jnp.sum(ok), 1.0)


def _terms(net, xb, yb, wb, key):
    """Per-batch loss terms of the multi-task objective (Eqs. 1-10, adapted)."""
    if key is None:
        out = jax.vmap(lambda x, m: net(x, m, key=None))(xb, wb)
    else:
        keys = jax.random.split(key, xb.shape[0])
        out = jax.vmap(lambda x, m, k: net(x, m, key=k))(xb, wb, keys)
    groups, landmarks, act, values = _split_output(out, net.n_groups)
    c = landmarks.shape[-1]
    g_true = yb[..., 0].astype(jnp.int32)
    y = yb[..., 1 : 1 + c]
    a = yb[..., 1 + c : 1 + 2 * c]
    total = jnp.maximum(jnp.sum(wb), 1.0)
    ce = -jnp.take_along_axis(jax.nn.log_softmax(groups, axis=-1), g_true[..., None], axis=-1)[..., 0]
    bce = jnp.mean(jax.nn.softplus(act) - a * act, axis=-1)  # binary cross-entropy from logits
    on = a * wb[..., None]
    return {
        "phone_group": jnp.sum(ce * wb) / total,
        "landmark": jnp.sum(jnp.mean(jnp.abs(landmarks - y), axis=-1) * wb) / total,
        "landmark_smooth": _smooth_l1(landmarks, wb),
        "activation": jnp.sum(bce * wb) / total,
        "value": jnp.sum(jnp.abs(values - y) * on) / jnp.maximum(jnp.sum(on), 1.0),
        "value_smooth": _smooth_l1(values, wb),
    }


def pretrain_loss(net, xb, yb, wb, key):
    """Stages 1-2 (Eq. 1): phone groups, landmarks and their smoothness."""
    t = _terms(net, xb, yb, wb, key)
    return sum(LOSS_WEIGHTS[k] * t[k] for k in ("phone_group", "landmark", "landmark_smooth"))


def joint_loss(net, xb, yb, wb, key):
    """All stages (Eq. 5): Eq. 1 plus activations, active values and their smoothness."""
    t = _terms(net, xb, yb, wb, key)
    return sum(LOSS_WEIGHTS[k] * t[k] for k in LOSS_WEIGHTS)


class VisemeNet(NeuralSynthesizer):
    """VisemeNet of Zhou et al. (2018), adapted to articulatory controls (see the module notes).

    Parameters
    ----------
    n_past, n_future : int, default 12, 12
        Frames of audio features before and after the current one that the
        phone-group and landmark stages read (the paper's look-ahead sets its
        120 ms lag).
    hidden_size : int, default 64
        LSTM units (the paper: 256).
    n_layers : int, default 3
        LSTM layers of every stage (the paper: 3).
    fc_size : int, default 64
        Units of the first fully connected layer of every decoder.
    activation_threshold : float, default 0.5
        A control is active where it is this many standard deviations from its rest value.
    pretrain_epochs : int, default 10
        Epochs of stages 1-2 alone before joint training.
    gate : bool, default True
        Controls whose activation probability is below their threshold take
        their rest value (the paper); False outputs the predicted values everywhere.
    seq_len : int, default 100
        Training windows, frames.
    dropout : float, default 0.1
    optimizer : {"adam", "sgd"}, default "adam"
    learning_rate : float, default 3e-3
    batch_size : int, default 32
    max_epochs : int, default 30
        Epochs of joint training.
    patience : int, default 5
    validation_fraction : float, default 0.1
        Also the hold-out set of the activation thresholds (the paper: 10%).
    encoder : str, default "mfcc-mfb-ssc"
        The paper's 65 audio features; any audio encoder works.
    random_state, verbose, unknown_phone
        See :class:`baselines.nn.base.NeuralSynthesizer` (``unknown_phone``
        does not apply: prediction reads no phones).

    Attributes
    ----------
    phone_groups_ : list of str
        The phone groups (articulatory classes) of the training phones.
    rest_ : ndarray, shape (n_channels,)
        Rest value of every control (mean over the training silence frames).
    thresholds_ : ndarray, shape (n_channels,)
        Activation-probability threshold per control.
    """

    name = "visemenet"
    _tags = {"reads": ("audio",)}
    _clip_norm = 1.0
    _parameter_constraints = {
        **dict.fromkeys(["n_past", "n_future", "pretrain_epochs"], [Interval(int, 0, None, closed="left")]),
        **dict.fromkeys(["hidden_size", "n_layers", "fc_size", "seq_len"], [Interval(int, 1, None, closed="left")]),
        "activation_threshold": [Interval(float, 0, None, closed="neither")],
        "gate": ["boolean"],
    }

    def __init__(
        self,
        *,
        n_past: int = 12,
        n_future: int = 12,
        hidden_size: int = 64,
        n_layers: int = 3,
        fc_size: int = 64,
        activation_threshold: float = 0.5,
        pretrain_epochs: int = 10,
        gate: bool = True,
        seq_len: int = 100,
        dropout: float = 0.1,
        optimizer: str = "adam",
        learning_rate: float = 3e-3,
        batch_size: int = 32,
        max_epochs: int = 30,
        patience: int = 5,
        validation_fraction: float = 0.1,
        encoder: str = "mfcc-mfb-ssc",
        random_state: int | None = 0,
        verbose: int = 1,
        unknown_phone: str = "error",
    ):
        self.n_past = n_past
        self.n_future = n_future
        self.hidden_size = hidden_size
        self.n_layers = n_layers
        self.fc_size = fc_size
        self.activation_threshold = activation_threshold
        self.pretrain_epochs = pretrain_epochs
        self.gate = gate
        self.seq_len = seq_len
        self.dropout = dropout
        self.optimizer = optimizer
        self.learning_rate = learning_rate
        self.batch_size = batch_size
        self.max_epochs = max_epochs
        self.patience = patience
        self.validation_fraction = validation_fraction
        self.encoder = encoder
        self.random_state = random_state
        self.verbose = verbose
        self.unknown_phone = unknown_phone

    @classmethod
    def get_test_params(cls) -> list[dict]:
        return [
            {
                "n_past": 3,
                "n_future": 3,
                "hidden_size": 16,
                "n_layers": 1,
                "fc_size": 16,
                "seq_len": 32,
                "dropout": 0.0,
                "pretrain_epochs": 3,
                "max_epochs": 30,
                "learning_rate": 1e-2,
                "batch_size": 16,
                "verbose": 0,
            },
            {
                "n_past": 2,
                "n_future": 1,
                "hidden_size": 8,
                "n_layers": 2,
                "fc_size": 8,
                "seq_len": 32,
                "dropout": 0.0,
                "pretrain_epochs": 2,
                "max_epochs": 25,
                "learning_rate": 1e-2,
                "batch_size": 16,
                "gate": False,
                "encoder": "mfcc",
                "verbose": 0,
            },
        ]

    def _check_param_relations(self) -> None:
        from dam import InvalidParameterError

        if "audio" not in self.reads():
            raise InvalidParameterError(
                f"VisemeNet: parameter 'encoder' is {self.encoder!r}; VisemeNet reads audio: "
                "use an audio encoder ('mfcc-mfb-ssc', 'mfcc', 'fbank' or 'features')"
            )

    # -- data -----------------------------------------------------------------
    def _groups_of(self, alignment) -> np.ndarray:
        from dam.corpus import phone_class

        index = {g: i for i, g in enumerate(self.phone_groups_)}
        groups = [index.get(phone_class(lab) or "other", index.get("other", 0)) for lab in alignment.labels]
        return np.asarray(groups)[alignment.segment_index(self.frame_rate_)]

    def _fit(self, corpus) -> None:
        from dam.corpus import frame_labels, phone_class

        self.phone_groups_ = sorted({phone_class(lab) or "other" for a in corpus.alignments for lab in a.labels})
        sil = np.concatenate(
            [
                u.trajectory[np.asarray(frame_labels(u.alignment, u.frame_rate, u.n_frames)) == u.alignment.silence]
                for u in corpus
            ]
        )
        # No silence at all: the corpus mean is the rest.
        self.rest_ = (sil if len(sil) else np.concatenate(corpus.trajectories)).mean(axis=0)
        super()._fit(corpus)

    def _active(self, y_std: np.ndarray) -> np.ndarray:
        rest = (self.rest_ - self.y_mean_) / self.y_scale_
        return (np.abs(y_std - rest) > self.activation_threshold).astype(np.float32)

    def _inputs(self, encoder, source, n_frames):
        from dam.corpus import window_offsets

        F = encoder.frames(source, self.frame_rate_, n_frames)
        k = int(self.n_past) + 1 + int(self.n_future)
        offsets = window_offsets(k, "causal") + int(self.n_future)  # -n_past .. +n_future
        pos = np.clip(np.arange(n_frames)[:, None] + offsets[None, :], 0, n_frames - 1)
        return F[pos].reshape(n_frames, -1)

    def _samples(self, encoder, utterance, y):
        X = self._inputs(encoder, utterance, utterance.n_frames)
        n = len(X)
        groups = self._groups_of(utterance.alignment)[:n]
        target = np.concatenate([groups[:, None].astype(np.float32), y.astype(np.float32), self._active(y)], axis=1)
        L = int(self.seq_len)
        starts = sequence_windows(n, L)
        Xs = np.zeros((len(starts), L, X.shape[1]), np.float32)
        Ys = np.zeros((len(starts), L, target.shape[1]), np.float32)
        Ws = np.zeros((len(starts), L), np.float32)
        for i, s in enumerate(starts):
            m = min(L, n - s)
            Xs[i, :m], Ys[i, :m], Ws[i, :m] = X[s : s + m], target[s : s + m], 1.0
        return Xs, Ys, Ws

    # -- network and training --------------------------------------------------
    def _network_spec(self, n_inputs, n_outputs):
        n_channels = len(self.channels_)
        n_groups = len(self.phone_groups_)
        k = int(self.n_past) + 1 + int(self.n_future)
        return VisemeNetwork, dict(
            n_inputs=n_inputs,
            n_outputs=n_groups + 3 * n_channels,
            n_features=n_inputs // k,
            n_past=int(self.n_past),
            n_groups=n_groups,
            hidden_size=int(self.hidden_size),
            n_layers=int(self.n_layers),
            fc_size=int(self.fc_size),
            dropout=float(self.dropout),
        )

    def _train(self, net, train, val, key, loss=None, max_epochs=None):
        """Pre-training of stages 1-2, then joint training (Sec. 5)."""
        from .train import TrainHistory

        k1, k2 = jax.random.split(key)
        pre = TrainHistory(initial_loss=float("nan"))
        if self.pretrain_epochs:
            net, pre = super()._train(net, train, val, k1, loss=pretrain_loss, max_epochs=int(self.pretrain_epochs))
        net, hist = super()._train(net, train, val, k2, loss=joint_loss)
        self.pretrain_curve_ = list(pre.loss_curve)
        return net, hist

    def _finish_fit(self, encoder, train, val) -> None:
        """Per-control activation thresholds: the best F1 (precision and recall) on the
        validation utterances (the training ones when there are none), on a grid of 0.05..0.95."""
        probs, truth = [], []
        for u in val or train:
            y = (u.trajectory - self.y_mean_) / self.y_scale_
            probs.append(self._parts(self._net, encoder, u, u.n_frames)[2])
            truth.append(self._active(y))
        P, A = np.concatenate(probs), np.concatenate(truth) > 0
        grid = np.round(np.arange(0.05, 0.96, 0.05), 2)
        best = np.full(P.shape[1], 0.5)
        for c in range(P.shape[1]):
            f1 = [_f1(P[:, c] > t, A[:, c]) for t in grid]
            best[c] = grid[int(np.argmax(f1))]
        self.thresholds_ = best

    # -- prediction ------------------------------------------------------------
    def _parts(self, network, encoder, source, n_frames):
        out = predict_padded(network, self._inputs(encoder, source, n_frames), sequence=True)
        groups, landmarks, act, values = _split_output(out, len(self.phone_groups_))
        return groups, landmarks, 1.0 / (1.0 + np.exp(-act)), values

    def _forward(self, network, encoder, source, n_frames):
        _, _, p, values = self._parts(network, encoder, source, n_frames)
        if not self.gate:
            return values
        rest = (self.rest_ - self.y_mean_) / self.y_scale_
        return np.where(p > self.thresholds_, values, rest)

    def predict_stages(self, source) -> dict:
        """Every stage's output for one utterance with audio (or an AudioClip).

        Returns
        -------
        dict
            ``phone_group_probabilities`` (n_frames, n_groups), ``landmarks``,
            ``values`` (n_frames, n_channels, channel units), ``activation_probabilities``
            and ``active`` (n_frames, n_channels; probability above the threshold).
        """
        from dam.corpus import Utterance

        self._check_fitted()
        n = (source.alignment if isinstance(source, Utterance) else source).n_frames(self.frame_rate_)
        g, lm, p, v = self._parts(self._network(), self._input_encoder(), source, n)
        g = np.exp(g - g.max(axis=1, keepdims=True))
        return {
            "phone_group_probabilities": g / g.sum(axis=1, keepdims=True),
            "landmarks": lm * self.y_scale_ + self.y_mean_,
            "values": v * self.y_scale_ + self.y_mean_,
            "activation_probabilities": p,
            "active": p > self.thresholds_,
        }

    def activation_scores(self, corpus) -> dict:
        """Precision and recall of control activations (Zhou et al.'s Table 1 measures) on ``corpus``.

        Returns
        -------
        dict
            ``precision``, ``recall`` (pooled over controls and frames; NaN when
            nothing is predicted or nothing is active), ``per_channel``
            ``{channel: (precision, recall)}`` and ``phone_group_accuracy``.
        """
        pred, truth, right, total = [], [], 0, 0
        for u in corpus:
            st = self.predict_stages(u)
            pred.append(st["active"])
            truth.append(self._active((u.trajectory - self.y_mean_) / self.y_scale_) > 0)
            g = self._groups_of(u.alignment)[: u.n_frames]
            right += int(np.sum(st["phone_group_probabilities"].argmax(axis=1)[: len(g)] == g))
            total += len(g)
        P, A = np.concatenate(pred), np.concatenate(truth)
        return {
            "precision": _ratio((P & A).sum(), P.sum()),
            "recall": _ratio((P & A).sum(), A.sum()),
            "per_channel": {
                c: (_ratio((P[:, i] & A[:, i]).sum(), P[:, i].sum()), _ratio((P[:, i] & A[:, i]).sum(), A[:, i].sum()))
                for i, c in enumerate(self.channels_)
            },
            "phone_group_accuracy": right / max(total, 1),
        }


def _ratio(a, b) -> float:
    return float(a) / float(b) if b else float("nan")


def _f1(pred: np.ndarray, truth: np.ndarray) -> float:
    tp = float(np.sum(pred & truth))
    return 2 * tp / max(float(pred.sum() + truth.sum()), 1e-12)
