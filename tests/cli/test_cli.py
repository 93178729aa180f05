"""The command line: conventions, the main jobs and one-line errors."""

import subprocess
import sys

import numpy as np

from dam.cli import main, parse_param


def run(*args):
    return subprocess.run([sys.executable, "-m", "dam.cli", *args], capture_output=True, text=True)


def test_help_everywhere():
    for cmd in ([], ["fit"], ["predict"], ["evaluate"], ["models"], ["demo"]):
        r = run(*cmd, "--help")
        assert r.returncode == 0 and "usage: dam" in r.stdout


def test_fit_predict_evaluate(tmp_path, capsys):
    model = tmp_path / "m.dam"
    assert main(["-q", "fit", "target-interpolation", "tiny", "-o", str(model)]) == 0
    assert main(["evaluate", str(model), "tiny"]) == 0
    assert "overall" in capsys.readouterr().out
    from dam.datasets import path

    tg = sorted(path("tiny").glob("*.TextGrid"))[0]
    out = tmp_path / "y.csv"
    assert main(["-q", "predict", str(model), str(tg), "-o", str(out)]) == 0
    data = np.loadtxt(out, delimiter=",", skiprows=1)
    assert data.shape[1] == 5 and np.allclose(np.diff(data[:, 0]), 0.01)


def test_errors_are_one_line_without_traceback(tmp_path):
    r = run("fit", "no-such-model", "tiny", "-o", str(tmp_path / "m.dam"))
    assert r.returncode == 1 and r.stderr.count("\n") == 1 and "unknown model 'no-such-model'" in r.stderr
    r = run("evaluate", str(tmp_path / "missing.dam"), "tiny")
    assert r.returncode == 1 and "Traceback" not in r.stderr and "missing.dam" in r.stderr
    r = run("fit", "phone-mean", str(tmp_path), "-o", "x")
    assert r.returncode == 1 and "no .TextGrid or .lab" in r.stderr
    r = run("fit", "phone-mean")
    assert r.returncode == 2  # usage error, as argparse does


def test_param_parsing():
    assert parse_param("degree=3") == ("degree", 3)
    assert parse_param("normalize=true") == ("normalize", True)
    assert parse_param("modes=single") == ("modes", "single")
    assert parse_param("w_c=1e3") == ("w_c", 1000.0)


def test_models_lists_registry(capsys):
    assert main(["models"]) == 0
    out = capsys.readouterr().out
    assert "phone-mean" in out and "target-interpolation" in out
