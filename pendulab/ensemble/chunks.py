"""Chunks of an ensemble: splitting the runs into chunk tasks, running them locally (threads or forked
worker processes, Ctrl-C handled) and joining the chunks' outputs into per-run arrays.
"""

from __future__ import annotations

import contextlib
import contextvars
import math
import multiprocessing
import threading
from collections.abc import Callable, Iterator
from concurrent.futures import Executor, ProcessPoolExecutor, ThreadPoolExecutor

import numpy as np

from .batch import BatchKey, ChunkOut, ChunkStoppedError, ChunkTask, build, run_chunk
from .pool import completed, ignore_sigint, shutdown_now, sigint_blocked

__all__ = ["local_chunk_size", "shared_workers"]


# -- execution ---------------------------------------------------------------------
def local_chunk_size(n: int, chunk_size: int, batch_size: int, threads: int) -> int:
    """Runs per local chunk: at most ``chunk_size``, small enough to keep ``threads`` workers busy.

    A pure function of its arguments (never of the host), reported in the ensemble's stats. The results
    do not depend on it (each lane's arithmetic and time are its own).

    Parameters
    ----------
    n : int
        Number of runs.
    chunk_size : int
        Upper bound per chunk.
    batch_size : int
        SIMD lanes (a chunk never has fewer runs than lanes, unless ``chunk_size`` says so).
    threads : int
        Local workers.

    Returns
    -------
    int
        ``min(chunk_size, max(batch_size, ceil(n / (4 threads))))``.
    """
    return min(chunk_size, max(batch_size, math.ceil(n / (4 * threads))))


def _tasks(
    key: BatchKey,
    X0: np.ndarray,
    P: np.ndarray,
    tf: float,
    te: np.ndarray | None,
    size: int,
    max_steps: int,
    deadline: float | None,
) -> list[ChunkTask]:
    n = len(X0)
    return [
        ChunkTask(key, i, X0[a : a + size], P[a : a + size], tf, te, max_steps, deadline) for i, a in enumerate(range(0, n, size))
    ]


def _forked_processes(n_runs: int) -> bool:
    """Worker processes (fork) for big ensembles, threads for small ones.

    heyoka releases the GIL while it integrates, but the per-lane bookkeeping between event
    stops is Python: measured on the 400x400 flip map, 2 threads ran no faster than 1 while 2
    processes ran 1.5-1.9x faster. Forked workers inherit the compiled integrator (:func:`_run_local`
    builds it before the fork), so they start in milliseconds; below _PROCESS_MIN_RUNS runs, or where fork
    is unavailable, threads are used.
    """
    return n_runs >= _PROCESS_MIN_RUNS and "fork" in multiprocessing.get_all_start_methods()


def _process_pool(workers: int) -> ProcessPoolExecutor:
    """Forked workers that ignore SIGINT: Ctrl-C reaches the parent, which cancels the queue and ends them."""
    return ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("fork"), initializer=ignore_sigint)


#: Ensembles of at least this many runs use worker processes (see :func:`_forked_processes`).
_PROCESS_MIN_RUNS = 5000


class _Shared:
    """The worker processes kept by :func:`shared_workers` (None until the first ensemble forks them)."""

    def __init__(self) -> None:
        self.pool: ProcessPoolExecutor | None = None
        self.workers = 0


_SHARED: contextvars.ContextVar[_Shared | None] = contextvars.ContextVar("pendulab_shared_workers", default=None)


@contextlib.contextmanager
def shared_workers() -> Iterator[None]:
    """Let the local ensembles run inside this block share one set of forked worker processes.

    A caller that splits one job into several ensembles (the flip map records its runs in blocks)
    otherwise forks a new pool per ensemble and waits for each pool to drain: measured on the
    400 x 400 flip map in blocks of 5000 runs, 0.5-0.9 s more wall time (2.9-3.3 s against 2.1-2.4 s)
    than one ensemble of all runs. The pool is forked by the first ensemble that needs processes (after
    it built its integrator, which the workers inherit) and ended when the block exits; an error or
    Ctrl-C ends it at once, as for an ensemble's own pool.
    """
    shared = _Shared()
    token = _SHARED.set(shared)
    try:
        yield
    finally:
        _SHARED.reset(token)
        if shared.pool is not None:
            shared.pool.shutdown(wait=True)


def _run_local(tasks: list[ChunkTask], threads: int, report: Callable[[int | None], None]) -> list[ChunkOut]:
    if tasks:
        # Compile (or fetch from this process's cache) before any worker is forked: forked workers
        # inherit the compiled integrator. Built in the workers instead, every ensemble call (the CLI's
        # flip map makes one per recorded block of 5000 runs) paid a translation (~0.07 s) plus a JIT
        # compilation (~0.4 s without a hit in heyoka's on-disk cache) in each worker: measured
        # +1.2 s of CPU per 400x400 map with a warm disk cache and +4.7 s without one.
        try:
            build(tasks[0].key)
        except Exception:  # noqa: S110 -- the chunks hit it again and report it as they always did (chunk indices)
            pass
    if threads == 1 or len(tasks) == 1:
        # In this thread: a SIGINT raises KeyboardInterrupt between two propagation slices.
        outs = []
        for t in tasks:
            outs.append(_guarded(t))
            report(len(t.x0))
        return outs
    outs_by: dict[int, ChunkOut] = {}
    failed: list[tuple[int, BaseException]] = []
    stop = threading.Event()
    shared = _SHARED.get()
    pool: Executor
    if shared is not None and shared.pool is not None and shared.workers == threads:
        pool = shared.pool  # already forked: also the right place for a small ensemble of the block
    elif not _forked_processes(sum(len(t.x0) for t in tasks)):
        pool = ThreadPoolExecutor(max_workers=min(threads, len(tasks)))
    elif shared is None:
        pool = _process_pool(min(threads, len(tasks)))
    else:
        if shared.pool is not None:  # forked for another worker count: no more use
            shared.pool.shutdown(wait=True)
        # One worker per thread asked for, not per task: later ensembles of the block may have more tasks.
        shared.pool, shared.workers = _process_pool(threads), threads
        pool = shared.pool
    kept = shared is not None and pool is shared.pool
    try:
        if isinstance(pool, ThreadPoolExecutor):
            futures = {pool.submit(run_chunk, t, stop.is_set): t for t in tasks}
        else:
            with sigint_blocked():  # workers are forked in the first submit; ignore_sigint unblocks it in them
                futures = {pool.submit(run_chunk, t): t for t in tasks}
        for f in completed(futures):
            t = futures[f]
            exc = f.exception()
            if exc is not None:
                failed.append((t.index, exc))
                continue
            outs_by[t.index] = f.result()
            report(len(t.x0))
    except BaseException:
        # Ctrl-C (or any error here): running thread chunks stop at their next slice, queued chunks are
        # cancelled, worker processes are ended; nothing waits for the rest of the ensemble.
        stop.set()
        shutdown_now(pool)
        if kept:
            shared.pool = None
        raise
    if not kept:
        pool.shutdown(wait=True)
    if failed:
        failed.sort(key=lambda e: e[0])
        idx = [i for i, _ in failed]
        raise RuntimeError(
            f"ensemble: chunks {idx} failed; first error: {type(failed[0][1]).__name__}: {failed[0][1]}"
        ) from failed[0][1]
    return [outs_by[t.index] for t in tasks]


def _guarded(task: ChunkTask) -> ChunkOut:
    try:
        return run_chunk(task)
    except ChunkStoppedError:
        raise KeyboardInterrupt from None
    except Exception as exc:
        raise RuntimeError(f"ensemble: chunks [{task.index}] failed; first error: {type(exc).__name__}: {exc}") from exc


def _assemble(outs: list[ChunkOut], n: int, n_ev: int) -> tuple:
    cat = np.concatenate
    offsets = np.cumsum([0] + [len(o.t_final) for o in outs])
    message = [""] * n
    for o, a in zip(outs, offsets[:-1], strict=False):
        for r, msg in o.messages.items():
            message[a + r] = msg
    X = cat([o.x for o in outs]) if outs[0].x is not None else None
    ev = cat([o.event_times for o in outs], axis=1) if n_ev else np.empty((0, n))
    status = cat([o.status for o in outs])
    if np.any(status == 0):
        raise RuntimeError(f"ensemble: runs {np.flatnonzero(status == 0)[:10].tolist()} did not finish (internal error)")
    return (
        cat([o.x_final for o in outs]),
        cat([o.t_final for o in outs]),
        status,
        message,
        ev,
        cat([o.terminal_event for o in outs]),
        X,
    )
