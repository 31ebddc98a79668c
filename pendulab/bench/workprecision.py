"""Work-precision benchmark: median wall time against *achieved* error.

Every method runs over a sweep of its accuracy setting (tolerance for the
adaptive methods, step for the fixed-step ones) on every case of
:mod:`pendulab.bench.cases`; errors are measured against the stored
references (:mod:`pendulab.bench.reference`) three ways:

* ``final_error``: max-abs state error at t_final,
* ``grid_error``: max-abs state error over the output grid,
* ``energy_drift``: max over the grid of |E(t) - E(0)| [J] (the cases are
  undamped, so the exact value is zero; chaos does not amplify it).

Wall time is the median of up to ``repeats`` timed runs of the whole
``simulate`` call after one untimed warm-up run (which builds and caches the
CasADi functions; its time is kept as ``first_run``); a point stops repeating
once its timed runs took ``REPEAT_BUDGET_S``. When a point's median exceeds
``slow_run_s`` the tighter settings of that method on that case are skipped.
CPU time (``time.process_time``) is recorded next to wall time because the
benchmark machine may be shared.

Methods are entries of ``BENCH_METHODS`` (see :mod:`.methods`): the native
ones come from the integrate registry, the FMU's embedded solvers from
:mod:`.fmu_methods`; see ``docs/benchmarks.md``.
"""

from __future__ import annotations

import contextlib
import math
import signal
import statistics
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import asdict, fields
from pathlib import Path
from typing import Any

import numpy as np

from .._checks import check_budget, is_interrupt, positive_float
from ..integrate import SimulationError
from ..model.model import Model
from ..scene import Scene
from .cases import get_cases
from .journal import Journal
from .methods import BenchMethod
from .reference import Reference, load_reference
from .wp_report import fastest_table, plot_work_precision  # noqa: F401  (re-exported: their old home)
from .wp_rows import BENCH_METHODS, Row, merge_rows, read_csv, write_csv  # noqa: F401  (re-exported: their old home)

# Row, BENCH_METHODS and the CSV in :mod:`.wp_rows`; figures and tables in :mod:`.wp_report` (re-exported here).
__all__ = [
    "BenchMethod",
    "BENCH_METHODS",
    "Row",
    "run_work_precision",
    "write_csv",
    "read_csv",
    "plot_work_precision",
    "fastest_table",
    "merge_rows",
]

Progress = Callable[[int, int, str], None]

REPEAT_BUDGET_S = 2.0  # stop repeating a point once its timed runs took this long [s]


def _measure(method: BenchMethod, case: Scene, model: Model, x0: np.ndarray, ref: Reference, setting: float, repeats: int) -> Row:
    row = Row(case.name, method.name, method.sweep, setting, "ok", reference_accuracy=ref.accuracy)
    times: list[float] = []
    cpu: list[float] = []
    traj = None
    # Run 0 is a warm-up (it builds and caches the CasADi functions); then up to
    # `repeats` timed runs, fewer once they have used REPEAT_BUDGET_S.
    for i in range(repeats + 1):
        start, cpu_start = time.perf_counter(), time.process_time()
        try:
            traj = method.run(model, x0, case.t_final, case.dt, setting)
        except SimulationError as exc:
            # CasADi turns a Ctrl-C inside the integrator into an error: that is no failed point.
            if is_interrupt(exc):
                raise KeyboardInterrupt from exc
            row.status = "unstable" if "non-finite" in str(exc) else "failed"
            row.message = str(exc).splitlines()[0][:200]
            return row
        if i == 0:
            row.first_run = time.perf_counter() - start
            continue
        times.append(time.perf_counter() - start)
        cpu.append(time.process_time() - cpu_start)
        if sum(times) > REPEAT_BUDGET_S:
            break
    X = traj.x
    if X.shape != ref.x.shape:
        row.status, row.message = "failed", f"grid shape {X.shape} differs from the reference {ref.x.shape}"
        return row
    if not np.all(np.isfinite(X)) or np.max(np.abs(X)) > 1e6:
        row.status, row.message = "unstable", "state blew up"
        return row
    err = np.abs(X - ref.x)
    E = model.energy(X)
    row.final_error = float(np.max(err[-1]))
    row.grid_error = float(np.max(err))
    row.energy_drift = float(np.max(np.abs(E - E[0])))
    row.wall_median = float(statistics.median(times))
    row.wall_min = float(min(times))
    row.cpu_median = float(statistics.median(cpu))
    row.repeats = len(times)
    row.n_steps = float(traj.stats.get("n_steps") or math.nan)
    row.n_rhs = float(traj.stats.get("n_rhs") or math.nan)
    return row


def run_work_precision(
    cases: Sequence[str] | None = None,
    methods: Sequence[str] | None = None,
    *,
    quick: bool = False,
    repeats: int = 3,
    slow_run_s: float = 5.0,
    progress: Progress | None = None,
    journal: str | Path | None = None,
    resume: bool = False,
) -> list[Row]:
    """Run the work-precision sweep.

    Each finished point is recorded in ``journal`` (rewritten atomically), so an
    interrupted or crashed run keeps its finished points and ``resume=True``
    continues it. A point that raises (any ``Exception``) is recorded with
    status ``"failed"`` and its reason, and the sweep goes on.

    Parameters
    ----------
    cases : sequence of str, optional
        Case names (default: all of ``CASES``).
    methods : sequence of str, optional
        Method names of ``BENCH_METHODS`` (default: all).
    quick : bool
        Use the short sweeps (CI smoke run).
    repeats : int
        Timed runs per point (median reported).
    slow_run_s : float
        A point whose median wall time exceeds this [s] (or whose warm-up run
        exceeds four times this) ends the method's sweep on that case.
    progress : callable, optional
        ``progress(done, total, label)`` after each point (resumed points count as done).
    journal : str or Path, optional
        JSON file recording every finished point (see :class:`~pendulab.bench.journal.Journal`).
    resume : bool
        Skip the points already recorded in ``journal`` (written with the same
        ``quick``, ``repeats`` and ``slow_run_s``).

    Returns
    -------
    list of Row
        One per (case, method, setting), in case, method, setting order.

    Raises
    ------
    ValueError
        ``repeats`` < 1, an unknown method or case name, or a journal to
        resume that was written with other settings.
    ReferenceMissingError
        A case has no stored (or only a stale) reference.
    """
    if not isinstance(repeats, int) or repeats < 1:
        raise ValueError(f"repeats must be a positive integer, got {repeats!r}")
    check_budget("repeats", "repeats", repeats)
    slow_run_s = positive_float("slow_run_s", slow_run_s, "[s]")
    selected = list(BENCH_METHODS) if methods is None else list(methods)
    unknown = [m for m in selected if m not in BENCH_METHODS]
    if unknown:
        raise ValueError(f"unknown method(s) {unknown}; expected some of {list(BENCH_METHODS)}")
    case_list = get_cases(cases)
    refs = {c.name: load_reference(c) for c in case_list}
    config = {"quick": quick, "repeats": repeats, "slow_run_s": slow_run_s}
    log = Journal(journal, "work-precision", config, resume=resume, check=_check_row)
    plan = [(c, BENCH_METHODS[m]) for c in case_list for m in selected]
    total = sum(len(bm.quick if quick else bm.settings) for _, bm in plan)
    rows: list[Row] = []
    done = 0
    with watch_interrupt() as interrupted:
        for case, bm in plan:
            settings = bm.quick if quick else bm.settings
            stop = False
            for s in settings:
                key = f"{case.name}|{bm.name}|{s!r}"
                if key in log:
                    row = Row(**log.get(key))
                elif stop:
                    row = Row(case.name, bm.name, bm.sweep, s, "skipped", message=f"a looser setting took > {slow_run_s:g} s")
                else:
                    row = _measure_or_fail(bm, case, refs[case.name], s, repeats)
                    # A native solver may have swallowed a Ctrl-C (and retried): stop anyway (unrecorded).
                    if interrupted():
                        raise KeyboardInterrupt
                if key not in log:
                    log.record(key, asdict(row))
                rows.append(row)
                stop = stop or (row.status == "ok" and (row.wall_median > slow_run_s or row.first_run > 4 * slow_run_s))
                done += 1
                if progress is not None:
                    progress(done, total, f"{case.name} {bm.name} {bm.sweep}={s:g}")
    return rows


def _check_row(key: str, value: Any) -> None:
    """Raise for a journaled point that is not a whole :class:`Row` (it is measured again instead of breaking the report)."""
    for f in fields(Row):
        if f.name not in value:
            raise KeyError(f.name)
    Row(**value)


def _measure_or_fail(bm: BenchMethod, case: Scene, ref: Reference, setting: float, repeats: int) -> Row:
    """:func:`_measure`, or a ``"failed"`` row naming the error: one broken point never ends the study."""
    try:
        return _measure(bm, case, case.model, case.x0, ref, setting, repeats)
    except Exception as exc:
        if is_interrupt(exc):
            raise KeyboardInterrupt from exc
        reason = (str(exc).strip().splitlines() or [""])[0][:300]
        return Row(
            case.name,
            bm.name,
            bm.sweep,
            setting,
            "failed",
            reference_accuracy=ref.accuracy,
            message=f"{type(exc).__name__}: {reason}",
        )


@contextlib.contextmanager
def watch_interrupt() -> Iterator[Callable[[], bool]]:
    """Record SIGINTs while the block runs, for loops whose native calls may swallow the interrupt.

    The caller's SIGINT handler still runs (Python's default raises
    ``KeyboardInterrupt``); outside the main thread nothing is installed.

    Yields
    ------
    callable
        ``interrupted()``: True once a SIGINT has arrived during the block.
    """
    hit = [False]
    previous = signal.getsignal(signal.SIGINT) if threading.current_thread() is threading.main_thread() else None
    if previous in (None, signal.SIG_IGN):
        yield lambda: hit[0]
        return

    def on_sigint(signum: int, frame: Any) -> None:
        if not callable(previous):  # SIG_DFL would end the process: interrupt instead
            hit[0] = True
            raise KeyboardInterrupt
        try:
            previous(signum, frame)
        except KeyboardInterrupt:
            hit[0] = True
            raise

    signal.signal(signal.SIGINT, on_sigint)
    try:
        yield lambda: hit[0]
    finally:
        signal.signal(signal.SIGINT, previous)
