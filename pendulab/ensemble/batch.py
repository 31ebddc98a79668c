"""heyoka batch integration of one chunk of runs, with per-lane events and lane refilling.

:func:`run_chunk` is a top-level function of plain data (:class:`ChunkTask`), so it runs the
same in a thread of this process and in a Dask worker: the worker rebuilds (and caches, once
per process) the compiled batch integrator from the task's :class:`BatchKey`.

**Per-lane events.** heyoka's batch mode stops *every* lane when a terminal event triggers in
*any* lane. That is used, not fought: the lane that triggered is truncated at its event
(state and time are the crossing's), the other lanes end a normal step, so their step
sequences are those of a single run. After each ``propagate_until`` the chunk reads each lane's
outcome, records finished lanes (target time reached, terminal event, failure) and refills them
with the next run of the chunk (time 0, new state and parameters, cooldowns reset); the others
go on where they stopped. Lanes with no run left idle (target = their current time). Recorded
(non-terminal) events are ``nt_event_batch`` with a callback that stores the first crossing
time of the lane's current run.

**Streaming.** That stepped loop stops the batch once per finished run. Without an output grid or
recorded events a chunk first streams its runs through the lanes instead: every terminal event's
callback records the run and refills its lane without stopping the batch (:mod:`.stream`, which
says how the time axis and the horizon are kept exact); only the runs still going near ``t_final``
are finished by the stepped loop. The results are the same doubles (the flip map: every cell).
"""

from __future__ import annotations

import copy
import math
import os
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from .._checks import bounded_int
from ..integrate.taylor import TaylorSystem, translate
from ..integrate.taylor.availability import heyoka_module
from ..integrate.taylor.translate import used_parameter_count
from ..model.builders import build_elastic, build_rigid
from ..model.model import model_functions
from .events import EventPlan
from .stream import CLOCK_EVENT, CLOCK_STILL, Stream, Terminal

__all__ = [
    "BatchKey",
    "ChunkTask",
    "ChunkOut",
    "ChunkStoppedError",
    "run_chunk",
    "default_batch_size",
    "check_batch_size",
    "SIMD_ENV",
    "SLICE_STEPS",
    "MAX_BATCH_SIZE",
    "STATUS_OK",
    "STATUS_EVENT",
    "STATUS_FAILED",
]

STATUS_PENDING, STATUS_OK, STATUS_EVENT, STATUS_FAILED = 0, 1, 2, 3
_TERMINAL_MIN = -(2**32)  # heyoka: outcome -i-1 (> -2**32) = stopped by terminal event i
#: Environment variable that overrides heyoka's recommended SIMD width (e.g. to compare hosts).
SIMD_ENV = "PENDULAB_SIMD_SIZE"
#: Largest accepted batch width (lanes); wider batches only cost compile time and idle lanes.
MAX_BATCH_SIZE = 64
#: Batch steps per propagation slice: budgets and the stop flag are checked between slices.
SLICE_STEPS = 2000
#: Target time of the streaming phase's propagations: never reached (the runs' clocks end them).
_FAR_TIME = 1e300
#: Internal event indices of the elastic model's spring-collapse events (r1 = 0, r2 = 0).
_SPRING_EVENTS = {-10: 1, -11: 2}
#: Name of the run clock's state variable (not a state name of any model).
_CLOCK_NAME = "pendulab_run_clock"


class ChunkStoppedError(Exception):
    """A chunk stopped because its stop flag was set (Ctrl-C in the process that runs the ensemble)."""


def check_batch_size(value: object, name: str = "batch_size") -> int:
    """``value`` as a batch width in [1, :data:`MAX_BATCH_SIZE`], else ``ValueError`` naming ``name``.

    Parameters
    ----------
    value : object
        Received value.
    name : str
        Argument name used in the message.

    Returns
    -------
    int
        The width.
    """
    return bounded_int(name, value, low=1, high=MAX_BATCH_SIZE, why="SIMD lanes of one batch integrator")


def default_batch_size() -> int:
    """The batch width (SIMD lanes) used when none is given: the one place that decides it.

    Returns
    -------
    int
        ``PENDULAB_SIMD_SIZE`` when set, else ``heyoka.recommended_simd_size()``.

    Raises
    ------
    ValueError
        ``PENDULAB_SIMD_SIZE`` is not an integer in [1, 64].
    """
    env = os.environ.get(SIMD_ENV)
    if env is not None and env.strip():
        return check_batch_size(env.strip(), f"environment variable {SIMD_ENV}")
    return int(heyoka_module().recommended_simd_size())


@dataclass(frozen=True)
class BatchKey:
    """What a compiled batch integrator depends on (never a parameter value).

    Attributes
    ----------
    kind : {"rigid", "elastic"}
    zero_params : tuple of int
        Parameters that are exactly 0 in every run (specialised away, as ``method="taylor"`` does).
    tol : float
        heyoka tolerance ``min(rtol, atol)``.
    events : EventPlan
        Resolved events.
    batch_size : int
        SIMD lanes.
    """

    kind: str
    zero_params: tuple[int, ...]
    tol: float
    events: EventPlan
    batch_size: int


@dataclass(frozen=True)
class ChunkTask:
    """One chunk of runs (plain data; pickle-friendly).

    Attributes
    ----------
    key : BatchKey
    index : int
        Chunk number (for messages).
    x0 : ndarray, shape (m, nx)
    p : ndarray, shape (m, np)
        Model parameter vectors.
    t_final : float
    t_eval : ndarray or None
    max_steps : int
        Step budget of each run (batch steps of its lane).
    deadline : float or None
        Wall-clock time (``time.time()``, seconds since the epoch) after which unfinished runs
        fail with a budget message; None for no limit.
    """

    key: BatchKey
    index: int
    x0: np.ndarray
    p: np.ndarray
    t_final: float
    t_eval: np.ndarray | None
    max_steps: int = 1_000_000
    deadline: float | None = None


@dataclass
class ChunkOut:
    """Results of one chunk (arrays over its m runs).

    Attributes
    ----------
    index : int
        Chunk number.
    x_final : ndarray, shape (m, nx)
    t_final : ndarray, shape (m,)
    status : ndarray of int8, shape (m,)
        ``STATUS_OK``, ``STATUS_EVENT`` or ``STATUS_FAILED``.
    messages : dict of int to str
        Failure message by run.
    event_times : ndarray, shape (n_events, m)
    terminal_event : ndarray of int, shape (m,)
        Index of the terminal event that stopped the run, -1 when none.
    x : ndarray, shape (m, len(t_eval), nx), or None
    n_steps : int
        Batch steps summed over lanes.
    """

    index: int
    x_final: np.ndarray
    t_final: np.ndarray
    status: np.ndarray
    messages: dict[int, str]
    event_times: np.ndarray  # (n_events, m)
    terminal_event: np.ndarray  # (m,) event index or -1
    x: np.ndarray | None
    n_steps: int


@dataclass
class _Built:
    ode: TaylorSystem
    ev_derived: Any  # callable p -> ndarray or None
    n_ev_derived: int
    template: Any
    nt_index: tuple[int, ...]  # nt event j -> event index
    t_index: tuple[int, ...]  # terminal event j -> event index
    lock: threading.Lock


_BUILT: dict[BatchKey, _Built] = {}
_BUILD_LOCK = threading.Lock()


def _state_names(kind: str) -> tuple[str, ...]:
    return (build_rigid() if kind == "rigid" else build_elastic()).state_names


class _Recorder:
    """nt-event callback: first crossing time per run of the lane (its arrays are set per chunk)."""

    def __init__(self, event: int) -> None:
        self.event = event
        self.times: np.ndarray | None = None
        self.lane_run: np.ndarray | None = None

    def __call__(self, ta: Any, t: float, d_sgn: Any, lane: int) -> None:
        r = self.lane_run[lane]
        if r >= 0 and math.isnan(self.times[self.event, r]):
            self.times[self.event, r] = t


def build(key: BatchKey) -> _Built:
    """The compiled batch integrator of ``key`` (translated and JIT-compiled once per key and process)."""
    built = _BUILT.get(key)
    if built is not None:
        return built
    with _BUILD_LOCK:
        built = _BUILT.get(key)
        if built is not None:
            return built
        hy = heyoka_module()
        names = _state_names(key.kind)
        # The same translation as method="taylor" with zero torques (identical ODE expressions).
        ode = translate(model_functions(key.kind)["rhs"], zero_params=key.zero_params, zero_inputs=(0, 1), state_names=names)
        xs = [v for v, _ in ode.sys]
        n_base = ode.n_inputs + ode.n_derived
        plan = key.events
        ev_exprs: dict[int, Any] = {}
        ev_derived, n_ev = None, 0
        if plan.sx_function:
            g = ca.Function.deserialize(plan.sx_function)
            ev_exprs, ev_derived, n_ev = _translate_events(hy, g, key, names, n_base, xs)
        t_events, nt_events, t_index, nt_index = [], [], [], []
        for k, kind, arg, direction in plan.components:
            if kind == "square":
                expr = xs[arg] * xs[arg] - math.pi**2
            elif kind == "state":
                expr = xs[arg[0]] - arg[1]
            else:
                expr = ev_exprs[arg]
            d = {0: hy.event_direction.any, 1: hy.event_direction.positive, -1: hy.event_direction.negative}[direction]
            if plan.terminal[k]:
                t_events.append(hy.t_event_batch(expr, direction=d, callback=Terminal(k)))
                t_index.append(k)
            else:
                nt_events.append(hy.nt_event_batch(expr, _Recorder(k), direction=d))
                nt_index.append(k)
        if key.kind == "elastic":  # a spring through zero length ends its run as failed (simulate's rule)
            for k, j in _SPRING_EVENTS.items():
                t_events.append(hy.t_event_batch(xs[1 + j], direction=hy.event_direction.negative, callback=Terminal(k)))
                t_index.append(k)
        S = key.batch_size
        # heyoka sizes the parameters by the highest index used (structural zeros can remove the last ones).
        events_used = [ev.expression for ev in (*t_events, *nt_events)]
        n_used = used_parameter_count([rhs for _, rhs in ode.sys] + events_used)
        # Each run's own clock (module pendulab.ensemble.stream): rate and end are the last two parameters.
        clock = hy.make_vars(_CLOCK_NAME)
        t_events.append(
            hy.t_event_batch(clock - hy.par[n_used + 1], direction=hy.event_direction.positive, callback=Terminal(CLOCK_EVENT))
        )
        t_index.append(CLOCK_EVENT)
        template = hy.taylor_adaptive_batch(
            [*ode.sys, (clock, hy.par[n_used])],
            np.zeros((len(names) + 1, S)),
            pars=np.zeros((n_used + 2, S)),
            tol=key.tol,
            t_events=t_events,
            nt_events=nt_events,
        )
        built = _Built(ode, ev_derived, n_ev, template, tuple(nt_index), tuple(t_index), threading.Lock())
        _BUILT[key] = built
    return built


def _translate_events(hy: Any, g: Any, key: BatchKey, names: tuple[str, ...], n_base: int, xs: list) -> tuple:
    """heyoka expressions of the rows of ``g(x, u, p)``; their coefficients go after the ODE's parameters.

    The translator numbers hoisted coefficients after the inputs, so ``g`` is re-wrapped with a
    dummy input vector of size ``n_base`` (all specialised to zero).
    """
    nx = len(names)
    x = ca.SX.sym("x", nx)
    p = ca.SX.sym("p", g.nnz_in(2))
    rows = g(x, ca.DM.zeros(g.nnz_in(1)), p)
    n_rows = rows.numel()
    exprs: dict[int, Any] = {}
    derived_fns: list[tuple[Any, int]] = []
    offset = n_base
    for start in range(0, n_rows, nx):
        stop = min(start + nx, n_rows)
        u = ca.SX.sym("u", offset)
        f = ca.Function("g", [x, u, p], [ca.densify(rows[start:stop])])
        sys_g = translate(f, zero_params=key.zero_params, zero_inputs=range(offset), state_names=names)
        # The translator makes its own variables with the same names: rebuild on ours by name (identical).
        for r in range(stop - start):
            exprs[start + r] = sys_g.sys[r][1]
        derived_fns.append((sys_g.derived, sys_g.n_derived))
        offset += sys_g.n_derived
    n_ev = offset - n_base

    def derived(pv: Any) -> np.ndarray:
        return (
            np.concatenate([np.asarray(fn(pv), dtype=float).reshape(m) for fn, m in derived_fns]) if derived_fns else np.empty(0)
        )

    return exprs, derived, n_ev


def _pars(built: _Built, P: np.ndarray, nu: int) -> np.ndarray:
    """Runtime parameters (n_par, m) of the runs' parameter rows ``P`` (m, np); one evaluation per distinct row."""
    if (P == P[:1]).all():  # one parameter set (the flip map): np.unique's row sort cost 4 ms per chunk
        uniq, inv = P[:1], np.zeros(len(P), dtype=np.intp)
    else:
        uniq, inv = np.unique(P, axis=0, return_inverse=True)
        inv = np.asarray(inv).reshape(-1)
    n_par = nu + built.ode.n_derived + built.n_ev_derived
    cols = np.zeros((n_par, len(uniq)))
    for j, row in enumerate(uniq):
        cols[nu : nu + built.ode.n_derived, j] = built.ode.derived(row)
        if built.ev_derived is not None:
            cols[nu + built.ode.n_derived :, j] = built.ev_derived(row)
    return cols[:, inv]


def run_chunk(task: ChunkTask, stop: Callable[[], bool] | None = None) -> ChunkOut:
    """Integrate one chunk of runs with one batch integrator (see the module docstring).

    Without an output grid or recorded events the runs first stream through the lanes
    (:mod:`pendulab.ensemble.stream`: refilled inside event callbacks, the batch never stops for a
    finished run); the runs still going near ``t_final`` are finished exactly by the stepped loop,
    which otherwise runs every run.

    Parameters
    ----------
    task : ChunkTask
        The runs, their horizon and budgets.
    stop : callable, optional
        ``stop() -> bool``, checked between propagation slices; True ends the chunk.

    Returns
    -------
    ChunkOut
        Per-run results; a run over its step budget or past the deadline has status failed
        with a message naming the budget.

    Raises
    ------
    ChunkStoppedError
        ``stop()`` returned True.
    """
    built = build(task.key)
    with built.lock:
        ta = copy.copy(built.template)
    m, nx = task.x0.shape
    out = _Outcomes(task, len(task.key.events.names), nx)
    pars_all = _pars(built, task.p, built.ode.n_inputs)[: ta.pars.shape[0] - 2]
    if task.t_eval is None and not built.nt_index:
        starts = _stream(ta, task, pars_all, out, stop)
    else:
        starts = [(r, task.x0[r], 0.0, 0.0, 0) for r in range(m)]
    if starts:
        _stepped(ta, built, task, pars_all, out, starts, stop)
    out.check_finite()
    return ChunkOut(task.index, out.x_final, out.t_end, out.status, out.messages, out.ev_times, out.term_ev, out.X, out.n_steps)


class _Outcomes:
    """Per-run result arrays of one chunk, and the rules that fill them."""

    def __init__(self, task: ChunkTask, n_events: int, nx: int) -> None:
        m = len(task.x0)
        self.x_final = np.full((m, nx), np.nan)
        self.t_end = np.full(m, np.nan)
        self.status = np.full(m, STATUS_PENDING, dtype=np.int8)
        self.messages: dict[int, str] = {}
        self.ev_times = np.full((n_events, m), np.nan)
        self.term_ev = np.full(m, -1, dtype=np.int64)
        t_eval = task.t_eval
        self.X = np.full((m, len(t_eval), nx), np.nan) if t_eval is not None else None
        self.n_steps = 0

    def fail(self, r: int, t: float, why: str) -> None:
        self.status[r] = STATUS_FAILED
        self.messages[r] = f"method 'taylor' (ensemble) failed at t = {t!r}: {why}"

    def terminal(self, r: int, k: int, t: float, x: np.ndarray) -> None:
        """Run ``r`` ended by terminal event ``k`` at ``t`` in state ``x``."""
        if k in _SPRING_EVENTS:
            self.fail(r, t, f"spring length r{_SPRING_EVENTS[k]} reached 0 m (a bob passed through its joint)")
        else:
            self.status[r] = STATUS_EVENT
            self.term_ev[r] = k
            self.ev_times[k, r] = t
        self.end(r, t, x)

    def end(self, r: int, t: float, x: np.ndarray) -> None:
        """Final state and time of run ``r`` (checked for finiteness by :meth:`check_finite`)."""
        self.x_final[r] = x
        self.t_end[r] = t

    def check_finite(self) -> None:
        """A run that ended in a non-finite state fails (one vectorised check for the chunk).

        Raises
        ------
        RuntimeError
            A run was left without an outcome (a defect of the chunk's loops, named instead of reported as a
            non-finite state).
        """
        pending = np.flatnonzero(self.status == STATUS_PENDING)
        if pending.size:
            raise RuntimeError(f"ensemble chunk left runs {pending.tolist()} without an outcome")
        for r in np.flatnonzero(~np.isfinite(self.x_final).all(axis=1) & (self.status != STATUS_FAILED)):
            self.fail(int(r), float(self.t_end[r]), "the state became non-finite")


def _stream(ta: Any, task: ChunkTask, pars_all: np.ndarray, out: _Outcomes, stop: Callable[[], bool] | None) -> list:
    """Streaming phase (:mod:`.stream`); returns the runs to finish in the stepped loop, as its starts."""
    hy = heyoka_module()
    nf = hy.taylor_outcome.err_nf_state
    stream = Stream(ta, task.x0, pars_all, float(task.t_final), out.terminal)
    callbacks = [ev.callback for ev in ta.t_events]
    for cb in callbacks:
        cb.stream = stream
    try:
        S = ta.batch_size
        ta.set_dtime(np.zeros(S), np.zeros(S))
        for lane in range(S):
            stream.fill(lane, 0.0, 0.0)
        far = np.full(S, _FAR_TIME)
        max_steps, deadline = int(task.max_steps), task.deadline
        while stream.active():
            if stop is not None and stop():
                raise ChunkStoppedError(f"ensemble chunk {task.index} stopped")
            before = list(stream.runs)
            budget_left = max_steps - max(n for n, r in zip(stream.steps, before, strict=True) if r >= 0)
            ta.propagate_until(far, max_steps=max(1, min(SLICE_STEPS, budget_left)))
            late = deadline is not None and time.time() > deadline
            hi, lo = (np.array(a) for a in ta.dtime)
            ended = []
            for lane, (outcome, _hmin, _hmax, steps) in enumerate(ta.propagate_res):
                r = stream.runs[lane]
                if r >= 0 or before[lane] >= 0:  # an idle lane's steps are no run's
                    out.n_steps += steps
                if r < 0:
                    continue
                t = stream.run_elapsed(lane, float(hi[lane]), float(lo[lane]))[0]
                if r == before[lane]:  # a run started inside the slice is charged from the next one
                    stream.steps[lane] += steps
                if outcome == nf:
                    out.fail(r, t, "the state became non-finite (err_nf_state)")
                elif stream.steps[lane] >= max_steps:
                    out.fail(r, t, f"step budget exhausted (max_steps = {max_steps} steps)")
                elif late:
                    out.fail(r, t, "wall-time budget exhausted (max_wall_time)")
                else:
                    continue
                out.end(r, t, ta.state[: stream.nx, lane])
                ended.append(lane)
            if late:  # the budget is spent: the lanes' runs failed above, nothing more starts
                for r, x, t, _lo, _n in stream.finish:
                    out.fail(r, t, "wall-time budget exhausted (max_wall_time)")
                    out.end(r, t, x)
                stream.finish.clear()
                _fail_unstarted(out, task, stream.next_run)
                break
            for lane in ended:
                stream.fill(lane, float(hi[lane]), float(lo[lane]))
                ta.reset_cooldowns(lane)
    finally:
        for cb in callbacks:
            cb.stream = None
    return stream.finish


def _fail_unstarted(out: _Outcomes, task: ChunkTask, first: int) -> None:
    """Runs not started when the wall-time budget ran out fail at once."""
    for r in range(first, len(task.x0)):
        out.fail(r, 0.0, "wall-time budget exhausted (max_wall_time) before the run started")
        out.t_end[r] = 0.0
        out.x_final[r] = task.x0[r]


def _stepped(
    ta: Any, built: _Built, task: ChunkTask, pars_all: np.ndarray, out: _Outcomes, starts: list, stop: Callable[[], bool] | None
) -> None:
    """The stepped loop: every lane's end stops the batch; ``starts`` are (run, state, t hi, t lo, steps)."""
    hy = heyoka_module()
    S = ta.batch_size
    nx = task.x0.shape[1]
    npar = pars_all.shape[0]
    # The bookkeeping between two event stops is per-lane Python: it works on plain lists and on the
    # integrator's own state and parameter buffers (heyoka returns them as writable views), and only
    # the lanes whose outcome ends their run take the slow branch.
    state, pars = ta.state, ta.pars
    lane_run = np.full(S, -1, dtype=np.int64)  # read by the nt-event recorders
    runs: list[int] = [-1] * S  # lane_run as plain ints
    lane_steps = [0] * S
    ptr = np.zeros(S, dtype=np.int64)
    for ev in ta.nt_events if built.nt_index else ():
        cb = ev.callback
        cb.times, cb.lane_run = out.ev_times, lane_run
    target = np.empty(S)
    times = np.zeros(S)
    lows = np.zeros(S)
    queue = iter(starts)
    t_index = built.t_index
    outcome_names = hy.taylor_outcome
    time_limit, nf, step_limit = outcome_names.time_limit, outcome_names.err_nf_state, outcome_names.step_limit
    going_on = (outcome_names.success, step_limit)
    has_events = bool(built.nt_index or built.t_index)
    max_steps, deadline = int(task.max_steps), task.deadline
    t_final, t_eval, X = float(task.t_final), task.t_eval, out.X
    benign = (task.x0[0], pars_all[:, 0])

    def fill(lane: int) -> None:
        start = next(queue, None)
        if start is not None:
            r, x, t_hi, t_lo, steps = start
            runs[lane] = lane_run[lane] = r
            lane_steps[lane] = steps
            times[lane], lows[lane] = t_hi, t_lo
            target[lane] = t_final
            state[:nx, lane] = x
            pars[:npar, lane] = pars_all[:, r]
            ptr[lane] = 0
        else:  # idle: a benign finite state and parameters, no time to go
            runs[lane] = lane_run[lane] = -1
            target[lane] = times[lane]
            lows[lane] = 0.0
            state[:nx, lane], pars[:npar, lane] = benign
        state[nx, lane] = 0.0  # the run clock stands still here (rate 0, end never reached)
        pars[npar, lane], pars[npar + 1, lane] = CLOCK_STILL
        if has_events:
            ta.reset_cooldowns(lane)

    for lane in range(S):
        fill(lane)
    ta.set_dtime(times, lows)
    while any(r >= 0 for r in runs):
        if stop is not None and stop():
            raise ChunkStoppedError(f"ensemble chunk {task.index} stopped")
        # A slice ends at the first step budget of a lane, so a budget is exact, not rounded up to a slice.
        budget_left = max_steps - max(n for n, r in zip(lane_steps, runs, strict=True) if r >= 0)
        res = ta.propagate_until(target, max_steps=max(1, min(SLICE_STEPS, budget_left)), c_output=X is not None)
        times[:] = ta.time
        if X is not None:
            _record_grid(res[0], t_eval, times, lane_run, ptr, X, nx)
        late = deadline is not None and time.time() > deadline
        refill = []
        for lane, (outcome, _hmin, _hmax, steps) in enumerate(ta.propagate_res):
            out.n_steps += steps
            r = runs[lane]
            if r < 0:
                continue
            lane_steps[lane] += steps
            t = float(times[lane])
            if outcome in going_on:
                if lane_steps[lane] >= max_steps:
                    out.fail(r, t, f"step budget exhausted (max_steps = {max_steps} steps)")
                elif late:
                    out.fail(r, t, "wall-time budget exhausted (max_wall_time)")
                else:
                    continue
                out.end(r, t, state[:nx, lane])
            elif outcome == time_limit:
                out.status[r] = STATUS_OK
                out.end(r, t, state[:nx, lane])
            elif _TERMINAL_MIN < (o := int(outcome)) < 0:
                out.terminal(r, t_index[-o - 1], t, state[:nx, lane])
            elif o >= 0:  # a terminal event whose callback let the run go on (not used here)
                continue
            else:
                why = "the state became non-finite (err_nf_state)" if outcome == nf else f"heyoka outcome {outcome}"
                out.fail(r, t, why)
                out.end(r, t, state[:nx, lane])
            refill.append(lane)
        if late:  # runs not started (or not resumed) yet fail at once: the budget is spent
            for r, x, t_hi, _lo, _n in queue:
                why = "wall-time budget exhausted (max_wall_time)"
                out.fail(r, t_hi, f"{why} before the run started" if t_hi == 0.0 else why)
                out.end(r, t_hi, x)
        for lane in refill:
            fill(lane)
        if refill:
            # heyoka keeps each lane's time in double length (hi + lo). Resetting only the refilled lanes
            # keeps the others' exactly: set_time() on all lanes dropped their low parts at moments that
            # depend on which runs share the batch, so a run's result changed at the last bit with the
            # chunking (a resumed flip map differed from an uninterrupted one by 1 ulp).
            hi, lo = (np.array(a) for a in ta.dtime)
            hi[refill], lo[refill] = times[refill], lows[refill]
            ta.set_dtime(hi, lo)


def _record_grid(
    co: Any, t_eval: np.ndarray, times: np.ndarray, lane_run: np.ndarray, ptr: np.ndarray, X: np.ndarray, nx: int
) -> None:
    """Dense output of the last propagation at the grid points each lane passed."""
    stops = np.searchsorted(t_eval, times, side="right")
    counts = np.where(lane_run >= 0, stops - ptr, 0)
    mmax = int(counts.max(initial=0))
    if mmax <= 0:
        return
    tm = np.tile(times, (mmax, 1))
    for lane in np.flatnonzero(counts > 0):
        tm[: counts[lane], lane] = t_eval[ptr[lane] : stops[lane]]
    vals = co(tm)  # (mmax, nx, S)
    for lane in np.flatnonzero(counts > 0):
        r = lane_run[lane]
        X[r, ptr[lane] : stops[lane]] = vals[: counts[lane], :nx, lane]
        ptr[lane] = stops[lane]
