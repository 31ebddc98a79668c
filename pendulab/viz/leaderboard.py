"""Leaderboard figures: where each controller fails on robustness v2 (success against each category's level), v3 per
seed, and the v3 hardware protocol against the real robot."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ..evaluate.realai.leaderboard import TASKS, LeaderboardRun  # noqa: E402
from ..evaluate.realai.leaderboard_published import PUBLISHED_ROBUSTNESS_ROWS, PUBLISHED_V3_ROWS  # noqa: E402
from ..evaluate.realai.robustness_grid import CATEGORY_LABELS  # noqa: E402
from .save import save_figure  # noqa: E402

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from ..evaluate.realai.upstream_records import EntryScores

__all__ = ["plot_robustness_levels", "plot_v3_seeds", "plot_hardware_agreement", "PERTURBATION_BINS"]

_TITLES = {
    "model": "model parameters",
    "measurement_noise": "velocity measurement noise",
    "u_noise": "torque noise",
    "u_responsiveness": "torque responsiveness",
    "delay": "measurement delay",
    "perturbation": "perturbations",
}
_XLABELS = {
    **CATEGORY_LABELS,
    "model": (
        "grid point of every parameter (0 = low end, 20 = high end:\nIr 0…1e-4 kg m², m r, I, m2 ×0.75…×1.25, b ±0.1, cf ±0.2)"
    ),
    "delay": "measurement delay [ms]",
    "perturbation": "largest pulse on the driven joint [N m] (runs binned)",
}
#: Bin edges [N m] of the perturbation runs' largest pulse on the driven joint (amplitudes are 0.5 ... 5 N m).
PERTURBATION_BINS: tuple[float, ...] = (0.5, 1.5, 2.5, 3.5, 4.5, 5.0)
_COLORS = ("tab:blue", "tab:orange", "tab:green", "tab:purple", "tab:brown", "tab:pink", "tab:olive", "tab:cyan")


def _curve(summary: dict[str, Any], cat: str) -> tuple[np.ndarray, np.ndarray]:
    """(level, success [%]) of one category of a robustness-v2 summary."""
    lr, lv = summary["level_rates"], summary["levels"]
    if cat == "model":
        per = [np.asarray(v, dtype=float) for v in lr["model"].values()]
        if not per:
            return np.array([]), np.array([])
        idx = summary.get("model_level_indices") or list(range(len(per[0])))
        return np.asarray(idx, dtype=float), 100 * np.mean(per, axis=0)
    if cat == "perturbation":
        amp = np.asarray(summary.get("perturbation_amplitude", []), dtype=float)
        ok = np.asarray(lr["perturbation"], dtype=float)
        if amp.size == 0 or amp.size != ok.size:
            return np.array([]), np.array([])
        edges = np.asarray(PERTURBATION_BINS)
        k = np.clip(np.digitize(amp, edges) - 1, 0, len(edges) - 2)
        xs, ys = [], []
        for b in range(len(edges) - 1):
            sel = k == b
            if np.any(sel):
                xs.append(0.5 * (edges[b] + edges[b + 1]))
                ys.append(100 * float(np.mean(ok[sel])))
        return np.asarray(xs), np.asarray(ys)
    x = np.asarray(lv.get(cat, []), dtype=float)
    y = 100 * np.asarray(lr.get(cat, []), dtype=float)
    return (1e3 * x if cat == "delay" else x), y


def _published_strip(ax: Axes, x_strip: float, task: str, cat: str) -> None:
    rows = PUBLISHED_ROBUSTNESS_ROWS[task]
    vals = [100 * r.values[cat] for r in rows]
    ax.scatter([x_strip] * len(vals), vals, marker="_", s=160, color="0.35", lw=1.5, zorder=3)
    best = max(rows, key=lambda r: r.values[cat])
    ax.annotate(best.label, (x_strip, 100 * best.values[cat]), xytext=(0, 4), textcoords="offset points",
                ha="center", fontsize=6, color="0.25")  # fmt: skip


_STYLES = ("-", "--", "-.", ":")
_MARKERS = ("o", "s", "^", "D", "v", "P", "X", "*")


def plot_robustness_levels(run: LeaderboardRun, task: str, path: str | Path) -> Path:
    """Robustness v2 on one task: success against each category's level, one line per controller (six panels).

    Published entries appear only as their category rate (a gray tick right of each panel): upstream
    publishes no per-level successes.

    Parameters
    ----------
    run : LeaderboardRun
        Leaderboard cases (robustness-v2 ones are used).
    task : {"pendubot", "acrobot"}
        Task.
    path : str or Path
        Output image (e.g. ``leaderboard_robustness_pendubot.png``).

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    ValueError
        Unknown task.
    """
    from matplotlib.lines import Line2D

    if task not in TASKS:
        raise ValueError(f"task must be one of {list(TASKS)}, got {task!r}")
    cases = [run.case("robustness-v2", task, n) for n in run.controllers("robustness-v2")]
    fig, axes = plt.subplots(2, 3, figsize=(14, 8.4), constrained_layout=True)
    note = "" if run.settings.comparable else " — QUICK GRID, not comparable"
    fig.suptitle(f"RealAIGym robustness v2, {task}: success rate against each category's level{note}")
    handles: list[Any] = []
    for j, c in enumerate(cases):
        score = c.summary.get("score") if c.status == "done" else None
        lab = f"pendulab {c.controller}: " + (f"score {score:.3f}" if score is not None else c.status)
        handles.append(Line2D([], [], color=_COLORS[j % len(_COLORS)], ls=_STYLES[j % len(_STYLES)],
                              marker=_MARKERS[j % len(_MARKERS)], ms=4, label=lab))  # fmt: skip
    pub = "published entries: category rate only (upstream gives no per-level data); best named"
    handles.append(Line2D([], [], color="0.35", marker="_", ms=12, ls="none", label=pub))
    for k, cat in enumerate(("model", "measurement_noise", "u_noise", "u_responsiveness", "delay", "perturbation")):
        ax = axes.flat[k]
        lo, hi = (PERTURBATION_BINS[0], PERTURBATION_BINS[-1]) if cat == "perturbation" else (np.inf, -np.inf)
        rates = []
        for j, c in enumerate(cases):
            if c.status != "done":
                continue
            x, y = _curve(c.summary, cat)
            if x.size == 0:
                continue
            lo, hi = min(lo, float(x.min())), max(hi, float(x.max()))
            rate = c.summary["rates"].get(cat)
            if rate is not None:
                rates.append(f"{c.controller} {100 * rate:.1f} %")
            ax.plot(x, y, ls=_STYLES[j % len(_STYLES)], marker=_MARKERS[j % len(_MARKERS)], ms=4, lw=1.4,
                    color=_COLORS[j % len(_COLORS)], alpha=0.9)  # fmt: skip
        if not np.isfinite(lo):
            lo, hi = 0.0, 1.0
        span = (hi - lo) or 1.0
        ax.axvline(hi + 0.07 * span, color="0.8", lw=0.8)
        _published_strip(ax, hi + 0.16 * span, task, cat)
        if cat in ("measurement_noise", "u_noise"):
            ax.axhline(50, color="k", ls="--", lw=0.7)
            ax.text(lo, 52, "a level counts above 50 %", fontsize=7)
        ax.set_xlim(lo - 0.04 * span, hi + 0.27 * span)
        ax.set_xticks([t for t in ax.get_xticks() if lo - 0.04 * span <= t <= hi + 1e-9 * span])
        ax.set_ylim(-5, 112)
        ax.set_xlabel(_XLABELS[cat], fontsize=8)
        ax.set_ylabel("success [%]")
        ax.set_title(_TITLES[cat] + (": " + ", ".join(rates) if rates else ""), fontsize=9)
    fig.legend(handles=handles, loc="outside lower center", fontsize=8, ncol=min(4, len(handles)))
    return save_figure(fig, path)


def _task_panels(
    run: LeaderboardRun, protocol: str, panel: tuple[float, float], min_width: float
) -> tuple[list[str], Any, Any, str]:
    """The tasks with cases of ``protocol``, a figure with one panel [in] per task, and the quick-run note of its title."""
    tasks = [t for t in TASKS if any(c.protocol == protocol and c.task == t for c in run.cases)]
    fig, axes = plt.subplots(1, max(1, len(tasks)), figsize=(max(min_width, panel[0] * len(tasks)), panel[1]),
                             constrained_layout=True, squeeze=False)  # fmt: skip
    note = "" if run.settings.comparable else "\nQUICK: the first 10 s of seed 0, not comparable"
    return tasks, fig, axes[0], note


def plot_v3_seeds(run: LeaderboardRun, path: str | Path) -> Path:
    """v3: each controller's score (uptime fraction) per seed and its mean, beside the best published score.

    Parameters
    ----------
    run : LeaderboardRun
        Leaderboard cases (v3 ones are used).
    path : str or Path
        Output image (e.g. ``leaderboard_v3.png``).

    Returns
    -------
    Path
        The file written.
    """
    tasks, fig, axes, note = _task_panels(run, "v3", (6.5, 4.8), 8.0)
    seeds = list(run.settings.v3_seeds)
    fig.suptitle(f"RealAIGym v3: fraction of the episode with the end effector above 0.9 (L1 + L2), per seed{note}")
    names = run.controllers("v3")
    width = 0.8 / max(1, len(names))
    for ax, task in zip(axes, tasks, strict=False):
        for j, name in enumerate(names):
            c = run.case("v3", task, name)
            xs = np.arange(len(seeds) + 1) + (j - (len(names) - 1) / 2) * width
            if c.status != "done":
                ax.text(xs[0], 0.02, f"{name}: {c.status}", rotation=90, fontsize=7, va="bottom")
                continue
            vals = [s["uptime_fraction"] for s in c.summary["seeds"]] + [c.summary["mean"]]
            bars = ax.bar(xs, vals, width=width, color=_COLORS[j % len(_COLORS)], label=name)
            for b, v in zip(bars, vals, strict=True):  # vertical: five bars a group leave no room across
                ax.text(b.get_x() + b.get_width() / 2, v + 0.01, f"{v:.3f}", ha="center", va="bottom", fontsize=6.5,
                        rotation=90)  # fmt: skip
        scored = [p for p in PUBLISHED_V3_ROWS[task] if p.score is not None]
        if scored:
            top = max(scored, key=lambda p: p.score or 0.0)
            ax.axhline(top.score, color="k", ls="--", lw=1.0, label=f"published best: {top.label} {top.score:.3f} (one run)")
        ax.set_xticks(range(len(seeds) + 1), [f"seed {s}" for s in seeds] + ["mean"])
        ax.set_xlim(-0.5, len(seeds) + 0.5)
        ax.set_ylim(0, 1.22)  # room for the legend above the bars and their labels
        ax.set_ylabel("score = uptime / episode length [-]")
        ax.set_title(task)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=7, loc="upper center", ncol=3)
    return save_figure(fig, path)


def plot_hardware_agreement(
    run: LeaderboardRun, upstream: Mapping[str, tuple[Sequence[EntryScores], Sequence[str]]], path: str | Path
) -> Path:
    """v3-hardware: each ICRA 2025 entry's simulated score against its score on the real robot; pendulab's controllers.

    One panel per task. An upstream entry is a point: x its best run on the robot, y its mean (± standard deviation
    over seeds) on pendulab's hardware-faithful protocol; the diagonal is perfect agreement. pendulab's own
    controllers have no real-robot run: each is a horizontal line at its mean over the leaderboard's seeds.

    Parameters
    ----------
    run : LeaderboardRun
        Leaderboard cases (the v3-hardware ones are drawn).
    upstream : mapping
        Task -> (entries, skipped) of :func:`pendulab.evaluate.realai.upstream_records.read_hardware_entries`.
    path : str or Path
        Output image (e.g. ``leaderboard_v3_hardware.png``).

    Returns
    -------
    Path
        The file written.
    """
    tasks, fig, axes, note = _task_panels(run, "v3-hardware", (5.6, 5.4), 6.0)
    fig.suptitle(
        f"RealAIGym v3 hardware protocol on the simulated C.1 robot (passive allowance {run.settings.passive_allowance:g} N m)"
        f" against the ICRA 2025 final on the real robot{note}",
        fontsize=10,
    )
    for ax, task in zip(axes, tasks, strict=False):
        entries = upstream.get(task, ((), ()))[0]
        for k, e in enumerate(entries):
            approx = bool(e.approximation)
            ax.errorbar(e.published_hardware, e.mean, yerr=e.std, fmt="s", color="tab:blue", capsize=3,
                        mfc="white" if approx else "tab:blue")  # fmt: skip
            label = f"{e.label} ({len(e.seeds)} seeds{', approximated' if approx else ''})"
            # Labels to the left (the right edge is the best real-robot score), alternately above and below.
            ax.annotate(label, (e.published_hardware, e.mean), textcoords="offset points", ha="right",
                        xytext=(-8, 6 if k % 2 == 0 else -12), fontsize=8)  # fmt: skip
        lines = []
        for j, name in enumerate(run.controllers("v3-hardware")):
            c = run.case("v3-hardware", task, name)
            if c.status == "done":
                lines.append((c.summary["mean"], name, _COLORS[(j + 1) % len(_COLORS)]))
        label_y = -1.0
        for mean, name, color in sorted(lines):
            ax.axhline(mean, color=color, ls="--", lw=1.0)
            label_y = max(mean + 0.008, label_y + 0.03)  # close means: each label above the one below (readable)
            ax.text(0.02, label_y, f"pendulab {name}: {mean:.3f}", color=color, fontsize=8,
                    bbox={"facecolor": "white", "edgecolor": "none", "pad": 0.5})  # fmt: skip
        ax.plot([0, 1], [0, 1], "k:", lw=0.8)
        ax.plot([], [], "s", color="tab:blue", label="upstream entry, pendulab v3-hardware (mean ± std over seeds)")
        if any(e.approximation for e in entries):
            ax.plot([], [], "s", color="tab:blue", mfc="white", label="the same, controller approximated (see the table)")
        ax.plot([], [], "k:", lw=0.8, label="simulated = real robot")
        ax.plot([], [], "--", color="gray", lw=1.0, label="pendulab controller (no real-robot run)")
        if not entries:
            ax.text(0.5, 0.05, "no recorded upstream episodes", ha="center", fontsize=8, color="gray")
        ax.set(xlim=(0, 1), ylim=(0, 1), title=task)
        ax.set_xlabel("score on the real robot, ICRA 2025 final (best run) [-]")
        ax.set_ylabel("score on pendulab's v3-hardware protocol [-]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper left")
    return save_figure(fig, path)
