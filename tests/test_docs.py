"""The API reference builds, and the Examples in the public docstrings run (doctest).

The reference is generated from the numpydoc docstrings (docs/, Sphinx autosummary), so a
docstring that breaks it, or a module that no longer imports, fails here.
"""

import doctest
import importlib
import inspect
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

import dam

DOCS = Path(__file__).resolve().parent.parent / "docs"
PUBLIC_PACKAGES = ["dam", "dam.corpus", "dam.model", "dam.evaluation", "dam.crossmap"]


def _public_objects():
    seen = {}
    for pkg_name in PUBLIC_PACKAGES:
        pkg = importlib.import_module(pkg_name)
        for name in getattr(pkg, "__all__", []):
            obj = getattr(pkg, name)
            if inspect.isclass(obj) or inspect.isfunction(obj):
                seen.setdefault(f"{obj.__module__}.{obj.__qualname__}", obj)
    return seen


@pytest.mark.skipif(not DOCS.joinpath("conf.py").exists(), reason="run from a checkout: docs/ is not installed")
def test_api_reference_builds(tmp_path):
    import shutil

    shutil.rmtree(DOCS / "api" / "generated", ignore_errors=True)  # autosummary's output: stale pages would fail
    out = subprocess.run(
        [
            sys.executable,
            "-m",
            "sphinx",
            "-q",
            "-b",
            "html",
            "-d",
            str(tmp_path / "doctrees"),
            str(DOCS),
            str(tmp_path / "html"),
        ],
        capture_output=True,
        text=True,
        env={**os.environ, "MPLBACKEND": "Agg"},
    )
    problems = [
        line for line in out.stderr.splitlines() if "ERROR" in line or "failed to import" in line or "CRITICAL" in line
    ]
    assert out.returncode == 0, out.stderr[-3000:]
    assert not problems, "\n".join(problems[:30])
    html = tmp_path / "html" / "api" / "generated"
    for name in ("dam.Corpus", "dam.Synthesizer", "dam.model.DAM", "dam.evaluation.compare"):
        assert any(html.glob(f"{name.rsplit('.', 1)[0]}*.html")), name


TOP_LEVEL = [n for n in dam.__all__ if inspect.isclass(getattr(dam, n)) or inspect.isfunction(getattr(dam, n))]


@pytest.mark.parametrize("name", TOP_LEVEL)
def test_top_level_names_have_runnable_examples(name):
    obj = getattr(dam, name)
    if inspect.isclass(obj) and issubclass(obj, Warning | Exception):
        pytest.skip("an exception type: its examples are the functions that raise it")
    doc = inspect.getdoc(obj) or ""
    assert "Examples\n--------" in doc, f"dam.{name} has no Examples section"


@pytest.mark.parametrize("qualname", sorted(_public_objects()))
def test_docstring_examples_run(qualname, tmp_path, monkeypatch):
    obj = _public_objects()[qualname]
    monkeypatch.chdir(tmp_path)  # examples that write files write here,
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))  # and so do those that make a tempfile.mkdtemp()
    finder = doctest.DocTestFinder(recurse=False)
    module = inspect.getmodule(obj)
    # as doctest runs a module's examples: in the module's namespace
    tests = [t for t in finder.find(obj, qualname, module=module, globs={**vars(module), "dam": dam}) if t.examples]
    if not tests:
        pytest.skip("no examples in this docstring")
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    for t in tests:
        runner.run(t)
    assert runner.failures == 0, f"{runner.failures} failing example(s) in {qualname}; run it with doctest -v"
