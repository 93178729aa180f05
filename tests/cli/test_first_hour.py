"""Issue 13, what a new user meets first: mistakes caught before any work, missing extras that
say what to install, messages without placeholders, the demo saying what it does."""

import json
import subprocess
import sys

import numpy as np

import dam


def _dam(*args, cwd, env=None):
    return subprocess.run(
        [sys.executable, "-m", "dam.cli", *args], cwd=cwd, capture_output=True, text=True, timeout=600, env=env
    )


def test_compare_refuses_an_unknown_model_before_fitting_any(tmp_path):
    done = _dam("--progress", "json", "compare", "--models", "phone-mean,dam,foo", "--train", "tiny", cwd=tmp_path)
    assert done.returncode == 1
    assert done.stderr.startswith("dam: error: unknown model 'foo'") and "dam models" in done.stderr
    # no task started: no progress record at all
    assert not [line for line in done.stderr.splitlines() if line.startswith("{")]


def test_compare_refuses_a_bad_parameter_value_before_fitting_any(tmp_path):
    done = _dam(
        "--progress",
        "json",
        "compare",
        "--models",
        "phone-mean,dam",
        "-p",
        "dam.degree=abc",
        "--train",
        "tiny",
        cwd=tmp_path,
    )
    assert done.returncode == 1
    assert "'degree'" in done.stderr and "'abc'" in done.stderr
    assert not [line for line in done.stderr.splitlines() if line.startswith("{")]


def test_compare_refuses_an_unknown_parameter_name(tmp_path):
    done = _dam("compare", "--models", "phone-mean,dam", "-p", "dam.degre=3", "--train", "tiny", cwd=tmp_path)
    assert done.returncode == 1 and "'degre'" in done.stderr


def test_fit_refuses_a_bad_parameter_before_saying_fitting(tmp_path):
    done = _dam("fit", "dam", "tiny", "-o", "m.dam", "--param", "degree=abc", cwd=tmp_path)
    assert done.returncode == 1
    assert "fitting" not in done.stderr and "'degree' is 'abc'" in done.stderr
    assert not (tmp_path / "m.dam").exists()


def test_fit_refuses_an_unwritable_output_before_fitting(tmp_path):
    done = _dam("fit", "dam", "tiny", "-o", str(tmp_path / "no" / "such" / "m.dam"), cwd=tmp_path)
    assert done.returncode == 1 and "fitting" not in done.stderr and "does not exist" in done.stderr


_NO_EQUINOX = "import sys; sys.modules['equinox'] = None\n"


def test_a_missing_extra_says_which_pip_command(tmp_path):
    code = _NO_EQUINOX + (
        "import dam\ntry:\n    dam.make('gru')\nexcept ImportError as exc:\n    print(type(exc).__name__, exc)\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("MissingExtraError")
    assert "'equinox'" in done.stdout and 'pip install "dam[jax]"' in done.stdout


def test_dam_models_says_exactly_what_is_missing(tmp_path):
    code = _NO_EQUINOX + "from dam.cli import main\nmain(['models'])\n"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    lines = {ln.split()[0]: ln for ln in done.stdout.splitlines() if ln.strip()}
    assert "unavailable" in lines["gru"] and "'equinox'" in lines["gru"] and "dam[jax]" in lines["gru"]
    assert "unavailable" not in lines["dam"]
    # with equinox installed (this environment), the network is listed as usable
    done2 = _dam("models", cwd=tmp_path)
    gru = next(ln for ln in done2.stdout.splitlines() if ln.startswith("gru "))
    assert "unavailable" not in gru and "installed" in gru


def test_extra_for_reads_pyproject_extras():
    from dam.registry import extra_for

    assert extra_for("equinox") == "jax" and extra_for("optax") == "jax"
    assert extra_for("vocaltractlab_cython") == "vtl"
    assert extra_for("numpy") is None


def test_retarget_chooses_modes_that_fit_and_names_the_corpus(tmp_path):
    corpus = dam.datasets.load("tiny").select_channels(["lip_aperture", "jaw_open", "tongue_tip"])
    dam.save_corpus(corpus, tmp_path / "three")
    done = _dam("retarget", "three", "--save-poses", "poses.csv", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert done.stderr.startswith("3 modes explain")
    assert np.loadtxt(tmp_path / "poses.csv", delimiter=",", ndmin=2, comments="#").shape[0] in (6, 7)
    bad = _dam("retarget", "three", "--n-modes", "5", cwd=tmp_path)
    assert bad.returncode == 1 and "<input>" not in bad.stderr
    assert bad.stderr.startswith("dam: error: three: field 'n_modes'")
    sigma = _dam("retarget", "three", "--sigma", "-1", cwd=tmp_path)
    assert sigma.returncode == 1 and "<input>" not in sigma.stderr


def test_predict_positionals_have_help(tmp_path):
    done = _dam("predict", "--help", cwd=tmp_path)
    text = " ".join(done.stdout.split())
    assert "MODEL_FILE a fitted model" in text and "ALIGNMENT_FILE the phone timings" in text


def test_compare_names_its_files_without_a_double_slash(tmp_path):
    done = _dam(
        "compare",
        "--models",
        "phone-mean,target-interpolation",
        "--train",
        "tiny",
        "--cv",
        "2",
        "--out",
        "results/",
        cwd=tmp_path,
    )
    assert done.returncode == 0, done.stderr
    assert "wrote results/summary.csv" in done.stderr and "//" not in done.stderr
    assert (tmp_path / "results" / "summary.csv").exists()


def test_demo_says_what_it_does_before_doing_it(tmp_path):
    from dam.evaluation.compare import demo_plan

    plan = demo_plan("vtl")
    assert len(plan["channels"]) == 3 and plan["train_minutes"] is None and len(plan["models"]) == 6
    assert plan["description"].startswith("dam demo: fits 6 models") and "minute" in plan["description"]
    assert "cohen-massaro" in plan["description"].split("--full")[1]
    done = _dam("demo", "--corpus", "tiny", "--out", "d", "--progress", "json", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    first = done.stderr.splitlines()[0]
    assert first.startswith("dam demo: fits 8 models") and "tiny" in first
    recs = [json.loads(ln) for ln in done.stderr.splitlines() if ln.startswith("{")]
    assert sum(r["type"] == "progress" and r["task"] == "compare" for r in recs) == 8
    assert (tmp_path / "d" / "predictions.png").exists()
