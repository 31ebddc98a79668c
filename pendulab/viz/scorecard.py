"""Figure of a robustness scorecard: success rate per level, one panel per category, and the category scores."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ..evaluate.card import Scorecard  # noqa: E402
from .save import save_figure  # noqa: E402

__all__ = ["plot_scorecard", "plot_realai"]


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
    fed = f" fed by {card.estimator}" if getattr(card, "estimator", None) else ""
    fig.suptitle(f"Robustness of {card.controller}{fed} on {card.task}: overall score {card.overall:.2f}")
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


def plot_realai(result: Any, path: str | Path) -> Path:
    """The leaderboard run of ``pendulab score --realai``: angles, torques against the limit, end-effector height.

    Parameters
    ----------
    result : RealAIResult
        A run of :func:`pendulab.evaluate.realai.realai_score`.
    path : str or Path
        Output image (e.g. ``realai.png``).

    Returns
    -------
    Path
        The written file.
    """
    from ..control.realai.spec import TORQUE_LIMIT, leaderboard_model
    from ..evaluate.realai.criteria import to_relative

    t, x, u = result.t, result.x, result.u
    model = leaderboard_model(result.task)
    L1, L2 = model.params.L1, model.params.L2
    fig, axes = plt.subplots(3, 1, figsize=(8, 7.5), sharex=True, layout="constrained")
    q2 = to_relative(x)[:, 1]
    axes[0].plot(t, x[:, 0], label="theta1 (absolute)")
    axes[0].plot(t, x[:, 1], label="theta2 (absolute)")
    axes[0].plot(t, q2, ls="--", lw=1.0, label="q2 = theta2 - theta1")
    axes[0].axhline(np.pi, color="k", lw=0.6, ls=":")
    axes[0].set_ylabel("angle from\nhanging [rad]")
    for j, name in enumerate(("tau1", "tau2")):
        axes[1].step(t, u[:, j], where="post", label=name)
    for sign in (-1.0, 1.0):
        axes[1].axhline(sign * TORQUE_LIMIT, color="C3", lw=0.9, ls="--")
    axes[1].plot([], [], color="C3", lw=0.9, ls="--", label=f"limit +-{TORQUE_LIMIT:g} N.m")
    axes[1].set_ylabel("torque [N.m]")
    height = -L1 * np.cos(x[:, 0]) - L2 * np.cos(x[:, 1])
    axes[2].plot(t, height, color="C2", label="end-effector height")
    axes[2].axhline(0.9 * (L1 + L2), color="C3", lw=0.9, ls="--", label="0.9 (L1 + L2): success line")
    t_up = result.swingup_time
    if result.success:
        for ax in axes:
            ax.axvline(t_up, color="0.4", lw=0.8, ls="-.")
        axes[2].plot([], [], color="0.4", lw=0.8, ls="-.", label=f"swing-up time {t_up:.3f} s")
    axes[2].set_ylabel("height [m]")
    axes[-1].set_xlabel("time [s]")
    for ax in axes:
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8, loc="best", framealpha=0.8)
    outcome = f"success, score {result.score:.3f}" if result.success else "no swing-up, score 0"
    fig.suptitle(f"RealAIGym {result.task} / {result.controller}: {outcome}")
    return save_figure(fig, path, dpi=110)
