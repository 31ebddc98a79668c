"""Several processes building and loading the same cache entries at once: all succeed, each entry is built once.

Four processes (``multiprocessing`` spawn: fresh interpreters, as separate commands would be) wait on a barrier,
then all ask for the same entries: the native library of the rigid model in a fresh ``PENDULAB_CACHE_DIR``
(compiled once: the others wait on the entry's lock and load the published file), and plan-library entries in
a temporary folder (each solved once). Every entry each process got verifies against its seal. No timing
assertion: the joins only bound how long a hang may take to be reported.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import time
from pathlib import Path

import numpy as np
import pytest

N_PROCESSES = 4
STARTS = np.array([[0.0, 0.0, 0.0, 0.0], [3.0, 0.0, -5.0, 2.0], [-1.0, 2.0, 4.0, 0.5], [0.5, -0.5, 1.0, 8.0]])
DESIGN = {"task": "pendubot", "params": [0.1, 0.2]}


def _plan(start: np.ndarray, n: int = 40) -> dict[str, np.ndarray]:
    s = np.linspace(0.0, 1.0, n)[:, None]
    return {
        "ok": np.array(True),
        "x_ref": start + s * np.array([1.0, -0.5, 2.0, 0.3]),
        "u_ref": np.linspace(-1.0, 1.0, n - 1) + start[0],
        "K": np.tile([1.0, 2.0, 0.3, 0.4], (n - 1, 1)) * (1.0 + start[1]),
    }


def _native_worker(counter: str, barrier, results) -> None:
    import pendulab as pl
    import pendulab.native.build as build
    from pendulab.native import native_library
    from pendulab.native.cache import sealed_key, verify_cached

    real = build.compile_shared

    def counting(*args, **kwargs):
        with open(counter, "a") as fh:  # one line per compilation, in whichever process runs it
            fh.write(f"{os.getpid()}\n")
        return real(*args, **kwargs)

    build.compile_shared = counting
    barrier.wait(timeout=300)
    lib = native_library("rigid")
    tr = pl.simulate(pl.rigid(), [2.0, 0.0, 0.0, 0.0], 0.5, method="compiled-dopri5", rtol=1e-10, atol=1e-10)
    results.put((str(lib.path), verify_cached(lib.path, sealed_key(lib.path)), tr.x[-1].tolist()))


def _plan_worker(folder: str, order: list[int], counters: str, barrier, results) -> None:
    from pendulab.control.plan_library import PlanCache
    from pendulab.native.cache import verify_cached

    cache = PlanCache(folder, DESIGN)

    def solve(i: int):
        def run():
            with open(Path(counters) / f"start{i}", "a") as fh:
                fh.write(f"{os.getpid()}\n")
            time.sleep(0.2)  # a solve takes a while: the others arrive while it runs
            return _plan(STARTS[i])

        return run

    barrier.wait(timeout=300)
    got = {}
    for i in order:
        entry = cache.get(STARTS[i], solve(i))
        got[i] = ({k: np.array(v) for k, v in entry.items()}, verify_cached(cache.path(STARTS[i]), cache.key(STARTS[i])))
    results.put(got)


def _run_all(target, args_of) -> list:
    ctx = mp.get_context("spawn")
    barrier, results = ctx.Barrier(N_PROCESSES), ctx.Queue()
    procs = [ctx.Process(target=target, args=(*args_of(k), barrier, results)) for k in range(N_PROCESSES)]
    for p in procs:
        p.start()
    try:
        out = [results.get(timeout=600) for _ in procs]
        for p in procs:
            p.join(timeout=120)
            assert p.exitcode == 0, f"worker exit code {p.exitcode}"
    finally:
        for p in procs:
            if p.is_alive():
                p.kill()
    return out


@pytest.mark.needs_cc
def test_processes_building_the_same_native_library_compile_it_once(tmp_path, monkeypatch):
    cache = tmp_path / "cache"
    counter = tmp_path / "compilations"
    monkeypatch.setenv("PENDULAB_CACHE_DIR", str(cache))  # inherited by the spawned interpreters
    out = _run_all(_native_worker, lambda k: (str(counter),))
    paths = {path for path, _, _ in out}
    assert len(paths) == 1 and all(reason is None for _, reason, _ in out)
    assert len(counter.read_text().splitlines()) == 1  # one compilation for four processes
    assert len({tuple(x) for _, _, x in out}) == 1  # the same library, the same arithmetic
    assert not [p for p in (cache / "native").iterdir() if p.name.startswith(".")]  # no temporary left


def test_processes_building_the_same_plan_entries_solve_each_once(tmp_path):
    folder, counters = tmp_path / "plans", tmp_path / "counters"
    counters.mkdir()
    n = len(STARTS)
    out = _run_all(_plan_worker, lambda k: (str(folder), [(i + k) % n for i in range(n)], str(counters)))
    for i in range(n):
        assert len((counters / f"start{i}").read_text().splitlines()) == 1  # solved once, by one of the four
        expected = _plan(STARTS[i])
        for got in out:
            entry, reason = got[i]
            assert reason is None
            for key, value in expected.items():
                np.testing.assert_array_equal(entry[key], value)
    assert len(list(folder.glob("plan-*.npz"))) == n
    assert not [p for p in folder.iterdir() if p.name.startswith(".")]
