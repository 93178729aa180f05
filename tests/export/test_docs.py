"""The Examples in dam.export's docstrings run (dam.export is not among tests/test_docs.py's packages)."""

import doctest
import importlib
import warnings

import pytest

MODULES = [
    "dam.export",
    "dam.export.tables",
    "dam.export.gltf",
    "dam.export.meshes",
    "dam.export.presets",
    "dam.export.textgrid",
    "dam.export.streaming",
    "dam.export.runtime",
]


@pytest.mark.parametrize("name", MODULES)
def test_examples_run(name, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    mod = importlib.import_module(name)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = doctest.testmod(mod, optionflags=doctest.ELLIPSIS)
    assert result.failed == 0


def test_public_functions_are_documented_with_shapes():
    from dam.export import export
    from dam.export.streaming import StreamingSynthesizer

    for obj in (export, StreamingSynthesizer):
        doc = obj.__doc__
        assert "Parameters\n    ----------" in doc and "Examples\n    --------" in doc
