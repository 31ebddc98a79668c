"""Figures of a co-simulation run: time histories (PNG) and an animation of the pendulum (GIF)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._io import atomic_path
from ..integrate.trajectory import Trajectory

__all__ = ["plot_cosim", "animate_cosim", "plot_side_by_side"]


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_cosim(traj: Trajectory, path: str | Path, title: str = "") -> Path:
    """Angles, torques (held per communication step), energy and, for elastic plants, spring stretch vs time.

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

    Returns
    -------
    Path
        The written file.
    """
    plt = _plt()
    elastic = "stretch1" in traj.output_names
    fig, axes = plt.subplots(4 if elastic else 3, 1, figsize=(8, 9 if elastic else 7.5), sharex=True)
    # A balancing run never leaves the upright neighbourhood: on a -pi..pi axis it would be a
    # flat line, so show the deviation from upright instead.
    from_up = {n: (traj[n] % (2 * np.pi)) - np.pi for n in ("theta1", "theta2")}
    near_up = all(np.max(np.abs(v)) < 0.5 for v in from_up.values())
    for name in ("theta1", "theta2"):
        axes[0].plot(traj.t, from_up[name] if near_up else traj[name], label=name)
    if near_up:
        axes[0].axhline(0.0, color="k", lw=0.6, ls=":")
        axes[0].set_ylabel("angle - pi (from upright) [rad]")
    else:
        for up in (-np.pi, np.pi):  # upright, reached either way round
            axes[0].axhline(up, color="k", lw=0.6, ls=":")
        axes[0].set_ylabel("angle from hanging [rad]")
    for name in traj.input_names:
        axes[1].step(traj.t, traj[name], where="post", label=name)
    axes[1].set_ylabel("torque [N.m]")
    axes[2].plot(traj.t, traj["energy"], color="C2", label="energy (FMU output)")
    axes[2].set_ylabel("energy [J]")
    if elastic:
        for name in ("stretch1", "stretch2"):
            axes[3].plot(traj.t, traj[name] * 1e3, label=name)
        axes[3].set_ylabel("spring stretch [mm]")
    axes[-1].set_xlabel("time [s]")
    for ax in axes:
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8, loc="upper right")
    axes[0].set_title(title or traj.message)
    fig.tight_layout()
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
    """
    from PIL import Image

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
