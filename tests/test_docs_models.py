"""docs/models.rst explains every registered model: a section, an equation, a figure that exists and is
small, and a `dam fit` line that names the model."""

import re
from pathlib import Path

import pytest
from PIL import Image

import dam

DOCS = Path(__file__).resolve().parent.parent / "docs"


def _sections():
    text = (DOCS / "models.rst").read_text(encoding="utf-8")
    parts = re.split(r"\n``([\w-]+)``: [^\n]+\n-+\n", text)
    return dict(zip(parts[1::2], parts[2::2]))


@pytest.mark.parametrize("name", dam.registry.names())
def test_every_registered_model_is_explained(name):
    sections = _sections()
    assert name in sections, f"docs/models.rst has no section for {name}"
    body = sections[name]
    assert ".. math::" in body
    assert re.search(rf"\$ dam fit {re.escape(name)} \S+ -o {re.escape(name)}\.npz", body)
    assert f".. image:: models/{name}.png" in body
    png = DOCS / "models" / f"{name}.png"
    assert png.exists(), f"run python docs/make_model_figures.py {name}"
    assert png.stat().st_size < 60_000  # small figures in the repository
    assert max(Image.open(png).size) <= 800


def test_no_section_for_a_model_that_is_not_registered():
    assert set(_sections()) <= set(dam.registry.names())
