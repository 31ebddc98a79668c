"""Figures and animation of a swing-up episode (matplotlib, Agg backend)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.animation import FuncAnimation, PillowWriter  # noqa: E402

from .._io import atomic_path  # noqa: E402
from ..control.swingup.episode import Episode  # noqa: E402
from .drawing import link_polylines  # noqa: E402
from .save import save_figure  # noqa: E402

__all__ = ["plot_episode", "animate_episode"]


def plot_episode(ep: Episode, out_dir: str | Path) -> list[Path]:
    """Write PNG figures of one episode.

    Figures: angles, rates, torques with limits, phase portraits, spring stretch
    (elastic models), and the end-effector height against the success threshold.
    Optimal (open-loop plan) and closed-loop curves are overlaid.

    Parameters
    ----------
    ep : Episode
        The episode; without a closed loop only the optimal curves are drawn.
    out_dir : str or Path
        Output directory, created if missing.

    Returns
    -------
    list of Path
        ``states_torques.png``, ``phase.png``, then ``height.png`` (when the
        closed loop and its height check exist), ``stretch.png`` (elastic) and
        ``error.png`` (when the plan has an error estimate).
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    res, cl, task = ep.result, ep.closed_loop, ep.task
    model = task.model
    nq = model.nq
    paths: list[Path] = []
    T = res.horizon

    def finish(fig: plt.Figure, name: str) -> None:
        fig.tight_layout()
        paths.append(save_figure(fig, out / name, dpi=110))

    fig, axes = plt.subplots(3, 1, figsize=(8, 8.5), sharex=True)
    for i, name in enumerate(("theta1", "theta2")):
        if cl is not None:
            axes[0].plot(cl.t, np.degrees(cl[name]), color=f"C{i}", lw=1.0, label=f"{name} closed loop")
        axes[0].plot(res.t, np.degrees(res.x[:, i]), "--", color="k" if i == 0 else "grey", lw=1.0, label=f"{name} optimal")
    axes[0].axhline(180.0, color="k", lw=0.5)
    axes[0].set_ylabel("angle from hanging [deg]")
    axes[0].legend(fontsize=8, ncol=2)
    for i, name in enumerate(("omega1", "omega2")):
        if cl is not None:
            axes[1].plot(cl.t, cl[name], color=f"C{i}", lw=1.0, label=f"{name} closed loop")
        axes[1].plot(res.t, res.x[:, nq + i], "--", color="k" if i == 0 else "grey", lw=1.0, label=f"{name} optimal")
    axes[1].set_ylabel("angular rate [rad/s]")
    axes[1].legend(fontsize=8, ncol=2)
    lim = task.problem.torque_limit
    for i in task.problem.actuated:
        name = model.input_names[i]
        if cl is not None:
            axes[2].step(cl.t, cl.u[:, i], where="post", color="C0", lw=1.0, label=f"{name} closed loop")
        axes[2].step(res.t[:-1], res.u[:, i], where="post", ls="--", color="k", lw=1.0, label=f"{name} optimal")
    axes[2].axhline(lim, color="r", lw=0.8, ls=":", label="torque limit")
    axes[2].axhline(-lim, color="r", lw=0.8, ls=":")
    if task.problem.margin < 1.0:
        plan_lim = task.problem.plan_torque_limit
        axes[2].axhline(plan_lim, color="C1", lw=0.8, ls="--", label=f"plan limit ({task.problem.margin:g} x)")
        axes[2].axhline(-plan_lim, color="C1", lw=0.8, ls="--")
    axes[2].set_ylabel("torque [N.m]")
    axes[2].set_xlabel("time [s]")
    axes[2].legend(fontsize=8, ncol=3)
    for ax in axes:
        ax.axvline(T, color="grey", lw=0.8, ls="-.")
        ax.grid(alpha=0.3)
    axes[0].set_title(f"{task.name}: swing-up ({res.method}, N={res.N}); TVLQR to T = {T:.3g} s, then LQR")
    finish(fig, "states_torques.png")

    fig, axes = plt.subplots(1, 2, figsize=(9, 4))
    for i, ax in enumerate(axes):
        if cl is not None:
            ax.plot(cl.x[:, i], cl.x[:, nq + i], color=f"C{i}", lw=1.0, label="closed loop")
        ax.plot(res.x[:, i], res.x[:, nq + i], "--", color="k", lw=1.0, label="optimal")
        ax.plot(np.pi, 0.0, "k*", ms=10, label="goal")
        ax.set_xlabel(f"theta{i + 1} [rad]")
        ax.set_ylabel(f"omega{i + 1} [rad/s]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(f"{task.name}: phase portraits")
    finish(fig, "phase.png")

    if cl is not None and ep.height is not None:
        fig, ax = plt.subplots(figsize=(8, 3.2))
        ax.plot(cl.t, ep.height.height, label="end-effector height y2")
        ax.axhline(ep.height.threshold, color="r", ls=":", label=f"{task.success_fraction:g} (L1 + L2)")
        if np.isfinite(ep.height.t_up):
            ax.axvline(ep.height.t_up, color="g", ls="--", label=f"up at {ep.height.t_up:.2f} s")
        ax.set_xlabel("time [s]")
        ax.set_ylabel("height [m]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        finish(fig, "height.png")

    if model.kind == "elastic":
        fig, ax = plt.subplots(figsize=(8, 3.5))
        L = np.array(task.rest_lengths)
        for i in range(2):
            if cl is not None:
                ax.plot(cl.t, 1e3 * cl[f"stretch{i + 1}"], color=f"C{i}", lw=1.0, label=f"stretch{i + 1} closed loop")
            ax.plot(
                res.t,
                1e3 * (res.x[:, 2 + i] - L[i]),
                "--",
                color="k" if i == 0 else "grey",
                lw=1.0,
                label=f"stretch{i + 1} optimal",
            )
        if task.problem.stretch_limits is not None:
            for k, lim_s in enumerate(task.problem.stretch_limits):
                ax.axhline(1e3 * lim_s, color="r", ls=":", lw=0.8, label="stretch limits" if k == 0 else None)
        ax.set_xlabel("time [s]")
        ax.set_ylabel("spring stretch r - L [mm]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, ncol=2)
        finish(fig, "stretch.png")

    if ep.error is not None:
        _error_figure(ep, finish)
    return paths


def _error_figure(ep: Episode, finish) -> None:
    """Per-interval relative defect on the (possibly non-uniform) mesh, with the tolerance, and the interval widths."""
    est, res = ep.error, ep.result
    t = np.asarray(res.t)
    h = np.diff(t)
    worst = np.maximum(est.interval_worst, 1e-16)  # log axis: an exact zero shows at the floor
    fig, axes = plt.subplots(2, 1, figsize=(8, 5.5), sharex=True, gridspec_kw={"height_ratios": [2.2, 1]})
    ax = axes[0]
    # One bar per interval, as wide as the interval: refined regions show as narrow bars.
    colors = np.where(worst <= est.tolerance, "C0", "C3")
    ax.bar(t[:-1], worst, width=h, align="edge", color=colors, edgecolor="k", linewidth=0.2)
    ax.axhline(est.tolerance, color="r", ls="--", lw=1.0, label=f"tolerance {est.tolerance:.0e}")
    ax.set_yscale("log")
    ax.set_ylabel("relative defect per interval [-]")
    verdict = "pass" if est.passed else "FAIL"
    level = f", planned on {ep.plan.level}" if ep.plan is not None else ""
    ax.set_title(
        f"{ep.task.name}: error estimate ({est.method}) worst {est.worst:.2e}: {verdict}; N = {res.N}{level}", fontsize=10
    )
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3, which="both")
    axes[1].stairs(1e3 * h, t, baseline=None, color="k", lw=1.0)
    axes[1].set_ylabel("interval width [ms]")
    axes[1].set_xlabel("time [s]")
    axes[1].set_ylim(0.0, 1.15e3 * h.max())
    axes[1].grid(alpha=0.3)
    finish(fig, "error.png")


def animate_episode(
    ep: Episode,
    path: str | Path,
    fps: int = 25,
    max_seconds: float | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> Path:
    """Animated GIF of the closed-loop episode (swing-up and hold), real time at ``fps``.

    Rigid links are drawn as bars, elastic links as springs (their stretch visible), with a
    trace of bob 2 over the last 2 s and, when checked, the success height dotted.

    Parameters
    ----------
    ep : Episode
        The episode; it must have a closed-loop trajectory.
    path : str or Path
        GIF file to write (parent directories created).
    fps : int, default 25
        Frames per second of simulated time.
    max_seconds : float, optional
        Simulated time shown [s] (default: the whole closed loop).
    progress : callable, optional
        ``progress(done, total)`` in frames, after each frame is drawn (writing a GIF takes minutes
        on a loaded machine: the CLI shows a bar with it).

    Returns
    -------
    Path
        The written file.

    Raises
    ------
    ValueError
        The episode has no closed-loop trajectory (the solve failed).
    """
    cl = ep.closed_loop
    if cl is None:
        raise ValueError("episode has no closed-loop trajectory to animate (the solve failed)")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    t_end = cl.t[-1] if max_seconds is None else min(cl.t[-1], max_seconds)
    frames = np.arange(0.0, t_end + 1e-9, 1.0 / fps)
    pos = np.column_stack([np.interp(frames, cl.t, cl[n]) for n in ("x1", "y1", "x2", "y2")])
    reach = sum(ep.task.rest_lengths) * 1.15
    fig, ax = plt.subplots(figsize=(4, 4))
    ax.set_xlim(-reach, reach)
    ax.set_ylim(-reach, reach)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    if ep.height is not None:
        ax.axhline(ep.height.threshold, color="r", ls=":", lw=0.8)
    (trace,) = ax.plot([], [], "-", color="tab:orange", lw=0.6, alpha=0.6)
    # Rigid links are bars; elastic ones are drawn as springs (link_polylines), so their stretch shows.
    elastic = ep.task.model.kind == "elastic"
    lines = [ax.plot([], [], "-", color="tab:blue", lw=1.4 if elastic else 3)[0] for _ in range(2)]
    (bobs,) = ax.plot([], [], "o", color="tab:blue", ms=6)
    ax.plot([0.0], [0.0], "k^", ms=6)
    # Two-line placeholder so tight_layout reserves room for the per-frame title.
    title = ax.set_title(f"{ep.task.name}\nt = 0.00 s", fontsize=8)
    T = ep.result.horizon

    def draw(i: int):
        for line, poly in zip(lines, link_polylines(ep.task.model, pos[i]), strict=True):
            line.set_data(poly[:, 0], poly[:, 1])
        bobs.set_data(pos[i, [0, 2]], pos[i, [1, 3]])
        lo = max(0, i - 2 * fps)
        trace.set_data(pos[lo : i + 1, 2], pos[lo : i + 1, 3])
        phase = "TVLQR swing-up" if frames[i] < T else "LQR hold"
        title.set_text(f"{ep.task.name}\nt = {frames[i]:4.2f} s  {phase}")
        return (*lines, bobs, trace, title)

    fig.tight_layout()
    anim = FuncAnimation(fig, draw, frames=len(frames), blit=False)
    try:
        with atomic_path(path) as tmp:  # an interrupted animation never leaves a truncated GIF
            report = None if progress is None else (lambda i, n: progress(i + 1, n))
            anim.save(tmp, writer=PillowWriter(fps=fps), progress_callback=report)
    finally:
        plt.close(fig)
    return path
