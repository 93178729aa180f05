"""Progress of long runs: one reporter, any depth of nested work, an honest ETA.

Long loops of the toolkit (the DAM's and Cohen–Massaro's channels, the
models and folds of a comparison, the epochs of a network) announce their
work units here; whoever started the run decides where progress goes:

* ``"bar"``: one line on standard error, redrawn in place, with the units
  done, the percentage, the time spent and the time left;
* ``"json"``: one JSON object per line on standard error for every step
  (``{"type": "progress", "task": ..., "done": ..., "total": ..., "fraction": ...,
  "elapsed": ..., "eta": ...}``, plus ``"start"`` and ``"end"`` events), for tools
  that embed dam, as Rhubarb Lip Sync's ``--machineReadable``;
* ``"none"``: nothing.

``mode="auto"`` (what the command line uses) is the bar on a terminal and
nothing otherwise. A library call made without :func:`reporting` reports
nothing.

The ETA is ``elapsed * (1 - f) / f`` where ``f`` is the fraction of the
*expected cost* done: every unit carries a weight (its expected cost; equal
by default), and a unit still running counts by the fraction its own nested
work has reached. Counting units alone would promise "4:52 left" after the
cheap models of a comparison finished first.

Examples
--------
>>> from dam import progress
>>> with progress.reporting("none"):
...     for c in progress.track(range(3), "channels", unit="channel"):
...         pass
"""

from __future__ import annotations

import contextlib
import contextvars
import json
import sys
import threading
import time

__all__ = ["Reporter", "reporting", "track", "task", "current", "active", "resolve_mode", "MODES"]

MODES = ("auto", "bar", "json", "none")


class _Task:
    """One level of work: ``total`` units with weights, ``done`` of them finished."""

    def __init__(self, name: str, weights, unit: str):
        self.name, self.unit = name, unit
        self.weights = [float(w) for w in weights]
        self.total_weight = sum(self.weights) or 1.0
        self.done = 0  # units finished
        self.done_weight = 0.0
        self.running = 0  # index of the unit being worked on (for nested fractions)
        self.label = ""

    @property
    def total(self) -> int:
        return len(self.weights)


class Reporter:
    """Where progress goes (``"bar"``, ``"json"`` or ``"none"``).

    Parameters
    ----------
    mode : {"bar", "json", "none"}
    stream : file, default sys.stderr
    tick : float, default 1.0
        Seconds between redraws of the bar while a unit runs (the elapsed
        time keeps moving on long units); 0 for none.
    """

    def __init__(self, mode: str = "bar", stream=None, tick: float = 1.0):
        if mode not in ("bar", "json", "none"):
            raise ValueError(f"progress mode is {mode!r}; use one of {', '.join(MODES)}")
        self.mode = mode
        self.stream = stream if stream is not None else sys.stderr
        self.stack: list[_Task] = []
        self.t0: float | None = None
        self._lock = threading.Lock()
        self._width = 0
        self._tick = tick
        self._stop: threading.Event | None = None

    # -- the fraction of expected cost done, over every nesting level --------
    def fraction(self) -> float:
        """Fraction of the outermost task's expected cost done, in [0, 1]."""
        f, scale = 0.0, 1.0
        for t in self.stack:
            f += scale * t.done_weight / t.total_weight
            if t.done >= t.total:
                break
            scale *= t.weights[min(t.running, t.total - 1)] / t.total_weight
        return min(max(f, 0.0), 1.0)

    def eta(self) -> float | None:
        """Seconds left, or None before any work is done."""
        f = self.fraction()
        if self.t0 is None or f <= 0.0:
            return None
        return (time.perf_counter() - self.t0) * (1.0 - f) / f

    # -- events ----------------------------------------------------------------
    def start(self, name: str, weights, unit: str) -> _Task:
        with self._lock:
            t = _Task(name, weights, unit)
            if not self.stack:
                self.t0 = time.perf_counter()
                self._start_ticker()
            self.stack.append(t)
            self._emit("start", t)
        return t

    def step(self, t: _Task, label: str = "", index: int | None = None) -> None:
        """A unit of ``t`` finished: unit ``index``, or the next in order (``label`` says which)."""
        with self._lock:
            i = t.done if index is None else int(index)
            if 0 <= i < t.total:
                t.done_weight += t.weights[i]
            t.done += 1
            t.running = t.done
            t.label = label
            self._emit("progress", t)

    def begin(self, t: _Task, label: str = "") -> None:
        """Unit ``t.done`` of ``t`` starts (shown while it runs)."""
        with self._lock:
            t.label = label
            self._emit("begin", t)

    def end(self, t: _Task) -> None:
        with self._lock:
            self._emit("end", t)
            if t in self.stack:
                self.stack.remove(t)
            if not self.stack:
                self._stop_ticker()
                if self.mode == "bar" and self._width:
                    self.stream.write("\r" + " " * self._width + "\r")
                    self.stream.flush()
                    self._width = 0
                self.t0 = None

    # -- output ----------------------------------------------------------------
    def _emit(self, kind: str, t: _Task) -> None:
        if self.mode == "none":
            return
        elapsed = 0.0 if self.t0 is None else time.perf_counter() - self.t0
        if self.mode == "json":
            if kind == "begin":
                return
            eta = self.eta()
            rec = {
                "type": kind,
                "task": t.name,
                "unit": t.unit,
                "done": t.done,
                "total": t.total,
                "label": t.label,
                "depth": self.stack.index(t) if t in self.stack else 0,
                "fraction": round(self.fraction(), 4),
                "elapsed": round(elapsed, 3),
                "eta": None if eta is None else round(eta, 3),
            }
            self.stream.write(json.dumps(rec) + "\n")
            self.stream.flush()
            return
        self._draw()

    def _draw(self) -> None:
        if not self.stack:
            return
        elapsed = time.perf_counter() - self.t0
        eta = self.eta()
        parts = [f"{t.name} {t.done}/{t.total} {t.unit}{'s' if t.total != 1 else ''}" for t in self.stack]
        label = next((t.label for t in reversed(self.stack) if t.label), "")
        line = (
            f"{' > '.join(parts)}  {100 * self.fraction():3.0f}%  {_clock(elapsed)} elapsed, "
            f"{'?' if eta is None else _clock(eta)} left" + (f"  [{label}]" if label else "")
        )
        pad = max(0, self._width - len(line))
        self.stream.write("\r" + line + " " * pad)
        self.stream.flush()
        self._width = len(line)

    def _start_ticker(self) -> None:
        if self.mode != "bar" or not self._tick:
            return
        self._stop = threading.Event()

        def run(stop=self._stop):
            while not stop.wait(self._tick):
                with self._lock:
                    if self.stack:
                        self._draw()

        threading.Thread(target=run, daemon=True, name="dam-progress").start()

    def _stop_ticker(self) -> None:
        if self._stop is not None:
            self._stop.set()
            self._stop = None


def _clock(seconds: float) -> str:
    s = int(round(seconds))
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}" if s >= 3600 else f"{s // 60}:{s % 60:02d}"


_NULL = Reporter("none")
_CURRENT: contextvars.ContextVar[Reporter] = contextvars.ContextVar("dam_progress", default=_NULL)


def current() -> Reporter:
    """The active reporter (a silent one outside :func:`reporting`)."""
    return _CURRENT.get()


def active() -> bool:
    """Whether a :func:`reporting` block (of any mode, ``"none"`` included) is in force."""
    return _CURRENT.get() is not _NULL


def resolve_mode(mode: str = "auto", *, quiet: bool = False, stream=None) -> str:
    """``"bar"``, ``"json"`` or ``"none"`` for ``mode``: ``"auto"`` is the bar on a terminal."""
    if mode not in MODES:
        raise ValueError(f"progress mode is {mode!r}; use one of {', '.join(MODES)}")
    if mode == "json":
        return "json"  # asked for explicitly: machine-readable even when quiet about the rest
    if quiet or mode == "none":
        return "none"
    stream = stream if stream is not None else sys.stderr
    if mode == "bar":
        return "bar"
    return "bar" if getattr(stream, "isatty", lambda: False)() else "none"


@contextlib.contextmanager
def reporting(mode: str = "auto", *, quiet: bool = False, stream=None):
    """Send the progress of everything run inside to ``mode`` (see the module docstring).

    Parameters
    ----------
    mode : {"auto", "bar", "json", "none"}, default "auto"
    quiet : bool, default False
        Silences ``"auto"`` and ``"bar"`` (not ``"json"``, which was asked for).
    stream : file, default sys.stderr

    Yields
    ------
    Reporter
    """
    rep = Reporter(resolve_mode(mode, quiet=quiet, stream=stream), stream=stream)
    token = _CURRENT.set(rep)
    try:
        yield rep
    finally:
        _CURRENT.reset(token)
        for t in list(reversed(rep.stack)):
            rep.end(t)


@contextlib.contextmanager
def task(name: str, total: int | None = None, *, weights=None, unit: str = "step"):
    """A unit of nested work; ``step(label)`` after each unit, ``begin(label)`` before it.

    Parameters
    ----------
    name : str
        What is being done (``"DAM EM"``, ``"compare"``).
    total : int, optional
        Number of units (or give ``weights``).
    weights : sequence of float, optional
        Expected cost of every unit (default: equal); the ETA weighs by it.
    unit : str, default "step"
        Singular noun for a unit (``"channel"``, ``"epoch"``).

    Yields
    ------
    handle with ``step(label="", index=None)`` (``index``: which unit finished, when units
    finish out of order) and ``begin(label="")``
    """
    if weights is None:
        if total is None:
            raise ValueError("give total or weights")
        weights = [1.0] * int(total)
    rep = current()
    t = rep.start(name, weights, unit)

    class _Handle:
        def step(self, label: str = "", index: int | None = None) -> None:
            rep.step(t, label, index)

        def begin(self, label: str = "") -> None:
            rep.begin(t, label)

    try:
        yield _Handle()
    finally:
        rep.end(t)


def track(iterable, name: str, *, unit: str = "step", labels=None, weights=None, total: int | None = None):
    """Iterate over ``iterable``, reporting a step after each item.

    Parameters
    ----------
    iterable : iterable
    name, unit : str
        As :func:`task`.
    labels : sequence of str, optional
        Shown for each item (e.g. the channel names).
    weights : sequence of float, optional
        Expected cost of each item.
    total : int, optional
        Number of items when ``iterable`` has no ``len``.

    Yields
    ------
    the items of ``iterable``
    """
    items = iterable if hasattr(iterable, "__len__") else list(iterable) if total is None else iterable
    n = total if total is not None else len(items)
    with task(name, n, weights=weights, unit=unit) as h:
        for i, item in enumerate(items):
            lab = str(labels[i]) if labels is not None and i < len(labels) else ""
            h.begin(lab)
            yield item
            h.step(lab)
