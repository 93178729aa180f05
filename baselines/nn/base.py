"""``NeuralSynthesizer``: what every neural predictor shares.

A subclass says how to build its network and how to turn utterances into
training samples and network outputs back into frames:

``_network_spec(n_inputs, n_outputs) -> (NetworkClass, kwargs)``
    The network is built from hyperparameters alone (``kwargs`` hashable
    values: ints, floats, str, tuples), so a saved model is rebuilt from its
    parameters and its weight arrays (nothing is pickled), and refits of the
    same architecture reuse the compiled code.
``_samples(encoder, utterance, y) -> (X, Y, W)``
    Training samples of one utterance; ``y`` is its standardized trajectory.
``_forward(network, encoder, alignment, n_frames) -> (n_frames, n_channels)``
    Standardized prediction for one alignment.

The base class standardizes the channels, splits off validation utterances,
runs the one training loop (:func:`baselines.nn.train.train_network`) and
keeps the weights as a list of numpy arrays (``weights_``) that the generic
npz + JSON model format saves; the equinox network is rebuilt lazily on the
first prediction after loading.
"""

from __future__ import annotations

import numpy as np

from dam import Alignment, Corpus, Interval, Options, Synthesizer

from .encoders import ENCODERS, EncoderSpec, encoder_from_state, encoder_reads, make_encoder

__all__ = ["NeuralSynthesizer"]


class NeuralSynthesizer(Synthesizer):
    """Base class of the neural predictors (jax + equinox + optax).

    Every subclass has these hyperparameters (besides its network's).

    Parameters
    ----------
    encoder : str, default "phones"
        The input encoder (:data:`baselines.nn.encoders.ENCODERS`): ``"phones"``
        (the alignment), or ``"mfcc"``, ``"fbank"``, ``"features"``, which read
        the utterance's audio (or ``<stem>.features.npy``) and refuse a corpus
        without it; audio encoders take options, ``"mfcc:n_mfcc=27,window=0.02"``.
        A model with an audio encoder predicts from an Utterance with audio or a
        :class:`dam.corpus.AudioClip` (:meth:`predict_audio` reads a file).
    optimizer : {"adam", "sgd"}
        optax Adam, or SGD with momentum 0.9.
    learning_rate : float
    batch_size : int
    max_epochs : int
    patience : int
        Early stopping: epochs without a validation improvement before stopping.
    validation_fraction : float
        Fraction of the training utterances held out for early stopping
        (whole utterances, at least one when the corpus has two or more;
        0 disables early stopping).
    dropout : float
    random_state : int or None, default 0
        Seeds the validation split and the initial weights (numpy), and the
        shuffling and dropout (``jax.random.key``). None draws a fresh seed.
    verbose : int, default 1
        0 silences the progress bar (it is shown only on a terminal anyway).
    unknown_phone : {"error", "fallback"}, default "error"

    Attributes
    ----------
    weights_ : list of ndarray
        The network's arrays in pytree order.
    n_inputs_, n_outputs_ : int
        Input and output width of the network.
    encoder_state_ : dict
        The fitted encoder (its vocabulary).
    y_mean_, y_scale_ : ndarray, shape (n_channels,)
        Channel standardization (the networks predict standardized values).
    loss_curve_ : list of float
        Mean training loss per epoch (standardized units, dropout on).
    validation_curve_ : list of float
        Validation loss per epoch (empty without validation).
    initial_loss_ : float
        Training loss of the untrained network.
    n_epochs_, best_epoch_ : int
        Epochs run; epoch whose weights were kept.
    n_parameters_ : int
        Number of trainable numbers.
    """

    _tags = {"requires": ("jax",), "deterministic": True, "slow": True}
    _parameter_constraints = {
        "encoder": [EncoderSpec(ENCODERS)],
        "optimizer": [Options({"adam", "sgd"})],
        "learning_rate": [Interval(float, 0, None, closed="neither")],
        "batch_size": [Interval(int, 1, None, closed="left")],
        "max_epochs": [Interval(int, 0, None, closed="left")],
        "patience": [Interval(int, 1, None, closed="left")],
        "validation_fraction": [Interval(float, 0, 1, closed="left")],
        "dropout": [Interval(float, 0, 1, closed="left")],
    }  # unknown_phone, random_state and verbose: as declared by dam.Synthesizer; the network's: subclasses
    _clip_norm: float | None = None  # recurrent networks clip their gradients

    # -- hooks ---------------------------------------------------------------
    def _network_spec(self, n_inputs: int, n_outputs: int) -> tuple:  # pragma: no cover - abstract
        raise NotImplementedError

    def _make_network(self, n_inputs: int, n_outputs: int, seed: int):
        """The network with its initial weights drawn from ``seed``."""
        from .train import initial_network

        cls, kwargs = self._network_spec(n_inputs, n_outputs)
        return initial_network(cls, kwargs, seed)

    def _samples(self, encoder, utterance, y: np.ndarray):  # pragma: no cover - abstract
        raise NotImplementedError

    def _forward(self, network, encoder, alignment: Alignment, n_frames: int) -> np.ndarray:  # pragma: no cover
        raise NotImplementedError

    # -- fitting -------------------------------------------------------------
    def _seed(self) -> int:
        if self.random_state is None:
            return int(np.random.default_rng().integers(2**31 - 1))
        return int(self.random_state)

    def _validation_split(self, corpus: Corpus, seed: int) -> tuple[list, list]:
        utts = list(corpus)
        n_val = int(round(self.validation_fraction * len(utts)))
        if self.validation_fraction > 0 and len(utts) >= 2:
            n_val = min(max(n_val, 1), len(utts) - 1)
        else:
            n_val = 0
        order = np.random.default_rng(seed).permutation(len(utts))
        val = set(order[:n_val].tolist())
        return [u for i, u in enumerate(utts) if i not in val], [u for i, u in enumerate(utts) if i in val]

    def _stack(self, encoder, utterances) -> tuple:
        """Training samples of ``utterances``, concatenated: (X, Y, W)."""
        if not utterances:
            return None, None, None
        parts = [self._samples(encoder, u, (u.trajectory - self.y_mean_) / self.y_scale_) for u in utterances]
        return tuple(np.concatenate([p[i] for p in parts]) for i in range(3))

    def _fit(self, corpus: Corpus) -> None:
        import jax

        from .train import network_leaves

        self._net = self._encoder = None  # caches of a previous fit
        seed = self._seed()
        encoder = make_encoder(self.encoder, corpus)
        self.encoder_state_ = encoder.state()
        Y = np.concatenate(corpus.trajectories)
        self.y_mean_ = Y.mean(axis=0)
        std = Y.std(axis=0)
        self.y_scale_ = np.where(std > 1e-12, std, 1.0)
        train, val = self._validation_split(corpus, seed)
        X, Yt, W = self._stack(encoder, train)
        Xv, Yv, Wv = self._stack(encoder, val)
        self.n_inputs_, self.n_outputs_ = int(X.shape[-1]), int(Yt.shape[-1])
        net = self._make_network(self.n_inputs_, self.n_outputs_, seed)
        net, hist = self._train(net, (X, Yt, W), (Xv, Yv, Wv), jax.random.key(seed))
        self._net = net
        self._encoder = encoder
        self._finish_fit(encoder, train, val)
        self.weights_ = network_leaves(net)
        self.n_parameters_ = int(sum(w.size for w in self.weights_))
        self.loss_curve_ = list(hist.loss_curve)
        self.validation_curve_ = list(hist.validation_curve)
        self.initial_loss_ = hist.initial_loss
        self.n_epochs_ = len(hist.loss_curve)
        self.best_epoch_ = hist.best_epoch

    def _train(self, net, train: tuple, val: tuple, key, loss=None, max_epochs: int | None = None):
        """Run :func:`baselines.nn.train.train_network` with this model's settings
        (a multi-stage model calls it once per stage with its own ``loss``)."""
        from .train import make_optimizer, train_network

        return train_network(
            net,
            *train,
            X_val=val[0],
            Y_val=val[1],
            W_val=val[2],
            optimizer=make_optimizer(self.optimizer, self.learning_rate, self._clip_norm),
            batch_size=self.batch_size,
            max_epochs=self.max_epochs if max_epochs is None else max_epochs,
            patience=self.patience,
            key=key,
            verbose=self.verbose,
            desc=self.name or type(self).__name__,
            loss=loss,
        )

    def _finish_fit(self, encoder, train: list, val: list) -> None:
        """Hook after training (the network is ``self._net``); e.g. thresholds chosen on ``val``."""

    # -- prediction ----------------------------------------------------------
    def reads(self) -> tuple:
        """``("audio",)`` with an audio encoder, else ``("phones",)``."""
        return encoder_reads(self.encoder)

    def predict_audio(self, audio, sample_rate: float | None = None) -> np.ndarray:
        """Synthesize from audio alone (no transcript), with an audio encoder.

        Parameters
        ----------
        audio : path-like or array-like, shape (n_samples,)
            A sound file (WAV, FLAC ...; needs the ``audio`` extra) or samples.
        sample_rate : float, optional
            Required with samples.

        Returns
        -------
        ndarray, shape (n_frames, n_channels)
            ``n_frames = floor(duration * frame_rate_) + 1``.
        """
        import os

        from dam.corpus import AudioClip

        if "audio" not in self.reads():
            raise TypeError(
                f"{type(self).__name__} with encoder={self.encoder!r} reads phones, not audio; "
                "fit it with an audio encoder (encoder='mfcc')"
            )
        if isinstance(audio, (str, os.PathLike)):
            from dam.speech import load_audio

            x, name = load_audio(audio, rate=16000)
            return self.predict(AudioClip(x, 16000, name=name))
        if sample_rate is None:
            raise TypeError("predict_audio of samples needs their sample_rate")
        return self.predict(AudioClip(audio, sample_rate))

    def _predict_audio(self, source, n_frames: int) -> np.ndarray:
        out = self._forward(self._network(), self._input_encoder(), source, n_frames)
        return out * self.y_scale_ + self.y_mean_

    def _network(self):
        """The equinox network, rebuilt from ``weights_`` after loading."""
        if getattr(self, "_net", None) is None:
            import equinox as eqx
            import jax

            from .train import network_from_leaves

            # Shapes only: nothing is drawn or compiled, the saved arrays fill it.
            cls, kwargs = self._network_spec(self.n_inputs_, self.n_outputs_)
            skeleton = eqx.filter_eval_shape(lambda k: cls(**kwargs, key=k), jax.random.key(0))
            self._net = network_from_leaves(skeleton, self.weights_)
        return self._net

    def _input_encoder(self):
        if getattr(self, "_encoder", None) is None:
            self._encoder = encoder_from_state(self.encoder_state_)
        return self._encoder

    def _predict(self, alignment: Alignment, n_frames: int) -> np.ndarray:
        encoder = self._input_encoder()
        vocab = set(getattr(encoder, "vocabulary", ()))
        if vocab and any(lab not in vocab for lab in alignment.labels):
            labels = self._known_labels(alignment, self.unknown_phone)
            alignment = Alignment(
                labels, alignment.starts, alignment.ends, source=alignment.source, silence=alignment.silence
            )
        out = self._forward(self._network(), encoder, alignment, n_frames)
        return out * self.y_scale_ + self.y_mean_

    def _set_state(self, state: dict) -> None:
        """Restore the saved state; the network is rebuilt on the first prediction."""
        super()._set_state(state)
        self._net = None
        self._encoder = None
