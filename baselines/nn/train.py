"""The one training loop of the neural predictors, and their batched prediction.

Every network here is an equinox module called on ONE sample as
``net(x, mask, key=None)``: ``x`` a frame window ``(n_inputs,)`` or a
sequence ``(length, n_inputs)``, ``mask`` the sample's validity (a scalar
or ``(length,)``), ``key`` a PRNG key for dropout (``None`` means inference).
Training samples are stacked arrays ``X (n, ...)``, ``Y (n, ..., n_outputs)``
and weights ``W (n, ...)`` (0 on padding), so one loop serves the sliding
window networks, the recurrent networks and the Transformer alike.

The loop (:func:`train_network`): optax optimiser, explicit PRNG keys, one
jit-compiled ``lax.scan`` per epoch over shuffled mini-batches, a validation
set with early stopping on it (the weights of the best epoch are kept), and
progress per epoch (:mod:`dam.progress`) showing the losses.

Prediction (:func:`predict_padded`): the input is padded to a bucketed
length (a power of two) so that the jit cache is reused across utterances of
similar length; a second call with the same bucket never recompiles.
"""

from __future__ import annotations

import contextlib
import functools
import math
from dataclasses import dataclass, field

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optax

__all__ = [
    "TrainHistory",
    "train_network",
    "make_optimizer",
    "weighted_mse",
    "predict_padded",
    "bucket_length",
    "TRACE_COUNT",
    "initial_network",
    "network_leaves",
    "network_from_leaves",
]

# How many times the prediction function has been traced (compiled); the
# tests read it to prove that a second prediction does not recompile.
TRACE_COUNT = {"predict": 0}


@dataclass
class TrainHistory:
    """What the training loop records.

    Attributes
    ----------
    loss_curve : list of float
        Mean training loss of each epoch (over its mini-batches, dropout on).
    validation_curve : list of float
        Validation loss after each epoch (dropout off); empty without a
        validation set.
    initial_loss : float
        Training-set loss of the initial network (dropout off).
    best_epoch : int
        Epoch (1-based) whose weights were kept.
    stopped_early : bool
    """

    loss_curve: list = field(default_factory=list)
    validation_curve: list = field(default_factory=list)
    initial_loss: float = float("nan")
    best_epoch: int = 0
    stopped_early: bool = False


@functools.lru_cache(maxsize=64)
def make_optimizer(name: str, learning_rate: float, clip_norm: float | None = None):
    """An optax optimiser: ``"adam"`` or ``"sgd"`` (momentum 0.9), optionally clipped.

    Cached, so equal settings give the same object and the compiled training
    step is reused across fits.
    """
    if name == "adam":
        opt = optax.adam(learning_rate)
    elif name == "sgd":
        opt = optax.sgd(learning_rate, momentum=0.9)
    else:
        raise ValueError(f"parameter 'optimizer' is {name!r}; use 'adam' or 'sgd'")
    if clip_norm:
        opt = optax.chain(optax.clip_by_global_norm(clip_norm), opt)
    return opt


def weighted_mse(pred, y, w):
    """Sum of ``w``-weighted squared errors (mean over outputs) and the sum of weights.

    ``pred`` and ``y`` have shape ``w.shape + (n_outputs,)``.
    """
    se = jnp.mean((pred - y) ** 2, axis=-1)
    return jnp.sum(se * w), jnp.sum(w)


def _batched_apply(net, X, W, key):
    """Apply ``net`` to every sample of a batch; ``key=None`` for inference."""
    if key is None:
        return jax.vmap(lambda x, m: net(x, m, key=None))(X, W)
    keys = jax.random.split(key, X.shape[0])
    return jax.vmap(lambda x, m, k: net(x, m, key=k))(X, W, keys)


def _epoch_order(key, n: int, batch_size: int) -> jnp.ndarray:
    """Shuffled sample indices shaped (n_batches, batch_size); the last batch is
    filled up with the first indices of the permutation so shapes stay static."""
    n_batches = max(1, math.ceil(n / batch_size))
    perm = jax.random.permutation(key, n)
    pad = n_batches * batch_size - n
    perm = jnp.concatenate([perm, perm[:pad]]) if pad else perm
    return perm.reshape(n_batches, batch_size)


def _host(X, Y, W):
    """Inputs keep a compact dtype (0/1 features as uint8); targets and weights float32."""
    X = np.asarray(X)
    X = X if X.dtype == np.uint8 else X.astype(np.float32)
    return X, np.asarray(Y, dtype=np.float32), np.asarray(W, dtype=np.float32)


def train_network(
    net,
    X,
    Y,
    W,
    *,
    X_val=None,
    Y_val=None,
    W_val=None,
    optimizer,
    batch_size: int,
    max_epochs: int,
    patience: int,
    key,
    verbose: int = 1,
    desc: str = "training",
    tol: float = 0.0,
    loss=None,
):
    """Fit ``net`` to ``(X, Y, W)`` by mini-batch gradient descent on the weighted MSE.

    Parameters
    ----------
    net : equinox.Module
        Called per sample as ``net(x, mask, key=...)``.
    X, Y, W : ndarray
        Inputs ``(n, ...)``, targets ``(n, ..., n_outputs)``, weights ``(n, ...)``.
    X_val, Y_val, W_val : ndarray, optional
        A validation set; with it, training stops when the validation loss
        has not improved by more than ``tol`` (relative) for ``patience``
        epochs and the best epoch's weights are returned.
    optimizer : optax.GradientTransformation
    batch_size, max_epochs, patience : int
    key : jax PRNG key
        Drives shuffling and dropout; the same key gives the same weights.
    verbose : int, default 1
        0 reports nothing; otherwise every epoch goes to :mod:`dam.progress` (the
        command line's reporter, or a bar of its own on a terminal).
    desc : str
        Progress bar label.
    tol : float, default 0.0
        Minimum relative improvement of the validation loss that counts.
    loss : callable, optional
        ``loss(net, xb, yb, wb, key) -> scalar``, the mean loss of a batch
        (``key=None``: inference). Default: the weighted MSE. Use a
        module-level function: it is a static argument of the compiled epoch.

    Returns
    -------
    net : equinox.Module
        The trained network (best validation epoch when validating).
    history : TrainHistory
    """
    from dam import progress

    opt_state = optimizer.init(eqx.filter(net, eqx.is_inexact_array))
    host = _host(X, Y, W)
    X, Y, W = (jnp.asarray(a) for a in host)
    n = X.shape[0]
    eval_chunk = int(min(n, 1024))
    batch_size = int(min(batch_size, n))
    validate = X_val is not None and len(X_val) > 0
    if validate:
        host_val = _host(X_val, Y_val, W_val)

    loss_fn = _batch_loss if loss is None else loss

    def evaluate(net, X, Y, W):
        # Host-side chunks of one compiled size; padded rows carry weight 0.
        total = count = 0.0
        for lo in range(0, X.shape[0], eval_chunk):
            sl = [a[lo : lo + eval_chunk] for a in (X, Y, W)]
            pad = eval_chunk - sl[0].shape[0]
            if pad:
                sl = [np.concatenate([a, np.zeros((pad,) + a.shape[1:], a.dtype)]) for a in sl]
            s, c = _chunk_error(net, *sl) if loss is None else _chunk_loss(net, *sl, loss)
            total, count = total + float(s), count + float(c)
        return total / max(count, 1e-12)

    history = TrainHistory(initial_loss=evaluate(net, *host))
    best = (math.inf, net, 0)
    since_best = 0
    with contextlib.ExitStack() as stack:
        if verbose and not progress.active():  # a library call: a bar of its own on a terminal
            stack.enter_context(progress.reporting("auto"))
        bar = stack.enter_context(progress.task(desc, max_epochs, unit="epoch")) if verbose else None
        for epoch in range(1, max_epochs + 1):
            net, opt_state, value, key = _run_epoch(net, opt_state, X, Y, W, key, optimizer, batch_size, loss_fn)
            value = float(value)
            if not math.isfinite(value):
                raise FloatingPointError(
                    f"{desc}: the training loss became {value} at epoch {epoch}; lower the learning rate"
                )
            history.loss_curve.append(value)
            shown = f"loss {value:.4g}"
            if validate:
                val = evaluate(net, *host_val)
                history.validation_curve.append(val)
                shown += f", validation {val:.4g}"
                if val < best[0] * (1.0 - tol):
                    best, since_best = (val, net, epoch), 0
                else:
                    since_best += 1
            else:
                best = (value, net, epoch)
            if bar is not None:
                bar.step(f"epoch {epoch}: {shown}")
            if validate and since_best >= patience:
                history.stopped_early = True
                break
    if max_epochs > 0:
        net = best[1]
        history.best_epoch = best[2]
    return net, history


# The compiled pieces are module-level so that refits of the same architecture
# on data of the same shapes reuse them (equinox hashes the static structure).
def _batch_loss(net, xb, yb, wb, key):
    s, c = weighted_mse(_batched_apply(net, xb, wb, key), yb, wb)
    return s / jnp.maximum(c, 1e-12)


@eqx.filter_jit
def _run_epoch(net, opt_state, X, Y, W, key, optimizer, batch_size, loss_fn=_batch_loss):
    """One pass over shuffled mini-batches as a single ``lax.scan``."""
    key, k_order, k_drop = jax.random.split(key, 3)
    order = _epoch_order(k_order, X.shape[0], batch_size)
    params, static = eqx.partition(net, eqx.is_inexact_array)

    def step(carry, idx_k):
        params, state = carry
        idx, kb = idx_k
        loss, grads = jax.value_and_grad(lambda p: loss_fn(eqx.combine(p, static), X[idx], Y[idx], W[idx], kb))(params)
        updates, state = optimizer.update(grads, state, params)
        return (optax.apply_updates(params, updates), state), loss

    keys = jax.random.split(k_drop, order.shape[0])
    (params, opt_state), losses = jax.lax.scan(step, (params, opt_state), (order, keys))
    return eqx.combine(params, static), opt_state, jnp.mean(losses), key


@eqx.filter_jit
def _chunk_error(net, xb, yb, wb):
    return weighted_mse(_batched_apply(net, xb, wb, None), yb, wb)


@eqx.filter_jit
def _chunk_loss(net, xb, yb, wb, loss_fn):
    """A custom batch loss as (sum, weight) so chunks average like :func:`_chunk_error`."""
    c = jnp.sum(wb)
    return loss_fn(net, xb, yb, wb, None) * c, c


def bucket_length(n: int, minimum: int = 64) -> int:
    """The padded length for ``n`` rows: the next power of two, at least ``minimum``."""
    return max(minimum, 1 << max(0, int(n - 1).bit_length()))


@eqx.filter_jit
def _predict_rows(net, X, W):
    TRACE_COUNT["predict"] += 1  # runs only while tracing
    return _batched_apply(net, X, W, None)


def predict_padded(net, X, W=None, *, sequence: bool = False) -> np.ndarray:
    """Run ``net`` in inference mode with the input padded to a bucketed length.

    Parameters
    ----------
    net : equinox.Module
    X : ndarray, shape (n, n_inputs) or (n, window, n_inputs)
        Independent samples (``sequence=False``) or, with ``sequence=True``,
        the frames of one sequence ``(n, n_inputs)``.
    W : ndarray, shape (n,), optional
        Sample validity (defaults to ones).
    sequence : bool, default False

    Returns
    -------
    ndarray, shape (n, ...)
        The network outputs of the ``n`` real rows, float64.
    """
    X = np.asarray(X, dtype=np.float32)
    n = X.shape[0]
    W = np.ones(n, np.float32) if W is None else np.asarray(W, np.float32)
    m = bucket_length(n)
    Xp = np.zeros((m,) + X.shape[1:], np.float32)
    Xp[:n] = X
    Wp = np.zeros(m, np.float32)
    Wp[:n] = W
    if sequence:  # one sequence: a batch of one
        out = _predict_rows(net, Xp[None], Wp[None])[0]
    else:
        out = _predict_rows(net, Xp, Wp)
    return np.asarray(out[:n], dtype=float)


def initial_network(cls, kwargs: dict, seed: int):
    """``cls(**kwargs)`` with equinox's default initial weights, drawn with numpy.

    equinox draws: uniform(-l, l) with ``l = 1/sqrt(in_features)`` for a
    Linear layer and ``l = 1/sqrt(hidden_size)`` for GRU/LSTM cells;
    LayerNorm starts at weight 1, bias 0. Any other array (a position
    embedding) gets normal(0, 0.02). The same rules are applied here to a
    shape-only skeleton with ``numpy.random.default_rng(seed)``: jax's own
    draws took longer to compile on a CPU than training a small network.
    """
    rng = np.random.default_rng(seed)
    skeleton = eqx.filter_eval_shape(lambda: cls(**kwargs, key=jax.random.key(0)))
    cells = (eqx.nn.GRUCell, eqx.nn.LSTMCell)

    def draw(limit):
        return lambda s: jnp.asarray(rng.uniform(-limit, limit, s.shape), s.dtype)

    def init(node):
        if isinstance(node, eqx.nn.LayerNorm):
            return eqx.tree_at(
                lambda m: (m.weight, m.bias),
                node,
                (jnp.ones(node.weight.shape, node.weight.dtype), jnp.zeros(node.bias.shape, node.bias.dtype)),
            )
        if isinstance(node, eqx.nn.Linear):
            fill = draw(1.0 / math.sqrt(max(1, node.weight.shape[1])))
        elif isinstance(node, cells):
            fill = draw(math.sqrt(1.0 / node.hidden_size))
        elif isinstance(node, jax.ShapeDtypeStruct):
            return jnp.asarray(0.02 * rng.standard_normal(node.shape), node.dtype)
        else:  # not an array (a dropout rate)
            return node
        return jax.tree_util.tree_map(lambda s: fill(s) if isinstance(s, jax.ShapeDtypeStruct) else s, node)

    is_leaf = lambda x: isinstance(x, (eqx.nn.LayerNorm, eqx.nn.Linear, *cells, jax.ShapeDtypeStruct))  # noqa: E731
    return jax.tree_util.tree_map(init, skeleton, is_leaf=is_leaf)


def network_leaves(net) -> list[np.ndarray]:
    """The arrays of an equinox network, in pytree order (for saving)."""
    return [np.asarray(leaf) for leaf in jax.tree_util.tree_leaves(eqx.filter(net, eqx.is_array))]


def network_from_leaves(skeleton, leaves) -> eqx.Module:
    """Put saved ``leaves`` into ``skeleton`` (a network of the same hyperparameters,
    e.g. from ``equinox.filter_eval_shape``, whose arrays may be shape placeholders).

    Raises ValueError if the number or the shapes of the arrays differ.
    """
    params, static = eqx.partition(skeleton, lambda x: eqx.is_array(x) or isinstance(x, jax.ShapeDtypeStruct))
    old, treedef = jax.tree_util.tree_flatten(params)
    if len(old) != len(leaves):
        raise ValueError(f"the saved weights hold {len(leaves)} arrays, the network needs {len(old)}")
    for i, (a, b) in enumerate(zip(old, leaves)):
        if tuple(a.shape) != tuple(np.shape(b)):
            raise ValueError(f"saved weight array {i} has shape {np.shape(b)}, the network needs {a.shape}")
    new = [jnp.asarray(b, dtype=a.dtype) for a, b in zip(old, leaves)]
    return eqx.combine(jax.tree_util.tree_unflatten(treedef, new), static)
