"""The seed paper's figures (Figs. 2-6) plus spring stretch and energy exchange.

Every function takes ``runs``: a mapping ``label -> (model, trajectory)`` (or a
list of :class:`~pendulab.viz.drawing.Run`), so the same figures serve one
simulation (``pendulab simulate --plot``) and the rigid-vs-elastic comparison
(``pendulab demo``). Functions return a matplotlib ``Figure`` and never show
it; :func:`save_figures` writes them all as PNG.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from .drawing import Run, as_runs, link_polylines, run_colors, view_limits  # noqa: E402
from .save import save_figure  # noqa: E402

__all__ = [
    "FIGURES",
    "fig_snapshots",
    "fig_angles",
    "fig_angles_compare",
    "fig_positions",
    "fig_phase",
    "fig_stretch",
    "fig_energy",
    "energy_components",
    "save_figures",
]

_LABELS = {
    "theta1": r"$\theta_1$ [rad]",
    "theta2": r"$\theta_2$ [rad]",
    "omega1": r"$\omega_1$ [rad/s]",
    "omega2": r"$\omega_2$ [rad/s]",
    "x1": r"$x_1$ [m]",
    "y1": r"$y_1$ [m]",
    "x2": r"$x_2$ [m]",
    "y2": r"$y_2$ [m]",
}
_TIME = "time $t$ [s]"


def _figure(nrows: int, ncols: int, width: float = 10.0, height: float = 3.0, **kw: Any) -> tuple[Figure, np.ndarray]:
    fig, axes = plt.subplots(nrows, ncols, figsize=(width, height * nrows), squeeze=False, **kw)
    return fig, axes


def _title(runs: tuple[Run, ...]) -> str:
    return " vs ".join(r.label for r in runs)


def fig_snapshots(runs: Any, n_snapshots: int = 5, t_max: float | None = None) -> Figure:
    """Fig. 2: the pendulums drawn at a few instants (one panel per run).

    Parameters
    ----------
    runs : mapping of str to (Model, Trajectory), or sequence of Run
        Runs by label (see :func:`~pendulab.viz.drawing.as_runs`).
    n_snapshots : int, default 5
        Configurations drawn, evenly spaced over ``[0, t_max]``; later ones darker.
    t_max : float, optional
        Last instant drawn [s] (default: 2 s or the horizon, whichever is shorter),
        short enough that the configurations stay readable.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (not shown; close it when done).

    Raises
    ------
    ValueError
        ``runs`` is empty or malformed (from :func:`~pendulab.viz.drawing.as_runs`).
    """
    runs = as_runs(runs)
    xlim, ylim = view_limits(runs)
    ratio = (ylim[1] - ylim[0]) / (xlim[1] - xlim[0])
    fig, axes = _figure(1, len(runs), width=5.0 * len(runs), height=5.0 * ratio + 0.75)
    for ax, run, color in zip(axes[0], runs, run_colors(len(runs)), strict=True):
        t = run.traj.t
        last = min(t[-1], 2.0) if t_max is None else min(t_max, t[-1])
        idx = np.searchsorted(t, np.linspace(0.0, last, n_snapshots))
        pos = run.positions
        ax.plot(pos[: idx[-1] + 1, 2], pos[: idx[-1] + 1, 3], color=color, lw=0.8, alpha=0.35, label="path of bob 2")
        for j, k in enumerate(idx):
            alpha = 0.25 + 0.75 * j / max(1, len(idx) - 1)
            for line in link_polylines(run.model, pos[k]):
                ax.plot(line[:, 0], line[:, 1], color="0.2", lw=1.2, alpha=alpha)
            ax.plot(pos[k, [0, 2]], pos[k, [1, 3]], "o", color=color, ms=7, alpha=alpha)
            ax.annotate(f"{t[k]:.1f} s", pos[k, 2:4], textcoords="offset points", xytext=(5, 5), fontsize=7, alpha=alpha)
        ax.plot([0], [0], "k^", ms=8)
        ax.set_xlim(*xlim)
        ax.set_ylim(*ylim)
        ax.set_aspect("equal")
        ax.set_xlabel("$x$ [m]")
        ax.set_ylabel("$y$ [m]")
        ax.set_title(f"{run.label}: configurations, t = 0 to {last:.1f} s")
        ax.legend(loc="best", fontsize=8)
        ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig


def fig_angles(runs: Any) -> Figure:
    """Fig. 3: theta1 and theta2 [rad] against time, one panel per run.

    Parameters
    ----------
    runs : mapping of str to (Model, Trajectory), or sequence of Run
        Runs by label (see :func:`~pendulab.viz.drawing.as_runs`).

    Returns
    -------
    matplotlib.figure.Figure
        The figure (not shown; close it when done).

    Raises
    ------
    ValueError
        ``runs`` is empty or malformed (from :func:`~pendulab.viz.drawing.as_runs`).
    """
    runs = as_runs(runs)
    fig, axes = _figure(len(runs), 1, sharex=True)
    for ax, run in zip(axes[:, 0], runs, strict=True):
        ax.plot(run.traj.t, run.traj["theta1"], label=r"$\theta_1$")
        ax.plot(run.traj.t, run.traj["theta2"], label=r"$\theta_2$")
        ax.set_ylabel("angle [rad]")
        ax.set_title(f"{run.label}: link angles from the downward vertical")
        ax.legend(loc="upper right")
        ax.grid(alpha=0.3)
    axes[-1, 0].set_xlabel(_TIME)
    fig.tight_layout()
    return fig


def _overlay(runs: tuple[Run, ...], names: tuple[str, ...], ncols: int, what: str) -> Figure:
    nrows = -(-len(names) // ncols)
    fig, axes = _figure(nrows, ncols, width=10.0, sharex=True)
    for ax, name in zip(axes.flat, names, strict=False):
        for run, color in zip(runs, run_colors(len(runs)), strict=True):
            ax.plot(run.traj.t, run.traj[name], color=color, label=run.label, lw=1.1)
        ax.set_ylabel(_LABELS[name])
        ax.grid(alpha=0.3)
        ax.legend(loc="best", fontsize=8, framealpha=0.9)
    for ax in axes[-1]:
        ax.set_xlabel(_TIME)
    fig.suptitle(f"{what}: {_title(runs)}")
    fig.tight_layout()
    return fig


def fig_angles_compare(runs: Any) -> Figure:
    """Fig. 4: theta1 and theta2 [rad] of every run overlaid (rigid vs elastic).

    Parameters
    ----------
    runs : mapping of str to (Model, Trajectory), or sequence of Run
        Runs by label (see :func:`~pendulab.viz.drawing.as_runs`).

    Returns
    -------
    matplotlib.figure.Figure
        The figure (not shown; close it when done).

    Raises
    ------
    ValueError
        ``runs`` is empty or malformed (from :func:`~pendulab.viz.drawing.as_runs`).
    """
    return _overlay(as_runs(runs), ("theta1", "theta2"), 1, "Angles")


def fig_positions(runs: Any) -> Figure:
    """Fig. 5: bob positions x1, y1, x2, y2 [m] of every run overlaid (y up, pivot at the origin).

    Parameters
    ----------
    runs : mapping of str to (Model, Trajectory), or sequence of Run
        Runs by label (see :func:`~pendulab.viz.drawing.as_runs`).

    Returns
    -------
    matplotlib.figure.Figure
        The figure (not shown; close it when done).

    Raises
    ------
    ValueError
        ``runs`` is empty or malformed (from :func:`~pendulab.viz.drawing.as_runs`).
    """
    return _overlay(as_runs(runs), ("x1", "y1", "x2", "y2"), 2, "Bob positions")


def fig_phase(runs: Any) -> Figure:
    """Fig. 6: phase portraits (theta [rad], omega [rad/s]) of both links, every run overlaid.

    A dot marks each run's initial state.

    Parameters
    ----------
    runs : mapping of str to (Model, Trajectory), or sequence of Run
        Runs by label (see :func:`~pendulab.viz.drawing.as_runs`).

    Returns
    -------
    matplotlib.figure.Figure
        The figure (not shown; close it when done).

    Raises
    ------
    ValueError
        ``runs`` is empty or malformed (from :func:`~pendulab.viz.drawing.as_runs`).
    """
    runs = as_runs(runs)
    fig, axes = _figure(1, 2, width=11.0, height=4.6)
    for ax, (th, om, link) in zip(axes[0], (("theta1", "omega1", 1), ("theta2", "omega2", 2)), strict=True):
        for run, color in zip(runs, run_colors(len(runs)), strict=True):
            ax.plot(run.traj[th], run.traj[om], color=color, lw=0.7, alpha=0.8, label=run.label)
            ax.plot(run.traj[th][0], run.traj[om][0], "o", color=color, ms=5)
        ax.set_xlabel(_LABELS[th])
        ax.set_ylabel(_LABELS[om])
        ax.set_title(f"link {link} (dot: start)")
        ax.grid(alpha=0.3)
        ax.legend(loc="upper right", fontsize=8)
    fig.suptitle(f"Phase portraits: {_title(runs)}")
    fig.tight_layout()
    return fig


def fig_stretch(runs: Any) -> Figure | None:
    """Spring extension r - L of both springs against time, one panel per elastic run.

    Plotted in cm, with the static hanging stretch of each spring dotted.

    Parameters
    ----------
    runs : mapping of str to (Model, Trajectory), or sequence of Run
        Runs by label (see :func:`~pendulab.viz.drawing.as_runs`).

    Returns
    -------
    matplotlib.figure.Figure or None
        The figure, or None when no run is elastic.

    Raises
    ------
    ValueError
        ``runs`` is empty or malformed (from :func:`~pendulab.viz.drawing.as_runs`).
    """
    runs = tuple(r for r in as_runs(runs) if r.model.kind == "elastic")
    if not runs:
        return None
    fig, axes = _figure(len(runs), 1, sharex=True)
    for ax, run in zip(axes[:, 0], runs, strict=True):
        for j in (1, 2):
            ax.plot(run.traj.t, 100.0 * run.traj[f"stretch{j}"], lw=0.9, label=f"spring {j}")
        p = run.model.params
        static = 100.0 * np.array([(p.m1 + p.m2) * p.g / p.k1, p.m2 * p.g / p.k2])
        for j, s in enumerate(static):
            ax.axhline(s, color=f"C{j}", ls=":", lw=1.0, label=f"static stretch {j + 1} ({s:.1f} cm)")
        ax.axhline(0.0, color="k", lw=0.6)
        ax.set_ylabel("stretch $r - L$ [cm]")
        ax.set_title(f"{run.label}: spring extension (k1 = {p.k1:g} N/m, k2 = {p.k2:g} N/m)")
        ax.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), fontsize=8)
        ax.grid(alpha=0.3)
    axes[-1, 0].set_xlabel(_TIME)
    fig.tight_layout()
    return fig


def energy_components(run: Run) -> dict[str, np.ndarray]:
    """Energy components along a run.

    Parameters
    ----------
    run : Run
        One simulated pendulum.

    Returns
    -------
    dict of str to ndarray, shape (N,)
        ``kinetic`` (all motion, spring stretching included), ``gravitational``
        (zero at the pivot height), ``spring`` (zero for rigid) and ``total``
        energy [J] at every output time.
    """
    x = run.traj.x
    kinetic = np.atleast_1d(run.model.kinetic_energy(x))
    spring = np.atleast_1d(run.model.spring_energy(x))
    gravity = np.atleast_1d(run.model.potential_energy(x)) - spring
    return {"kinetic": kinetic, "gravitational": gravity, "spring": spring, "total": kinetic + gravity + spring}


def fig_energy(runs: Any) -> Figure:
    """Energy exchange: kinetic, gravitational, spring (elastic only) and total energy [J], one panel per run.

    The legend reports the largest drift of the total energy from its initial value; for a forced or
    damped run, the balance ``E(0) + input work - dissipated`` is drawn dashed over the total, and the
    legend reports the energy balance error (the largest gap between them).

    Parameters
    ----------
    runs : mapping of str to (Model, Trajectory), or sequence of Run
        Runs by label (see :func:`~pendulab.viz.drawing.as_runs`).

    Returns
    -------
    matplotlib.figure.Figure
        The figure (not shown; close it when done).

    Raises
    ------
    ValueError
        ``runs`` is empty or malformed (from :func:`~pendulab.viz.drawing.as_runs`).
    """
    from ..integrate.simulate import trajectory_energy_flows

    runs = as_runs(runs)
    fig, axes = _figure(len(runs), 1, sharex=True, height=3.2, layout="constrained")
    for ax, run in zip(axes[:, 0], runs, strict=True):
        parts = energy_components(run)
        t = run.traj.t
        ax.plot(t, parts["kinetic"], lw=0.9, label="kinetic")
        ax.plot(t, parts["gravitational"], lw=0.9, label="gravitational")
        if run.model.kind == "elastic":
            ax.plot(t, parts["spring"], lw=0.9, label="spring")
        total = parts["total"]
        work, dissipated = trajectory_energy_flows(run.model, run.traj)
        if np.any(work) or np.any(dissipated):
            balance = total[0] + work - dissipated
            error = float(np.max(np.abs(total - balance)))
            ax.plot(t, total, "k", lw=1.4, label=f"total (change {total[-1] - total[0]:+.3g} J)")
            ax.plot(t, balance, "--", color="tab:red", lw=1.2, label=f"E(0) + work - dissipated\n(balance error {error:.1e} J)")
        else:
            drift = float(np.max(np.abs(total - total[0])))
            ax.plot(t, total, "k", lw=1.4, label=f"total (max drift {drift:.1e} J)")
        ax.set_ylabel("energy [J]")
        ax.set_title(f"{run.label}: energy exchange (gravity zero at the pivot height)")
        ax.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), fontsize=8)
        ax.grid(alpha=0.3)
    axes[-1, 0].set_xlabel(_TIME)
    return fig


#: File stem -> figure function, in the order of the paper.
FIGURES: Mapping[str, Callable[[Any], Figure | None]] = {
    "fig2_snapshots": fig_snapshots,
    "fig3_angles": fig_angles,
    "fig4_angles_compare": fig_angles_compare,
    "fig5_positions": fig_positions,
    "fig6_phase": fig_phase,
    "spring_stretch": fig_stretch,
    "energy": fig_energy,
}


def save_figures(runs: Any, out_dir: str | Path, dpi: int = 110) -> dict[str, Path]:
    """Render every figure of :data:`FIGURES` to ``out_dir/<name>.png``.

    Figures that do not apply (spring stretch without an elastic run) are skipped.

    Parameters
    ----------
    runs : mapping of str to (Model, Trajectory), or sequence of Run
        Runs by label (see :func:`~pendulab.viz.drawing.as_runs`).
    out_dir : str or Path
        Output directory, created if missing.
    dpi : int, default 110
        Resolution [dots per inch].

    Returns
    -------
    dict of str to Path
        Figure name -> written file.

    Raises
    ------
    ValueError
        ``runs`` is empty or malformed (from :func:`~pendulab.viz.drawing.as_runs`).
    """
    runs = as_runs(runs)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written: dict[str, Path] = {}
    for name, make in FIGURES.items():
        fig = make(runs)
        if fig is None:
            continue
        written[name] = save_figure(fig, out / f"{name}.png", dpi=dpi)
    return written
