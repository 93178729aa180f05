"""Import paths of dam 0.1 (the flat layout), kept for one release with a DeprecationWarning.

``import dam.data`` (and the rest below) returns the module at its new place and warns
once. Remove in 0.3.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys
import warnings

MOVED = {
    "dam.data": "dam.corpus.data",
    "dam.io": "dam.corpus.io",
    "dam.est": "dam.corpus.formats.est",
    "dam.phonetics": "dam.corpus.phonetics",
    "dam.features": "dam.corpus.features",
    **{
        f"dam.{m}": f"dam.model.{m}"
        for m in ("dominance", "animeme", "astar", "em", "estep", "mstep", "modes", "synthesis")
    },
    "dam.metrics": "dam.evaluation.metrics",
    "dam.compare": "dam.evaluation.compare",
    **{f"dam.{m}": f"dam.crossmap.{m}" for m in ("rig", "retarget", "landmarks", "outlines")},
    "dam.cli_rig": "dam.cli.rig",
}


class _Alias(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    def find_spec(self, fullname, path=None, target=None):
        if fullname in MOVED:
            return importlib.util.spec_from_loader(fullname, self)
        return None

    def create_module(self, spec):
        new = MOVED[spec.name]
        warnings.warn(
            f"{spec.name} moved to {new}; the old path goes away in dam 0.3", DeprecationWarning, stacklevel=3
        )
        return importlib.import_module(new)

    def exec_module(self, module):
        pass  # the module is already executed at its new place


def install() -> None:
    if not any(isinstance(f, _Alias) for f in sys.meta_path):
        sys.meta_path.append(_Alias())
