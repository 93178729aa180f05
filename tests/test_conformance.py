"""Every registered synthesizer through the public conformance suite: one case per check and model."""
import pytest

from dam import registry
from dam.testing import all_checks, default_corpora


def _cases():
    for name in registry.names():
        for check in all_checks():
            yield pytest.param(name, check, id=f"{name}-{check.__name__[len('check_'):]}")


# get_test_params caps EM iterations to keep the suite fast: the warning is expected there.
@pytest.mark.filterwarnings("ignore::dam.base.ConvergenceWarning")
@pytest.mark.parametrize("name,check", list(_cases()))
def test_conformance(name, check):
    ok, why = registry.available(name)
    if not ok:
        pytest.skip(f"{name} needs an optional dependency: {why}")
    cls = registry.get(name)
    estimator = cls(**cls.get_test_params()[0])
    train, test = default_corpora()
    check(estimator, train, test)


def test_registry_names_match_classes():
    for name in registry.names():
        if registry.available(name)[0]:
            assert registry.get(name).name == name
