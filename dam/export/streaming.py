"""Streaming synthesis: phones go in as they become known, final frames come out.

:class:`StreamingSynthesizer` wraps a fitted model. Push each phone with its
end time (or duration) as soon as it is known; every call returns the frames
that no later phone can change. :meth:`~StreamingSynthesizer.finish` closes
the utterance and returns the rest. The concatenation of everything returned
equals ``model.predict(alignment)`` of the whole utterance (to 1e-9).

For the DAM a frame is final when

* no phone still to come can reach it: a phone starting at the current end
  ``E`` and lasting at most ``max_duration`` reaches back at most
  ``reach * max_duration`` seconds (``reach``: the truncated dominance reach,
  in phone durations, of the widest sigma of the model;
  :func:`dam.model.dominance.reach`), so frames before
  ``E - reach * max_duration`` are safe from new phones
  (:attr:`~StreamingSynthesizer.lookahead`); and
* every phone that reaches it has its mode decided. Modes are chosen by the
  cheapest path (A*, Section VI); the stream runs the same minimisation as a
  Viterbi recursion and decides a phone's mode as soon as every surviving
  partial path agrees on it (at the latest, at the next phone with a single
  mode). A phone's context cost needs its right neighbour, so a mode is never
  decided before the next phone arrives.

Other models are streamed through :class:`BufferedStream`: nothing is final
before :meth:`finish` (infinite lookahead), which is exact and honest.
"""

from __future__ import annotations

import math

import numpy as np

from dam.corpus import Alignment, DataError

__all__ = ["StreamingSynthesizer", "BufferedStream", "stream"]


def stream(model, **kw):
    """A streaming synthesizer for ``model``: exact incremental for the DAM, buffered otherwise."""
    from dam.model import DAM

    if isinstance(model, DAM):
        return StreamingSynthesizer(model, **kw)
    kw.pop("max_duration", None)
    return BufferedStream(model, **kw)


class _Stream:
    """Phone bookkeeping shared by the streaming classes."""

    def __init__(self, model, *, source=None):
        model._check_fitted()
        self.model = model
        self.frame_rate = float(model.frame_rate_)
        self.channels = tuple(model.channels_)
        self.source = source or "<stream>"
        self.raw: list[str] = []  # labels as pushed (canonical silence), for the alignment
        self.labels: list[str] = []  # the model's labels (after any fallback)
        self.starts: list[float] = []
        self.ends: list[float] = []
        self.n_emitted = 0
        self.finished = False
        self.alignment_silence = Alignment(["sil"], [0.0], [1.0]).silence

    @property
    def end(self) -> float:
        """End time of the last phone pushed (seconds)."""
        return self.ends[-1] if self.ends else 0.0

    def _accept(self, label, end, duration, max_duration=math.inf):
        """Check and record a phone; returns the model's label, or None when a silence extended the last one.

        Adjacent silences merge into one segment, as :class:`dam.Alignment` merges them.
        """
        if self.finished:
            raise DataError(self.source, "push", label, "the utterance is finished")
        if (end is None) == (duration is None):
            raise DataError(
                self.source,
                f"phone {len(self.labels)} ({label!r})",
                (end, duration),
                "give exactly one of end= and duration=",
            )
        start = self.end
        end = start + float(duration) if end is None else float(end)
        d = end - start
        if not (math.isfinite(end) and d > 1e-9):
            raise DataError(
                self.source,
                f"phone {len(self.labels)} ({label!r}) end",
                end,
                f"must be finite and after the previous end {start:g}",
            )
        one = Alignment([label], [0.0], [d], source=self.source)
        merge = bool(self.raw) and one.labels[0] == one.silence == self.raw[-1]
        total = end - self.starts[-1] if merge else d
        if total > max_duration + 1e-9:
            raise DataError(
                self.source,
                f"phone {len(self.labels)} ({label!r}) duration",
                total,
                f"longer than max_duration={max_duration:g} s, the bound the stream's "
                "lookahead was promised for" + (" (adjacent silences merge)" if merge else ""),
                "create the stream with a larger max_duration",
            )
        if merge:
            self.ends[-1] = end
            return None
        # the model's own check of the label (unknown phones, fallback), on a one-phone alignment
        lab = self.model._known_labels(one, getattr(self.model, "unknown_phone", "error"))[0]
        self.raw.append(one.labels[0])
        self.labels.append(lab)
        self.starts.append(start)
        self.ends.append(end)
        return lab

    def alignment(self) -> Alignment:
        """The phones pushed so far (as given: the model's fallback labels are not applied)."""
        return Alignment(self.raw, self.starts, self.ends, source=self.source)


class BufferedStream(_Stream):
    """Streaming for any model: frames become final only when the utterance is finished.

    Parameters
    ----------
    model : Synthesizer
        Fitted.

    Attributes
    ----------
    lookahead : float
        ``inf``: the whole utterance.
    """

    lookahead = math.inf

    def push(self, label: str, *, end: float | None = None, duration: float | None = None) -> np.ndarray:
        """Add a phone; returns no frames (shape (0, n_channels))."""
        self._accept(label, end, duration)
        return np.zeros((0, len(self.channels)))

    def finish(self) -> np.ndarray:
        """All frames of the utterance, shape (n_frames, n_channels)."""
        if not self.labels:
            raise DataError(self.source, "phones", 0, "no phone was pushed")
        self.finished = True
        out = np.asarray(self.model.predict(self.alignment()))
        self.n_emitted = len(out)
        return out


class StreamingSynthesizer(_Stream):
    """Incremental DAM synthesis (Eq. 2 with A*-chosen modes) whose output equals batch.

    Parameters
    ----------
    model : dam.model.DAM
        A fitted DAM (or DAM with M=0).
    max_duration : float, default 0.5
        The longest phone (seconds) the stream accepts; with the dominance
        reach it fixes the lookahead. A longer phone is refused
        (:class:`dam.DataError`), since frames already returned could
        otherwise change.
    source : str, optional
        Name used in error messages.

    Attributes
    ----------
    lookahead : float
        Seconds behind the last pushed end before which frames can be
        final: ``reach * max_duration``.
    lookahead_frames : int
        The same in frames (rounded up).
    reach : float
        Truncated dominance reach of the model's widest sigma, in phone durations.

    Examples
    --------
    >>> import dam, dam.datasets
    >>> from dam.export.streaming import StreamingSynthesizer
    >>> corpus = dam.datasets.load("tiny")
    >>> model = dam.make("dam").fit(corpus)
    >>> s = StreamingSynthesizer(model, max_duration=0.5)
    >>> frames = [s.push(p, end=e) for p, e in [("sil", 0.1), ("aa", 0.25), ("sil", 0.4)]]
    >>> frames.append(s.finish())
    >>> import numpy as np
    >>> out = np.concatenate(frames)
    >>> bool(np.allclose(out, model.predict(s.alignment()), atol=1e-9))
    True
    """

    def __init__(self, model, *, max_duration: float = 0.5, source=None):
        from dam.model.dominance import reach

        super().__init__(model, source=source)
        try:
            self.max_duration = float(max_duration)
        except (TypeError, ValueError):
            raise DataError(self.source, "max_duration", max_duration, "not a number") from None
        if not (self.max_duration > 0 and math.isfinite(self.max_duration)):
            raise DataError(self.source, "max_duration", max_duration, "must be a positive finite number")
        m = model
        self._eps, self._tol = float(m.eps), float(m.dominance_tol)
        names = list(m.phone_modes_)
        self._index = {p: i for i, p in enumerate(names)}
        self._first = np.array([m.phone_modes_[p][0] for p in names], dtype=np.int64)
        count = np.array([m.phone_modes_[p][1] for p in names], dtype=np.int64)
        self._count = count
        self._G = int(count.max())
        sig_phone = np.array([m.sigma_[f : f + c].max() for f, c in zip(self._first, count)])
        self._reach_phone = reach(sig_phone, self._eps, self._tol)
        self.reach = float(reach(m.sigma_.max(), self._eps, self._tol))
        self.lookahead = self.reach * self.max_duration
        self.lookahead_frames = (
            math.inf if not math.isfinite(self.lookahead) else int(math.ceil(self.lookahead * self.frame_rate))
        )
        self._pid: list[int] = []
        self._acc = None  # Viterbi costs of the modes of the last costed segment, (G,)
        self._back: list = []  # back pointers per costed segment (None for the first)
        self._decided: list[int] = []  # global mode of segments 0 .. len-1

    # -- mode choice: Viterbi over the same node and edge costs A* minimises ----------------
    def _pad(self, row, fill=np.inf):
        out = np.full(self._G, fill)
        out[: len(row)] = row
        return out

    def _costs(self, lo: int, hi: int):
        """The model's own node and edge costs of the animeme graph of segments lo .. hi-1."""
        d = np.array(self.ends[lo:hi]) - np.array(self.starts[lo:hi])
        nodes, edges, _ = self.model._graph(self.labels[lo:hi], d)
        return nodes, edges

    def _node_row(self, j: int, last: bool) -> np.ndarray:
        """``w_c E_c`` of segment j's modes with its real neighbours (the utterance edge if none)."""
        lo = max(j - 1, 0)
        nodes, _ = self._costs(lo, j + 1 if last else j + 2)
        return self._pad(nodes[j - lo, : self._count[self._pid[j]]])

    def _edge(self, j: int) -> np.ndarray:
        """``w_s E_s`` from segment j - 1 to j, shape (G, G)."""
        _, edges = self._costs(j - 1, j + 1)
        a, b = self._count[self._pid[j - 1]], self._count[self._pid[j]]
        out = np.full((self._G, self._G), np.inf)
        out[:a, :b] = edges[0][:a, :b]
        return out

    def _step(self, j: int, last: bool) -> None:
        node = self._node_row(j, last)
        if j == 0:
            self._acc, self._back = node, [None]
            return
        tot = self._acc[:, None] + self._edge(j)
        back = np.argmin(tot, axis=0)
        self._acc = tot[back, np.arange(self._G)] + node
        self._back.append(back)

    def _trace(self, g: int, stop: int) -> list[int]:
        """Local modes of segments stop .. last costed, ending in mode g."""
        path = [g]
        for j in range(len(self._back) - 1, stop, -1):
            g = int(self._back[j][g])
            path.append(g)
        return path[::-1]

    def _decide(self, final: bool) -> None:
        n_costed = len(self._back)
        k = len(self._decided)
        if n_costed == k:
            return
        if final:
            paths = [self._trace(int(np.argmin(self._acc)), k)]
        else:
            alive = np.flatnonzero(np.isfinite(self._acc))
            paths = [self._trace(int(g), k) for g in alive]
        paths = np.array(paths)  # (n_paths, n_costed - k)
        agree = np.all(paths == paths[0], axis=0)
        n_new = len(agree) if agree.all() else int(np.argmin(agree))
        for i in range(n_new):
            pid = self._pid[k + i]
            self._decided.append(int(self._first[pid] + paths[0, i]))

    # -- frames -------------------------------------------------------------------------------
    def _frames(self, a: int, b: int) -> np.ndarray:
        """Frames a .. b-1 from the decided segments (times shifted by a frames: O(1) per call)."""
        from dam.model.synthesis import concatenate

        C = len(self.channels)
        if b <= a:
            return np.zeros((0, C))
        n = len(self._decided)
        s = np.array(self.starts[:n])
        e = np.array(self.ends[:n])
        r = self._reach_phone[np.array(self._pid[:n], dtype=np.int64)]
        t0, t1 = a / self.frame_rate, b / self.frame_rate
        use = np.flatnonzero((e + r * (e - s) >= t0 - 1e-6) & (s - r * (e - s) <= t1 + 1e-6))
        if use.size == 0:
            return np.zeros((b - a, C))
        glob = np.array(self._decided)[use]
        m = self.model
        return concatenate(
            s[use] - t0,
            e[use] - t0,
            m.coef_[glob],
            m.sigma_[glob],
            self.frame_rate,
            b - a,
            normalize=bool(m.normalize),
            extrapolate=m.extrapolate,
            eps=self._eps,
            tol=self._tol,
            support=m._support_of(glob),
        )

    def _emit(self, bound_frames: int) -> np.ndarray:
        a = self.n_emitted
        b = max(a, bound_frames)
        out = self._frames(a, b)
        self.n_emitted = b
        return out

    def push(self, label: str, *, end: float | None = None, duration: float | None = None) -> np.ndarray:
        """Add the next phone; returns the frames that became final, shape (n_new, n_channels).

        Parameters
        ----------
        label : str
        end : float, optional
            End time in seconds (the phone starts where the previous ended, the first at 0).
        duration : float, optional
            Instead of ``end``.
        """
        lab = self._accept(label, end, duration, self.max_duration)
        if lab is not None:
            self._pid.append(self._index[lab])
            j = len(self._pid) - 1
            if j >= 1:
                self._step(j - 1, last=False)  # segment j-1 now has its right neighbour and final length
                self._decide(final=False)
        undecided = range(len(self._decided), len(self._pid))
        bound = self.end - self.lookahead
        for i in undecided:
            d = self.ends[i] - self.starts[i]
            if i == len(self._pid) - 1 and self.raw[i] == self.alignment_silence:
                d = self.max_duration  # a trailing silence may still grow (silences merge)
            bound = min(bound, self.starts[i] - self._reach_phone[self._pid[i]] * d)
        if not math.isfinite(bound):
            return np.zeros((0, len(self.channels)))
        return self._emit(int(math.ceil(bound * self.frame_rate - 1e-6)))

    def finish(self) -> np.ndarray:
        """Close the utterance; returns every frame not yet returned."""
        if not self._pid:
            raise DataError(self.source, "phones", 0, "no phone was pushed")
        if self.finished:
            return np.zeros((0, len(self.channels)))
        if len(self._pid) == 1:  # a graph of one segment: the model's own choice
            self._decided = [int(g) for g in self.model.select_modes(self.alignment())[0]]
        else:
            self._step(len(self._pid) - 1, last=True)
            self._decide(final=True)
        self.finished = True
        return self._emit(self.alignment().n_frames(self.frame_rate))

    @property
    def modes(self) -> list[int]:
        """Global modes decided so far (rows of ``model.coef_``), one per phone from the first."""
        return list(self._decided)
