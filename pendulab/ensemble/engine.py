"""The ensemble front end: :func:`ensemble` checks its arguments once, splits the runs into
chunks, runs the chunks on local threads or a Dask cluster and assembles one
:class:`~pendulab.ensemble.result.EnsembleResult`.
"""

from __future__ import annotations

import math
import multiprocessing
import os
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import Executor, ProcessPoolExecutor, ThreadPoolExecutor
from typing import Any

import numpy as np

from .._checks import bounded_int, check_model, check_spring_lengths, positive_float, relative_tolerance
from ..integrate import METHODS, simulate
from ..integrate.taylor.availability import check_tolerance_floor, heyoka_module
from ..model.model import Model
from .batch import (
    STATUS_EVENT,
    STATUS_FAILED,
    STATUS_OK,
    BatchKey,
    ChunkOut,
    ChunkStoppedError,
    ChunkTask,
    check_batch_size,
    default_batch_size,
    run_chunk,
)
from .events import Event, EventPlan, resolve_events
from .pool import _sigint_blocked, completed, ignore_sigint, shutdown_now
from .result import EnsembleResult

__all__ = ["ensemble", "check_params", "check_x0", "MAX_RUNS", "DEFAULT_MAX_STEPS"]

#: Largest number of runs of one ensemble (a (n, nx) float array of 10**8 runs is already 6 GB).
MAX_RUNS = 10**8
#: Largest number of dense output points (runs x times) of one ensemble (10**9 x nx x 8 bytes).
MAX_DENSE = 10**8
#: Most local workers (threads or forked processes) of one ensemble.
MAX_WORKERS = 256
#: Default step budget of each run (as ``simulate``'s option ``max_steps``).
DEFAULT_MAX_STEPS = 1_000_000

_STATUS_NAMES = {STATUS_OK: "ok", STATUS_EVENT: "event", STATUS_FAILED: "failed"}


def ensemble(
    model: Model,
    x0: Any,
    t_final: float,
    *,
    params: Mapping[str, Any] | np.ndarray | None = None,
    events: Sequence[Event | str] | None = None,
    method: str = "taylor",
    t_eval: Any = None,
    client: Any = None,
    chunk_size: int = 2000,
    threads: int | None = None,
    rtol: float = 1e-12,
    atol: float = 1e-12,
    progress: Callable[[int, int], Any] | bool | None = None,
    batch_size: int | None = None,
    max_steps: int = DEFAULT_MAX_STEPS,
    max_wall_time: float | None = None,
) -> EnsembleResult:
    """Integrate many runs of one model, each with its own initial state and parameters.

    With ``method="taylor"`` (default) the runs go through heyoka's SIMD batch integrator
    (``taylor_adaptive_batch`` with ``batch_size`` lanes), its ODE built from
    the model's CasADi graph by the same translator as ``simulate(method="taylor")``;
    parameters are runtime parameters, so per-run values never recompile. Events are handled
    per lane: a run stops at its own terminal event and records its own first crossing times
    (see :mod:`pendulab.ensemble.batch`). Chunks of runs run in a thread pool (heyoka releases
    the GIL) or, with ``client``, as Dask tasks.

    Parameters
    ----------
    model : Model
        Rigid or elastic pendulum; parameters not given in ``params`` keep its values.
    x0 : array_like, shape (n, nx) or (nx,)
        Initial states in ``model.state_names`` order; one state is broadcast to the n runs
        that ``params`` defines.
    t_final : float
        Horizon [s], > 0 (the same for every run).
    params : mapping of str to array_like (n,), or array_like (n, np), optional
        Per-run parameter values by name (others at the model's values), or full parameter
        vectors in ``model.param_names`` order.
    events : sequence of Event or "flip", optional
        ``"flip"``: built-in terminal event, ``|theta1|`` or ``|theta2|`` reaching pi.
        :class:`~pendulab.ensemble.events.Event`: a terminal or recorded event of the state
        and parameters (a callable ``expr(x, p) -> casadi.SX`` of the model's symbols, or a
        state/output name with a threshold ``value``).
    method : str
        ``"taylor"`` (batch engine); any other key of :data:`pendulab.METHODS` runs one
        ``simulate`` per run (a slow fallback, without events or ``t_eval``).
    t_eval : array_like, optional
        Increasing output times in ``[0, t_final]`` [s]; fills :attr:`EnsembleResult.x`
        (dense output, NaN after a run ended).
    client : distributed.Client or str, optional
        Run the chunks as Dask tasks on this client (or a new client to this scheduler
        address, closed afterwards). Needs ``pip install "pendulab[dask]"``.
    chunk_size : int
        Runs per chunk (Dask: one task per chunk; locally chunks are smaller when needed to
        keep every thread busy).
    threads : int, optional
        Local workers (default ``os.cpu_count()``): forked processes for ensembles of 5,000 runs
        or more, threads below; ignored with ``client``.
    rtol, atol : float
        Tolerances, ``rtol`` in (0, 1); heyoka's ``tol = min(rtol, atol)``, at least the
        double-precision epsilon 2.2e-16 (a smaller one only lengthens the compilation).
    progress : callable or bool, optional
        ``progress(done, total)`` after each chunk (runs), or True for a tqdm bar.
    batch_size : int, optional
        SIMD lanes of the batch integrator, in [1, 64]. Default
        :func:`~pendulab.ensemble.batch.default_batch_size`: the environment variable
        ``PENDULAB_SIMD_SIZE`` when set, else ``heyoka.recommended_simd_size()`` (2, 4 or 8
        depending on the host). Results are identical (bitwise) for the same chunking and
        ``batch_size``; another width or chunking changes them at the rounding level only.
    max_steps : int, default 1 000 000
        Step budget of each run (batch steps of its lane, checked every
        :data:`~pendulab.ensemble.batch.SLICE_STEPS` steps); a run over it ends with status
        ``"failed"`` and a message naming the budget.
    max_wall_time : float, optional
        Wall-time budget of the whole ensemble [s]; runs unfinished when it is spent end with
        status ``"failed"`` (their message names the budget). Default: none.

    Returns
    -------
    EnsembleResult

    Raises
    ------
    TypeError
        ``model`` is not a pendulab Model.
    ValueError
        Empty ensemble, mismatched shapes, non-finite states or parameters, elastic spring
        lengths <= 0, ``rtol`` outside (0, 1), unknown parameter or event names, bad ``t_eval``,
        ``chunk_size``, ``threads``, ``batch_size`` or budgets (the message names the argument
        and the value).
    KeyboardInterrupt
        Ctrl-C: running chunks stop within one propagation slice, queued ones are cancelled
        and worker processes ended.
    ImportError
        heyoka (``pendulab[taylor]``) or, with ``client``, dask.distributed (``pendulab[dask]``)
        is not installed; the message names the extra.
    RuntimeError
        A chunk failed (the message names the chunk indices); never a partial result.
    """
    check_model(model)
    tf = positive_float("t_final", t_final, "[s]")
    P = check_params(model, params)
    X0 = check_x0(model, x0, None if P is None else len(P))
    n = len(X0)
    if P is None:
        P = np.tile(model.p, (n, 1))
    rt, at = relative_tolerance("rtol", rtol), positive_float("atol", atol)
    te = _check_t_eval(t_eval, tf)
    if te is not None:
        bounded_int("len(x0) * len(t_eval)", n * len(te), high=MAX_DENSE, why="memory of the dense output x (8 bytes per value)")
    plan = resolve_events(model, events)
    cs = bounded_int("chunk_size", chunk_size, high=MAX_RUNS, why="runs per chunk")
    nthreads = (
        (os.cpu_count() or 1)
        if threads is None
        else bounded_int("threads", threads, high=MAX_WORKERS, why="local workers; each may be a forked process")
    )
    if not isinstance(method, str) or method not in METHODS:
        raise ValueError(f"method must be 'taylor' or a key of pendulab.METHODS {sorted(METHODS)}, got {method!r}")
    steps = bounded_int("max_steps", max_steps, low=1, high=2**31 - 1, why="the step budget of each run")
    wall = None if max_wall_time is None else positive_float("max_wall_time", max_wall_time, "[s]")
    S = None if batch_size is None else check_batch_size(batch_size)
    report = _progress(progress, n)
    start = time.perf_counter()
    deadline = None if wall is None else time.time() + wall
    try:
        if method != "taylor":
            out = _fallback(model, X0, P, tf, plan, method, te, rt, at, report, steps, wall)
            stats = {"method": method, "n_runs": n, "n_chunks": n, "threads": 1}
        else:
            heyoka_module()  # names the extra when heyoka is missing
            check_tolerance_floor("rtol" if rt <= at else "atol", min(rt, at))
            S = default_batch_size() if S is None else S
            zero = tuple(int(i) for i in np.flatnonzero(np.all(P == 0.0, axis=0)))
            key = BatchKey(model.kind, zero, min(rt, at), plan, S)
            if client is not None:
                from .cluster import run_on_dask

                size = cs
                tasks = _tasks(key, X0, P, tf, te, size, steps, deadline)
                outs = run_on_dask(client, tasks, report)
                workers = "dask"
            else:
                size = local_chunk_size(n, cs, S, nthreads)
                tasks = _tasks(key, X0, P, tf, te, size, steps, deadline)
                outs = _run_local(tasks, nthreads, report)
                workers = nthreads
            out = _assemble(outs, n, len(plan.names))
            stats = {
                "method": "taylor",
                "n_runs": n,
                "n_chunks": len(tasks),
                "chunk_size": size,
                "threads": workers,
                "batch_size": S,
                "tol": min(rt, at),
                "n_steps": int(sum(o.n_steps for o in outs)),
            }
    finally:
        report(None)  # closes a progress bar also after Ctrl-C or an error
    stats.update(rtol=rt, atol=at, max_steps=steps, max_wall_time=wall)
    stats["wall_time"] = time.perf_counter() - start
    x_final, t_end, status, message, ev_times, term_ev, X = out
    names = plan.names
    term_names = np.array([names[k] if k >= 0 else "" for k in term_ev], dtype=object).astype(str) if n else np.array([], str)
    return EnsembleResult(
        x_final=x_final,
        t_final=t_end,
        event_times={name: ev_times[k] for k, name in enumerate(names)},
        status=np.array([_STATUS_NAMES[int(s)] for s in status]),
        message=np.array(message, dtype=str),
        terminal_event=term_names,
        x=X,
        t_eval=te,
        x0=X0,
        params=P,
        state_names=model.state_names,
        param_names=model.param_names,
        stats=stats,
    )


# -- argument checks ----------------------------------------------------------------
def check_params(model: Model, params: Any) -> np.ndarray | None:
    """Per-run parameter vectors (n, np) from ``params`` (None stays None).

    Parameters
    ----------
    model : Model
    params : mapping of str to array_like (n,), array_like (n, np), or None

    Returns
    -------
    ndarray, shape (n, np), or None

    Raises
    ------
    ValueError
        Unknown names, mismatched lengths, empty, non-finite or inadmissible values.
    """
    if params is None:
        return None
    names = model.param_names
    if isinstance(params, Mapping):
        if not params:
            raise ValueError("params must name at least one parameter, got an empty mapping")
        unknown = [k for k in params if k not in names]
        if unknown:
            raise ValueError(
                f"params: unknown parameter names {unknown} for the {model.kind} model; expected some of {list(names)}"
            )
        cols = {}
        for k, v in params.items():
            try:
                a = np.asarray(v, dtype=float)
            except (TypeError, ValueError) as exc:
                raise ValueError(f"params[{k!r}] must be an array of numbers, got {v!r}") from exc
            if a.ndim != 1:
                raise ValueError(f"params[{k!r}] must have shape (n,), got shape {a.shape}")
            cols[k] = a
        lengths = {k: len(a) for k, a in cols.items()}
        if len(set(lengths.values())) != 1:
            raise ValueError(f"params: every array must have the same length n, got lengths {lengths}")
        n = next(iter(lengths.values()))
        P = np.tile(model.p, (n, 1))
        for k, a in cols.items():
            P[:, names.index(k)] = a
    else:
        try:
            P = np.array(params, dtype=float)
        except (TypeError, ValueError) as exc:
            raise ValueError(
                f"params must be a mapping name -> array (n,) or an array (n, {len(names)}), got {params!r}"
            ) from exc
        if P.ndim != 2 or P.shape[1] != len(names):
            raise ValueError(f"params must have shape (n, {len(names)}) in param_names order {list(names)}, got shape {P.shape}")
    if len(P) == 0:
        raise ValueError("params: the ensemble is empty (n = 0 runs); give at least one run")
    bounded_int("number of runs (rows of params)", len(P), high=MAX_RUNS, why="memory of the result arrays")
    bad = np.flatnonzero(~np.all(np.isfinite(P), axis=1))
    if bad.size:
        raise ValueError(f"params must be finite; run {int(bad[0])} has {dict(zip(names, P[bad[0]].tolist(), strict=True))}")
    # Each distinct run is validated as a whole by the model's own parameter checks: some rules join
    # parameters (m2 lc2^2 + I2 > 0), so mixing columns of different runs would refuse valid runs.
    uniq, first = np.unique(P, axis=0, return_index=True)
    for row, i in zip(uniq, first, strict=True):
        try:
            model.params.replace(**dict(zip(names, row.tolist(), strict=True)))
        except (ValueError, TypeError) as exc:
            raise ValueError(f"params: run {int(i)} is inadmissible ({exc})") from exc
    return P


def check_x0(model: Model, x0: Any, n: int | None) -> np.ndarray:
    """Initial states (n, nx) from ``x0`` (broadcast one state to ``n`` runs).

    Parameters
    ----------
    model : Model
    x0 : array_like, shape (n, nx) or (nx,)
    n : int or None
        Number of runs set by ``params`` (None: ``x0`` sets it).

    Returns
    -------
    ndarray, shape (n, nx)

    Raises
    ------
    ValueError
        Wrong shape, empty, a mismatch with ``n`` or a non-finite state (naming the run).
    """
    nx = model.nx
    try:
        X = np.array(x0, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"x0 must be an array of shape (n, {nx}) or ({nx},), got {x0!r}") from exc
    if X.ndim == 1:
        if X.shape != (nx,):
            raise ValueError(f"x0 must have shape (n, {nx}) or ({nx},) {list(model.state_names)}, got shape {X.shape}")
        if n is None:
            raise ValueError(
                f"x0 has shape ({nx},): one state needs params to define the number of runs; give x0 of shape (n, {nx})"
            )
        X = np.tile(X, (n, 1))
    elif X.ndim != 2 or X.shape[1] != nx:
        raise ValueError(f"x0 must have shape (n, {nx}) in state order {list(model.state_names)}, got shape {X.shape}")
    if len(X) == 0:
        raise ValueError(f"x0: the ensemble is empty (shape {X.shape}); give at least one run")
    bounded_int("number of runs (rows of x0)", len(X), high=MAX_RUNS, why="memory of the result arrays")
    if n is not None and len(X) != n:
        raise ValueError(f"x0 has {len(X)} runs but params has {n}; they must match")
    bad = np.flatnonzero(~np.all(np.isfinite(X), axis=1))
    if bad.size:
        raise ValueError(f"x0 must be finite; run {int(bad[0])} has {X[bad[0]].tolist()}")
    check_spring_lengths(model.kind, X, "x0")
    return X


def _check_t_eval(t_eval: Any, tf: float) -> np.ndarray | None:
    if t_eval is None:
        return None
    try:
        te = np.array(t_eval, dtype=float).reshape(-1)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"t_eval must be an array of times [s], got {t_eval!r}") from exc
    if te.size == 0 or not np.all(np.isfinite(te)) or np.any(np.diff(te) <= 0) or te[0] < 0 or te[-1] > tf:
        raise ValueError(f"t_eval must be non-empty, finite, strictly increasing and within [0, t_final={tf}], got {t_eval!r}")
    return te


def _progress(progress: Any, total: int) -> Callable[[int | None], None]:
    """``report(k)``: k more runs done; ``report(None)``: finished."""
    if progress is None or progress is False:
        return lambda k: None
    if progress is True:
        from tqdm.auto import tqdm

        bar = tqdm(total=total, unit="run", desc="ensemble")

        def report(k: int | None) -> None:
            if k is None:
                bar.close()
            else:
                bar.update(k)

        return report
    if not callable(progress):
        raise ValueError(f"progress must be a callable progress(done, total), True or None, got {progress!r}")
    done = [0]

    def report_cb(k: int | None) -> None:
        if k is not None:
            done[0] += k
            progress(done[0], total)

    return report_cb


# -- execution ---------------------------------------------------------------------
def local_chunk_size(n: int, chunk_size: int, batch_size: int, threads: int) -> int:
    """Runs per local chunk: at most ``chunk_size``, small enough to keep ``threads`` workers busy.

    A pure function of its arguments (never of the host): the same arguments give the same
    chunking, hence bitwise-identical results.

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


def _executor(threads: int, n_tasks: int, n_runs: int) -> Executor:
    """Worker processes (fork) for big ensembles, threads for small ones.

    heyoka releases the GIL while it integrates, but the per-lane bookkeeping between event
    stops is Python: measured on the 400x400 flip map, 2 threads ran no faster than 1 while 2
    processes ran 1.5-1.9x faster. Forked workers inherit the compiled integrators, so they start in
    milliseconds; below _PROCESS_MIN_RUNS runs, or where fork is unavailable, threads are used.
    Worker processes ignore SIGINT: Ctrl-C reaches the parent, which cancels the queue and ends them.
    """
    workers = min(threads, n_tasks)
    if n_runs >= _PROCESS_MIN_RUNS and "fork" in multiprocessing.get_all_start_methods():
        return ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("fork"), initializer=ignore_sigint)
    return ThreadPoolExecutor(max_workers=workers)


#: Ensembles of at least this many runs use worker processes (see :func:`_executor`).
_PROCESS_MIN_RUNS = 5000


def _run_local(tasks: list[ChunkTask], threads: int, report: Callable[[int | None], None]) -> list[ChunkOut]:
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
    pool = _executor(threads, len(tasks), sum(len(t.x0) for t in tasks))
    try:
        if isinstance(pool, ThreadPoolExecutor):
            futures = {pool.submit(run_chunk, t, stop.is_set): t for t in tasks}
        else:
            with _sigint_blocked():  # workers are forked in the first submit; ignore_sigint unblocks it in them
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
        raise
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


def _fallback(
    model: Model,
    X0: np.ndarray,
    P: np.ndarray,
    tf: float,
    plan: EventPlan,
    method: str,
    te: np.ndarray | None,
    rtol: float,
    atol: float,
    report: Callable[[int | None], None],
    max_steps: int,
    max_wall_time: float | None,
) -> tuple:
    """One ``simulate`` per run (methods other than taylor; no events, no t_eval), each within the budgets."""
    if plan.names:
        raise ValueError(f"events need method='taylor' (heyoka, {_extra()}), got method={method!r}")
    if te is not None:
        raise ValueError(f"t_eval needs method='taylor' (heyoka, {_extra()}), got method={method!r}")
    n, nx = X0.shape
    x_final = np.full((n, nx), np.nan)
    t_end = np.full(n, np.nan)
    status = np.full(n, STATUS_OK, dtype=np.int8)
    message = [""] * n
    names = model.param_names
    start = time.perf_counter()
    for r in range(n):
        opts: dict[str, Any] = {"max_steps": max_steps}
        if max_wall_time is not None:
            left = max_wall_time - (time.perf_counter() - start)
            if left <= 0:
                status[r:] = STATUS_FAILED
                for k in range(r, n):
                    message[k] = "wall-time budget exhausted (max_wall_time) before the run started"
                report(n - r)
                break
            opts["max_wall_time"] = left
        m = model if np.array_equal(P[r], model.p) else model.with_params(**dict(zip(names, P[r].tolist(), strict=True)))
        try:
            traj = simulate(m, X0[r], tf, dt=tf, method=method, rtol=rtol, atol=atol, options=opts)
            x_final[r], t_end[r] = traj.x[-1], traj.t[-1]
        except Exception as exc:  # a failed run is reported per run, never silently
            status[r] = STATUS_FAILED
            message[r] = f"{type(exc).__name__}: {exc}"
        report(1)
    return x_final, t_end, status, message, np.empty((0, n)), np.full(n, -1), None


def _extra() -> str:
    return 'pip install "pendulab[taylor]"'
