"""The README works as written: its "Writing your own model" code runs, and its numbers come
from the benchmark results files (benchmarks/update_readme.py), never typed by hand."""

import json
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "README.md"


def _section_code(title: str) -> str:
    text = README.read_text(encoding="utf-8")
    start = text.index(title)
    end = text.find("\n## ", start)
    blocks = re.findall(r"```python\n(.*?)```", text[start:end], flags=re.S)
    assert blocks, f"no python block under {title!r}"
    return blocks[0]


def _run(code: str, cwd) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", code], cwd=cwd, capture_output=True, text=True, timeout=300)


def test_writing_your_own_model_runs_as_written_and_loads_back_in_a_fresh_session(tmp_path):
    code = _section_code("### Writing your own model")
    done = _run(code, tmp_path)
    assert done.returncode == 0, done.stderr
    rmse = float(done.stdout.strip().splitlines()[-1])
    assert 0 < rmse < 1
    # The file records the registered name, not the class name.
    from dam.modelfile import read_model_file

    meta, _ = read_model_file(tmp_path / "smooth.dam")
    assert meta["model"] == "smooth-pm"
    # A fresh session that knows the class only as "smooth-pm" loads it and predicts what it predicted.
    class_src = code[code.index("class SmoothPhoneMean") : code.index("check_synthesizer(SmoothPhoneMean())")]
    again = textwrap.dedent(f"""
        import numpy as np
        import dam
        {textwrap.indent(class_src, "        ").strip()}
        dam.register("smooth-pm", SmoothPhoneMean)
        m = dam.load("smooth.dam")
        test = dam.datasets.load("tiny").train_test_split(0.25)[1]
        print(type(m).__name__, m.width, dam.evaluate(m, test).rmse)
    """)
    done2 = _run(again, tmp_path)
    assert done2.returncode == 0, done2.stderr
    cls, width, rmse2 = done2.stdout.split()
    assert (cls, width) == ("SmoothPhoneMean", "7")
    np.testing.assert_allclose(float(rmse2), rmse, rtol=1e-12)


def _update_readme():
    import importlib.util

    spec = importlib.util.spec_from_file_location("update_readme", ROOT / "benchmarks" / "update_readme.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _block_names():
    import re

    return re.findall(r"<!-- generated:([\w-]+)", README.read_text(encoding="utf-8"))


def test_the_readme_has_generated_blocks_and_a_renderer_for_each():
    mod = _update_readme()
    names = _block_names()
    assert {"demo", "all-models", "crossmap"} <= set(names)
    assert set(names) <= set(mod.BLOCKS)


@pytest.mark.parametrize("name", _block_names())
def test_readme_numbers_come_from_the_results_files(name):
    mod = _update_readme()
    block = next(m for m in mod.BLOCK.finditer(README.read_text(encoding="utf-8")) if m.group("name") == name)
    assert mod.render(name) == block.group("body"), (
        f"README block {name!r} differs from benchmarks/results: run benchmarks/update_readme.py"
    )


def test_the_generated_all_models_table_has_every_results_row():
    # independent of the renderer: read nn.json ourselves and find each RMSE, to 3 decimals, in its row
    mod = _update_readme()
    rows = json.loads((ROOT / "benchmarks" / "results" / "nn.json").read_text())["rows"]
    table = mod.render_all_models()
    for r in rows:
        if r["model"] == "phone-mean":
            continue
        line = next(
            ln for ln in table.splitlines() if ln.startswith(f"| {mod.NN_LABELS.get(r['model'], r['model'])} |")
        )
        assert f"{r['rmse']:.3f}" in line


def test_update_readme_check_mode_fails_on_a_hand_edit(tmp_path, monkeypatch):
    mod = _update_readme()
    m = next(b for b in mod.BLOCK.finditer(README.read_text(encoding="utf-8")) if b.group("name") == "all-models")
    text = f"# a README\n\n{m.group(0)}\n\nmore text\n"
    m = next(mod.BLOCK.finditer(text))
    edited = text[: m.start("body")] + m.group("body").replace("|", "| 0.123 |", 1) + text[m.end("body") :]
    fake = tmp_path / "README.md"
    fake.write_text(edited, encoding="utf-8")
    monkeypatch.setattr(mod, "README", fake)
    assert mod.main(["--check"]) == 1
    assert mod.main([]) == 0 and mod.main(["--check"]) == 0
    assert fake.read_text(encoding="utf-8") == text
