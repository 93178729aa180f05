"""Every figure function of the toolkit renders in the one style (dam.plotting): a title saying what
and on which data, labelled axes with units, the phones under time axes, legends outside the data,
the colour-blind-safe palette. (The examples' figures are checked the same way in tests/examples.)"""

from types import SimpleNamespace

import pytest

import dam
from dam import plotting
from dam.evaluation.figures import plot_loss_curves, plot_predictions, plot_rmse
from dam.model.figures import inspected_phones, mode_label, plot_animemes, plot_astar, plot_dominance, plot_modes


@pytest.fixture(scope="module")
def tiny():
    corpus = dam.datasets.load("tiny")
    return corpus, *corpus.train_test_split(0.25, random_state=0)


@pytest.fixture(scope="module")
def comparison(tiny):
    corpus, train, test = tiny
    return dam.compare(["phone-mean", "target-interpolation", ("dam", "dam", {"max_iter": 2})], train, test, verbose=0)


@pytest.fixture(scope="module")
def fitted_dam(tiny):
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", dam.ConvergenceWarning)
        return dam.make("dam", max_iter=2).fit(tiny[1])


def _texts(fig):
    return [t.get_text() for ax in fig.axes for t in ax.texts]


def _ylabels(fig):
    return [ax.get_ylabel() for ax in fig.axes if ax.get_ylabel()]


def _check(fig):
    problems = plotting.check_figure(fig)
    assert not problems, problems
    assert fig._suptitle is not None and len(fig._suptitle.get_text()) > 20


def test_predictions_small_multiples_with_units_and_phones(comparison, tiny):
    fig = plot_predictions(comparison.example, comparison.summary, corpus=comparison.corpus)
    _check(fig)
    title = fig._suptitle.get_text()
    assert comparison.example["utterance"] in title and "tiny" in title
    # a row per channel (all 4), a column per model (all 3): one model per panel, not spaghetti
    data_axes = [
        ax for ax in fig.axes if ax.get_lines() and ax.get_ylabel() != "phones" and not ax.get_yticks().size == 0
    ]
    assert len(data_axes) == 4 * 3
    assert max(len([ln for ln in ax.get_lines() if ln.get_xydata().shape[0] > 2]) for ax in data_axes) == 2
    # units from corpus.json ("a.u." for the toy corpus) on every channel's axis
    assert sum("(a.u.)" in y for y in _ylabels(fig)) == 4
    # the phones of the utterance under each column
    labels = list(comparison.example["alignment"].labels)
    assert _texts(fig).count(labels[1]) >= 3 * labels.count(labels[1])
    plotting.pyplot().close(fig)


def test_rmse_figure_says_which_channels_and_explains_the_best_colour(comparison):
    fig = plot_rmse(
        comparison.summary,
        comparison.per_channel,
        best=comparison.best,
        corpus=comparison.corpus,
        metadata={"units": dict.fromkeys(["lip_aperture", "lip_protrusion", "jaw_open", "tongue_tip"], "a.u.")},
    )
    _check(fig)
    title = fig._suptitle.get_text()
    assert all(c in title for c in ("lip_aperture", "tongue_tip")) and "lower is better" in title
    legend_texts = [t.get_text() for leg in fig.legends for t in leg.get_texts()]
    assert any("best" in t for t in legend_texts)
    assert all("(a.u.)" in ax.get_xlabel() for ax in fig.axes if ax.get_visible() and ax.get_xlabel())
    plotting.pyplot().close(fig)


def test_loss_curves_have_a_title_and_labels():
    nets = {
        name: SimpleNamespace(loss_curve_=[1.0, 0.5, 0.4], validation_curve_=[0.9, 0.6, 0.65], best_epoch_=2)
        for name in ("sliding-dnn", "gru")
    }
    fig = plot_loss_curves(nets, corpus="tiny")
    _check(fig)
    assert "tiny" in fig._suptitle.get_text()
    plotting.pyplot().close(fig)


def test_dam_figures(fitted_dam, tiny):
    corpus, train, test = tiny
    phones = inspected_phones(fitted_dam)
    figs = [
        plot_dominance(fitted_dam, test[0], 0, corpus="tiny", metadata=corpus.metadata),
        plot_animemes(fitted_dam, phones, 0, corpus="tiny", metadata=corpus.metadata),
        plot_modes(fitted_dam, phones, 0, corpus="tiny", metadata=corpus.metadata),
        plot_astar(fitted_dam, test[0].alignment, name="tiny"),
    ]
    for fig in figs:
        _check(fig)
    # the dominance figure has the phones under its time axis
    assert set(test[0].alignment.labels) <= set(_texts(figs[0]))
    # modes are never labelled like ARPAbet stress digits (iy0, ao1)
    legend = [t.get_text() for ax in figs[2].axes if ax.get_legend() for t in ax.get_legend().get_texts()]
    assert legend and all("/mode " in t for t in legend if not t.split(":")[0].isalpha())
    assert not any(t[:-1].isalpha() and t[-1].isdigit() for t in legend)
    for fig in figs:
        plotting.pyplot().close(fig)


def test_mode_labels_cannot_be_read_as_stress_digits():
    assert mode_label("iy", 0, 2) == "iy/mode 1" and mode_label("ao", 1, 3) == "ao/mode 2"
    assert mode_label("sh", 0, 1) == "sh"


def test_channel_labels_say_the_unit():
    meta = {"units": {"JA": "deg", "VS": ""}}
    assert plotting.channel_label("JA", meta) == "JA (deg)"
    assert plotting.channel_label("VS", meta) == "VS (no unit)"
    assert plotting.channel_label("X", {}) == "X (channel units)"
    assert plotting.channel_label("X", {"length_unit": "mm"}) == "X (mm)"


def test_bundled_corpora_carry_units():
    vtl = dam.datasets.load("vtl", "test")
    assert vtl.metadata["units"]["JA"] == "deg" and vtl.metadata["units"]["LD"] == "cm"
    assert set(vtl.metadata["units"]) == set(vtl.channels)
    # VocalTractLab's own parameter table is the truth
    import vocaltractlab_cython  # the test extra installs it: a missing one fails the run

    info = {p["name"]: p["unit"] for p in vocaltractlab_cython.get_param_info("tract")}
    for ch, unit in vtl.metadata["units"].items():
        assert unit == info[ch].replace("deg.", "deg").replace("^2", "²")
    tiny = dam.datasets.load("tiny")
    assert set(tiny.metadata["units"]) == set(tiny.channels)


def test_check_figure_finds_what_breaks_the_rules():
    plt = plotting.pyplot()
    fig, ax = plt.subplots()
    ax.plot([0, 1], [0, 1], color="red")
    ax.legend(["x"], loc="center")
    problems = plotting.check_figure(fig)
    assert "no title" in problems
    assert any("no x label" in p for p in problems) and any("no y label" in p for p in problems)
    assert any("palette" in p for p in problems) and any("legend covers" in p for p in problems)
    plt.close(fig)


def test_save_is_atomic_and_needs_a_title(tmp_path):
    with pytest.raises(ValueError, match="title"):
        plotting.figure(1, 1, title="")
    fig, axes = plotting.figure(1, 1, title="a title")
    axes[0, 0].plot([0, 1], [0, 1])
    path = plotting.save(fig, tmp_path / "f.png")
    assert open(path, "rb").read(8) == b"\x89PNG\r\n\x1a\n"
    assert [p.name for p in tmp_path.iterdir()] == ["f.png"]
