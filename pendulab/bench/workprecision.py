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
import csv
import math
import signal
import statistics
import textwrap
import threading
import time
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .._checks import is_interrupt, positive_float
from .._io import atomic_open
from ..integrate import SimulationError
from ..model.model import Model
from ..scene import Scene
from .cases import get_cases
from .fmu_methods import fmu_bench_methods
from .journal import Journal
from .methods import TOLS, TOLS_QUICK, BenchMethod, native_bench_methods
from .reference import Reference, load_reference

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

#: The benchmark's methods (insertion order = legend order): native methods, then the FMU's solvers.
BENCH_METHODS: dict[str, BenchMethod] = {
    **native_bench_methods(),
    **{m.name: m for m in fmu_bench_methods(TOLS, TOLS_QUICK)},
}


@dataclass
class Row:
    """One (case, method, setting) measurement.

    Errors are max-abs state differences from the stored reference (mixed
    state units: rad, m, rad/s, m/s); nan unless ``status`` is ``"ok"``.

    Attributes
    ----------
    case : str
        Case name.
    method : str
        Method name (a key of ``BENCH_METHODS``).
    sweep : str
        ``"tol"`` (rtol = atol = setting) or ``"step"`` (fixed step [s]).
    setting : float
        The tolerance or step of this point.
    status : str
        ``"ok"``, ``"failed"``, ``"unstable"`` (non-finite or blown-up state)
        or ``"skipped"`` (a looser setting was already too slow).
    final_error : float
        Max-abs state error at t_final.
    grid_error : float
        Max-abs state error over the output grid.
    energy_drift : float
        Max over the grid of |E(t) - E(0)| [J].
    wall_median, wall_min : float
        Median and smallest wall time of the timed runs [s].
    cpu_median : float
        Median CPU time (``time.process_time``) of the timed runs [s].
    first_run : float
        Wall time of the untimed warm-up run [s].
    repeats : int
        Number of timed runs.
    n_steps, n_rhs : float
        Steps and right-hand-side evaluations reported by the method (nan if not).
    reference_accuracy : float
        Accuracy of the reference; smaller errors are not resolved.
    message : str
        Why a point failed or was skipped.
    """

    case: str
    method: str
    sweep: str
    setting: float
    status: str  # ok | failed | unstable | skipped
    final_error: float = math.nan
    grid_error: float = math.nan
    energy_drift: float = math.nan
    wall_median: float = math.nan
    wall_min: float = math.nan
    cpu_median: float = math.nan
    first_run: float = math.nan
    repeats: int = 0
    n_steps: float = math.nan
    n_rhs: float = math.nan
    reference_accuracy: float = math.nan
    message: str = ""


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
    slow_run_s = positive_float("slow_run_s", slow_run_s, "[s]")
    selected = list(BENCH_METHODS) if methods is None else list(methods)
    unknown = [m for m in selected if m not in BENCH_METHODS]
    if unknown:
        raise ValueError(f"unknown method(s) {unknown}; expected some of {list(BENCH_METHODS)}")
    case_list = get_cases(cases)
    refs = {c.name: load_reference(c) for c in case_list}
    log = Journal(journal, "work-precision", {"quick": quick, "repeats": repeats, "slow_run_s": slow_run_s}, resume=resume)
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


_FIELDS = [f for f in Row.__dataclass_fields__]


def write_csv(rows: Iterable[Row], path: str | Path) -> Path:
    """Write rows to CSV (one line per case, method and setting).

    Parameters
    ----------
    rows : iterable of Row
        The measurements.
    path : str or Path
        CSV file (parent directories are created); columns are the fields of
        :class:`Row`, floats with 6 significant digits.

    Returns
    -------
    Path
        The written file.
    """
    path = Path(path)
    with atomic_open(path, "w", newline="") as fh:  # never a truncated CSV after an interrupt
        w = csv.DictWriter(fh, fieldnames=_FIELDS)
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in asdict(r).items()})
    return path


def read_csv(path: str | Path) -> list[Row]:
    """Read rows written by :func:`write_csv`.

    Parameters
    ----------
    path : str or Path
        CSV file with the fields of :class:`Row` as columns.

    Returns
    -------
    list of Row
        In file order.
    """
    out = []
    with Path(path).open() as fh:
        for d in csv.DictReader(fh):
            kw: dict[str, Any] = {}
            for k, v in d.items():
                typ = Row.__dataclass_fields__[k].type
                kw[k] = float(v) if typ == "float" else int(v) if typ == "int" else v
            out.append(Row(**kw))
    return out


def merge_rows(old: Iterable[Row], new: Iterable[Row]) -> list[Row]:
    """Rows of ``old`` whose (case, method) was not re-measured, plus ``new``.

    Parameters
    ----------
    old : iterable of Row
        Earlier results (e.g. from :func:`read_csv`).
    new : iterable of Row
        Re-measured results; they replace every old row of the same (case, method).

    Returns
    -------
    list of Row
        Sorted by case order of ``CASES`` and method order of ``BENCH_METHODS``
        (unknown names last), so a partial re-run merged into a complete CSV
        gives the same layout as a full run.
    """
    from .cases import CASES

    new = list(new)
    remeasured = {(r.case, r.method) for r in new}
    rows = [r for r in old if (r.case, r.method) not in remeasured] + new
    case_rank = {c: i for i, c in enumerate(CASES)}
    method_rank = {m: i for i, m in enumerate(BENCH_METHODS)}
    big = len(case_rank) + len(method_rank)
    return sorted(rows, key=lambda r: (case_rank.get(r.case, big), method_rank.get(r.method, big)))


# tab20 comes in dark/light pairs: use the dark ones first so neighbours differ.
_COLOR_ORDER = (0, 2, 4, 6, 8, 10, 12, 14, 16, 18, 1, 3, 5, 7, 9, 11, 13, 15, 17, 19)
_TIME_LABEL = {"wall_median": "median wall time [s]", "cpu_median": "median CPU time [s]"}
_METRIC_LABEL = {
    "grid_error": "achieved error: max |x - x_ref| over the output grid",
    "final_error": "achieved error: max |x(T) - x_ref(T)|",
    "energy_drift": "energy drift: max |E(t) - E(0)| [J]",
}


def _family(method: str) -> str:
    bm = BENCH_METHODS.get(method)
    return bm.family if bm is not None else ""


def plot_work_precision(
    rows: Sequence[Row], path: str | Path, metric: str = "grid_error", title: str = "", time_metric: str = "wall_median"
) -> Path:
    """Median wall (or CPU) time against achieved error (log-log), one panel per case.

    Only rows with status ``"ok"`` are drawn; a dotted line marks the
    reference accuracy (error metrics only).

    Parameters
    ----------
    rows : sequence of Row
        The measurements.
    path : str or Path
        Image file to write (parent directories are created).
    metric : {"grid_error", "final_error", "energy_drift"}
        Error on the horizontal axis.
    title : str
        Figure title; default describes the line styles.
    time_metric : {"wall_median", "cpu_median"}
        Time on the vertical axis [s].

    Returns
    -------
    Path
        The written file.

    Raises
    ------
    ValueError
        Unknown ``metric`` or ``time_metric``.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    if metric not in _METRIC_LABEL:
        raise ValueError(f"metric must be one of {list(_METRIC_LABEL)}, got {metric!r}")
    if time_metric not in _TIME_LABEL:
        raise ValueError(f"time_metric must be one of {list(_TIME_LABEL)}, got {time_metric!r}")
    cases = list(dict.fromkeys(r.case for r in rows))
    methods = list(dict.fromkeys(r.method for r in rows))
    ncol = min(2, len(cases))
    nrow = math.ceil(len(cases) / ncol)
    # Constrained layout keeps the title, labels and the legend below the panels inside the figure.
    fig, axes = plt.subplots(nrow, ncol, figsize=(6.4 * ncol, 4.2 * nrow + 0.8), squeeze=False, layout="constrained")
    cmap = plt.get_cmap("tab20")
    markers = "osD^v<>ph*Xd8PH+"
    for ax, case in zip(axes.flat, cases, strict=False):
        acc = math.nan
        for i, m in enumerate(methods):
            pts = [r for r in rows if r.case == case and r.method == m and r.status == "ok"]
            if not pts:
                continue
            acc = pts[0].reference_accuracy
            xs = [max(getattr(r, metric), 1e-17) for r in pts]
            ys = [getattr(r, time_metric) for r in pts]
            ls = "-." if _family(m) == "fmu" else "--" if pts[0].sweep == "step" else "-"
            color = cmap(_COLOR_ORDER[i % len(_COLOR_ORDER)])
            if _family(m) == "fmu":  # tab20's light shades are hard to see; the FMU lines get black and grey
                color = ("black", "dimgray")[sum(_family(n) == "fmu" for n in methods[:i]) % 2]
            ax.loglog(xs, ys, ls, marker=markers[i % len(markers)], color=color, ms=4, lw=1, label=m)
        if metric != "energy_drift" and math.isfinite(acc):
            ax.axvline(acc, color="k", ls=":", lw=1)
            ax.text(acc, ax.get_ylim()[1], " reference\n accuracy", va="top", fontsize=7)
        ax.set_title(case, fontsize=10)
        ax.set_xlabel(_METRIC_LABEL[metric], fontsize=8)
        ax.set_ylabel(_TIME_LABEL[time_metric], fontsize=8)
        ax.grid(True, which="major", alpha=0.3)
    for ax in list(axes.flat)[len(cases) :]:
        ax.axis("off")
    handles, labels = axes.flat[0].get_legend_handles_labels()
    for ax in axes.flat:
        h, lab = ax.get_legend_handles_labels()
        if len(lab) > len(labels):
            handles, labels = h, lab
    fig.legend(
        handles, labels, loc="outside lower center", ncol=min(7 if ncol > 1 else 4, len(labels)), fontsize=8, frameon=False
    )
    default_title = "Work-precision: solid = tolerance sweep, dashed = fixed-step sweep, dash-dot = FMU via fmpy"
    # One panel is 6.4 in wide: wrap the title to fit it (about 11 characters per inch at 11 pt).
    fig.suptitle(textwrap.fill(title or default_title, width=int(6.4 * ncol * 11)), fontsize=11)
    from ..viz.save import save_figure

    return save_figure(fig, path, dpi=110)


def fastest_table(rows: Sequence[Row], case: str, levels: Sequence[float] = (1e-2, 1e-4, 1e-6, 1e-8, 1e-10)) -> list[dict]:
    """For each error level, the method reaching it (grid error) in the least median time.

    Parameters
    ----------
    rows : sequence of Row
        The measurements (only status ``"ok"`` counts).
    case : str
        Case to rank.
    levels : sequence of float
        Grid-error levels to reach.

    Returns
    -------
    list of dict
        One per level: ``level``, ``method``, ``setting``, ``sweep``,
        ``grid_error``, ``wall_median`` [s], and ``runner_up`` with its time
        ``ratio`` when there is one; ``method`` is None when nobody reaches
        the level.
    """
    ok = [r for r in rows if r.case == case and r.status == "ok"]
    table = []
    for lev in levels:
        best: dict[str, Row] = {}
        for r in ok:
            if r.grid_error <= lev and (r.method not in best or r.wall_median < best[r.method].wall_median):
                best[r.method] = r
        ranked = sorted(best.values(), key=lambda r: r.wall_median)
        entry: dict[str, Any] = {"level": lev, "method": None}
        if ranked:
            w = ranked[0]
            entry.update(method=w.method, setting=w.setting, sweep=w.sweep, grid_error=w.grid_error, wall_median=w.wall_median)
            if len(ranked) > 1:
                entry.update(runner_up=ranked[1].method, ratio=ranked[1].wall_median / w.wall_median)
        table.append(entry)
    return table
