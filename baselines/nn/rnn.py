"""Medina et al. (2022): the recurrent decoders (``gru``; ``cell="lstm"`` for their LSTMs).

Section 4: "LSTM and GRU architectures were evaluated in both unidirectional
(forward in time) and bidirectional configurations ... with 1, 2, and 5
layers, and each of the RNN models output a prediction for each 20 ms input
feature". Here: ``n_layers`` stacked GRU or LSTM layers over the per-frame
encoder features (:mod:`baselines.nn.encoders`), each layer's forward and
(when ``bidirectional``) backward outputs concatenated, dropout between
layers, and a linear layer from the last hidden state to the channels.

Training reads windows of ``seq_len`` frames that tile the utterances (the
paper samples 300 ms windows at random; shuffling the windows every epoch
does the same); synthesis runs over the whole utterance. A unidirectional decoder is causal: its output at
a frame never depends on later frames (the latency of one frame the paper
reports). Padding added for batching is masked: the recurrent state is held
on padded frames, so the backward direction starts at the utterance's last
real frame.

The optional ``dense_size`` input layer (tanh) gives the Fan et al. (2015)
network Taylor et al. (2017) compared with (:mod:`baselines.nn.lstm`).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from dam import Interval, Options

from .base import NeuralSynthesizer
from .train import predict_padded

__all__ = ["RecurrentNet", "RecurrentDecoder", "run_recurrent_layer", "sequence_windows"]

_CELLS = {"gru": eqx.nn.GRUCell, "lstm": eqx.nn.LSTMCell}


def run_recurrent_layer(cell, xs, mask, *, reverse: bool = False):
    """Run ``cell`` over a sequence, holding the state on masked frames.

    The update is that of ``cell`` (equinox's GRUCell or LSTMCell, same
    equations and weights), with the input projection of all frames done in
    one matrix product before the scan: only the recurrent product stays in
    the sequential loop.

    Parameters
    ----------
    cell : equinox.nn.GRUCell or equinox.nn.LSTMCell
    xs : array, shape (length, n_inputs)
    mask : bool array, shape (length,)
        False on padding; the state passes through unchanged there.
    reverse : bool, default False
        Run from the last frame to the first (the backward direction).

    Returns
    -------
    array, shape (length, hidden_size)
        The hidden state after each frame (in the original frame order).
    """
    sig, tanh = jax.nn.sigmoid, jnp.tanh
    proj = xs @ cell.weight_ih.T + cell.bias  # (length, 3 or 4 x hidden)
    zeros = jnp.zeros(cell.hidden_size, proj.dtype)
    if isinstance(cell, eqx.nn.LSTMCell):

        def update(state, p):
            h, c = state
            i, f, g, o = jnp.split(p + cell.weight_hh @ h, 4)
            c = sig(f) * c + sig(i) * tanh(g)
            return sig(o) * tanh(c), c

        init = (zeros, zeros)
    else:

        def update(h, p):
            ir, iz, i_n = jnp.split(p, 3)
            hr, hz, hn = jnp.split(cell.weight_hh @ h, 3)
            reset, inp = sig(ir + hr), sig(iz + hz)
            new = tanh(i_n + reset * (hn + cell.bias_n))
            return new + inp * (h - new)

        init = zeros

    def step(state, p_m):
        p, m = p_m
        state = jax.tree_util.tree_map(lambda a, b: jnp.where(m, a, b), update(state, p), state)
        return state, (state[0] if isinstance(state, tuple) else state)

    _, out = jax.lax.scan(step, init, (proj, mask), reverse=reverse)
    return out


class RecurrentNet(eqx.Module):
    """Optional dense input layer, stacked (bi)directional GRU/LSTM layers, linear output.

    Called on one sequence ``x (length, n_inputs)`` with ``mask (length,)``;
    returns ``(length, n_outputs)``. ``key=None`` switches dropout off.
    """

    dense: eqx.nn.Linear | None
    forward: list
    backward: list
    head: eqx.nn.Linear
    dropout: eqx.nn.Dropout

    def __init__(
        self,
        n_inputs: int,
        n_outputs: int,
        cell: str,
        hidden_size: int,
        n_layers: int,
        bidirectional: bool,
        dense_size: int,
        dropout: float,
        *,
        key,
    ):
        k_dense, k_f, k_b, k_head = jax.random.split(key, 4)
        self.dense = eqx.nn.Linear(n_inputs, dense_size, key=k_dense) if dense_size else None
        width = dense_size or n_inputs
        make = _CELLS[cell]
        self.forward, self.backward = [], []
        for _i, (kf, kb) in enumerate(zip(jax.random.split(k_f, n_layers), jax.random.split(k_b, n_layers))):
            self.forward.append(make(width, hidden_size, key=kf))
            if bidirectional:
                self.backward.append(make(width, hidden_size, key=kb))
            width = hidden_size * (2 if bidirectional else 1)
        self.head = eqx.nn.Linear(width, n_outputs, key=k_head)
        self.dropout = eqx.nn.Dropout(dropout)

    def __call__(self, x, mask, *, key=None):
        h = x.astype(jnp.float32)
        mask = mask > 0
        n = len(self.forward) + 1
        keys = [None] * n if key is None else list(jax.random.split(key, n))
        if self.dense is not None:
            h = self.dropout(jnp.tanh(jax.vmap(self.dense)(h)), key=keys[-1], inference=key is None)
        for i, fwd in enumerate(self.forward):
            out = run_recurrent_layer(fwd, h, mask)
            if self.backward:
                out = jnp.concatenate([out, run_recurrent_layer(self.backward[i], h, mask, reverse=True)], axis=-1)
            h = self.dropout(out, key=keys[i], inference=key is None)
        return jax.vmap(self.head)(h)


def sequence_windows(n_frames: int, length: int) -> np.ndarray:
    """Start frames of training windows of ``length`` frames that tile the
    utterance, the last one ending at its end, shape (n_windows,)."""
    if n_frames <= length:
        return np.array([0])
    starts = np.arange(0, n_frames - length + 1, length)
    if starts[-1] != n_frames - length:
        starts = np.append(starts, n_frames - length)
    return starts


class RecurrentDecoder(NeuralSynthesizer):
    """GRU/LSTM decoder of Medina et al. (2022), uni- or bidirectional, 1 to n layers.

    Parameters
    ----------
    cell : {"gru", "lstm"}, default "gru"
    n_layers : int, default 2
        The paper compares 1, 2 and 5.
    bidirectional : bool, default False
        False: causal (no look-ahead). True: each layer also runs backwards.
    hidden_size : int, default 64
        Units per direction and layer.
    dense_size : int, default 0
        Units of a tanh input layer before the recurrent layers (0: none).
    seq_len : int, default 100
        Length of the training windows, frames.
    dropout : float, default 0.25
    optimizer : {"adam", "sgd"}, default "adam"
    learning_rate : float, default 3e-3
    batch_size : int, default 32
        Windows per mini-batch.
    max_epochs : int, default 40
        The paper trains for 40 epochs.
    patience : int, default 5
    validation_fraction : float, default 0.1
    encoder, random_state, verbose, unknown_phone
        See :class:`baselines.nn.base.NeuralSynthesizer`.

    Notes
    -----
    Gradients are clipped to a global norm of 1 (recurrent networks).
    """

    name = "gru"
    _clip_norm = 1.0
    _parameter_constraints = {
        "cell": [Options(_CELLS)],
        **dict.fromkeys(["n_layers", "hidden_size", "seq_len"], [Interval(int, 1, None, closed="left")]),
        "dense_size": [Interval(int, 0, None, closed="left")],
        "bidirectional": ["boolean"],
    }

    def __init__(
        self,
        *,
        cell: str = "gru",
        n_layers: int = 2,
        bidirectional: bool = False,
        hidden_size: int = 64,
        dense_size: int = 0,
        seq_len: int = 100,
        dropout: float = 0.25,
        optimizer: str = "adam",
        learning_rate: float = 3e-3,
        batch_size: int = 32,
        max_epochs: int = 40,
        patience: int = 5,
        validation_fraction: float = 0.1,
        encoder: str = "phones",
        random_state: int | None = 0,
        verbose: int = 1,
        unknown_phone: str = "error",
    ):
        self.cell = cell
        self.n_layers = n_layers
        self.bidirectional = bidirectional
        self.hidden_size = hidden_size
        self.dense_size = dense_size
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
                "n_layers": 1,
                "hidden_size": 16,
                "seq_len": 32,
                "dropout": 0.0,
                "max_epochs": 25,
                "learning_rate": 1e-2,
                "batch_size": 16,
                "verbose": 0,
            },
            {
                "cell": "lstm",
                "n_layers": 2,
                "bidirectional": True,
                "hidden_size": 8,
                "seq_len": 16,
                "max_epochs": 2,
                "verbose": 0,
            },
        ]

    def _network_spec(self, n_inputs, n_outputs):
        return RecurrentNet, dict(
            n_inputs=n_inputs,
            n_outputs=n_outputs,
            cell=self.cell,
            hidden_size=int(self.hidden_size),
            n_layers=int(self.n_layers),
            bidirectional=bool(self.bidirectional),
            dense_size=int(self.dense_size),
            dropout=float(self.dropout),
        )

    def _samples(self, encoder, utterance, y):
        frames = encoder.frames(utterance, self.frame_rate_, utterance.n_frames)
        L, n = int(self.seq_len), len(frames)
        starts = sequence_windows(n, L)
        X = np.zeros((len(starts), L, frames.shape[1]), frames.dtype)
        Y = np.zeros((len(starts), L, y.shape[1]), np.float32)
        W = np.zeros((len(starts), L), np.float32)
        for i, s in enumerate(starts):
            m = min(L, n - s)
            X[i, :m], Y[i, :m], W[i, :m] = frames[s : s + m], y[s : s + m], 1.0
        return X, Y, W

    def _forward(self, network, encoder, alignment, n_frames):
        frames = encoder.frames(alignment, self.frame_rate_, n_frames)
        return predict_padded(network, frames, sequence=True)
