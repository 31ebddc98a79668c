"""pendulab.ensemble on a Dask LocalCluster (2 processes): same results as local; errors name chunks."""

from __future__ import annotations

import sys

import numpy as np
import pytest

import pendulab as pl
from pendulab._checks import MissingExtraError
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
    # Like with like: the batch width is forced (not the host's SIMD width) and chunk_size 2 is below
    # every local rule's floor, so local and Dask chunks are the same runs in the same lanes: bitwise equal.
    local = pl.ensemble(model, x0, 2.0, events=["flip"], threads=1, chunk_size=2, batch_size=4)
    remote = pl.ensemble(model, x0, 2.0, events=["flip"], client=client, chunk_size=2, batch_size=4)
    assert remote.stats["chunk_size"] == local.stats["chunk_size"] == 2 and remote.stats["n_chunks"] == 12
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

    key = BatchKey("rigid", (), 1e-12, EventPlan(), 4)
    tasks = [
        ChunkTask(key, 0, good.x0, good.params, 1.0, None),
        ChunkTask(key, 1, np.zeros((2, 3)), good.params[:2], 1.0, None),  # wrong state size: fails in the worker
    ]
    with pytest.raises(RuntimeError, match=r"chunks \[1\] failed"):
        run_on_dask(client, tasks, lambda k: None)


def test_without_distributed_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)
    with pytest.raises(MissingExtraError, match=r"pendulab\[dask\]"):
        pl.ensemble(pl.rigid(), _x0(2), 1.0, client="tcp://127.0.0.1:1")


def test_no_workers_ends_with_one_line_error(monkeypatch):
    # A cluster with no worker at all: the wait is bounded (here 1 s) and says what is wrong.
    monkeypatch.setenv("PENDULAB_DASK_NO_WORKER_TIMEOUT", "1")
    with distributed.LocalCluster(n_workers=0, processes=False, dashboard_address=":0") as cluster:
        with distributed.Client(cluster) as c:
            with pytest.raises(RuntimeError, match=r"no Dask worker connected to .* for 1 s") as info:
                pl.ensemble(pl.rigid(), _x0(4), 1.0, client=c, chunk_size=2)
    assert "\n" not in str(info.value) and "NoneType" not in str(info.value)


def test_repeated_calls_never_reuse_an_earlier_result(client):
    # Keys used to contain id(tasks), which Python reuses once a list is freed: Dask then handed back
    # the finished chunks of the previous ensemble (another horizon) as this one's result.
    model = pl.rigid()
    x0 = _x0(4)
    finals = [pl.ensemble(model, x0, t, client=client, chunk_size=2, batch_size=2).t_final for t in (0.5, 1.0, 1.5)]
    for t, tf in zip((0.5, 1.0, 1.5), finals, strict=True):
        np.testing.assert_array_equal(tf, t)  # each run ends at its own horizon exactly
