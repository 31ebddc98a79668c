"""CSVs and charts of a stability run (``pendulab bench stability``): see :mod:`pendulab.bench.stability`."""

from __future__ import annotations

import csv
import math
from pathlib import Path
from typing import Any

import numpy as np

from .._io import atomic_open
from ..integrate.fixed_step import FIXED_METHODS, IMAG_AXIS_LIMIT
from .stability_result import ACCURATE, FAILED, INACCURATE, UNSTABLE, StabilityResult

__all__ = ["write_stability"]


def write_stability(res: StabilityResult, out: str | Path) -> list[Path]:
    """Write CSVs and charts of a stability run.

    Parameters
    ----------
    res : StabilityResult
        As returned by :func:`run_stability`.
    out : str or Path
        Output directory (created).

    Returns
    -------
    list of Path
        ``stability_map.csv``, ``rk4_limit.csv``, ``step_counts.csv`` and the
        charts ``stability_map.png``, ``stability_steps.png``,
        ``stability_energy.png``.
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    paths = [out / "stability_map.csv", out / "rk4_limit.csv", out / "step_counts.csv"]
    names = {UNSTABLE: "unstable", INACCURATE: "stable-inaccurate", ACCURATE: "stable-accurate", FAILED: "failed"}
    # Atomic writes: an interrupted run never leaves a truncated CSV.
    with atomic_open(paths[0], "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["method", "k", "omega_max", "h", "h_omega_max", "class", "position_error"])
        for m, grid in res.maps.items():
            for i, k in enumerate(res.ks):
                for j, h in enumerate(res.hs):
                    w.writerow(
                        [
                            m,
                            f"{k:.6g}",
                            f"{res.omega_max[i]:.6g}",
                            f"{h:.6g}",
                            f"{h * res.omega_max[i]:.4g}",
                            names[grid[i, j]],
                            f"{res.errors[m][i, j]:.3e}",
                        ]
                    )
    with atomic_open(paths[1], "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["k", "h_measured", "h_predicted", "relative_difference"])
        for k, hm, hp in res.blowup:
            w.writerow([f"{k:.6g}", f"{hm:.6g}", f"{hp:.6g}", f"{hm / hp - 1:.4f}"])
    with atomic_open(paths[2], "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=["k", "start", "method", "steps"])
        w.writeheader()
        w.writerows(res.step_counts)
    paths += [_plot_map(res, out / "stability_map.png"), _plot_steps(res, out / "stability_steps.png")]
    paths.append(_plot_energy(res, out / "stability_energy.png"))
    return paths


def _plt() -> Any:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _plot_map(res: StabilityResult, path: Path) -> Path:
    plt = _plt()
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    methods = list(res.maps)
    ncol = 3
    nrow = math.ceil(len(methods) / ncol)
    fig, axes = plt.subplots(
        nrow, ncol, figsize=(4.6 * ncol, 3.8 * nrow + 0.6), squeeze=False, sharex=True, sharey=True, layout="constrained"
    )
    cmap = ListedColormap(["#d62728", "#ffbf40", "#2ca02c"])
    lk, lh = np.log10(res.ks), np.log10(res.hs)

    def edges(v: np.ndarray) -> np.ndarray:
        mid = 0.5 * (v[1:] + v[:-1])
        return np.concatenate([[v[0] - (mid[0] - v[0])], mid, [v[-1] + (v[-1] - mid[-1])]])

    kk = np.logspace(lk[0], lk[-1], 100)
    wmax = np.interp(np.log10(kk), lk, np.log10(res.omega_max))
    for ax, m in zip(axes.flat, methods, strict=False):
        # Failed cells (FAILED < 0) stay blank.
        cells = np.ma.masked_less(res.maps[m].T, 0)
        ax.pcolormesh(10 ** edges(lk), 10 ** edges(lh), cells, cmap=cmap, vmin=0, vmax=2, shading="flat")
        ax.set_xscale("log")
        ax.set_yscale("log")
        lim = IMAG_AXIS_LIMIT.get(m)
        if lim:
            ax.plot(kk, lim / 10**wmax, "k-", lw=2, label=f"h w_max = {lim:.2f}")
        ax.plot(kk, 1.0 / 10**wmax, "k:", lw=1, label="h w_max = 1")
        fm = FIXED_METHODS[m]
        ax.set_title(f"{m} (order {fm.order}, {'explicit' if fm.explicit else 'implicit'})", fontsize=9)
        ax.legend(fontsize=7, loc="lower left")
        ax.set_xlabel("spring stiffness k [N/m]")
        ax.set_ylabel("step h [s]")
    for ax in list(axes.flat)[len(methods) :]:
        ax.axis("off")
    patches = [Patch(color=c) for c in ("#2ca02c", "#ffbf40", "#d62728")]
    names = ["stable and accurate (bob positions within 1 mm)", "stable but inaccurate", "unstable (energy x10 within 1 s)"]
    if any(np.any(g == FAILED) for g in res.maps.values()):
        patches.append(Patch(facecolor="white", edgecolor="0.5"))
        names.append("failed (reason in the run's failures)")
    fig.legend(patches, names, loc="outside lower center", ncol=len(names), fontsize=9, frameon=False)
    fig.suptitle("Fixed-step methods on the elastic pendulum (theta = 0.3 rad, springs at rest length, 1 s)", fontsize=11)
    from ..viz.save import save_figure

    return save_figure(fig, path, dpi=110)


def _plot_steps(res: StabilityResult, path: Path) -> Path:
    plt = _plt()
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), sharey=True, layout="constrained")
    ks = sorted({r["k"] for r in res.step_counts})
    for ax, start in zip(axes, ("quasi-static", "rest-length"), strict=False):
        for m, mk in zip(("RK45", "DOP853", "Radau", "cvodes-bdf"), "osD^", strict=False):
            pts = [(r["k"], r["steps"]) for r in res.step_counts if r["start"] == start and r["method"] == m]
            if pts:
                ax.loglog(*zip(*pts, strict=False), "-", marker=mk, label=m)
        if ks:
            ref = [r["steps"] for r in res.step_counts if r["method"] == "RK45" and r["start"] == start]
            if ref:
                guide = ref[-1] * np.sqrt(np.array(ks) / ks[-1])
                ax.loglog(ks, guide, "k:", lw=1, label="~ sqrt(k)")
        what = "quasi-static lengths" if start == "quasi-static" else "rest length"
        ax.set_title(f"start: springs at {what} (rtol = atol = 1e-6, 1 s)", fontsize=10)
        ax.set_xlabel("spring stiffness k [N/m]")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    axes[0].set_ylabel("accepted steps over 1 s")
    from ..viz.save import save_figure

    return save_figure(fig, path, dpi=110)


def _plot_energy(res: StabilityResult, path: Path) -> Path:
    plt = _plt()
    fig, ax = plt.subplots(figsize=(8, 4.2), layout="constrained")
    for label, (t, dE) in res.energy.items():
        ax.plot(t, dE, label=label, lw=1.2)
    ax.set_xlabel("time t [s]")
    ax.set_ylabel("energy change E(t) - E(0) [J]")
    ax.set_title("Undamped springs, k = 1e4 N/m, rest-length start: symplectic vs dissipative methods", fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    from ..viz.save import save_figure

    return save_figure(fig, path, dpi=110)
