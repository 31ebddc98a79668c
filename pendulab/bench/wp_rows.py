"""The work-precision benchmark's method table and its result rows: one :class:`Row` per point, CSV in and out.

Shared by the measurement (:mod:`.workprecision`) and the figures and tables
(:mod:`.wp_report`); a change of the CSV layout or of the method table happens here.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Iterable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from .._io import atomic_open
from .fmu_methods import fmu_bench_methods
from .methods import TOLS, TOLS_QUICK, BenchMethod, native_bench_methods

__all__ = ["BENCH_METHODS", "Row", "write_csv", "read_csv", "merge_rows"]

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
