"""The Dominated Animeme Model (Chen et al. 2012), one file per step of the paper.

Training (Section V):

- :mod:`~dam.model.dominance`: the dominance function, Eq. (1).
- :mod:`~dam.model.animeme`: the polynomial animeme (degree M), in a shifted Legendre basis.
- :mod:`~dam.model.modes`: modes per phone by affinity propagation.
- :mod:`~dam.model.estep`: the least-squares E-step, Eqs. (3)-(7).
- :mod:`~dam.model.mstep`: the Gauss-Newton M-step on sigma.
- :mod:`~dam.model.em`: the EM alternation of the two.

Synthesis (Section VI):

- :mod:`~dam.model.astar`: one mode per segment over the animeme graph: the paper's A*, and the
  exact dynamic program synthesis runs (proven equal to it by the tests); the graph's fixed part
  (:class:`~dam.model.astar.ModeGraph`) is built once at the end of fit and at load.
- :mod:`~dam.model.synthesis`: concatenation by Eq. (2).

The estimator :class:`DAM` (and the presets :class:`DAMM0`, M = 0, and :class:`DAMPaper`, the
paper's literal plain-sum Eq. (2) with M = 4) lives in
:mod:`~dam.model.estimator`; :func:`inspect_report` in :mod:`~dam.model.inspection`.
"""

from __future__ import annotations

from dam._lazy import lazy_exports

_EXPORTS = {"DAM": ".estimator", "DAMM0": ".estimator", "DAMPaper": ".estimator", "inspect_report": ".inspection"}
_SUBMODULES = ("dominance", "animeme", "modes", "estep", "mstep", "em", "astar", "synthesis", "estimator", "inspection")
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, _SUBMODULES)

__all__ = ["DAM", "DAMM0", "DAMPaper", "inspect_report"]
