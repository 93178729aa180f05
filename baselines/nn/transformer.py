"""Medina et al. (2022): the Transformer decoder over overlapping windows (``transformer``).

Section 4: "Our Transformer model follows [Dosovitskiy et al.; Zheng et al.]
by neglecting the decoder layers and using only stacked encoder layers with
Multi-head Self-Attention (MSA) ... trained to predict the 3D landmark
positions by projecting the last Transformer encoder layer into the output
space through a final linear layer. Finally, we calculate the mean of the
output of overlapping sliding predictions similar to our MLP
configuration." Their best setup has 4 encoder layers with 8 heads.

Here: every frame's window of ``window`` frames (centred) of per-frame
encoder features is embedded linearly, a learned position embedding is
added, 4 pre-norm encoder layers (8-head self-attention, GELU feed-forward,
dropout) follow, and a linear layer maps every token to the channels; the
overlapping window predictions are averaged frame by frame
(:func:`dam.features.overlap_average`). Training uses every ``window_hop``-th
window (neighbouring windows overlap almost completely) and Adam with the
squared loss (the paper's L1 warm-up and 5e-8 learning rate are for its
much larger model).
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from dam import Interval, InvalidParameterError

from .base import NeuralSynthesizer
from .train import predict_padded

__all__ = ["EncoderLayer", "WindowTransformer", "TransformerDecoder"]


class EncoderLayer(eqx.Module):
    """Pre-norm Transformer encoder layer: x + MSA(LN(x)), then x + FF(LN(x))."""

    norm1: eqx.nn.LayerNorm
    attention: eqx.nn.MultiheadAttention
    norm2: eqx.nn.LayerNorm
    ff1: eqx.nn.Linear
    ff2: eqx.nn.Linear
    dropout: eqx.nn.Dropout

    def __init__(self, d_model: int, n_heads: int, d_ff: int, dropout: float, *, key):
        k1, k2, k3 = jax.random.split(key, 3)
        self.norm1 = eqx.nn.LayerNorm(d_model)
        self.attention = eqx.nn.MultiheadAttention(
            n_heads, d_model, use_query_bias=True, use_key_bias=True, use_value_bias=True, use_output_bias=True, key=k1
        )
        self.norm2 = eqx.nn.LayerNorm(d_model)
        self.ff1 = eqx.nn.Linear(d_model, d_ff, key=k2)
        self.ff2 = eqx.nn.Linear(d_ff, d_model, key=k3)
        self.dropout = eqx.nn.Dropout(dropout)

    def __call__(self, x, *, key=None):
        """``x (length, d_model) -> (length, d_model)``; ``key=None`` switches dropout off."""
        k1, k2, k3 = (None, None, None) if key is None else jax.random.split(key, 3)
        off = key is None
        h = jax.vmap(self.norm1)(x)
        x = x + self.dropout(self.attention(h, h, h, inference=True), key=k1, inference=off)
        h = jax.nn.gelu(jax.vmap(self.ff1)(jax.vmap(self.norm2)(x)))
        h = jax.vmap(self.ff2)(self.dropout(h, key=k2, inference=off))
        return x + self.dropout(h, key=k3, inference=off)


class WindowTransformer(eqx.Module):
    """Linear embedding + learned positions, encoder layers, final norm and linear head.

    Called on one window ``x (window, n_inputs)``; returns the flattened
    window prediction ``(window * n_channels,)`` (frames slowest, the layout
    of :func:`dam.features.window_targets`).
    """

    embed: eqx.nn.Linear
    position: jax.Array
    layers: list
    norm: eqx.nn.LayerNorm
    head: eqx.nn.Linear

    def __init__(
        self,
        n_inputs: int,
        n_outputs: int,
        window: int,
        d_model: int,
        n_heads: int,
        n_layers: int,
        d_ff: int,
        dropout: float,
        *,
        key,
    ):
        k_embed, k_pos, k_layers, k_head = jax.random.split(key, 4)
        self.embed = eqx.nn.Linear(n_inputs, d_model, key=k_embed)
        self.position = 0.02 * jax.random.normal(k_pos, (window, d_model))
        self.layers = [
            EncoderLayer(d_model, n_heads, d_ff, dropout, key=k) for k in jax.random.split(k_layers, n_layers)
        ]
        self.norm = eqx.nn.LayerNorm(d_model)
        self.head = eqx.nn.Linear(d_model, n_outputs // window, key=k_head)

    def __call__(self, x, mask=None, *, key=None):
        h = jax.vmap(self.embed)(x.astype(jnp.float32)) + self.position
        keys = [None] * len(self.layers) if key is None else list(jax.random.split(key, len(self.layers)))
        for layer, k in zip(self.layers, keys):
            h = layer(h, key=k)
        return jax.vmap(self.head)(jax.vmap(self.norm)(h)).reshape(-1)


class TransformerDecoder(NeuralSynthesizer):
    """Transformer encoder over overlapping windows, outputs averaged (Medina et al. 2022).

    Parameters
    ----------
    window : int, default 15
        Frames per window (input and output), centred on the frame.
    n_layers : int, default 4
    n_heads : int, default 8
    d_model : int, default 64
        Width of the tokens (a multiple of ``n_heads``).
    d_ff : int, default 128
        Width of the feed-forward layers.
    window_hop : int, default 5
        Train on every ``window_hop``-th window (each frame is still in 3 of them).
    dropout : float, default 0.1
    optimizer : {"adam", "sgd"}, default "adam"
    learning_rate : float, default 1e-3
    batch_size : int, default 64
    max_epochs : int, default 20
    patience : int, default 4
    validation_fraction : float, default 0.1
    encoder, random_state, verbose, unknown_phone
        See :class:`baselines.nn.base.NeuralSynthesizer`.
    """

    name = "transformer"
    _parameter_constraints = dict.fromkeys(
        ["window", "n_layers", "n_heads", "d_model", "d_ff", "window_hop"], [Interval(int, 1, None, closed="left")]
    )

    def __init__(
        self,
        *,
        window: int = 15,
        n_layers: int = 4,
        n_heads: int = 8,
        d_model: int = 64,
        d_ff: int = 128,
        window_hop: int = 5,
        dropout: float = 0.1,
        optimizer: str = "adam",
        learning_rate: float = 1e-3,
        batch_size: int = 64,
        max_epochs: int = 20,
        patience: int = 4,
        validation_fraction: float = 0.1,
        encoder: str = "phones",
        random_state: int | None = 0,
        verbose: int = 1,
        unknown_phone: str = "error",
    ):
        self.window = window
        self.n_layers = n_layers
        self.n_heads = n_heads
        self.d_model = d_model
        self.d_ff = d_ff
        self.window_hop = window_hop
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
                "window": 9,
                "n_layers": 1,
                "n_heads": 2,
                "d_model": 16,
                "d_ff": 32,
                "window_hop": 1,
                "dropout": 0.0,
                "max_epochs": 20,
                "learning_rate": 3e-3,
                "verbose": 0,
            },
            {"window": 5, "n_layers": 2, "n_heads": 2, "d_model": 8, "d_ff": 8, "max_epochs": 2, "verbose": 0},
        ]

    def _check_param_relations(self) -> None:
        if self.d_model % self.n_heads:
            raise InvalidParameterError(
                f"{type(self).__name__}: parameter 'd_model' is {self.d_model!r}; it must "
                f"be a multiple of n_heads={self.n_heads}"
            )

    def _network_spec(self, n_inputs, n_outputs):
        return WindowTransformer, dict(
            n_inputs=n_inputs,
            n_outputs=n_outputs,
            window=int(self.window),
            d_model=int(self.d_model),
            n_heads=int(self.n_heads),
            n_layers=int(self.n_layers),
            d_ff=int(self.d_ff),
            dropout=float(self.dropout),
        )

    def _inputs(self, encoder, alignment, n_frames):
        """(n_frames, window, n_features): the per-frame features of every frame's window."""
        X = encoder.windows(alignment, self.frame_rate_, n_frames, k=self.window, align="center")
        return X.reshape(n_frames, self.window, -1)

    def _samples(self, encoder, utterance, y):
        from dam.corpus import window_targets

        X = self._inputs(encoder, utterance, utterance.n_frames)
        Y = window_targets(y, ky=self.window, align="center").astype(np.float32)
        keep = slice(None, None, int(self.window_hop))
        return X[keep], Y[keep], np.ones(len(X[keep]), np.float32)

    def _forward(self, network, encoder, alignment, n_frames):
        from dam.corpus import overlap_average

        windows = predict_padded(network, self._inputs(encoder, alignment, n_frames))
        return overlap_average(windows, self.window, len(self.channels_), align="center")
