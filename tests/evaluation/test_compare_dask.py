"""``compare`` spread over a Dask cluster (joblib's dask backend) gives the local run's table.

A lab runs the same comparison on its cluster with::

    from dask.distributed import Client
    import joblib, dam
    client = Client("scheduler-address:8786")          # or LocalCluster() on one machine
    with joblib.parallel_config(backend="dask"):
        dam.compare(["dam", "dam-m0", "cohen-massaro", "mmm"], "vtl:train", "vtl:test", n_jobs=-1)

Here the cluster is a ``dask.distributed.LocalCluster`` of two worker processes.
"""

import joblib
import numpy as np
import pytest
from distributed import Client, LocalCluster, get_task_stream

import dam

MODELS = ["phone-mean", "target-interpolation", ("dam-m0 quick", "dam-m0", {"max_iter": 2, "n_resample": 8})]


def _table(res):
    return [(row["model"], row["rmse"], row["pearson_r"]) for row in res.summary]


@pytest.mark.filterwarnings("ignore::dam.base.ConvergenceWarning")
def test_compare_on_a_dask_local_cluster_equals_the_local_run():
    local = dam.compare(MODELS, "tiny", cv=2, verbose=0)
    with (
        LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster,
        Client(cluster) as client,
    ):
        with get_task_stream(client) as stream, joblib.parallel_config(backend="dask"):
            spread = dam.compare(MODELS, "tiny", cv=2, verbose=0, n_jobs=-1)
        # every fit (3 models x 2 folds) ran as a task on the cluster's worker processes
        workers = {t["worker"] for t in stream.data}
        assert len(stream.data) >= len(MODELS) * 2 and workers <= set(client.scheduler_info()["workers"])
    a, b = _table(local), _table(spread)
    assert [m for m, *_ in a] == [m for m, *_ in b]
    np.testing.assert_allclose([v[1:] for v in a], [v[1:] for v in b], rtol=1e-12)
    assert len(a) == len(MODELS)
