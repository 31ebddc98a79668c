"""Figure of a RealAIGym robustness-v2 run: where the controller fails, category by category."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ..evaluate.realai.robustness import CATEGORY_LABELS, RobustnessResult  # noqa: E402
from .save import save_figure  # noqa: E402

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = ["plot_robustness"]

_MODEL_RANGE = "grid point: Ir 0…1e-4 kg m², m r, I, m2 ×0.75…×1.25,\nb −0.1…0.1 N m s/rad, cf −0.2…0.2 N m"


_TITLES = {
    "measurement_noise": "velocity measurement noise",
    "u_noise": "torque noise",
    "u_responsiveness": "torque responsiveness",
    "delay": "measurement delay",
}


def _not_run(ax: Axes, title: str) -> None:
    ax.set_axis_off()
    ax.set_title(f"{title}: not run", fontsize=9)


def plot_robustness(result: RobustnessResult, path: str | Path) -> Path:
    """Success against each category's level, six panels (model parameters as a 10 x 21 map).

    Parameters
    ----------
    result : RobustnessResult
        A robustness-v2 run (full or reduced grid).
    path : str or Path
        Output image (format from the suffix, e.g. ``robustness.png``).

    Returns
    -------
    Path
        The file written.
    """
    rates, lr, lv = result.rates, result.level_rates(), result.levels
    fig, axes = plt.subplots(2, 3, figsize=(13, 7), constrained_layout=True)
    fig.suptitle(
        f"RealAIGym robustness v2: {result.controller} on {result.task}, score {result.score:.3f}"
        + ("" if result.complete else " (reduced grid)")
    )
    # Model parameters: success map, one row per parameter, one column per grid point.
    ax = axes[0, 0]
    names = list(lr["model"])
    if not names:
        _not_run(ax, "model parameters")
    else:
        idx = sorted({r["level_index"] for r in result.records if r["category"] == "model"})
        grid = np.array([lr["model"][n] for n in names])
        ax.imshow(grid, cmap="RdYlGn", vmin=0, vmax=1, aspect="auto", interpolation="nearest")
        ax.set_yticks(range(len(names)), names, fontsize=8)
        ax.set_xticks(range(len(idx)), [str(i) if (len(idx) < 8 or i % 5 == 0) else "" for i in idx], fontsize=8)
        ax.set_xlabel(_MODEL_RANGE, fontsize=7)
        ax.set_title(f"model parameters: {100 * rates.get('model', 0):.1f} % (green = success)", fontsize=9)
    for k, cat in enumerate(("measurement_noise", "u_noise", "u_responsiveness", "delay")):
        ax = axes.flat[k + 1]
        if not lr[cat]:
            _not_run(ax, _TITLES[cat])
            continue
        x = np.asarray(lv[cat], dtype=float)
        y = 100 * np.asarray(lr[cat], dtype=float)
        width = 0.8 * (np.min(np.diff(x)) if len(x) > 1 else 1.0)
        noise = cat in ("measurement_noise", "u_noise")
        ok = y > 50 if noise else y > 0
        ax.bar(x, np.maximum(y, 1.5), width=width, color=np.where(ok, "tab:green", "tab:red"))
        if noise:
            ax.axhline(50, color="k", ls="--", lw=0.8)
            ax.text(x[0], 53, "a level passes above 50 % of its runs", fontsize=7, bbox={"fc": "white", "alpha": 0.8, "lw": 0})
        ax.set_ylim(0, 105)
        ax.set_xlabel(CATEGORY_LABELS[cat])
        ax.set_ylabel("success [%]")
        ax.set_title(f"{_TITLES[cat]}: {100 * rates.get(cat, 0):.1f} %", fontsize=9)
    # Perturbations: success of each run against its largest pulse on the driven joint.
    ax = axes[1, 2]
    act = 0 if result.task == "pendubot" else 1
    pr = [r for r in result.records if r["category"] == "perturbation"]
    if not pr:
        _not_run(ax, "perturbations")
        return save_figure(fig, path)
    amp = np.array([np.max(np.abs(r["amplitude"][act])) for r in pr])
    succ = np.array([r["success"] for r in pr], dtype=bool)
    ax.scatter(amp[succ], np.ones(succ.sum()), color="tab:green", label="success", s=18)
    ax.scatter(amp[~succ], np.zeros((~succ).sum()), color="tab:red", marker="x", label="failure", s=18)
    ax.set_yticks([0, 1], ["fail", "success"])
    ax.set_ylim(-0.5, 1.5)
    ax.set_xlim(0, 5.2)
    ax.set_xlabel("largest pulse on the driven joint [N m]")
    ax.set_title(f"perturbations ({len(pr)} runs): {100 * rates.get('perturbation', 0):.1f} %", fontsize=9)
    ax.legend(fontsize=7, loc="center right")
    return save_figure(fig, path)
