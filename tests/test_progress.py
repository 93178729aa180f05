"""dam.progress: one line (or one JSON object) per unit of work, an ETA weighted by expected cost,
quiet off a terminal; and the command line wiring (per channel, per model)."""

import io
import json
import subprocess
import sys

import pytest

from dam import progress


class Clock:
    """A fake time.perf_counter: the tests decide how long each unit takes."""

    def __init__(self):
        self.t = 100.0

    def __call__(self):
        return self.t


class TTY(io.StringIO):
    def isatty(self):
        return True


def _json_lines(text):
    return [json.loads(line) for line in text.splitlines() if line.strip()]


def test_eta_weighs_units_by_expected_cost(monkeypatch):
    # two units: a cheap one (cost 1, takes 1 s) then an expensive one (cost 9, takes 9 s)
    clock = Clock()
    monkeypatch.setattr(progress.time, "perf_counter", clock)
    out = io.StringIO()
    with progress.reporting("json", stream=out):
        with progress.task("compare", weights=[1.0, 9.0], unit="fit") as t:
            clock.t += 1.0
            t.step("cheap")
            clock.t += 9.0
            t.step("expensive")
    steps = [r for r in _json_lines(out.getvalue()) if r["type"] == "progress"]
    # after the cheap unit: 10% of the cost in 1 s, so 9 s left -- exactly what remained
    assert steps[0]["fraction"] == pytest.approx(0.1)
    assert steps[0]["eta"] == pytest.approx(9.0)
    assert steps[1]["fraction"] == 1.0 and steps[1]["eta"] == 0.0
    # counting units alone would have promised 1 s
    assert abs(steps[0]["eta"] - 1.0) > 7


def test_nested_work_counts_inside_the_running_unit(monkeypatch):
    clock = Clock()
    monkeypatch.setattr(progress.time, "perf_counter", clock)
    out = io.StringIO()
    with progress.reporting("json", stream=out):
        for _ in progress.track(range(2), "models", unit="model"):
            for _ in progress.track(range(4), "channels", unit="channel"):
                clock.t += 1.0
    recs = _json_lines(out.getvalue())
    inner = [r for r in recs if r["type"] == "progress" and r["task"] == "channels"]
    assert [r["fraction"] for r in inner] == pytest.approx([k / 8 for k in range(1, 9)])
    # every unit costs 1 s: the ETA is exactly the time left at every step
    assert [r["eta"] for r in inner] == pytest.approx([8.0 - k for k in range(1, 9)])
    assert [r["depth"] for r in inner] == [1] * 8
    assert {r["type"] for r in recs} == {"start", "progress", "end"}


def test_units_finishing_out_of_order_are_counted_by_their_own_weight():
    out = io.StringIO()
    with progress.reporting("json", stream=out):
        with progress.task("compare", weights=[8.0, 1.0, 1.0]) as t:
            t.step("b", index=1)
            t.step("c", index=2)
    steps = [r for r in _json_lines(out.getvalue()) if r["type"] == "progress"]
    assert [s["fraction"] for s in steps] == pytest.approx([0.1, 0.2])


def test_auto_is_silent_off_a_terminal_and_a_bar_on_one():
    plain = io.StringIO()
    with progress.reporting("auto", stream=plain):
        for _ in progress.track(range(3), "x", unit="channel"):
            pass
    assert plain.getvalue() == ""
    tty = TTY()
    with progress.reporting("auto", stream=tty):
        for _ in progress.track(range(3), "DAM EM", unit="channel", labels=["JA", "LP", "TTY"]):
            pass
    text = tty.getvalue()
    assert "DAM EM 3/3 channels" in text and "left" in text and "[TTY]" in text
    assert text.endswith("\r")  # the line is cleared at the end
    quiet = TTY()
    with progress.reporting("auto", quiet=True, stream=quiet):
        for _ in progress.track(range(3), "x"):
            pass
    assert quiet.getvalue() == ""


def test_a_library_call_reports_nothing():
    assert not progress.active()
    for _ in progress.track(range(2), "x"):  # no reporter: no output, no error
        pass


def test_bad_mode_is_refused():
    with pytest.raises(ValueError, match="progress mode"):
        with progress.reporting("verbose"):
            pass


def _dam(*args, cwd):
    return subprocess.run(
        [sys.executable, "-m", "dam.cli", *args], cwd=cwd, capture_output=True, text=True, timeout=600
    )


def _steps(*args, cwd, **where):
    """The "progress" records of ``dam --progress json ARGS`` whose fields match ``where``."""
    done = _dam("--progress", "json", *args, cwd=cwd)
    assert done.returncode == 0, done.stderr
    recs = [json.loads(line) for line in done.stderr.splitlines() if line.startswith("{")]
    return [r for r in recs if r["type"] == "progress" and all(r[k] == v for k, v in where.items())]


def test_dam_fit_reports_every_channel_as_json(tmp_path):
    steps = _steps("fit", "dam", "tiny", "-o", "m.dam", "-p", "max_iter=2", cwd=tmp_path, task="DAM EM")
    assert [r["label"] for r in steps] == ["lip_aperture", "lip_protrusion", "jaw_open", "tongue_tip"]
    assert [r["done"] for r in steps] == [1, 2, 3, 4] and steps[-1]["fraction"] == 1.0


def test_dam_fit_off_a_terminal_prints_no_progress(tmp_path):
    done = _dam("fit", "dam", "tiny", "-o", "m.dam", "-p", "max_iter=2", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "/4 channel" not in done.stderr and "\r" not in done.stderr and "{" not in done.stderr


def test_dam_compare_reports_every_model_as_json(tmp_path):
    steps = _steps(
        "compare",
        "--models",
        "phone-mean,target-interpolation",
        "--train",
        "tiny",
        "--cv",
        "2",
        cwd=tmp_path,
        task="compare",
    )
    assert len(steps) == 4 and steps[-1]["fraction"] == 1.0 and steps[-1]["total"] == 4
    assert sorted(r["label"].split(":")[0] for r in steps) == sorted(
        f"{m} fold {k}" for m in ("phone-mean", "target-interpolation") for k in (0, 1)
    )


def test_cohen_massaro_reports_every_channel(tmp_path):
    steps = _steps(
        "fit", "cohen-massaro", "tiny", "-o", "m.dam", "-p", "max_nfev=2", cwd=tmp_path, task="Cohen-Massaro"
    )
    assert [r["label"] for r in steps] == ["lip_aperture", "lip_protrusion", "jaw_open", "tongue_tip"]


def test_network_training_reports_every_epoch(tmp_path):
    steps = _steps(
        "fit",
        "causal-mlp",
        "tiny",
        "-o",
        "m.dam",
        "-p",
        "max_epochs=3",
        "-p",
        "hidden_layer_sizes=[8]",
        "-p",
        "validation_fraction=0",
        cwd=tmp_path,
        unit="epoch",
    )
    assert [r["done"] for r in steps] == [1, 2, 3] and all("loss" in r["label"] for r in steps)
