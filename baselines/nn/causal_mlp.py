"""Medina et al. (2022): the causal sliding MLP decoder, "MLP 15:5" (``causal-mlp``).

Section 4 of the paper: a sliding overlapping input and output window MLP
as proposed by Taylor et al. (2017), "with a slight modification": causal
prediction, "outputting the most recent value rather than predicting the
middle frame", so nothing after the current frame is looked at. The input
window is the 15 frames ending at the current one, the output window the 5
frames ending there; training fits all 5 output frames (the squared loss of
Taylor et al.), synthesis keeps the last, the current frame. The network is
one fully connected ReLU layer of 512 units and a linear output layer;
dropout 0.25 and mini-batches of 32 as in the paper, Adam (the paper's
learning rate, 1e-5, is too slow to train in minutes; 1e-3 here).

The paper's decoders read phone, MFCC or learned audio features per frame;
here the input comes through the encoder slot (:mod:`baselines.nn.encoders`).
Window lengths are in frames: the paper's 15 frames are 300 ms at its 50 Hz;
at 100 Hz pass ``kx=30, ky=10`` for the same span.
"""

from __future__ import annotations

from .sliding_dnn import SlidingDNN
from .train import predict_padded

__all__ = ["CausalMLP"]


class CausalMLP(SlidingDNN):
    """Causal sliding-window MLP of Medina et al. (2022): no look-ahead.

    Parameters
    ----------
    kx : int, default 15
        Input window: the ``kx`` frames ending at the current frame.
    ky : int, default 5
        Output window fitted in training: the ``ky`` frames ending at the current frame.
    features : {"raw", "linguistic"}, default "raw"
    hidden_layer_sizes : tuple of int, default (512,)
    activation : {"relu", "tanh"}, default "relu"
    dropout : float, default 0.25
    optimizer : {"adam", "sgd"}, default "adam"
    learning_rate : float, default 1e-3
    batch_size : int, default 32
    max_epochs : int, default 30
    patience : int, default 4
    validation_fraction : float, default 0.1
    encoder, random_state, verbose, unknown_phone
        See :class:`baselines.nn.base.NeuralSynthesizer`.
    """

    name = "causal-mlp"
    _align = "causal"
    _preset = {"kx": 15, "hidden_layer_sizes": (512,), "activation": "relu", "dropout": 0.25, "batch_size": 32}

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
            {"kx": 6, "ky": 2, "hidden_layer_sizes": (16,), "max_epochs": 3, "verbose": 0},
        ]

    def _forward(self, network, encoder, alignment, n_frames):
        windows = predict_padded(network, self._inputs(encoder, alignment, n_frames))
        return windows[:, -len(self.channels_) :]  # the current frame: the last of its causal window
