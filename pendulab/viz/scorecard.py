"""Figure of a robustness scorecard: success rate per level, one panel per category, and the category scores."""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ..control.scorecard import Scorecard  # noqa: E402
from .save import save_figure  # noqa: E402

__all__ = ["plot_scorecard"]


def plot_scorecard(card: Scorecard, path: str | Path) -> Path:
    """Bar charts of the success rate per level (a panel per category) and a radar chart of the category scores.

    Parameters
    ----------
    card : Scorecard
        The scorecard to draw.
    path : str or Path
        Output image (format from the suffix, e.g. ``scorecard.png``).

    Returns
    -------
    Path
        The file written.
    """
    cats = card.categories
    n = len(cats)
    cols = min(4, n + 1)
    rows = math.ceil((n + 1) / cols)
    fig = plt.figure(figsize=(3.4 * cols, 2.8 * rows), constrained_layout=True)
    fig.suptitle(f"Robustness of {card.controller} on {card.task}: overall score {card.overall:.2f}")
    for i, c in enumerate(cats):
        ax = fig.add_subplot(rows, cols, i + 1)
        x = np.arange(len(c.levels))
        ax.bar(x, 100 * np.asarray(c.success_rates), color="tab:blue")
        ax.set_xticks(x, [f"{lv:g}" for lv in c.levels], fontsize=8)
        ax.set_ylim(0, 105)
        ax.set_xlabel(f"{c.name.replace('_', ' ')} [{c.unit}]")
        ax.set_ylabel("success [%]")
        ax.set_title(f"score {c.score:.2f}", fontsize=9)
    ax = fig.add_subplot(rows, cols, n + 1, projection="polar")
    angles = np.linspace(0, 2 * np.pi, n, endpoint=False)
    values = np.array([c.score for c in cats])
    ax.plot(np.append(angles, angles[0]), np.append(values, values[0]), color="tab:red")
    ax.fill(np.append(angles, angles[0]), np.append(values, values[0]), color="tab:red", alpha=0.25)
    ax.set_xticks(angles, [c.name.replace("_", "\n") for c in cats], fontsize=7)
    ax.set_ylim(0, 1)
    ax.set_yticks([0.25, 0.5, 0.75, 1.0], ["", "0.5", "", "1"], fontsize=7)
    ax.set_title("category score (0-1)", fontsize=9)
    return save_figure(fig, path)
