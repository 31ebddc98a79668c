"""pendulab.ensemble on a Dask LocalCluster (2 processes): same results as local; errors name chunks."""

from __future__ import annotations

import sys

import numpy as np
import pytest

import pendulab as pl
from pendulab.ensemble.batch import ChunkTask
from pendulab.ensemble.cluster import run_on_dask

pytest.importorskip("heyoka")
distributed = pytest.importorskip("distributed")


@pytest.fixture(scope="module")
def client():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        with distributed.Client(cluster) as c:
            yield c


def _x0(n=24):
    rng = np.random.default_rng(7)
    x0 = np.zeros((n, 4))
    x0[:, :2] = rng.uniform(-3, 3, (n, 2))
    return x0


def test_dask_equals_local(client):
    model = pl.rigid()
    x0 = _x0()
    # chunk_size 8 = the local chunking of 24 runs on 1 thread: same lanes, bitwise-equal results.
    local = pl.ensemble(model, x0, 2.0, events=["flip"], threads=1, chunk_size=8)
    remote = pl.ensemble(model, x0, 2.0, events=["flip"], client=client, chunk_size=8)
    assert remote.stats["n_chunks"] == 3
    np.testing.assert_array_equal(remote.x_final, local.x_final)
    np.testing.assert_array_equal(remote.event_times["flip"], local.event_times["flip"])
    np.testing.assert_array_equal(remote.status, local.status)


def test_dask_address_string(client):
    model = pl.rigid()
    x0 = _x0(8)
    res = pl.ensemble(model, x0, 1.0, client=client.scheduler.address, chunk_size=4)
    np.testing.assert_allclose(res.x_final, pl.ensemble(model, x0, 1.0, threads=1).x_final, rtol=0, atol=1e-12)


def test_failed_chunk_raises_naming_it(client):
    model = pl.rigid()
    good = pl.ensemble(model, _x0(4), 1.0, threads=1)  # warm the key
    from pendulab.ensemble.batch import BatchKey
    from pendulab.ensemble.events import EventPlan

    key = BatchKey("rigid", (), 1e-12, EventPlan(), 8)
    tasks = [
        ChunkTask(key, 0, good.x0, good.params, 1.0, None),
        ChunkTask(key, 1, np.zeros((2, 3)), good.params[:2], 1.0, None),  # wrong state size: fails in the worker
    ]
    with pytest.raises(RuntimeError, match=r"chunks \[1\] failed"):
        run_on_dask(client, tasks, lambda k: None)


def test_without_distributed_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)
    with pytest.raises(ImportError, match=r"pendulab\[dask\]"):
        pl.ensemble(pl.rigid(), _x0(2), 1.0, client="tcp://127.0.0.1:1")
