"""Dask execution of ensemble chunks: one task per chunk, gathered in order, never a partial result.

The wait for results is bounded: with no worker connected for :data:`NO_WORKER_TIMEOUT` seconds,
or the scheduler gone, the ensemble ends with a one-line ``RuntimeError`` instead of waiting
forever; Ctrl-C cancels the submitted tasks.
"""

from __future__ import annotations

import os
import time
import uuid
from collections.abc import Callable
from typing import Any

from .._checks import require_extra
from .batch import ChunkOut, ChunkTask, run_chunk

__all__ = ["DASK_HINT", "NO_WORKER_TIMEOUT", "run_on_dask"]

#: How to install the Dask extra.
DASK_HINT = 'pip install "pendulab[dask]"'
#: Seconds without any Dask worker after which an ensemble gives up (env ``PENDULAB_DASK_NO_WORKER_TIMEOUT``).
NO_WORKER_TIMEOUT = 60.0
#: Seconds between two checks of the cluster while waiting for chunks.
_POLL = 0.5


def _distributed() -> Any:
    return require_extra("distributed", "dask", "ensemble(client=...) / --scheduler")


def _no_worker_timeout() -> float:
    text = os.environ.get("PENDULAB_DASK_NO_WORKER_TIMEOUT")
    if not text:
        return NO_WORKER_TIMEOUT
    try:
        value = float(text)
    except ValueError:
        raise ValueError(f"PENDULAB_DASK_NO_WORKER_TIMEOUT must be a number of seconds, got {text!r}") from None
    if not value > 0:
        raise ValueError(f"PENDULAB_DASK_NO_WORKER_TIMEOUT must be > 0 s, got {text!r}")
    return value


def _n_workers(client: Any, address: str) -> int:
    """Workers connected to the scheduler now; RuntimeError when the scheduler cannot be reached."""
    if getattr(client, "status", "running") not in ("running", "connecting", "newly-created"):
        raise RuntimeError(f"ensemble: lost the Dask scheduler at {address} (client status {client.status!r})")
    try:
        return len(client.nthreads())
    except Exception as exc:  # CommClosedError, OSError, TimeoutError: the scheduler is gone
        raise RuntimeError(f"ensemble: lost the Dask scheduler at {address} ({type(exc).__name__})") from None


def _run_chunk_remote(task: ChunkTask) -> ChunkOut:
    """:func:`run_chunk` on a Dask worker that stops between slices once the client cancelled the task.

    Best effort: it reads the worker's task state (``cancelled`` or gone), which is Dask internals;
    when that cannot be read the chunk simply runs to its end (budgets still apply).
    """
    try:
        from distributed import get_worker
        from distributed.worker import thread_state

        worker, key = get_worker(), thread_state.key
    except Exception:  # not on a worker, or another Dask version
        return run_chunk(task)

    def stop() -> bool:
        try:
            ts = worker.state.tasks.get(key)
            return ts is None or ts.state in ("cancelled", "released", "forgotten")
        except Exception:
            return False

    return run_chunk(task, stop)


def run_on_dask(client: Any, tasks: list[ChunkTask], report: Callable[[int | None], None]) -> list[ChunkOut]:
    """Run every chunk as one Dask task of :func:`~pendulab.ensemble.batch.run_chunk`.

    Each worker rebuilds (once per process) the compiled batch integrator from the task's
    plain-data key. A worker that dies loses its tasks and Dask recomputes them elsewhere; a
    task that errors (or that the scheduler gives up on, e.g. ``KilledWorker``) makes this
    raise.

    Parameters
    ----------
    client : distributed.Client or str
        A client, or a scheduler address (``"tcp://host:port"``) to connect a new client to
        (closed afterwards).
    tasks : list of ChunkTask
    report : callable
        ``report(k)`` after k more runs finished.

    Returns
    -------
    list of ChunkOut
        In task order.

    Raises
    ------
    MissingExtraError
        dask.distributed is not installed (an ``ImportError`` naming ``pendulab[dask]``).
    RuntimeError
        One or more chunks failed (the message names their indices and the first error); no
        worker for :data:`NO_WORKER_TIMEOUT` s; the scheduler was lost.
    ValueError
        ``client`` is neither a Client nor an address string.
    """
    dist = _distributed()
    own = False
    if isinstance(client, str):
        try:
            client = dist.Client(client)
        except Exception as exc:
            raise ValueError(f"client: cannot connect to the Dask scheduler at {client!r} ({type(exc).__name__}: {exc})") from exc
        own = True
    elif not isinstance(client, dist.Client):
        raise ValueError(f"client must be a distributed.Client or a scheduler address 'tcp://host:port', got {client!r}")
    address = str(getattr(getattr(client, "scheduler", None), "address", "") or "the scheduler")
    limit = _no_worker_timeout()
    futures: list[Any] = []
    try:
        # A fresh token per call: a key that repeats (id() of a freed list does) would make Dask hand back
        # the finished result of an earlier ensemble instead of computing this one.
        token = uuid.uuid4().hex
        futures = [client.submit(_run_chunk_remote, t, pure=False, key=f"pendulab-ensemble-{token}-{t.index}") for t in tasks]
        index = {f.key: t for f, t in zip(futures, tasks, strict=True)}
        failed: list[tuple[int, str]] = []
        pending = set(futures)
        idle_since: float | None = None
        while pending:
            try:
                done, pending = dist.wait(list(pending), timeout=_POLL, return_when="FIRST_COMPLETED")
                pending = set(pending)
            except TimeoutError:
                done = set()
            if not done:
                if _n_workers(client, address) == 0:
                    idle_since = time.monotonic() if idle_since is None else idle_since
                    if time.monotonic() - idle_since > limit:
                        raise RuntimeError(
                            f"ensemble: no Dask worker connected to {address} for {limit:g} s "
                            f"({len(pending)} of {len(tasks)} chunks pending); start workers or check the cluster"
                        )
                else:
                    idle_since = None
                continue
            for f in done:
                t = index[f.key]
                if f.status == "finished":
                    report(len(t.x0))
                    continue
                why = f"task {f.status}"
                try:
                    exc = f.exception(timeout=_POLL)
                    if exc is not None:
                        why = f"{type(exc).__name__}: {exc}"
                    elif f.status in ("cancelled", "lost"):
                        why = f"task {f.status} (its worker or the scheduler went away)"
                except Exception as e:  # cancelled or lost futures raise here
                    why = f"{type(e).__name__}: {e}" if str(e) else f"task {f.status} (its worker or the scheduler went away)"
                failed.append((t.index, why))
        if failed:
            failed.sort()
            raise RuntimeError(
                f"ensemble: Dask chunks {[i for i, _ in failed]} failed (of {len(tasks)}); first error: {failed[0][1]}; "
                "no partial result is returned"
            )
        outs = client.gather(futures)
    except BaseException:
        if futures and getattr(client, "status", "") == "running":
            try:
                client.cancel(futures)
            except Exception:  # the scheduler is gone already
                pass
        raise
    finally:
        if own:
            client.close()
    return list(outs)
