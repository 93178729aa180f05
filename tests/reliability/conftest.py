"""Fixtures of the reliability suite (issue 12): small corpora on disk and small model files."""

import shutil

import numpy as np
import pytest

import dam
from dam.datasets import DATA


@pytest.fixture
def small_corpus_dir(tmp_path):
    """A corpus directory: three utterances of the bundled tiny corpus and its corpus.json."""
    d = tmp_path / "corpus"
    d.mkdir()
    for name in (
        "corpus.json",
        "tiny000.TextGrid",
        "tiny000.csv",
        "tiny001.TextGrid",
        "tiny001.csv",
        "tiny002.TextGrid",
        "tiny002.csv",
    ):
        shutil.copy(DATA / "tiny" / name, d / name)
    return d


@pytest.fixture(scope="session")
def tiny_train():
    return dam.datasets.load("tiny")[:4]


@pytest.fixture(scope="session")
def phone_mean_file(tmp_path_factory, tiny_train):
    """A fitted phone-mean model file and its predictions for the first utterance."""
    path = tmp_path_factory.mktemp("models") / "pm.dam"
    model = dam.make("phone-mean").fit(tiny_train)
    model.save(path)
    return path, model.predict(tiny_train[0].alignment)


@pytest.fixture(scope="session")
def micro_model_file(tmp_path_factory):
    """The smallest phone-mean model file (2 phones, 1 channel; under 1 kB) for every-byte fuzzing."""
    a = dam.Alignment(["a", "b"], [0.0, 0.05], [0.05, 0.1])
    corpus = dam.Corpus([dam.Utterance(a, np.linspace(0, 1, 11)[:, None], 100.0, ["x"])])
    path = tmp_path_factory.mktemp("micro") / "micro.dam"
    model = dam.make("phone-mean").fit(corpus)
    model.save(path)
    return path, a, model.predict(a)
