"""Dask execution of ensemble chunks: one task per chunk, gathered in order, never a partial result."""

from __future__ import annotations

import importlib
from collections.abc import Callable
from typing import Any

from .batch import ChunkOut, ChunkTask, run_chunk

__all__ = ["DASK_HINT", "run_on_dask"]

#: How to install the Dask extra.
DASK_HINT = 'pip install "pendulab[dask]"'


def _distributed() -> Any:
    try:
        return importlib.import_module("distributed")
    except ImportError as exc:
        raise ImportError(
            f"ensemble(client=...) needs dask.distributed, which is not importable ({exc}); install it with: {DASK_HINT}"
        ) from exc


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
    ImportError
        dask.distributed is not installed (the message names ``pendulab[dask]``).
    RuntimeError
        One or more chunks failed; the message names their indices and the first error.
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
    try:
        futures = [client.submit(run_chunk, t, pure=False, key=f"pendulab-ensemble-chunk-{t.index}-{id(tasks)}") for t in tasks]
        index = {f.key: t for f, t in zip(futures, tasks, strict=True)}
        failed: list[tuple[int, str]] = []
        for f in dist.as_completed(futures):
            t = index[f.key]
            if f.status == "finished":
                report(len(t.x0))
            else:
                try:
                    exc = f.exception()
                    why = f"{type(exc).__name__}: {exc}"
                except Exception as e:  # cancelled or lost futures raise here
                    why = f"{type(e).__name__}: {e}"
                failed.append((t.index, why))
        if failed:
            failed.sort()
            raise RuntimeError(
                f"ensemble: Dask chunks {[i for i, _ in failed]} failed (of {len(tasks)}); first error: {failed[0][1]}; "
                "no partial result is returned"
            )
        outs = client.gather(futures)
    finally:
        if own:
            client.close()
    return list(outs)
