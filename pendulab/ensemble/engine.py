"""The ensemble front end: :func:`ensemble` checks its arguments once, splits the runs into
chunks, runs the chunks on local threads or a Dask cluster and assembles one
:class:`~pendulab.ensemble.result.EnsembleResult`.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from .._checks import bounded_int, check_model
from .._inputs import checked
from ..integrate import METHODS, simulate
from ..integrate.taylor.availability import check_tolerance_floor, heyoka_module
from ..model.model import Model
from .batch import STATUS_EVENT, STATUS_FAILED, STATUS_OK, BatchKey, check_batch_size, default_batch_size
from .chunks import _assemble, _run_local, _tasks, local_chunk_size
from .engine_checks import MAX_RUNS, _check_t_eval, _progress, check_params, check_x0
from .events import Event, EventPlan, resolve_events
from .result import EnsembleResult

__all__ = ["ensemble", "check_params", "check_x0", "MAX_RUNS", "DEFAULT_MAX_STEPS"]

#: Largest number of dense output points (runs x times) of one ensemble (10**9 x nx x 8 bytes).
MAX_DENSE = 10**8
#: Most local workers (threads or forked processes) of one ensemble.
MAX_WORKERS = 256
#: Default step budget of each run (as ``simulate``'s option ``max_steps``).
DEFAULT_MAX_STEPS = 1_000_000

_STATUS_NAMES = {STATUS_OK: "ok", STATUS_EVENT: "event", STATUS_FAILED: "failed"}


@checked()
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
        depending on the host). Results are identical (bitwise) for any chunking at one
        ``batch_size``; another width may change them at the rounding level.
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

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> model = pl.rigid()
    >>> theta = np.linspace(0.5, 3.0, 6)  # six releases from rest, both links at the same angle
    >>> x0 = np.column_stack([theta, theta, np.zeros(6), np.zeros(6)])
    >>> res = pl.ensemble(model, x0, 10.0, events=["flip"])  # "flip": stop when a link passes upright
    >>> res.status.tolist(), res.terminal_event.tolist()
    (['ok', 'ok', 'ok', 'event', 'event', 'event'], ['', '', '', 'flip', 'flip', 'flip'])
    >>> np.round(res.event_times["flip"], 2)  # flip time [s]; NaN: not within 10 s
    array([ nan,  nan,  nan, 4.82, 1.92, 0.56])
    >>> bool(np.all(np.abs(model.energy(res.x_final) - model.energy(res.x0)) < 1e-9))  # each run conserves energy
    True
    """
    check_model(model)
    tf = float(t_final)
    P = check_params(model, params)
    X0 = check_x0(model, x0, None if P is None else len(P))
    n = len(X0)
    if P is None:
        P = np.tile(model.p, (n, 1))
    rt, at = float(rtol), float(atol)
    te = _check_t_eval(t_eval, tf)
    if te is not None:
        bounded_int("len(x0) * len(t_eval)", n * len(te), high=MAX_DENSE, why="memory of the dense output x (8 bytes per value)")
    plan = resolve_events(model, events)
    cs = int(chunk_size)
    nthreads = (os.cpu_count() or 1) if threads is None else int(threads)
    if not isinstance(method, str) or method not in METHODS:
        raise ValueError(f"method must be 'taylor' or a key of pendulab.METHODS {sorted(METHODS)}, got {method!r}")
    steps = int(max_steps)
    wall = None if max_wall_time is None else float(max_wall_time)
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


# ``pendulab.ensemble`` is this function (the public name) and also the package that holds it. ``import
# pendulab.ensemble.flipmap as fm`` fetches the attribute ``ensemble`` of ``pendulab`` -- this function -- and then
# ``flipmap`` of it; failing that, Python looks for the module named ``<its __name__>.flipmap`` in sys.modules. Named
# as its package, the function lets that fallback find every submodule (errors and signatures use __qualname__).
ensemble.__name__ = "pendulab.ensemble"


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
