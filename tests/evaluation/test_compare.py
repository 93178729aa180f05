"""dam.compare: statistics against scipy and by hand, the files it writes, the CLI."""

import csv

import numpy as np
import pytest

from dam import registry
from dam.evaluation.compare import SUMMARY_COLUMNS, bootstrap_rmse_ci, compare, holm
from dam.testing import default_corpora

FAST = ["phone-mean", "target-interpolation", ("tree", "dtree", {"max_depth": 6, "kx": 5, "ky": 3})]


@pytest.fixture(scope="module")
def corpora():
    return default_corpora()


@pytest.fixture(scope="module")
def result(corpora):
    train, test = corpora
    return compare(FAST, train, test, n_boot=500, verbose=0)


def test_holm_by_hand():
    # sorted 0.01, 0.03, 0.04, 0.5 times 4, 3, 2, 1 -> 0.04, 0.09, 0.08 (raised to 0.09), 0.5
    np.testing.assert_allclose(holm([0.01, 0.04, 0.03, 0.5]), [0.04, 0.09, 0.09, 0.5])
    np.testing.assert_allclose(holm([0.6, 0.5]), [1.0, 1.0])


def test_scores_agree_with_scipy(result, corpora):
    from scipy.stats import pearsonr, wilcoxon

    from baselines.reference import PhoneMean, TargetInterpolation

    train, test = corpora
    truth = np.concatenate(test.trajectories)
    utt = {}
    for label, model in [("phone-mean", PhoneMean()), ("target-interpolation", TargetInterpolation())]:
        preds = model.fit(train).predict(test.alignments)
        P = np.concatenate(preds)
        row = result.row(label)
        assert row["rmse"] == pytest.approx(np.sqrt(np.mean((P - truth) ** 2)), rel=1e-12)
        r = [pearsonr(truth[:, c], P[:, c])[0] for c in range(truth.shape[1])]
        assert row["pearson_r"] == pytest.approx(np.mean(r), rel=1e-9)
        got = [x for x in result.per_channel if x["model"] == label]
        np.testing.assert_allclose([x["pearson_r"] for x in got], r, rtol=1e-9)
        utt[label] = np.array([np.sqrt(np.mean((p - u.trajectory) ** 2)) for p, u in zip(preds, test)])
        np.testing.assert_allclose([x["rmse"] for x in result.per_utterance if x["model"] == label], utt[label])
        assert row["rmse_ci_low"] < row["rmse"] < row["rmse_ci_high"]
    best = result.best
    assert best == "tree"  # the tree beats both references on held-out data
    tree = np.array([x["rmse"] for x in result.per_utterance if x["model"] == "tree"])
    p = [wilcoxon(utt[m], tree).pvalue for m in ("phone-mean", "target-interpolation")]
    for m, pv, ph in zip(("phone-mean", "target-interpolation"), p, holm(p)):
        assert result.row(m)["wilcoxon_p"] == pytest.approx(pv, rel=1e-12)
        assert result.row(m)["wilcoxon_p_holm"] == pytest.approx(ph, rel=1e-12)
    assert [r["model"] for r in result.summary][0] == best
    assert all(a["rmse"] <= b["rmse"] for a, b in zip(result.summary, result.summary[1:]))


def test_bootstrap_interval():
    # every utterance equally good: no spread to resample
    lo, hi = bootstrap_rmse_ci(np.full(6, 8.0), np.full(6, 2.0))
    assert lo == pytest.approx(2.0) and hi == pytest.approx(2.0)
    # two kinds of utterance: the interval lies between their RMSEs and contains the pooled one
    sse, cnt = np.r_[np.full(10, 1.0), np.full(10, 100.0)], np.full(20, 1.0)
    lo, hi = bootstrap_rmse_ci(sse, cnt, n_boot=4000)
    assert 1.0 < lo < np.sqrt(50.5) < hi < 10.0


def test_writes_files_with_columns_and_reports_skipped(tmp_path, corpora):
    train, test = corpora
    registry.register("zz-missing-dep", "zz_module_that_is_not_installed:Model")
    try:
        res = compare(["phone-mean", "zz-missing-dep"], train, test, out=tmp_path, n_boot=100, verbose=0)
    finally:
        registry._REGISTRY.pop("zz-missing-dep")
    for name in ("summary.csv", "per_channel.csv", "per_utterance.csv", "summary.md", "predictions.png", "rmse.png"):
        assert (tmp_path / name).stat().st_size > 0, name
    with open(tmp_path / "summary.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert tuple(rows[0]) == SUMMARY_COLUMNS
    assert [r["model"] for r in rows] == ["phone-mean", "zz-missing-dep"]
    assert rows[1]["status"] == "skipped" and "zz_module_that_is_not_installed" in rows[1]["reason"]
    assert float(rows[0]["rmse"]) == pytest.approx(res.row("phone-mean")["rmse"])
    with open(tmp_path / "per_channel.csv") as fh:
        pc = list(csv.DictReader(fh))
    assert tuple(pc[0]) == ("model", "channel", "rmse", "pearson_r") and len(pc) == train.n_channels
    with open(tmp_path / "per_utterance.csv") as fh:
        assert len(list(csv.DictReader(fh))) == len(test)
    assert "| phone-mean |" in (tmp_path / "summary.md").read_text()


def test_cross_validation_scores_every_utterance_once(corpora):
    train, _ = corpora
    res = compare(["phone-mean"], train, cv=3, n_jobs=2, n_boot=100, verbose=0)
    names = [x["utterance"] for x in res.per_utterance]
    assert sorted(names) == sorted(u.name for u in train)
    assert {x["fold"] for x in res.per_utterance} == {0, 1, 2}


def test_failed_model_is_reported_not_raised(corpora):
    from baselines.reference import PhoneMean

    train, test = corpora

    class Diverges(PhoneMean):
        def _fit(self, corpus):
            raise FloatingPointError("diverged")

    res = compare([("bad", Diverges()), "phone-mean"], train, test, verbose=0)
    assert res.row("bad")["status"] == "failed" and "FloatingPointError: diverged" in res.row("bad")["reason"]
    assert res.row("bad")["rmse"] is None and res.best == "phone-mean"


def test_bad_parameters_are_refused_before_any_fit(corpora):
    import dam

    train, test = corpora
    with pytest.raises(dam.InvalidParameterError, match="PhoneMean: parameter 'unknown_phone' is 'guess'"):
        compare([("bad", "phone-mean", {"unknown_phone": "guess"}), "phone-mean"], train, test, verbose=0)


def test_cli_compare(tmp_path, capsys):
    from dam.cli import main

    code = main(
        [
            "compare",
            "--models",
            "phone-mean,tree=dtree",
            "-p",
            "tree.max_depth=4",
            "--train",
            "tiny",
            "--out",
            str(tmp_path),
        ]
    )
    assert code == 0
    out = capsys.readouterr().out
    assert "| tree |" in out and "| phone-mean |" in out
    with open(tmp_path / "summary.csv") as fh:
        assert {r["model"] for r in csv.DictReader(fh)} == {"phone-mean", "tree"}
    assert main(["compare", "--models", "phone-mean", "-p", "nomodel.x=1", "--train", "tiny"]) == 1


def test_test_corpus_at_another_frame_rate_is_refused(corpora):
    from dam.corpus.data import Corpus, Utterance

    train, test = corpora
    fr = 2 * test.frame_rate
    other = Corpus(
        [
            Utterance(
                u.alignment, np.zeros((u.alignment.n_frames(fr), test.n_channels)), fr, test.channels, name=u.name
            )
            for u in test
        ]
    )
    with pytest.raises(ValueError, match="frame rates differ"):
        compare(["phone-mean"], train, other, verbose=0)


def test_the_four_steps_and_the_progress_callback(corpora):
    """plan_comparison -> run_tasks -> score_results is compare(); progress sees every task once."""
    from dam.evaluation.compare import ModelScore, TaskResult, plan_comparison, run_tasks, score_results

    train, _ = corpora
    models = ["phone-mean", "target-interpolation"]
    plan = plan_comparison(models, train, cv=2)
    assert [(t.label, t.fold) for t in plan.tasks] == [(m, k) for m in models for k in (0, 1)]
    seen = []
    results = run_tasks(plan, progress=lambda r, done, total: seen.append((r, done, total)))
    assert all(isinstance(r, TaskResult) and r.status == "ok" for r in results)
    assert sorted((r.model, r.fold) for r, _, _ in seen) == sorted((t.label, t.fold) for t in plan.tasks)
    assert [d for _, d, _ in seen] == [1, 2, 3, 4] and {t for _, _, t in seen} == {4}
    stepwise = score_results(plan, results, n_boot=100, verbose=0)
    whole = compare(models, train, cv=2, n_boot=100, verbose=0)
    for a, b in zip(stepwise.summary, whole.summary):
        assert isinstance(a, ModelScore) and a.model == b.model and a.rmse == b.rmse == a["rmse"]
        assert (a.rmse_ci_low, a.wilcoxon_p) == (b.rmse_ci_low, b.wilcoxon_p)
    best = stepwise.row(stepwise.best)
    assert best.wilcoxon_p is None and best.get("wilcoxon_p", "") == ""  # not tested against itself
