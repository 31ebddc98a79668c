"""A generic parallel map over independent runs: forked worker processes on Linux, in-process otherwise.

The ensemble engine (:mod:`.engine`) integrates many states of one model in
heyoka's batch mode; closed loops with a Python controller per run (the
robustness scorecard) cannot be batched that way, but they are independent and
each costs tens of milliseconds, so whole runs go to worker processes.

Workers are *forked*: they inherit the caller's memory, so ``fn`` may be a
closure over unpicklable objects (CasADi Functions, a solved trajectory
optimization); only the items and the results cross the process boundary.

Ctrl-C: workers ignore SIGINT (it goes to the whole process group), the parent catches it,
cancels the queued chunks and ends the workers at once (:func:`shutdown_now`), so the map
stops within about a second and no worker prints a traceback.
"""

from __future__ import annotations

import contextlib
import itertools
import math
import multiprocessing
import os
import signal
import sys
import threading
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import FIRST_COMPLETED, Executor, Future, ProcessPoolExecutor, wait
from typing import Any, TypeVar

from .._inputs import checked

__all__ = ["map_runs", "default_workers", "ignore_sigint", "shutdown_now", "completed", "sigint_blocked"]

#: Most worker processes of one map.
MAX_WORKERS = 256
#: Seconds between two checks for Ctrl-C while waiting for workers.
POLL_INTERVAL = 0.1

T = TypeVar("T")
R = TypeVar("R")

# Functions being mapped, by job id; set before the fork so the workers inherit them (never pickled).
_JOBS: dict[int, Callable[[Any], Any]] = {}
_IDS = itertools.count()


def default_workers() -> int:
    """Number of local worker processes by default.

    Returns
    -------
    int
        ``os.cpu_count()`` (at least 1).
    """
    return max(1, os.cpu_count() or 1)


def ignore_sigint() -> None:
    """Worker-process initializer: ignore SIGINT (the parent handles Ctrl-C and ends the workers).

    On Linux the worker also asks the kernel to end it when its parent dies (``PR_SET_PDEATHSIG``),
    so a parent killed outright never leaves workers computing on their own.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    # map_runs forks with SIGINT blocked (a Ctrl-C between fork and this line would raise in the child):
    # now that it is ignored, unblock it (a pending one is discarded).
    if hasattr(signal, "pthread_sigmask"):
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
    if sys.platform.startswith("linux"):
        try:
            import ctypes

            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG
            if os.getppid() == 1:  # the parent already died between fork and prctl
                os._exit(1)
        except (OSError, AttributeError):
            pass


def completed(futures: Iterable[Future], poll: float = POLL_INTERVAL) -> Iterator[Future]:
    """Futures as they complete, like ``as_completed``, but interruptible by Ctrl-C at any time.

    A blocking ``as_completed`` waits on a lock; when the kernel delivers SIGINT to another thread
    (the pool's feeder or manager thread) the main thread is not woken and Python's handler runs
    only once some future completes, which for long chunks is minutes later. Waiting in slices of
    ``poll`` seconds lets the handler run within ``poll``.

    Parameters
    ----------
    futures : iterable of Future
        The futures to wait for.
    poll : float
        Seconds per wait.

    Yields
    ------
    Future
        Each future once it is done.
    """
    pending = set(futures)
    while pending:
        done, pending = wait(pending, timeout=poll, return_when=FIRST_COMPLETED)
        yield from done


def shutdown_now(pool: Executor) -> None:
    """Cancel the queued work of ``pool`` and end its worker processes without waiting for running work.

    Thread pools cannot be killed: their running tasks must watch a stop flag
    (the ensemble's chunks check one between propagation slices).

    Parameters
    ----------
    pool : concurrent.futures.Executor
        A process or thread pool.
    """
    # The worker list and the pool's manager thread must be read before shutdown(), which forgets them.
    procs = list((getattr(pool, "_processes", None) or {}).values()) if isinstance(pool, ProcessPoolExecutor) else []
    manager = getattr(pool, "_executor_manager_thread", None) if isinstance(pool, ProcessPoolExecutor) else None
    pool.shutdown(wait=False, cancel_futures=True)
    if procs:
        for p in procs:
            if p.is_alive():
                p.terminate()
        for p in procs:
            p.join(timeout=5.0)
            if p.is_alive():  # a worker that a loaded machine has not let handle SIGTERM yet: no worker outlives the pool
                p.kill()
                p.join(timeout=5.0)
    if manager is not None:
        # With its workers gone the manager thread ends and closes its wake-up pipe. Left running, it could close
        # that pipe while the interpreter's exit hook writes to it (CPython 3.11's _python_exit does so without a
        # lock; gh-125451 added one in 3.12): "OSError: [Errno 9] Bad file descriptor" at exit after a Ctrl-C.
        manager.join(timeout=5.0)


@contextlib.contextmanager
def sigint_blocked() -> Iterator[None]:
    """Hold a Ctrl-C back while workers are forked; it is raised right after, once the pool knows every worker.

    Two layers: SIGINT is blocked in this thread (a child forked meanwhile starts with it blocked,
    until :func:`ignore_sigint`), and Python's handler is swapped for one that only records the
    signal, because the kernel may deliver SIGINT to another thread (a pool or heyoka thread) and
    Python would then raise ``KeyboardInterrupt`` in the middle of the pool's bookkeeping, leaving
    a worker the pool does not know about (seen as a worker still alive after Ctrl-C).
    """
    deferred: list[tuple[int, Any]] = []
    previous: Any = None
    if threading.current_thread() is threading.main_thread():
        previous = signal.getsignal(signal.SIGINT)
        if callable(previous):
            signal.signal(signal.SIGINT, lambda signum, frame: deferred.append((signum, frame)))
        else:
            previous = None
    old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT}) if hasattr(signal, "pthread_sigmask") else None
    try:
        yield
    finally:
        if old is not None:
            signal.pthread_sigmask(signal.SIG_SETMASK, old)
        if previous is not None:
            signal.signal(signal.SIGINT, previous)
            if deferred:
                previous(*deferred[0])  # the default handler raises KeyboardInterrupt here


def _run_chunk(job: int, chunk: list[Any]) -> list[Any]:
    fn = _JOBS[job]
    return [fn(item) for item in chunk]


@checked()
def map_runs(
    fn: Callable[[T], R],
    items: Iterable[T],
    *,
    workers: int | None = None,
    progress: Callable[[int, int], None] | None = None,
    chunks_per_worker: int = 4,
) -> list[R]:
    """``[fn(item) for item in items]``, spread over forked worker processes.

    Parameters
    ----------
    fn : callable
        ``fn(item) -> result``; any callable (a closure is fine: workers are
        forked, ``fn`` is not pickled). Items and results must be picklable.
    items : iterable
        The runs, e.g. small run descriptions.
    workers : int, optional
        Worker processes (default :func:`default_workers`). With 1 worker, a
        single item, or where ``fork`` is unavailable the map runs in this
        process (same results: ``fn`` must not depend on where it runs).
    progress : callable, optional
        ``progress(done, total)`` after every finished chunk of items.
    chunks_per_worker : int
        Items are sent in about ``workers * chunks_per_worker`` chunks (fewer
        round trips; more chunks balance uneven run times better).

    Returns
    -------
    list
        Results in the order of ``items``.

    Raises
    ------
    ValueError
        ``workers`` outside [1, 256] or ``chunks_per_worker`` outside [1, 10000].
    Exception
        Whatever ``fn`` raises (the first failure ends the map).

    Examples
    --------
    >>> import pendulab as pl
    >>> from pendulab.ensemble import map_runs
    >>> def max_stretch(k):  # one run per stiffness [N/m], in a forked worker
    ...     model = pl.elastic(k1=k, k2=k)
    ...     traj = pl.simulate(model, model.state(theta1=1.0, theta2=1.0), 2.0, method="cvodes")
    ...     return round(float(traj["r1"].max()) - 1.0, 4)  # largest stretch of spring 1 [m]
    >>> map_runs(max_stretch, [1000.0, 2000.0, 4000.0], workers=2)  # in the order of the items
    [0.0428, 0.0222, 0.0113]
    """
    todo = list(items)
    total = len(todo)
    n_workers = default_workers() if workers is None else int(workers)
    chunks_per_worker = int(chunks_per_worker)
    n_workers = min(n_workers, max(total, 1))
    if n_workers == 1 or total <= 1 or "fork" not in multiprocessing.get_all_start_methods():
        out: list[R] = []
        for k, item in enumerate(todo, 1):
            out.append(fn(item))
            if progress is not None:
                progress(k, total)
        return out
    size = max(1, math.ceil(total / (n_workers * chunks_per_worker)))
    starts = list(range(0, total, size))
    results: list[list[R] | None] = [None] * len(starts)
    job = next(_IDS)
    _JOBS[job] = fn
    try:
        ctx = multiprocessing.get_context("fork")
        pool = ProcessPoolExecutor(max_workers=n_workers, mp_context=ctx, initializer=ignore_sigint)
        try:
            with sigint_blocked():  # the workers are forked in the first submit
                futures = {pool.submit(_run_chunk, job, todo[s : s + size]): i for i, s in enumerate(starts)}
            done = 0
            for fut in completed(futures):
                results[futures[fut]] = fut.result()
                done += len(results[futures[fut]] or ())
                if progress is not None:
                    progress(done, total)
        except BaseException:
            # A failed run or Ctrl-C: drop the queued chunks and end the workers instead of finishing them.
            shutdown_now(pool)
            raise
        pool.shutdown(wait=True)
    finally:
        del _JOBS[job]
    return [r for chunk in results for r in (chunk or ())]
