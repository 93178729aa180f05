"""Outputs never overwrite inputs silently (issue 12): every command checks its output paths
before any work starts; `-o -` is standard output where the format allows it, else refused."""

import contextlib
import io
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest

import dam
from dam.cli import main
from dam.datasets import DATA


def run(*argv):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main([str(a) for a in argv])
        except SystemExit as exc:
            code = exc.code
    return code, out.getvalue(), err.getvalue()


def _one_error_line(err: str, *words) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("dam: error: "), err
    for w in words:
        assert w in lines[0], lines[0]
    return lines[0]


@pytest.fixture
def model_file(tmp_path, tiny_train):
    path = tmp_path / "m.dam"
    dam.make("phone-mean").fit(tiny_train).save(path)
    return path


@pytest.mark.parametrize("target", ["alignment", "model"])
def test_predict_refuses_to_write_over_its_inputs(model_file, small_corpus_dir, target):
    alignment = small_corpus_dir / "tiny000.TextGrid"
    out = alignment if target == "alignment" else model_file
    before = out.read_bytes()
    code, _, err = run("predict", model_file, alignment, "-o", out)
    assert code == 1
    _one_error_line(err, str(out), "is an input")
    assert out.read_bytes() == before


def test_predict_refuses_to_replace_recorded_data_beside_an_alignment(model_file, small_corpus_dir):
    target = small_corpus_dir / "tiny001.csv"
    before = target.read_bytes()
    code, _, err = run("predict", model_file, small_corpus_dir / "tiny000.TextGrid", "-o", target)
    assert code == 1
    _one_error_line(err, str(target), "corpus")
    assert target.read_bytes() == before


def test_predict_replaces_its_own_earlier_output_and_corpus_files_only_with_overwrite(
    model_file, small_corpus_dir, tmp_path
):
    alignment = small_corpus_dir / "tiny000.TextGrid"
    out = tmp_path / "prediction.csv"
    for _ in range(2):  # an output that is no corpus's data is simply replaced (atomically)
        assert run("predict", model_file, alignment, "-o", out)[0] == 0
    target = small_corpus_dir / "tiny001.csv"
    code, _, _ = run("predict", model_file, alignment, "-o", target, "--overwrite")
    assert code == 0 and target.read_bytes() == out.read_bytes()


def test_predict_dash_writes_csv_to_standard_output(model_file, small_corpus_dir):
    alignment = small_corpus_dir / "tiny000.TextGrid"
    code, out, _ = run("predict", model_file, alignment, "-o", "-")
    assert code == 0 and not os.path.exists("-")
    table = np.loadtxt(io.StringIO(out), delimiter=",", skiprows=1, ndmin=2)
    expected = dam.load(model_file).predict(dam.read_alignment(alignment))
    np.testing.assert_allclose(table[:, 1:], expected, rtol=1e-5, atol=1e-6)


def test_fit_refuses_an_output_inside_its_corpus(small_corpus_dir):
    before = sorted(os.listdir(small_corpus_dir))
    code, _, err = run("fit", "phone-mean", small_corpus_dir, "-o", small_corpus_dir / "x.csv")
    assert code == 1
    _one_error_line(err, "inside the input directory")
    assert sorted(os.listdir(small_corpus_dir)) == before


def test_fit_checks_the_output_directory_before_fitting(tmp_path):
    code, _, err = run("fit", "dam", "tiny", "-o", tmp_path / "missing" / "m.dam")
    assert code == 1
    _one_error_line(err, "does not exist")
    assert "fitting" not in err  # refused before the fit started


def test_fit_to_standard_output_is_refused():
    code, _, err = run("fit", "phone-mean", "tiny", "-o", "-")
    assert code == 1
    _one_error_line(err, "standard output")
    assert not os.path.exists("-")


@pytest.mark.parametrize(
    "model, param, name",
    [
        ("dam", "degree=true", "degree"),
        ("cohen-massaro", "ridge=abc", "ridge"),
        ("cohen-massaro", "max_nfev=-1", "max_nfev"),
        ("dam", "dominance_tol=2", "dominance_tol"),
        ("mmm", "smoothness=abc", "smoothness"),
    ],
)
def test_bad_hyperparameters_name_the_parameter_and_write_nothing(tmp_path, model, param, name):
    out = tmp_path / "m.dam"
    code, _, err = run("fit", model, "tiny", "-o", out, "--param", param)
    assert code == 1
    _one_error_line(err, f"parameter {name!r}")
    assert not out.exists()


def test_compare_refuses_to_write_into_a_corpus(tmp_path):
    """A corpus with an utterance named 'summary' would lose summary.csv to the comparison."""
    d = tmp_path / "user"
    d.mkdir()
    shutil.copy(DATA / "tiny" / "tiny000.TextGrid", d / "summary.TextGrid")
    shutil.copy(DATA / "tiny" / "tiny000.csv", d / "summary.csv")
    before = (d / "summary.csv").read_bytes()
    code, _, err = run("compare", "--models", "phone-mean", "--train", "tiny", "--out", d)
    assert code == 1
    _one_error_line(err, "holds a corpus")
    assert (d / "summary.csv").read_bytes() == before and sorted(os.listdir(d)) == ["summary.TextGrid", "summary.csv"]
    code, _, err = run("compare", "--models", "phone-mean", "--train", d, "--out", d)
    assert code == 1
    _one_error_line(err, "input")


def test_generate_tiny_never_writes_over_a_users_files(tmp_path):
    d = tmp_path / "mine"
    d.mkdir()
    (d / "thesis.TextGrid").write_text("months of work")
    code, _, err = run("generate-tiny", d)
    assert code == 1
    _one_error_line(err, "--overwrite")
    proc = subprocess.run([sys.executable, "-m", "dam.datasets.tiny", str(d)], capture_output=True, text=True)
    assert proc.returncode == 1 and "Traceback" not in proc.stderr
    assert os.listdir(d) == ["thesis.TextGrid"] and (d / "thesis.TextGrid").read_text() == "months of work"
    code, _, _ = run("generate-tiny", d, "--overwrite")
    assert code == 0 and "thesis.TextGrid" not in os.listdir(d)
    assert len(dam.load_corpus(d)) == 30


def test_crossmap_refuses_a_directory_holding_files_before_any_work(tmp_path):
    d = tmp_path / "out"
    d.mkdir()
    (d / "keep.txt").write_text("x")
    code, _, err = run("crossmap", "tiny", "-o", d)
    assert code == 1
    _one_error_line(err, "--overwrite")
    assert os.listdir(d) == ["keep.txt"]


def test_two_fits_saving_to_one_path_leave_a_model_that_loads(tmp_path):
    out = tmp_path / "same.dam"
    cli = "import sys; from dam.cli import main; sys.exit(main())"
    procs = [
        subprocess.Popen(
            [sys.executable, "-c", cli, "-q", "fit", "phone-mean", "tiny", "-o", str(out)],
            stderr=subprocess.PIPE,
            text=True,
        )
        for _ in range(2)
    ]
    for p in procs:
        assert p.wait(120) == 0, p.stderr.read()
    assert dam.load(out).table_.shape[1] == 4
    assert os.listdir(tmp_path) == ["same.dam"]
