"""Shared test set-up. Tests import ``dam`` as installed (pytest runs in importlib mode and
does not put the source tree on ``sys.path``)."""

import os

# One BLAS thread per test process: on a shared, loaded machine OpenBLAS's
# thread pool makes a 3000x80 SVD 50x slower (1.4 s instead of 0.04 s).
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import matplotlib  # noqa: E402

matplotlib.use("Agg")


def _missing_test_requirements() -> list[str]:
    """Distributions that ``pip install -e ".[test]"`` installs and that are missing here.

    Read from the installed package's metadata (pyproject.toml is the one list): the
    ``test`` extra and every extra of dam it pulls in (``dam[jax,audio,vtl]``).
    """
    import re
    from importlib.metadata import PackageNotFoundError, requires, version

    reqs = [
        re.match(r"\s*([A-Za-z0-9_.\-]+)(\[[^\]]*\])?[^;]*(?:;\s*extra\s*==\s*['\"]([^'\"]+)['\"])?", r)
        for r in requires("dam") or []
    ]
    by_extra: dict[str, list] = {}
    for m in reqs:
        if m and m.group(3):
            by_extra.setdefault(m.group(3), []).append((m.group(1), m.group(2)))
    wanted, todo, seen = set(), ["test"], set()
    while todo:
        extra = todo.pop()
        if extra in seen:
            continue
        seen.add(extra)
        for name, extras in by_extra.get(extra, []):
            if name.lower() == "dam":
                todo += [e.strip() for e in (extras or "[]")[1:-1].split(",") if e.strip()]
            else:
                wanted.add(name)
    missing = []
    for name in sorted(wanted):
        try:
            version(name)
        except PackageNotFoundError:
            missing.append(name)
    return missing


def pytest_sessionstart(session):
    # A required dependency that is missing fails the run; no test file skips itself for it.
    missing = _missing_test_requirements()
    if missing:
        import pytest

        pytest.exit(f'the test run needs {", ".join(missing)}: pip install -e ".[test]"', returncode=1)
