"""The tutorial notebooks run top to bottom (nbclient, a real Jupyter kernel) and say what they teach.

Each notebook is executed once per test session in a temporary directory; any cell that raises
fails the run. The key outputs are read back from the executed cells (by their tags) and checked
against what the lesson claims.
"""

import ast
import json
import re
import subprocess
import sys
from pathlib import Path

import nbformat
import pytest
from nbclient import NotebookClient
from PIL import Image

ROOT = Path(__file__).resolve().parent.parent.parent
EXAMPLES = ROOT / "examples"


def _execute(name, tmp_path_factory):
    path = EXAMPLES / name
    if not path.exists():
        pytest.fail(f"{path} is missing (run from a checkout)")
    nb = nbformat.read(path, as_version=4)
    cwd = tmp_path_factory.mktemp(path.stem)
    client = NotebookClient(nb, timeout=600, kernel_name="python3", resources={"metadata": {"path": str(cwd)}})
    client.execute()  # raises CellExecutionError on the first failing cell
    return nb, cwd


@pytest.fixture(scope="module")
def tutorial(tmp_path_factory):
    return _execute("tutorial.ipynb", tmp_path_factory)


@pytest.fixture(scope="module")
def solutions(tmp_path_factory):
    return _execute("tutorial_solutions.ipynb", tmp_path_factory)


def _cell(nb, tag):
    cells = [c for c in nb.cells if tag in c.get("metadata", {}).get("tags", [])]
    assert len(cells) == 1, f"no single cell tagged {tag!r}"
    return cells[0]


def _stdout(cell) -> str:
    return "".join(o.get("text", "") for o in cell.outputs if o.get("name") == "stdout")


def _printed(cell, prefix):
    """The Python literal printed after ``prefix`` on a line of the cell's output."""
    line = next(ln for ln in _stdout(cell).splitlines() if ln.startswith(prefix))
    return ast.literal_eval(line[len(prefix) :].strip())


def test_tutorial_runs_and_draws_every_figure(tutorial):
    nb, _ = tutorial
    errors = [o for c in nb.cells if c.cell_type == "code" for o in c.outputs if o.get("output_type") == "error"]
    assert not errors
    code = [c for c in nb.cells if c.cell_type == "code"]
    draws = [c for c in code if re.search(r"^fig\b[^=]*= ", c.source, re.M)]
    assert len(draws) >= 7
    for c in draws:  # every cell that makes a figure shows it
        assert any("image/png" in o.get("data", {}) for o in c.outputs), c.source[:80]


def test_tutorial_comparison_dam_beats_the_baselines(tutorial):
    nb, _ = tutorial
    scores = _printed(_cell(nb, "comparison"), "comparison:")
    assert set(scores) == {"phone-mean", "cohen-massaro", "dam"}
    assert scores["dam"] < scores["phone-mean"]
    assert scores["cohen-massaro"] < scores["phone-mean"]
    assert scores["dam"] < scores["cohen-massaro"]  # as Chen et al. (2012) report
    assert "best on held-out data: dam" in _stdout(_cell(nb, "comparison"))


def test_tutorial_sigma_and_degree_show_what_the_text_says(tutorial):
    nb, _ = tutorial
    out = _stdout(_cell(nb, "sigma"))
    curves = {
        ln.split(" ", 1)[0]: ast.literal_eval(ln.split(" ", 1)[1])
        for ln in out.splitlines()
        if ln.startswith(("polynomial ", "hold "))
    }
    poly, hold = curves["polynomial"], curves["hold"]
    # the fitted sigma sits near the bottom: shrinking or widening it tenfold-ish is worse
    assert poly[1.0] < poly[0.1] and poly[1.0] < poly[4.0]
    assert hold[1.0] < hold[0.1]
    # wide dominance: the polynomial tails blow up, holding the boundary value does not
    assert poly[4.0] > 5 * hold[4.0]
    degrees = {
        int(m.group(1)): float(m.group(2))
        for m in re.finditer(r"M = (\d+): held-out RMSE ([0-9.]+)", _stdout(_cell(nb, "degree")))
    }
    assert sorted(degrees) == [0, 1, 2, 4]
    assert degrees[4] < degrees[0]  # movements beat constant targets


def test_tutorial_animation_moves(tutorial):
    nb, cwd = tutorial
    cell = _cell(nb, "animation")
    gif = cwd / "tutorial_out" / "tongue.gif"
    im = Image.open(gif)
    n_control_frames = int(re.search(r"(\d+) frames x 19 controls", _stdout(cell)).group(1))
    assert im.n_frames == round(n_control_frames / 100 * 10)  # 100 Hz controls, 10 pictures/s
    assert any("image/gif" in o.get("data", {}) for o in cell.outputs)


def test_solutions_run_and_answer(solutions):
    nb, cwd = solutions
    ex2 = _printed(_cell(nb, "ex2"), "")
    assert ex2["dam"] < ex2["dam-m0"]
    ranges = _printed(_cell(nb, "ex3"), "")
    # the DAM is time-scale invariant (everything in the phone's own duration); Cohen-Massaro undershoots
    assert ranges["dam"]["fast / normal"] == pytest.approx(1.0, abs=0.03)
    assert ranges["cohen-massaro"]["fast / normal"] < ranges["dam"]["fast / normal"]
    page = (cwd / "tutorial_out" / "prediction_vs_truth.html").read_text()
    assert "recorded" in page and "https://" not in page


def test_docs_page_is_current():
    out = subprocess.run(
        [sys.executable, str(ROOT / "docs" / "notebook_page.py"), "--check"], capture_output=True, text=True
    )
    assert out.returncode == 0, out.stderr


def test_notebooks_are_committed_without_outputs():
    for name in ("tutorial.ipynb", "tutorial_solutions.ipynb"):
        nb = json.loads((EXAMPLES / name).read_text())
        assert all(not c.get("outputs") for c in nb["cells"] if c["cell_type"] == "code"), name
