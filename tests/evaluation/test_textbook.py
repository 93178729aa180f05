"""Textbook figures (issue 18): a typed phone sequence, its dominance functions and their weighted sum,
the same sequence under several models; every figure has a title and non-empty axis labels."""

import warnings

import numpy as np
import pytest

import dam
from dam.corpus import DataError
from dam.evaluation.textbook import phone_sequence, plot_dominance_sum, plot_sequence


@pytest.fixture(scope="module")
def fitted():
    train = dam.datasets.load("tiny")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", dam.base.ConvergenceWarning)  # a short fit is enough to draw
        return train, {
            "phone-mean": dam.make("phone-mean").fit(train),
            "dam": dam.make("dam", degree=2, max_iter=3).fit(train),
        }


def _data_axes(fig):
    """Panels with data (not the phone tiers, whose y axis is "phones")."""
    return [
        ax
        for ax in fig.axes
        if ax.get_visible()
        and (ax.lines or ax.collections or ax.patches)
        and ax.get_ylabel() != "phones"
        and not ax.get_label() == "<colorbar>"
    ]


def _labelled(fig):
    """A title, and every row of panels has a y label, every column an x label (small multiples
    label the row once, at the left, and the column once, at the bottom)."""
    assert fig._suptitle is not None and fig._suptitle.get_text().strip()
    fig.canvas.draw()
    panels = [ax for ax in fig.axes if ax.get_visible() and ax.get_label() != "<colorbar>"]
    rows, cols = {}, {}
    for ax in panels:
        box = ax.get_position()
        rows.setdefault(round(box.y0, 2), []).append(ax.get_ylabel().strip())
        cols.setdefault(round(box.x0, 2), []).append(ax.get_xlabel().strip())
    assert all(any(labels) for labels in rows.values()), rows
    assert all(any(labels) for labels in cols.values()), cols


def test_phone_sequence_lays_phones_end_to_end():
    a = phone_sequence("sil m iy sil", [0.2, 0.05, 0.1, 0.2])
    assert list(a.labels) == ["sil", "m", "iy", "sil"]
    np.testing.assert_allclose(a.starts, [0, 0.2, 0.25, 0.35])
    np.testing.assert_allclose(a.ends, [0.2, 0.25, 0.35, 0.55])
    with pytest.raises(DataError, match="durations"):
        phone_sequence("a b", [0.1, -1])
    with pytest.raises(DataError, match="phones"):
        phone_sequence("  ")


def test_dominance_sum_draws_eq1_and_the_weighted_average(fitted):
    train, models = fitted
    model = models["dam"]
    a = phone_sequence("sil m uw s iy sil", 0.12)
    fig = plot_dominance_sum(model, a, channel=1, metadata=train.metadata)
    _labelled(fig)
    by_title = {ax.get_title().split(",")[0]: ax for ax in _data_axes(fig)}
    ax_d = by_title["dominance of each segment"]
    ax_share = by_title["how much each segment counts at every instant"]
    ax_out = next(ax for t, ax in by_title.items() if t.startswith("animemes"))
    rows = model.explain(a)
    curves = [ln for ln in ax_d.lines if np.size(ln.get_xdata()) > 2]  # not the phone boundaries
    t = np.asarray(curves[0].get_xdata())
    # the first curve is Eq. (1) of the first segment, from the closed form with the model's sigma
    r = rows[0]
    sigma = model.modes_of(r["phone"])["sigma"][r["mode"], 1]
    tl = (t - r["start"]) / (r["end"] - r["start"])
    d = np.where(
        tl < 0,
        np.exp(-(tl**2) / (sigma**2 + model.eps)),
        np.where(tl > 1, np.exp(-((tl - 1) ** 2) / (sigma**2 + model.eps)), 1.0),
    )
    d[d < model.dominance_tol] = 0.0
    np.testing.assert_allclose(curves[0].get_ydata(), d, atol=1e-12)
    # the stacked shares sum to one at every instant
    top = ax_share.collections[-1].get_paths()[0].vertices[:, 1].max()
    assert top == pytest.approx(1.0, abs=1e-9)
    # the black line is the model's own output
    np.testing.assert_allclose(ax_out.lines[-1].get_ydata(), model.predict(a)[:, 1])
    dam.plotting.pyplot().close(fig)


def test_sequence_under_several_models(fitted):
    train, models = fitted
    u = train[3]
    fig = plot_sequence(
        models, u.alignment, ["jaw_open", "tongue_tip"], truth=u.trajectory, metadata=train.metadata, name=u.name
    )
    _labelled(fig)
    panels = _data_axes(fig)
    assert len([ax for ax in panels if ax.get_title() in models]) == 2
    assert "(a.u.)" in panels[0].get_ylabel()
    # each panel: the recording and the model's prediction of that channel
    ax = panels[0]
    np.testing.assert_allclose(ax.lines[-2].get_ydata(), u.trajectory[:, 2])
    np.testing.assert_allclose(ax.lines[-1].get_ydata(), models["phone-mean"].predict(u.alignment)[:, 2])
    with pytest.raises(DataError, match="not a channel"):
        plot_sequence(models, u.alignment, ["nope"])
    dam.plotting.pyplot().close(fig)


def test_every_figure_function_has_labelled_axes(fitted, tmp_path):
    """Every figure function of the toolkit returns a figure with a title and non-empty axis labels."""
    from dam.model import figures as mf

    train, models = fitted
    m, u = models["dam"], train[0]
    phones = mf.inspected_phones(m, 2)
    figs = [
        mf.plot_dominance(m, u, 0, metadata=train.metadata),
        mf.plot_animemes(m, phones, 0),
        mf.plot_modes(m, phones, 0),
        mf.plot_astar(m, u.alignment),
        plot_dominance_sum(m, u.alignment),
        plot_sequence(models, u.alignment),
    ]
    from dam.evaluation.figures import plot_predictions, plot_rmse

    ex = {
        "utterance": u.name,
        "frame_rate": train.frame_rate,
        "channels": list(train.channels),
        "truth": u.trajectory,
        "alignment": u.alignment,
        "predictions": {k: v.predict(u.alignment) for k, v in models.items()},
    }
    summary = [
        {"model": k, "status": "ok", "rmse": 0.1 * (i + 1), "rmse_ci_low": 0.05, "rmse_ci_high": 0.3}
        for i, k in enumerate(models)
    ]
    figs.append(plot_predictions(ex, summary))
    figs.append(
        plot_rmse(
            summary, [{"model": k, "channel": c, "rmse": 0.1} for k in models for c in train.channels], best="dam"
        )
    )
    for fig in figs:
        _labelled(fig)
        dam.plotting.pyplot().close(fig)
