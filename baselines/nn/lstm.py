"""The LSTM baseline of Taylor et al. (2017), after Fan et al. (2015) (``lstm``).

Taylor et al., Section 7: "We follow the basic setup of [Fan et al. 2015]
... three hidden layers, a fully-connected layer, and two LSTM layers ...
500 [units] achieves the best performance. Mini-batch size was 10, and to
prevent overfitting we use dropout with 50% probability." Fan et al.'s
network is a deep *bidirectional* LSTM, so the LSTM layers run both ways by
default. It is the recurrent decoder of :mod:`baselines.nn.rnn` with a tanh
input layer; the default width is 64 (not 500) and the mini-batch 32 (not 10)
so that it trains in minutes on a CPU: ``hidden_size=500, dense_size=500,
batch_size=10`` is the paper's setting.
"""

from __future__ import annotations

from .rnn import RecurrentDecoder

__all__ = ["FanLSTM"]


class FanLSTM(RecurrentDecoder):
    """A fully connected tanh layer and two (bidirectional) LSTM layers, dropout 0.5.

    Parameters
    ----------
    cell : {"lstm", "gru"}, default "lstm"
    n_layers : int, default 2
    bidirectional : bool, default True
    hidden_size : int, default 64
        Units per direction; Taylor et al. found 500 best.
    dense_size : int, default 64
        The fully connected input layer.
    seq_len : int, default 100
    dropout : float, default 0.5
    optimizer : {"adam", "sgd"}, default "adam"
    learning_rate : float, default 3e-3
    batch_size : int, default 32
        Windows per mini-batch; the paper's 10 trains 3x slower on a CPU.
    max_epochs : int, default 40
    patience : int, default 5
    validation_fraction : float, default 0.1
    encoder, random_state, verbose, unknown_phone
        See :class:`baselines.nn.base.NeuralSynthesizer`.
    """

    name = "lstm"
    _preset = {"cell": "lstm", "bidirectional": True, "dense_size": 64, "dropout": 0.5}

    @classmethod
    def get_test_params(cls) -> list[dict]:
        return [
            {
                "hidden_size": 16,
                "dense_size": 16,
                "seq_len": 32,
                "dropout": 0.0,
                "max_epochs": 25,
                "learning_rate": 1e-2,
                "batch_size": 16,
                "verbose": 0,
            },
            {
                "n_layers": 1,
                "bidirectional": False,
                "hidden_size": 8,
                "dense_size": 8,
                "seq_len": 16,
                "max_epochs": 2,
                "verbose": 0,
            },
        ]
