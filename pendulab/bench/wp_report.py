"""Figures and tables of the work-precision benchmark: time against achieved error, the fastest method per level."""

from __future__ import annotations

import math
import textwrap
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from .wp_rows import BENCH_METHODS, Row

__all__ = ["plot_work_precision", "fastest_table"]


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
