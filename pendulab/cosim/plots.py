"""Figures of a co-simulation run: time histories (PNG) and an animation of the pendulum (GIF)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .._checks import check_budget
from .._io import atomic_path
from ..integrate.trajectory import Trajectory

__all__ = ["plot_cosim", "animate_cosim", "plot_side_by_side"]


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_cosim(
    traj: Trajectory,
    path: str | Path,
    title: str = "",
    *,
    torque_limit: float | None = None,
    solve_times: Sequence[float] | None = None,
    sample_time: float | None = None,
) -> Path:
    """Angles, torques (held per communication step), energy, spring stretch (elastic) and controller solve times vs time.

    Angles are shown as the deviation from upright (angle mod 2 pi - pi) when
    both stay within 0.5 rad of it, else as absolute angles from hanging.

    Parameters
    ----------
    traj : Trajectory
        A co-simulation result with outputs ``energy`` (and ``stretch1``,
        ``stretch2`` for an elastic plant).
    path : str or Path
        Image file to write (parent directories are created).
    title : str
        Figure title; default ``traj.message``.
    torque_limit : float, optional
        Torque limit [N.m]: drawn as dashed lines at +- the limit, and the samples where
        a torque sits on it (within 0.1 %) are marked, when it binds at all.
    solve_times : sequence of float, optional
        Controller wall time per sample [s] (``NMPCController.solve_times``): adds a panel
        with the solve times and the sample time as the real-time limit.
    sample_time : float, optional
        Controller sample time [s] (the real-time limit of the solve-time panel; the
        solve times are plotted at ``k * sample_time``).

    Returns
    -------
    Path
        The written file.
    """
    plt = _plt()
    elastic = "stretch1" in traj.output_names
    timing = solve_times is not None and len(solve_times) > 0 and sample_time is not None
    n_ax = 3 + int(elastic) + int(timing)
    fig, axes = plt.subplots(n_ax, 1, figsize=(8, 2.4 * n_ax + 0.4), sharex=True, layout="constrained")
    # A balancing run never leaves the upright neighbourhood: on a -pi..pi axis it would be a
    # flat line, so show the deviation from upright instead.
    from_up = {n: (traj[n] % (2 * np.pi)) - np.pi for n in ("theta1", "theta2")}
    near_up = all(np.max(np.abs(v)) < 0.5 for v in from_up.values())
    for name in ("theta1", "theta2"):
        axes[0].plot(traj.t, from_up[name] if near_up else traj[name], label=name)
    if near_up:
        axes[0].axhline(0.0, color="k", lw=0.6, ls=":")
        axes[0].set_ylabel("angle - pi\n(from upright) [rad]")
    else:
        for up in (-np.pi, np.pi):  # upright, reached either way round
            axes[0].axhline(up, color="k", lw=0.6, ls=":")
        axes[0].set_ylabel("angle from\nhanging [rad]")
    for name in traj.input_names:
        axes[1].step(traj.t, traj[name], where="post", label=name)
    if torque_limit is not None:
        u = np.asarray(traj.u, dtype=float)
        at_limit = np.abs(u) >= torque_limit * (1.0 - 1e-3)
        if at_limit.any():
            for sign in (-1.0, 1.0):
                axes[1].axhline(sign * torque_limit, color="C3", lw=0.9, ls="--")
            rows = at_limit.any(axis=1)
            share = rows.sum() / max(len(traj.t), 1)
            peak_sign = np.sign(u[np.arange(len(u)), np.argmax(np.abs(u), axis=1)])
            # A translucent band on the limit where a torque sits on it (nan elsewhere: not drawn).
            axes[1].plot(traj.t, np.where(rows, peak_sign * torque_limit, np.nan), color="C3", lw=5, alpha=0.3,
                         solid_capstyle="butt", label=f"on the limit +-{torque_limit:g} N.m ({share:.0%} of steps)")  # fmt: skip
        else:
            peak = float(np.max(np.abs(u))) if u.size else 0.0
            axes[1].set_title(f"torque limit {torque_limit:g} N.m never reached (peak {peak:.3g} N.m)", fontsize=8, loc="left")
    axes[1].set_ylabel("torque [N.m]")
    axes[2].plot(traj.t, traj["energy"], color="C2", label="energy (FMU output)")
    axes[2].set_ylabel("energy [J]")
    k = 3
    if elastic:
        for name in ("stretch1", "stretch2"):
            axes[k].plot(traj.t, traj[name] * 1e3, label=name)
        axes[k].set_ylabel("spring stretch [mm]")
        k += 1
    if timing:
        st = np.asarray(solve_times, dtype=float) * 1e3
        ts = np.arange(st.size) * float(sample_time)
        axes[k].plot(ts, st, ".", ms=2.5, color="C4", label=f"solve time (median {np.median(st):.2f} ms, max {st.max():.2f} ms)")
        axes[k].axhline(float(sample_time) * 1e3, color="C3", lw=0.9, ls="--", label=f"sample time {sample_time * 1e3:g} ms")
        axes[k].set_yscale("log")
        axes[k].set_ylabel("controller\nsolve time [ms]")
    axes[-1].set_xlabel("time [s]")
    for ax in axes:
        ax.grid(True, alpha=0.3)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=8, loc="best", framealpha=0.8)
    fig.suptitle(title or traj.message)
    from ..viz.save import save_figure

    return save_figure(fig, path, dpi=110)


def animate_cosim(traj: Trajectory, path: str | Path, *, fps: int = 20, max_frames: int = 160, title: str = "") -> Path:
    """Animated GIF of the links (from the FMU outputs x1, y1, x2, y2) with the bob-2 trace and the torques.

    Parameters
    ----------
    traj : Trajectory
        A co-simulation result with outputs ``x1``, ``y1``, ``x2``, ``y2`` [m].
    path : str or Path
        GIF file to write (parent directories are created).
    fps : int
        Frames per second of real time (frames are picked evenly from the samples).
    max_frames : int
        Upper bound on the number of frames.
    title : str
        Prefix of each frame's caption (time [s] and torques [N.m]).

    Returns
    -------
    Path
        The written file.

    Raises
    ------
    BudgetError
        ``max_frames`` beyond the frames budget ``PENDULAB_MAX_FRAMES``.
    """
    from PIL import Image

    check_budget("frames", "max_frames", max_frames)
    plt = _plt()
    n = len(traj.t)
    wanted = min(max_frames, max(2, int(round((traj.t[-1] - traj.t[0]) * fps)) + 1))
    frames = np.unique(np.linspace(0, n - 1, wanted).round().astype(int))
    x1, y1, x2, y2 = (traj[name] for name in ("x1", "y1", "x2", "y2"))
    reach = 1.1 * float(np.max(np.hypot(x2, y2)))
    fig, ax = plt.subplots(figsize=(4.2, 4.4), dpi=80)
    ax.set_xlim(-reach, reach)
    ax.set_ylim(-reach, reach)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(True, alpha=0.3)
    (trace,) = ax.plot([], [], "-", color="C1", lw=0.8, alpha=0.6)
    (links,) = ax.plot([], [], "o-", color="C0", lw=3, ms=7)
    label = ax.set_title("")
    fig.subplots_adjust(left=0.17, right=0.97, bottom=0.11, top=0.93)
    images = []
    for k in frames:
        trace.set_data(x2[: k + 1], y2[: k + 1])
        links.set_data([0.0, x1[k], x2[k]], [0.0, y1[k], y2[k]])
        torques = ", ".join(f"{name} = {traj[name][k]:+.1f}" for name in traj.input_names)
        label.set_text(f"{title}t = {traj.t[k]:.2f} s   {torques} N.m")
        label.set_fontsize(8)
        fig.canvas.draw()
        images.append(Image.fromarray(np.asarray(fig.canvas.buffer_rgba())[..., :3]).convert("P", palette=Image.ADAPTIVE))
    plt.close(fig)
    path = Path(path)
    with atomic_path(path) as tmp:  # an interrupted run never leaves a truncated GIF
        images[0].save(tmp, format="GIF", save_all=True, append_images=images[1:], duration=int(1000 / fps), loop=0)
    return path


def plot_side_by_side(trajs: list[Trajectory], labels: list[str], path: str | Path, title: str = "") -> Path:
    """Plants stepped in one master with the same torques: theta1, and |angle difference| to the first plant (log).

    Parameters
    ----------
    trajs : list of Trajectory
        Results of :func:`pendulab.cosim.cosim_many`, on the same time grid; the
        first is the reference and gives the torque panel.
    labels : list of str
        One legend label per trajectory.
    path : str or Path
        Image file to write (parent directories are created).
    title : str
        Figure title.

    Returns
    -------
    Path
        The written file.
    """
    plt = _plt()
    fig, axes = plt.subplots(3, 1, figsize=(8, 8), sharex=True)
    ref = trajs[0]
    for i, (traj, label) in enumerate(zip(trajs, labels, strict=True)):
        axes[0].plot(traj.t, traj["theta1"], label=label, color=f"C{i}")
        if i:
            diff = np.abs(traj.x[1:, :2] - ref.x[1:, :2]).max(axis=1)  # t = 0: same start angles, zero difference
            axes[1].semilogy(traj.t[1:], np.maximum(diff, 1e-16), label=f"{label} vs {labels[0]}", color=f"C{i}")
    for name in ref.input_names:
        axes[2].step(ref.t, ref[name], where="post", label=name)
    axes[0].set_ylabel("theta1 [rad]")
    axes[1].set_ylabel("max |angle difference| [rad]")
    axes[2].set_ylabel("torque, same for all [N.m]")
    axes[-1].set_xlabel("time [s]")
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    axes[0].set_title(title)
    fig.tight_layout()
    from ..viz.save import save_figure

    return save_figure(fig, path, dpi=110)
