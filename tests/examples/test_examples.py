"""Every example runs on the tiny settings (--quick), writes only where the user says (by default
./dam-examples/<name>/, which git ignores), and every figure it saves follows dam.plotting's rules."""

import importlib.util
import subprocess
from pathlib import Path

import pytest

from dam import plotting

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = sorted(p.stem for p in (ROOT / "examples").glob("*.py"))


def _load(name):
    spec = importlib.util.spec_from_file_location(f"example_{name}", ROOT / "examples" / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture
def checked_figures(monkeypatch):
    """plotting.save, but every figure is checked against the style rules before it is written."""
    saved = []
    real = plotting.save

    def save(fig, path, **kw):
        problems = plotting.check_figure(fig)
        assert not problems, f"{Path(path).name}: {problems}"
        saved.append(Path(path).name)
        return real(fig, path, **kw)

    monkeypatch.setattr(plotting, "save", save)
    return saved


EXPECTED = {
    "animation_out": {"face.glb", "animation_out.png"},
    "vtl_corpus": {"vtl_corpus.png"},
    "dam_inspect": {"dam_dominance.png", "dam_animemes.png", "dam_modes.png", "dam_astar.png"},
    "compare_models": {"predictions.png", "rmse.png", "summary.csv", "summary.md", "per_channel.csv"},
    "neural_predictors": {"loss_curves.png", "predictions.png"},
    "crossmap_pipeline": {
        "1_captured_outlines.png",
        "2_key_shapes.png",
        "3_blend_weights.png",
        "4_target_key_shapes.png",
        "5_controls.png",
        "6_synthesis.png",
        "6_character.png",
        "7_retarget.png",
        "7_retarget_poses.png",
        "metrics.json",
    },
}


def test_every_example_is_covered():
    assert set(EXAMPLES) == set(EXPECTED)


@pytest.mark.parametrize("name", EXAMPLES)
def test_example_runs_quick_into_the_directory_named(name, tmp_path, monkeypatch, checked_figures):
    monkeypatch.chdir(tmp_path)  # the default output goes under the working directory
    out = tmp_path / "elsewhere"
    assert _load(name).main(["--quick", "--out", str(out)]) in (0, None)
    written = {p.name for p in out.rglob("*") if p.is_file() and "cache" not in p.parts}
    assert EXPECTED[name] <= written, EXPECTED[name] - written
    assert {n for n in EXPECTED[name] if n.endswith(".png")} <= set(checked_figures)
    # nothing written anywhere else: not in the working directory, not in the checkout
    assert [p.name for p in tmp_path.iterdir()] == ["elsewhere"]
    assert not (ROOT / "examples" / "out").exists()


def test_the_default_output_directory_is_ignored_by_git(tmp_path, monkeypatch):
    mod = _load("vtl_corpus")
    monkeypatch.chdir(tmp_path)
    mod.main([])
    made = [p.relative_to(tmp_path) for p in tmp_path.rglob("*") if p.is_file()]
    assert made == [Path("dam-examples/vtl_corpus/vtl_corpus.png")]
    # the same path inside the checkout is ignored, so running the examples there leaves git status clean
    done = subprocess.run(["git", "check-ignore", "-q", str(made[0])], cwd=ROOT)
    assert done.returncode == 0, f"{made[0]} is not ignored by git"
    tracked = subprocess.run(
        ["git", "ls-files", "examples/out", "dam-examples"], cwd=ROOT, capture_output=True, text=True
    ).stdout.split()
    assert tracked == [] or not all((ROOT / t).exists() for t in tracked), (
        f"generated files tracked by git: {tracked[:5]}"
    )
