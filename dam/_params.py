"""Parameter constraints: what every hyperparameter may be, declared once per class.

In the spirit of scikit-learn's ``_parameter_constraints``
(``sklearn/utils/_param_validation.py``): a synthesizer declares, for each
``__init__`` parameter, a list of constraints, and the value must satisfy at
least one of them. :meth:`dam.Synthesizer.fit` checks them before any work, and
:func:`dam.testing.check_parameter_constraints` (the conformance suite)
generates wrong values from the same declarations and asks that each is refused.

The vocabulary:

* :class:`Interval` ``(int | float, left, right, closed=...)``: a number in a
  range. ``int`` excludes ``bool`` (``degree=True`` is an error, not 1);
  ``float`` takes ints and floats but never NaN or infinity.
* :class:`Options` ``(values)``: one of a set of strings (or a mapping's keys,
  looked up when checked, so a registry can grow).
* :class:`TupleOf` ``(item, min_len=1, max_len=None, increasing=False)``: a
  tuple or list whose every item satisfies ``item``.
* ``"boolean"``: ``True`` or ``False`` (numpy's too); ``"random_state"``: ``None``
  or an int seed in ``[0, 2**32 - 1]``; ``"callable"``: anything callable;
  ``None``: the value ``None``; a class: an instance of it.

Examples
--------
>>> from dam._params import Interval, Options, validate_params
>>> constraints = {"degree": [Interval(int, 0, None, closed="left")],
...                "unknown_phone": [Options({"error", "fallback"})]}
>>> validate_params("DAM", constraints, {"degree": 4, "unknown_phone": "error"})
>>> validate_params("DAM", constraints, {"degree": True, "unknown_phone": "error"})
Traceback (most recent call last):
...
dam._params.InvalidParameterError: DAM: parameter 'degree' is True; it must be an int in [0, inf)
"""

from __future__ import annotations

import math
import numbers

import numpy as np

__all__ = [
    "InvalidParameterError",
    "Constraint",
    "Interval",
    "Options",
    "TupleOf",
    "make_constraint",
    "validate_params",
    "invalid_values",
]

_CLOSED = {"both": "[]", "left": "[)", "right": "(]", "neither": "()"}


class InvalidParameterError(ValueError, TypeError):
    """A hyperparameter outside its declared constraints (a ValueError and a TypeError,
    as scikit-learn's, so either ``except`` catches it)."""


class Constraint:
    """One thing a parameter may be. Subclasses say what satisfies them and give
    values that do not (for the generated tests)."""

    #: Whether the constraint restricts a range (bounds, options, a length), so that it
    #: must give out-of-range values besides wrong-typed ones.
    bounded = True

    def is_satisfied_by(self, value) -> bool:  # pragma: no cover - abstract
        raise NotImplementedError

    def __str__(self) -> str:  # pragma: no cover - abstract
        raise NotImplementedError

    def invalid_values(self) -> dict[str, list]:
        """Values this constraint refuses: ``{"wrong type": [...], "out of range": [...]}``."""
        return {"wrong type": [], "out of range": []}

    def __repr__(self) -> str:
        return f"<{type(self).__name__}: {self}>"


def _is_bool(value) -> bool:
    return isinstance(value, (bool, np.bool_))


class Interval(Constraint):
    """A number in a range.

    Parameters
    ----------
    kind : {int, float}
        ``int`` (numpy integers too, never ``bool``) or ``float`` (any finite real
        number, ints included, never ``bool``, NaN or infinity).
    left, right : number or None
        Bounds; None is unbounded.
    closed : {"both", "left", "right", "neither"}, default "both"
        Which bounds belong to the interval.

    Examples
    --------
    >>> import dam
    >>> degree = dam.Interval(int, 0, None, closed="left")
    >>> str(degree), degree.is_satisfied_by(4), degree.is_satisfied_by(True), degree.is_satisfied_by(4.0)
    ('an int in [0, inf)', True, False, False)
    >>> dam.Interval(float, 0, 1, closed="left").is_satisfied_by(float("nan"))
    False
    """

    def __init__(self, kind, left, right, *, closed: str = "both"):
        if kind in (int, numbers.Integral):
            kind = int
        elif kind in (float, numbers.Real):
            kind = float
        else:
            raise TypeError(f"Interval kind must be int or float, not {kind!r}")
        if closed not in _CLOSED:
            raise ValueError(f"Interval closed must be one of {sorted(_CLOSED)}, not {closed!r}")
        if left is not None and right is not None and left > right:
            raise ValueError(f"Interval left bound {left} is above its right bound {right}")
        self.kind, self.left, self.right, self.closed = kind, left, right, closed
        self.bounded = left is not None or right is not None

    def _type_ok(self, value) -> bool:
        if _is_bool(value):
            return False
        if self.kind is int:
            return isinstance(value, (int, np.integer))
        return isinstance(value, (int, float, np.integer, np.floating)) and math.isfinite(value)

    def is_satisfied_by(self, value) -> bool:
        if not self._type_ok(value):
            return False
        lo_ok = self.left is None or (value >= self.left if self.closed in ("both", "left") else value > self.left)
        hi_ok = self.right is None or (value <= self.right if self.closed in ("both", "right") else value < self.right)
        return bool(lo_ok and hi_ok)

    def __str__(self) -> str:
        what = "an int" if self.kind is int else "a finite number"
        lb, rb = _CLOSED[self.closed]
        lo = "-inf" if self.left is None else f"{self.left:g}"
        hi = "inf" if self.right is None else f"{self.right:g}"
        if self.left is None:
            lb = "("
        if self.right is None:
            rb = ")"
        if self.left is None and self.right is None:
            return what
        return f"{what} in {lb}{lo}, {hi}{rb}"

    def invalid_values(self) -> dict[str, list]:
        wrong = ["abc", True, None] + ([1.5] if self.kind is int else [float("nan"), float("inf")])
        out = []
        for bound, inside, step in (
            (self.left, self.closed in ("both", "left"), -1),
            (self.right, self.closed in ("both", "right"), +1),
        ):
            if bound is None:
                continue
            if self.kind is int:
                out.append(int(math.floor(bound) if step < 0 else math.ceil(bound)) + (step if inside else 0))
            else:
                out.append(float(np.nextafter(float(bound), step * np.inf)) if inside else float(bound))
        return {"wrong type": wrong, "out of range": [v for v in out if not self.is_satisfied_by(v)]}


class Options(Constraint):
    """One of a set of values (strings, normally).

    Parameters
    ----------
    options : set, tuple or mapping
        The allowed values; a mapping's keys are read when a value is checked,
        so the options of a registry (e.g. the input encoders) stay current.

    Examples
    --------
    >>> import dam
    >>> unknown_phone = dam.Options({"error", "fallback"})
    >>> str(unknown_phone), unknown_phone.is_satisfied_by("fallback"), unknown_phone.is_satisfied_by("guess")
    ("'error' or 'fallback'", True, False)
    """

    def __init__(self, options):
        self._options = options

    @property
    def options(self) -> list:
        return sorted(self._options, key=repr)

    def is_satisfied_by(self, value) -> bool:
        if _is_bool(value):
            return any(_is_bool(o) and o == value for o in self._options)
        try:
            return any(type(value) is type(o) and value == o for o in self._options) or (
                isinstance(value, str) and value in [o for o in self._options if isinstance(o, str)]
            )
        except TypeError:
            return False

    def __str__(self) -> str:
        opts = self.options
        return repr(opts[0]) if len(opts) == 1 else ", ".join(map(repr, opts[:-1])) + f" or {opts[-1]!r}"

    def invalid_values(self) -> dict[str, list]:
        strs = all(isinstance(o, str) for o in self._options)
        return {
            "wrong type": [1.5, ["x"]] if strs else ["abc"],
            "out of range": ["zz-not-an-option"] if strs else [-987654],
        }


class TupleOf(Constraint):
    """A tuple or list of items that each satisfy ``item``.

    Parameters
    ----------
    item : constraint
        What every element must be (anything :func:`make_constraint` takes).
    min_len : int, default 1
    max_len : int or None, default None
    increasing : bool, default False
        The elements must be strictly increasing (e.g. ``(low, high)`` bounds).

    Examples
    --------
    >>> import dam
    >>> bounds = dam.TupleOf(dam.Interval(float, 0, None, closed="neither"), min_len=2, max_len=2, increasing=True)
    >>> bounds.is_satisfied_by((0.25, 4.0)), bounds.is_satisfied_by((4.0, 0.25)), bounds.is_satisfied_by("ab")
    (True, False, False)
    """

    def __init__(self, item, *, min_len: int = 1, max_len: int | None = None, increasing: bool = False):
        self.item = make_constraint(item)
        self.min_len, self.max_len, self.increasing = min_len, max_len, increasing

    def is_satisfied_by(self, value) -> bool:
        if not isinstance(value, (tuple, list)):
            return False
        if len(value) < self.min_len or (self.max_len is not None and len(value) > self.max_len):
            return False
        if not all(self.item.is_satisfied_by(v) for v in value):
            return False
        return not self.increasing or all(a < b for a, b in zip(value, value[1:]))

    def __str__(self) -> str:
        if self.max_len == self.min_len:
            n = f"{self.min_len}"
        elif self.max_len is None:
            n = f"{self.min_len} or more"
        else:
            n = f"{self.min_len} to {self.max_len}"
        inc = ", increasing" if self.increasing else ""
        return f"a tuple of {n} items ({self.item}{inc})"

    def invalid_values(self) -> dict[str, list]:
        good = _example(self.item)
        out = []
        if self.min_len > 0:
            out.append(tuple([good] * (self.min_len - 1)))
        if self.max_len is not None:
            out.append(tuple([good] * (self.max_len + 1)))
        out += [(v,) * max(self.min_len, 1) for v in self.item.invalid_values()["out of range"][:1]]
        if self.increasing and self.min_len >= 2:
            out.append((good,) * self.min_len)  # equal items: not strictly increasing
        return {"wrong type": ["abc", 3.5], "out of range": [v for v in out if not self.is_satisfied_by(v)]}


def _example(c: Constraint):
    """A value ``c`` accepts (for building invalid tuples from valid items)."""
    if isinstance(c, Interval):
        if c.left is not None:
            v = c.left if c.closed in ("both", "left") else c.left + 1
        elif c.right is not None:
            v = c.right if c.closed in ("both", "right") else c.right - 1
        else:
            v = 0
        return c.kind(v)
    if isinstance(c, Options):
        return c.options[0]
    return None


class _Boolean(Constraint):
    bounded = False

    def is_satisfied_by(self, value) -> bool:
        return _is_bool(value)

    def __str__(self) -> str:
        return "True or False"

    def invalid_values(self) -> dict[str, list]:
        return {"wrong type": ["yes", 1, None], "out of range": []}


class _RandomState(Constraint):
    def is_satisfied_by(self, value) -> bool:
        return value is None or (
            isinstance(value, (int, np.integer)) and not _is_bool(value) and 0 <= value <= 2**32 - 1
        )

    def __str__(self) -> str:
        return "None or an int seed in [0, 4294967295]"

    def invalid_values(self) -> dict[str, list]:
        return {"wrong type": ["abc", 1.5, True], "out of range": [-1, 2**32]}


class _Callable(Constraint):
    bounded = False

    def is_satisfied_by(self, value) -> bool:
        return callable(value)

    def __str__(self) -> str:
        return "a callable"

    def invalid_values(self) -> dict[str, list]:
        return {"wrong type": ["abc", 1], "out of range": []}


class _NoneConstraint(Constraint):
    bounded = False

    def is_satisfied_by(self, value) -> bool:
        return value is None

    def __str__(self) -> str:
        return "None"


class _InstanceOf(Constraint):
    bounded = False

    def __init__(self, cls: type):
        self.cls = cls

    def is_satisfied_by(self, value) -> bool:
        return isinstance(value, self.cls)

    def __str__(self) -> str:
        return f"an instance of {self.cls.__name__}"

    def invalid_values(self) -> dict[str, list]:
        return {"wrong type": [v for v in (object(), "abc") if not isinstance(v, self.cls)], "out of range": []}


_NAMED = {"boolean": _Boolean, "random_state": _RandomState, "callable": _Callable}


def make_constraint(spec) -> Constraint:
    """The :class:`Constraint` an entry of a constraint list stands for."""
    if isinstance(spec, Constraint):
        return spec
    if spec is None:
        return _NoneConstraint()
    if isinstance(spec, str):
        if spec not in _NAMED:
            raise ValueError(
                f"unknown constraint {spec!r}; use one of {sorted(_NAMED)}, None, a class, Interval, Options or TupleOf"
            )
        return _NAMED[spec]()
    if isinstance(spec, type):
        return _InstanceOf(spec)
    raise TypeError(f"not a parameter constraint: {spec!r}")


def _constraints(specs) -> list[Constraint]:
    return [make_constraint(s) for s in (specs if isinstance(specs, list) else [specs])]


def describe(specs) -> str:
    """What a constraint list allows, in words: ``"None or a finite number in (0, inf)"``."""
    return " or ".join(str(c) for c in _constraints(specs))


def validate_params(owner: str, constraints: dict, params: dict) -> None:
    """Check every parameter of ``params`` that ``constraints`` declares.

    Parameters
    ----------
    owner : str
        The class name, for the message.
    constraints : dict
        ``{parameter: [constraint, ...]}``; a value must satisfy one of its list.
    params : dict
        ``{parameter: value}``; undeclared parameters are not checked
        (the conformance suite asks that none is left undeclared).

    Raises
    ------
    InvalidParameterError
        Naming the class, the parameter, the value and what is allowed.
    """
    for name, value in params.items():
        if name not in constraints:
            continue
        cs = _constraints(constraints[name])
        if not any(c.is_satisfied_by(value) for c in cs):
            raise InvalidParameterError(f"{owner}: parameter {name!r} is {value!r}; it must be {describe(cs)}")


def invalid_values(specs) -> list[tuple[str, object]]:
    """``(kind, value)`` pairs that no constraint of ``specs`` accepts, ``kind`` being
    "wrong type" or "out of range": what the generated tests try."""
    cs = _constraints(specs)
    out, seen = [], []
    for c in cs:
        for kind, values in c.invalid_values().items():
            for v in values:
                if any(o.is_satisfied_by(v) for o in cs):
                    continue
                if any(type(v) is type(s) and _same(v, s) for s in seen):
                    continue
                seen.append(v)
                out.append((kind, v))
    return out


def _same(a, b) -> bool:
    try:
        return bool(a == b) or (a != a and b != b)
    except Exception:
        return False
