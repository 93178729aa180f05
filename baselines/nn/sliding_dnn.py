"""Taylor et al. (2017): the deep-learning sliding-window predictor (``sliding-dnn``).

Section 5 of the paper, Fig. 4: the frame-wise phone sequence is cut into
overlapping input windows of ``K_x = 11`` frames (b); a fully connected
network with tanh hidden layers and dropout maps each to an output window of
``K_y = 5`` frames (c, d); the overlapping output windows are averaged frame
by frame (e). Training minimizes the squared loss over output windows by
mini-batch gradient descent. Inputs are the *raw* one-hot phone features or
the *linguistic* indicator features of the supplementary material
(:func:`dam.features.window_features`, shared with the decision tree).

The paper's network is 3 x 3000 tanh units, dropout 0.5, mini-batch 100,
plain SGD; ``SlidingDNN(**SlidingDNN.PAPER)`` is that configuration. The
default keeps the paper's depth, dropout, batch and windows but uses 3 x 256
units and Adam, so it trains on the bundled corpus in about a minute on a CPU.
"""

from __future__ import annotations

from collections.abc import Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from dam import Interval, Options, TupleOf

from .base import NeuralSynthesizer
from .train import predict_padded

__all__ = ["WindowMLP", "SlidingDNN"]

_ACTIVATIONS = {"tanh": jax.nn.tanh, "relu": jax.nn.relu}


class WindowMLP(eqx.Module):
    """Fully connected layers with dropout after every hidden layer; a linear output layer.

    Parameters
    ----------
    n_inputs, n_outputs : int
    hidden : sequence of int
        Units of each hidden layer.
    activation : {"tanh", "relu"}
    dropout : float
    key : jax PRNG key

    Called on one window ``x (n_inputs,)`` (any dtype; cast to float32),
    returns ``(n_outputs,)``; ``key=None`` switches dropout off.
    """

    layers: list
    dropout: eqx.nn.Dropout
    activation: str = eqx.field(static=True)

    def __init__(self, n_inputs: int, n_outputs: int, hidden: Sequence[int], activation: str, dropout: float, *, key):
        sizes = [int(n_inputs), *[int(h) for h in hidden], int(n_outputs)]
        keys = jax.random.split(key, len(sizes) - 1)
        self.layers = [eqx.nn.Linear(a, b, key=k) for a, b, k in zip(sizes[:-1], sizes[1:], keys)]
        self.dropout = eqx.nn.Dropout(dropout)
        self.activation = activation

    def __call__(self, x, mask=None, *, key=None):
        h = x.astype(jnp.float32)
        act = _ACTIVATIONS[self.activation]
        keys = [None] * len(self.layers) if key is None else list(jax.random.split(key, len(self.layers)))
        for layer, k in zip(self.layers[:-1], keys):
            h = self.dropout(act(layer(h)), key=k, inference=key is None)
        return self.layers[-1](h)


class SlidingDNN(NeuralSynthesizer):
    """Sliding-window deep network of Taylor et al. (2017).

    Parameters
    ----------
    kx : int, default 11
        Input window, frames (the paper's ``K_x``).
    ky : int, default 5
        Output window, frames (``K_y``); overlapping outputs are averaged.
    features : {"raw", "linguistic"}, default "raw"
        One-hot phones, or the paper's linguistic indicator features.
    hidden_layer_sizes : tuple of int, default (256, 256, 256)
        The paper: (3000, 3000, 3000).
    activation : {"tanh", "relu"}, default "tanh"
    dropout : float, default 0.5
    optimizer : {"adam", "sgd"}, default "adam"
        The paper: "sgd".
    learning_rate : float, default 1e-3
    batch_size : int, default 100
    max_epochs : int, default 30
    patience : int, default 4
    validation_fraction : float, default 0.1
    encoder, random_state, verbose, unknown_phone
        See :class:`baselines.nn.base.NeuralSynthesizer`.
    window_rate : float or None, default None
        Rate (Hz) of the window frames: ``window_rate=30`` spaces them
        ``round(frame_rate / 30)`` frames apart, the paper's span of context
        at 29.97 video frames per second (0.33 s for 11 frames at 100 Hz);
        None uses every data frame (0.11 s at 100 Hz). The decision tree
        (``dtree``) takes the same parameter (default 30).

    Attributes
    ----------
    See :class:`baselines.nn.base.NeuralSynthesizer`.
    """

    name = "sliding-dnn"
    #: The configuration of Taylor et al. (2017), Section 5.1.
    PAPER = {
        "hidden_layer_sizes": (3000, 3000, 3000),
        "dropout": 0.5,
        "batch_size": 100,
        "optimizer": "sgd",
        "learning_rate": 0.01,
        "kx": 11,
        "ky": 5,
        "activation": "tanh",
    }
    _align = "center"
    _parameter_constraints = {
        "kx": [Interval(int, 1, None, closed="left")],
        "ky": [Interval(int, 1, None, closed="left")],
        "features": [Options({"raw", "linguistic"})],
        "activation": [Options(_ACTIVATIONS)],
        "hidden_layer_sizes": [TupleOf(Interval(int, 1, None, closed="left"), min_len=0)],
        "window_rate": [Interval(float, 0, None, closed="neither"), None],
    }

    def __init__(
        self,
        *,
        kx: int = 11,
        ky: int = 5,
        features: str = "raw",
        hidden_layer_sizes: tuple = (256, 256, 256),
        activation: str = "tanh",
        dropout: float = 0.5,
        optimizer: str = "adam",
        learning_rate: float = 1e-3,
        batch_size: int = 100,
        max_epochs: int = 30,
        patience: int = 4,
        validation_fraction: float = 0.1,
        encoder: str = "phones",
        random_state: int | None = 0,
        verbose: int = 1,
        unknown_phone: str = "error",
        window_rate: float | None = None,
    ):
        self.kx = kx
        self.ky = ky
        self.window_rate = window_rate
        self.features = features
        self.hidden_layer_sizes = hidden_layer_sizes
        self.activation = activation
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
                "hidden_layer_sizes": (32,),
                "dropout": 0.0,
                "max_epochs": 20,
                "batch_size": 64,
                "learning_rate": 3e-3,
                "verbose": 0,
            },
            {"features": "linguistic", "hidden_layer_sizes": (16, 16), "kx": 5, "ky": 3, "max_epochs": 3, "verbose": 0},
        ]

    def _network_spec(self, n_inputs, n_outputs):
        return WindowMLP, dict(
            n_inputs=n_inputs,
            n_outputs=n_outputs,
            hidden=tuple(int(h) for h in self.hidden_layer_sizes),
            activation=self.activation,
            dropout=float(self.dropout),
        )

    def _dilation(self) -> int:
        """Frames between window frames (:func:`dam.corpus.window_dilation`; 1 without ``window_rate``)."""
        from dam.corpus import window_dilation

        return window_dilation(self.frame_rate_, getattr(self, "window_rate", None))

    def _inputs(self, encoder, alignment, n_frames):
        return encoder.windows(
            alignment,
            self.frame_rate_,
            n_frames,
            k=self.kx,
            align=self._align,
            features=self.features,
            dilation=self._dilation(),
        )

    def _samples(self, encoder, utterance, y):
        from dam.corpus import window_targets

        X = self._inputs(encoder, utterance, utterance.n_frames)
        Y = window_targets(y, ky=self.ky, align=self._align, dilation=self._dilation()).astype(np.float32)
        return X, Y, np.ones(len(X), np.float32)

    def _forward(self, network, encoder, alignment, n_frames):
        from dam.corpus import overlap_average

        windows = predict_padded(network, self._inputs(encoder, alignment, n_frames))
        return overlap_average(windows, self.ky, len(self.channels_), align=self._align, dilation=self._dilation())
