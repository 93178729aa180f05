"""Shared test set-up. Tests import ``dam`` as installed (pytest runs in importlib mode and
does not put the source tree on ``sys.path``)."""
import os

# One BLAS thread per test process: on a shared, loaded machine OpenBLAS's
# thread pool makes a 3000x80 SVD 50x slower (1.4 s instead of 0.04 s).
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import matplotlib  # noqa: E402

matplotlib.use("Agg")
