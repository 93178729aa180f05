"""Compare synthesizers on held-out data: the table a reviewer would accept.

>>> from dam.evaluation.compare import compare
>>> res = compare(["dam", "cohen-massaro", "mmm", "dtree"], "vtl:train", "vtl:test",
...               n_jobs=2, out="results/")                       # doctest: +SKIP
>>> print(res.table())                                             # doctest: +SKIP

For every model: held-out RMSE (channel units, all frames and channels
pooled) with a bootstrap 95% confidence interval over utterances, Pearson r
(per channel over all frames pooled, then averaged over channels), the same
per channel and per utterance, a paired two-sided Wilcoxon signed-rank test
of its per-utterance RMSE against the best model's (Holm-corrected over the
models compared), fit seconds, synthesis microseconds per phone and frames
per second.

:func:`compare` runs four steps, each a function of its own:

1. **planning** (:func:`plan_comparison`): model names, parameters, channels,
   frame rates and the output directory checked before any fit; the folds;
   one :class:`Task` per model and fold;
2. **running** (:func:`run_tasks`): the tasks through joblib, each giving a
   :class:`TaskResult`;
3. **statistics** (:func:`score_results`, with :mod:`dam.evaluation.statistics`):
   the scores, intervals and tests, one :class:`~dam.evaluation.report.ModelScore`
   row per model, in a :class:`ComparisonResult`;
4. **reporting** (:mod:`dam.evaluation.report`): the table, the files and the figures.

Models and cross-validation folds are independent tasks run through joblib
(``n_jobs``); any joblib backend works, so a Dask or Ray cluster takes the
same run (``with joblib.parallel_config(backend="dask"): compare(...)``).
Synthesis time is the median of up to five runs over the test alignments
(repeated while they take under a second in all). Timings of tasks that run
side by side share the machine: for speed figures use ``n_jobs=1``.

A model whose optional dependency is missing is reported as skipped with the
reason; one that raises while fitting is reported as failed with the error.
Neither stops the others.

Files written by :meth:`ComparisonResult.write`: ``summary.csv`` (one row
per model), ``per_channel.csv``, ``per_utterance.csv``, ``summary.md`` (a
Markdown table), ``predictions.png`` (predictions against the truth for one
test utterance) and ``rmse.png`` (RMSE per model with 95% intervals).
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from dam.corpus.atomic import check_output
from dam.corpus.data import Corpus
from dam.evaluation.report import SUMMARY_COLUMNS, ModelScore, markdown_table, plot_report, write_report
from dam.evaluation.statistics import bootstrap_rmse_ci, holm, tests_against

__all__ = [
    "compare",
    "ComparisonResult",
    "ModelScore",
    "Task",
    "TaskResult",
    "ComparisonPlan",
    "plan_comparison",
    "run_tasks",
    "score_results",
    "holm",
    "bootstrap_rmse_ci",
    "run_demo",
    "demo_plan",
    "DEMO_MODELS",
    "SUMMARY_COLUMNS",
]

DEMO_MODELS = (
    "phone-mean",
    "target-interpolation",
    "dam",
    "dam-m0",
    "cohen-massaro",
    "mmm",
    "dtree",
    ("dtree-linguistic", "dtree", {"features": "linguistic"}),
)


# -- the result ---------------------------------------------------------------
@dataclass
class ComparisonResult:
    """Everything :func:`compare` measured.

    Attributes
    ----------
    summary : list of ModelScore
        One row per model (:data:`~dam.evaluation.report.SUMMARY_COLUMNS`);
        ``status`` is ``"ok"``, ``"skipped"`` or ``"failed"`` (with ``reason``).
        Rows are sorted by RMSE, skipped and failed models last.
    per_channel : list of dict
        ``model, channel, rmse, pearson_r``.
    per_sensor : list of dict
        ``model, sensor, channels, distance``: the mean Euclidean distance of
        each sensor (Medina et al. 2022); empty when the channels form no
        sensors. The summary's ``sensor_error`` is their Eq. 1 averaged over
        utterances, in ``length_unit``.
    per_utterance : list of dict
        ``model, fold, utterance, n_frames, rmse, pearson_r``.
    best : str or None
        The model with the lowest held-out RMSE.
    corpus : str
        What was compared on (for the table's caption).
    example : dict
        One test utterance: ``utterance``, ``frame_rate``, ``channels``,
        ``truth`` (n_frames, n_channels) and ``predictions`` {model: array}.
    """

    summary: list
    per_channel: list
    per_utterance: list
    best: str | None
    corpus: str = ""
    example: dict = field(default_factory=dict)
    per_sensor: list = field(default_factory=list)
    length_unit: str | None = None

    def row(self, model: str) -> ModelScore:
        """The summary row of ``model``."""
        for r in self.summary:
            if r["model"] == model:
                return r
        raise KeyError(f"no model {model!r} in this comparison; models: {[r['model'] for r in self.summary]}")

    def table(self) -> str:
        """The summary as a Markdown table, with a note on the tests (:func:`~dam.evaluation.report.markdown_table`)."""
        return markdown_table(self)

    def write(self, out) -> list[str]:
        """Write the CSVs, the Markdown table and the figures into directory ``out``; return the paths."""
        return write_report(self, out)

    def plot(self, out) -> list[str]:
        """``predictions.png`` and ``rmse.png`` in ``out`` (:mod:`dam.evaluation.figures`); returns their paths."""
        return plot_report(self, out)


# -- planning -------------------------------------------------------------------
#: Expected fit cost relative to the DAM's (the demo's measured fit seconds), for the ETA of a
#: comparison: the cheap references finish first and must not make the rest look short.
EXPECTED_FIT_COST = {
    "phone-mean": 0.01,
    "target-interpolation": 0.01,
    "dam": 1.0,
    "dam-m0": 0.2,
    "cohen-massaro": 1.0,
    "mmm": 0.6,
    "dtree": 0.3,
    "sliding-dnn": 2.0,
    "causal-mlp": 1.0,
    "lstm": 5.0,
    "gru": 2.0,
    "transformer": 5.0,
}


def expected_fit_cost(model) -> float:
    """Relative expected fit cost of a registry name or an estimator (1 for unknown models)."""
    name = model if isinstance(model, str) else (getattr(model, "name", "") or "")
    return EXPECTED_FIT_COST.get(name, 1.0)


@dataclass
class Task:
    """One model fitted on one fold and scored on its test part (a joblib job).

    Attributes
    ----------
    label : str
        The model's row in the summary.
    name : str or None
        Registry name (None when ``estimator`` is given).
    params : dict
        Hyperparameters for ``name``.
    estimator : Synthesizer or None
        An instance to clone instead of a registry name.
    fold : int
    train, test : Corpus
    unknown_phone : str or None
        Given to a model that has this parameter and was not given it explicitly.
    """

    label: str
    name: str | None
    params: dict
    estimator: object
    fold: int
    train: Corpus
    test: Corpus
    unknown_phone: str | None = None


@dataclass
class ComparisonPlan:
    """What :func:`compare` will run: the checked models, the folds and the tasks.

    Attributes
    ----------
    specs : list of tuple
        ``(label, registry name or None, params, estimator or None)`` per model, in the order given.
    folds : list of (Corpus, Corpus)
        ``(train, test)`` per fold.
    where : str
        What is compared on, for the table's caption.
    tasks : list of Task
        One per model and fold, model major.
    """

    specs: list
    folds: list
    where: str
    tasks: list


def _check_specs(specs) -> None:
    """Refuse unknown model names and bad hyperparameters before any data is loaded or model fitted.

    A model whose optional dependency is missing passes: it is listed as skipped, with the reason.
    """
    from dam.registry import available, check_params, get, names

    known = names()
    for label, name, params, est in specs:
        if est is not None:
            check_params(est)
            continue
        if name not in known:
            raise KeyError(
                f"unknown model {name!r}"
                + (f" (row {label!r})" if label != name else "")
                + f"; known models: {', '.join(known)} (see `dam models`)"
            )
        if not available(name)[0]:
            continue
        cls = get(name)
        bad = sorted(set(params) - set(cls._param_names()))
        if bad:
            raise ValueError(
                f"model {label!r} ({cls.__name__}): unknown parameter(s) {bad}; "
                f"valid parameters are {cls._param_names()}"
            )
        check_params(cls(**params))


def _model_specs(models) -> list[tuple[str, str | None, dict, object]]:
    """(label, registry name, params, estimator or None) for every requested model."""
    from dam.base import Synthesizer

    if isinstance(models, str):
        models = [m.strip() for m in models.split(",") if m.strip()]
    if isinstance(models, dict):
        models = [(label, *(spec if isinstance(spec, tuple) else (spec,))) for label, spec in models.items()]
    out = []
    for m in models:
        if isinstance(m, Synthesizer):
            out.append((m.name or type(m).__name__, None, {}, m))
        elif isinstance(m, str):
            out.append((m, m, {}, None))
        elif isinstance(m, tuple) and len(m) in (2, 3):
            label, spec = m[0], m[1]
            params = dict(m[2]) if len(m) == 3 else {}
            if isinstance(spec, Synthesizer):
                out.append((label, None, {}, spec))
            else:
                out.append((label, spec, params, None))
        else:
            raise TypeError(f"a model is a registry name, a Synthesizer or (label, name[, params]); got {m!r}")
    labels = [o[0] for o in out]
    dup = {x for x in labels if labels.count(x) > 1}
    if dup:
        raise ValueError(f"model labels must be unique; repeated: {sorted(dup)} (give (label, name, params))")
    if not out:
        raise ValueError("no models to compare")
    return out


def _as_corpus(spec) -> Corpus:
    if isinstance(spec, Corpus):
        return spec
    from dam.datasets import resolve

    return resolve(spec)


def _audio_models(specs) -> list[str]:
    """Labels of the models that read audio (a model that cannot be built is left to its task)."""
    from dam.registry import get

    out = []
    for label, name, params, est in specs:
        try:
            model = est if est is not None else get(name)(**params)
            if "audio" in model.reads():
                out.append(label)
        except Exception:  # noqa: BLE001 - a missing extra or bad class is reported by its task
            continue
    return out


def _with_audio(corpus: Corpus, audio_models: list[str]) -> Corpus:
    """The utterances of ``corpus`` that have audio; says on stderr when that drops some."""
    from dam.corpus.data import DataError

    keep = [i for i, u in enumerate(corpus) if u.audio is not None]
    if not keep:
        raise DataError(
            corpus.source,
            "audio",
            corpus[0].name,
            f"no utterance of this corpus has audio, and {', '.join(audio_models)} read(s) audio",
        )
    if len(keep) < len(corpus):
        print(
            f"compare: {', '.join(audio_models)} read(s) audio: every model is trained and scored on the "
            f"{len(keep)} of {len(corpus)} utterances of {corpus.name or corpus.source} that have audio",
            file=sys.stderr,
        )
        corpus = corpus.subset(keep)
    return corpus


def plan_comparison(
    models,
    train,
    test=None,
    cv: int | None = None,
    out=None,
    *,
    test_size: float = 0.25,
    random_state: int = 0,
    unknown_phone: str | None = "fallback",
    channels=None,
) -> ComparisonPlan:
    """Check everything that can be checked before a fit and build the tasks.

    Parameters are those of :func:`compare`. Unknown model names and bad
    hyperparameters (:func:`dam.registry.check_params`), an output directory
    inside an input corpus, train and test channels or frame rates that differ
    raise here, before any model is fitted.

    Returns
    -------
    ComparisonPlan
    """
    specs = _model_specs(models)
    _check_specs(specs)  # a typo in a name or a parameter fails now, not after the other fits
    train = _as_corpus(train)
    if out is not None:  # checked before any fit: never into an input corpus, never over a corpus
        inputs = [train.source] + ([test] if isinstance(test, (str, os.PathLike)) else [getattr(test, "source", None)])
        check_output(out, inputs=inputs, directory=True, merge=True, option="out")
        os.makedirs(out, exist_ok=True)
    if channels is not None:
        train = train.select_channels(channels)
    audio_models = _audio_models(specs)
    if audio_models:  # every row on the same utterances: those that have audio
        train = _with_audio(train, audio_models)
    if test is not None and cv is not None:
        raise ValueError("give either test or cv, not both")
    if cv is not None:
        folds = list(train.kfold(int(cv), random_state=random_state))
        where = f"{train.name or train.source or 'corpus'} ({int(cv)}-fold cross-validation)"
    elif test is not None:
        test = _as_corpus(test)
        if channels is not None:
            test = test.select_channels(channels)
        if audio_models:
            test = _with_audio(test, audio_models)
        folds = [(train, test)]
        where = f"{test.name or test.source or 'test corpus'}"
    else:
        folds = [train.train_test_split(test_size, random_state=random_state)]
        where = f"{train.name or train.source or 'corpus'} (hold-out {test_size:g})"
    if tuple(folds[0][1].channels) != tuple(folds[0][0].channels):
        raise ValueError(
            f"train and test channels differ: {list(folds[0][0].channels)} vs {list(folds[0][1].channels)}"
        )
    if folds[0][1].frame_rate != folds[0][0].frame_rate:
        # models predict at the training frame rate: scores against another rate would be meaningless
        raise ValueError(
            f"train and test frame rates differ: {folds[0][0].frame_rate:g} Hz vs {folds[0][1].frame_rate:g} Hz"
        )
    tasks = [
        Task(label, name, params, est, k, tr, te, unknown_phone)
        for label, name, params, est in specs
        for k, (tr, te) in enumerate(folds)
    ]
    return ComparisonPlan(specs=specs, folds=folds, where=where, tasks=tasks)


# -- running ------------------------------------------------------------------
@dataclass
class TaskResult:
    """What one :class:`Task` gave.

    Attributes
    ----------
    model : str
        The task's label.
    fold : int
    status : {"ok", "skipped", "failed"}
    reason : str
    predictions : list of ndarray
        One ``(n_frames, n_channels)`` array per test utterance (empty unless ok).
    fit_seconds, first_predict_seconds, predict_seconds : float
        The first prediction includes jit compilation (neural models); ``predict_seconds``
        is the median of warm runs.
    n_phones, n_frames : int
        Of the test part.
    """

    model: str
    fold: int
    status: str = "ok"
    reason: str = ""
    predictions: list = field(default_factory=list)
    fit_seconds: float = float("nan")
    first_predict_seconds: float = float("nan")
    predict_seconds: float = float("nan")
    n_phones: int = 0
    n_frames: int = 0


def run_task(task: Task) -> TaskResult:
    """Fit one model on one fold and predict its test part (runs in a joblib worker)."""
    from dam.base import predict_inputs
    from dam.registry import available, get

    res = TaskResult(task.label, task.fold)
    params = task.params
    try:
        if task.estimator is None:
            ok, why = available(task.name)
            if not ok:
                return _not_ok(res, "skipped", f"optional dependency missing: {why}")
            model = get(task.name)(**params)
        else:
            from dam.base import clone

            model = clone(task.estimator)
            params = task.estimator.get_params()  # an instance keeps all its own settings
        if task.unknown_phone is not None and "unknown_phone" in model.get_params() and "unknown_phone" not in params:
            model.set_params(unknown_phone=task.unknown_phone)
        t0 = time.perf_counter()
        model.fit(task.train)
        res.fit_seconds = time.perf_counter() - t0
        t0 = time.perf_counter()
        inputs = predict_inputs(model, task.test)
        res.predictions = model.predict(inputs)
        res.first_predict_seconds = time.perf_counter() - t0
        times = []
        while not times or (sum(times) < 1.0 and len(times) < 5):  # warm runs; their median is steadier
            t0 = time.perf_counter()
            model.predict(inputs)
            times.append(time.perf_counter() - t0)
        res.predict_seconds = float(np.median(times))
    except ImportError as exc:
        return _not_ok(res, "skipped", f"optional dependency missing: {exc}")
    except KeyError as exc:
        return _not_ok(res, "failed", str(exc.args[0] if exc.args else exc))
    except Exception as exc:  # one broken model must not sink the comparison
        return _not_ok(res, "failed", f"{type(exc).__name__}: {exc}")
    res.n_phones = sum(len(a) for a in task.test.alignments)
    res.n_frames = sum(u.n_frames for u in task.test)
    return res


def _not_ok(res: TaskResult, status: str, reason: str) -> TaskResult:
    return TaskResult(res.model, res.fold, status=status, reason=reason)


def run_tasks(
    plan: ComparisonPlan, n_jobs: int = 1, progress: Callable[[TaskResult, int, int], None] | None = None
) -> list[TaskResult]:
    """Run every task of ``plan`` through joblib; results in the order they finish.

    Parameters
    ----------
    plan : ComparisonPlan
    n_jobs : int, default 1
        joblib workers (-1: all cores); the active joblib backend (Dask, Ray) is used.
    progress : callable, optional
        ``progress(result, done, total)`` after every task, besides :mod:`dam.progress`.

    Returns
    -------
    list of TaskResult
    """
    from joblib import Parallel, delayed

    from dam.progress import task as progress_task

    tasks = plan.tasks
    try:
        parallel = Parallel(n_jobs=n_jobs, return_as="generator_unordered")
    except ValueError:  # a backend without result generators (some Dask/Ray versions): results at the end
        parallel = Parallel(n_jobs=n_jobs)
    index = {(t.label, t.fold): i for i, t in enumerate(tasks)}
    several = len(plan.folds) > 1
    results = []
    with progress_task(
        "compare", weights=[expected_fit_cost(t.name or t.estimator) for t in tasks], unit="fold" if several else "fit"
    ) as bar:
        for r in parallel(delayed(run_task)(t) for t in tasks):
            results.append(r)
            bar.step(
                f"{r.model}" + (f" fold {r.fold}" if several else "") + f": {r.status}", index=index[(r.model, r.fold)]
            )
            if progress is not None:
                progress(r, len(results), len(tasks))
    return results


# -- statistics -----------------------------------------------------------------
def score_results(
    plan: ComparisonPlan, results: list, *, n_boot: int = 2000, random_state: int = 0, verbose: int = 1
) -> ComparisonResult:
    """Score the predictions of every model on the pooled test utterances of all folds.

    Returns
    -------
    ComparisonResult
        Rows sorted by RMSE, skipped and failed models last; every ok model but
        the best tested against the best (:func:`~dam.evaluation.statistics.tests_against`).
    """
    from dam.evaluation.metrics import evaluate

    folds = plan.folds
    pooled = Corpus([u for _, te in folds for u in te], name=plan.where, metadata=folds[0][1].metadata)
    fold_of = [k for k, (_, te) in enumerate(folds) for _ in te]
    summary, per_channel, per_utt, per_sensor, preds_by_model, utt_rmse = [], [], [], [], {}, {}
    for label, *_ in plan.specs:
        mine = sorted((r for r in results if r.model == label), key=lambda r: r.fold)
        bad = [r for r in mine if r.status != "ok"]
        if bad:
            summary.append(ModelScore(label, status=bad[0].status, reason=bad[0].reason))
            if verbose:
                print(f"compare: {label} {bad[0].status}: {bad[0].reason}", file=sys.stderr)
            continue
        preds = [p for r in mine for p in r.predictions]
        ev = evaluate(None, pooled, predictions=preds)
        preds_by_model[label] = preds
        # masked (missing) values are not scored
        sse = np.array(
            [np.sum((u.trajectory - p) ** 2 * (1 if u.mask is None else u.mask)) for u, p in zip(pooled, preds)]
        )
        cnt = np.array([u.trajectory.size if u.mask is None else u.mask.sum() for u in pooled], dtype=float)
        lo, hi = bootstrap_rmse_ci(sse, cnt, n_boot=n_boot, random_state=random_state)
        predict_s = sum(r.predict_seconds for r in mine)
        summary.append(
            ModelScore(
                label,
                rmse=ev.rmse,
                rmse_ci_low=lo,
                rmse_ci_high=hi,
                pearson_r=ev.pearson_r,
                sensor_error=ev.sensor_error if ev.sensors else None,
                fit_seconds=float(np.mean([r.fit_seconds for r in mine])),
                predict_us_per_phone=1e6 * predict_s / sum(r.n_phones for r in mine),
                frames_per_second=sum(r.n_frames for r in mine) / max(predict_s, 1e-12),
                n_utterances=len(pooled),
            )
        )
        utt_rmse[label] = np.array([row["rmse"] for row in ev.per_utterance])
        for c, e, rr in zip(ev.channels, ev.rmse_per_channel, ev.pearson_per_channel):
            per_channel.append({"model": label, "channel": c, "rmse": float(e), "pearson_r": float(rr)})
        for (sensor, chans), d in zip(ev.sensors.items(), ev.sensor_error_per_sensor):
            per_sensor.append({"model": label, "sensor": sensor, "channels": " ".join(chans), "distance": float(d)})
        for k, row in zip(fold_of, ev.per_utterance):
            per_utt.append({"model": label, "fold": k, **row})

    ok = [r for r in summary if r.status == "ok"]
    best = min(ok, key=lambda r: r.rmse).model if ok else None
    if best is not None:
        tested = tests_against(utt_rmse[best], {r.model: utt_rmse[r.model] for r in ok if r.model != best})
        for r in ok:
            if r.model in tested:
                r.wilcoxon_p, r.wilcoxon_p_holm = tested[r.model]
    summary.sort(key=lambda r: (r.status != "ok", r.rmse if r.rmse is not None else 0.0))

    example = {}
    if preds_by_model:
        u = pooled[0]
        example = {
            "utterance": u.name,
            "frame_rate": u.frame_rate,
            "channels": list(u.channels),
            "alignment": u.alignment,
            "units": pooled.metadata.get("units"),
            "truth": np.asarray(u.trajectory),
            "predictions": {m: p[0] for m, p in preds_by_model.items()},
        }
    return ComparisonResult(
        summary=summary,
        per_channel=per_channel,
        per_utterance=per_utt,
        best=best,
        corpus=plan.where,
        example=example,
        per_sensor=per_sensor,
        length_unit=pooled.metadata.get("length_unit"),
    )


# -- all four -----------------------------------------------------------------------
def compare(
    models,
    train,
    test=None,
    cv: int | None = None,
    n_jobs: int = 1,
    out=None,
    *,
    test_size: float = 0.25,
    random_state: int = 0,
    n_boot: int = 2000,
    unknown_phone: str | None = "fallback",
    channels=None,
    verbose: int = 1,
    progress: Callable[[TaskResult, int, int], None] | None = None,
) -> ComparisonResult:
    """Fit and score several synthesizers on the same held-out data.

    Parameters
    ----------
    models : str, list or dict
        Registry names (``"dam,mmm"`` or ``["dam", "mmm"]``), fitted-or-not
        Synthesizer instances, ``(label, name, params)`` tuples, or a dict
        ``{label: (name, params)}``.
    train : Corpus or str
        A corpus, a corpus directory or a bundled name (``"tiny"``, ``"vtl:train"``).
    test : Corpus or str, optional
        Held-out corpus. Without ``test`` and ``cv``, ``train`` is split
        ``test_size`` / rest (utterance level, ``random_state``).
    cv : int, optional
        K-fold cross-validation over the utterances of ``train`` instead
        (every utterance scored once, by the model not trained on it).
    n_jobs : int, default 1
        joblib workers over models x folds (-1: all cores).
    out : path, optional
        Write the tables and figures there (:meth:`ComparisonResult.write`).
    test_size : float, default 0.25
    random_state : int, default 0
        Seeds the split, the folds and the bootstrap.
    n_boot : int, default 2000
        Bootstrap resamples of the RMSE interval.
    unknown_phone : {"fallback", "error"} or None, default "fallback"
        Given to every model that has this parameter and was not given it
        explicitly: a test phone never seen in training is replaced by the
        documented fallback (:func:`dam.phonetics.fallback_phone`) instead of
        failing the model. None keeps the models' own defaults.
    channels : list of str, optional
        Compare on these channels only (see :meth:`dam.Corpus.select_channels`).
    verbose : int, default 1
        Progress bar on standard error (only when it is a terminal).
    progress : callable, optional
        ``progress(result, done, total)`` after every fitted task (a :class:`TaskResult`).

    Returns
    -------
    ComparisonResult

    Examples
    --------
    >>> import dam
    >>> res = dam.compare(["phone-mean", "target-interpolation"], "tiny", cv=2, verbose=0)
    >>> [row["model"] for row in res.summary]
    ['target-interpolation', 'phone-mean']
    """
    plan = plan_comparison(
        models,
        train,
        test,
        cv,
        out,
        test_size=test_size,
        random_state=random_state,
        unknown_phone=unknown_phone,
        channels=channels,
    )
    results = run_tasks(plan, n_jobs, progress=progress)
    result = score_results(plan, results, n_boot=n_boot, random_state=random_state, verbose=verbose)
    if out is not None:
        result.write(out)
    return result


# -- demo ---------------------------------------------------------------------
#: The full demo's channels (``dam demo --full``): jaw, lips, tongue body and tip.
DEMO_CHANNELS = {"vtl": ("JA", "LP", "LD", "TCX", "TCY", "TTY")}
#: The quick demo (``dam demo``, under a minute on two cores): jaw angle, lip distance and tongue-tip
#: height, all the training data, and the classical models but two: the 1993 Cohen-Massaro model
#: and the linguistic decision tree, which ``dam demo --full`` adds.
QUICK_DEMO = {
    "vtl": {
        "channels": ("JA", "LD", "TTY"),
        "train_minutes": None,
        "models": tuple(m for m in DEMO_MODELS[:-1] if m != "cohen-massaro"),
    }
}


def demo_plan(corpus: str = "vtl", *, full: bool = False, channels="demo") -> dict:
    """What ``dam demo`` runs on ``corpus``: ``models``, ``channels``, ``train_minutes`` and a
    one-paragraph ``description`` said up front.

    The quick plan (the default; ``QUICK_DEMO``) takes under a minute on two cores
    (``benchmarks/results/compare_demo.md``); ``full=True`` is every demo model on the six
    demo channels and all the training data (about 3 minutes).
    """
    import dam.datasets as datasets

    ds = datasets._get(corpus)
    quick = None if full else QUICK_DEMO.get(corpus)
    models = quick["models"] if quick else DEMO_MODELS
    if channels == "demo":
        channels = quick["channels"] if quick else DEMO_CHANNELS.get(corpus)
    minutes = quick["train_minutes"] if quick else None
    left_out = [m if isinstance(m, str) else m[0] for m in DEMO_MODELS if m not in models]
    names = [m if isinstance(m, str) else m[0] for m in models]
    part = (
        f"the {f'first {minutes:g} minutes of the ' if minutes else ''}training part"
        if "test" in ds.splits
        else "three quarters of the utterances"
    )
    held = "its held-out test part (words never seen in training)" if "test" in ds.splits else "the other quarter"
    cost = {
        ("vtl", True): f"Under a minute on two cores (--full adds {' and '.join(left_out)} and six channels: "
        "several minutes).",
        ("vtl", False): "Several minutes on two cores.",
    }.get((corpus, quick is not None), "The progress line shows the time left.")
    text = (
        f"dam demo: fits {len(models)} models ({', '.join(names)}) on {part} of the bundled corpus "
        f"'{corpus}' ({'channels ' + ', '.join(channels) if channels else 'all channels'}), scores them on "
        f"{held} and prints the comparison table. {cost}"
    )
    return {"models": models, "channels": channels, "train_minutes": minutes, "description": text}


def _first_minutes(corpus: Corpus, minutes: float | None) -> Corpus:
    if minutes is None:
        return corpus
    n, total = 0, 0.0
    while n < len(corpus) and total < 60.0 * minutes:
        total += corpus[n].duration
        n += 1
    return corpus.subset(range(n))


def run_demo(
    out_dir=None,
    *,
    corpus: str | None = None,
    models=None,
    n_jobs: int = 1,
    channels="demo",
    full: bool = False,
    verbose: int = 1,
) -> ComparisonResult:
    """The ``dam demo`` comparison on a bundled corpus (:func:`demo_plan`); prints the table.

    ``vtl`` by default: trained on its train part, scored
    on its held-out test part (disjoint words), on the plan's channels (``channels=None`` for
    all 19). Models whose dependencies are missing are listed as skipped.
    """
    import dam.datasets as datasets

    name = corpus or "vtl"
    ds = datasets._get(name)
    plan = demo_plan(name, full=full, channels=channels)
    models = plan["models"] if models is None else models
    if verbose:
        print(plan["description"], file=sys.stderr)
        print(file=sys.stderr)
        print(datasets.describe(name), file=sys.stderr)
        print(file=sys.stderr)
    if "test" in ds.splits:
        train = _first_minutes(datasets.load(name, "train"), plan["train_minutes"])
        res = compare(
            models, train, f"{name}:test", n_jobs=n_jobs, out=out_dir, channels=plan["channels"], verbose=verbose
        )
    else:
        res = compare(models, name, n_jobs=n_jobs, out=out_dir, channels=plan["channels"], verbose=verbose)
    print(res.table())
    return res
