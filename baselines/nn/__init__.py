"""Neural predictors (need the ``jax`` extra: jax, optax, equinox).

Each network lives in its own file, named after what it is in its paper:

* :mod:`~baselines.nn.sliding_dnn` -- ``sliding-dnn``, Taylor et al. (2017)
* :mod:`~baselines.nn.lstm` -- ``lstm``, Taylor et al.'s LSTM baseline (Fan et al. 2015)
* :mod:`~baselines.nn.causal_mlp` -- ``causal-mlp``, Medina et al. (2022), MLP 15:5
* :mod:`~baselines.nn.rnn` -- ``gru``, Medina et al.'s GRU/LSTM decoders (1-5 layers, uni/bidirectional)
* :mod:`~baselines.nn.transformer` -- ``transformer``, Medina et al.'s Transformer encoder

and what they share: :mod:`~baselines.nn.base` (``NeuralSynthesizer``),
:mod:`~baselines.nn.train` (the one training loop and batched prediction),
:mod:`~baselines.nn.encoders` (the input-encoder slot).

This package file imports nothing, so listing models never imports jax.
"""
