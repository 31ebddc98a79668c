"""Figures for modal analysis: mode-shape snapshots and frequency against spring stiffness.

Uses matplotlib's Agg backend (files only, never a window).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from ..analysis.equilibria import Equilibrium, equilibrium  # noqa: E402
from ..analysis.modes import Mode, modes, stiffness_sweep  # noqa: E402
from ..model.model import Model  # noqa: E402
from .save import save_figure  # noqa: E402

__all__ = ["plot_mode_shapes", "plot_frequency_vs_stiffness", "save_mode_figures"]


def _chain(model: Model, x: np.ndarray) -> np.ndarray:
    """Pivot, bob 1, bob 2 as a (3, 2) array [m]."""
    p = model.positions(x)
    return np.array([[0.0, 0.0], [p[0], p[1]], [p[2], p[3]]])


def _title(m: Mode) -> str:
    if m.kind == "unstable":
        return f"{m.label}\nunstable, grows x e in {m.time_constant:.3g} s"
    if m.kind == "oscillatory":
        zeta = f", zeta {m.damping_ratio:.2g}" if m.damping_ratio > 1e-9 else ""
        return f"{m.label}\n{m.omega_n:.4g} rad/s = {m.freq_hz:.3g} Hz{zeta}"
    return f"{m.label}\n{m.kind}, lambda = {m.eigenvalue.real:.3g} 1/s"


def _params_line(model: Model) -> str:
    """The key parameters of a mode figure: masses, lengths, springs, and the dampers that are not zero."""
    p = model.params
    parts = [f"m1 = {p.m1:g}, m2 = {p.m2:g} kg", f"L1 = {p.L1:g}, L2 = {p.L2:g} m"]
    if model.kind == "elastic":
        parts.append(f"k1 = {p.k1:g}, k2 = {p.k2:g} N/m")
        if p.c1 or p.c2:
            parts.append(f"c1 = {p.c1:g}, c2 = {p.c2:g} N.s/m")
    if p.b1 or p.b2:
        parts.append(f"b1 = {p.b1:g}, b2 = {p.b2:g} N.m.s/rad")
    return "; ".join(parts)


def _torque_line(eq: Equilibrium) -> str:
    """The torque holding the equilibrium, and which joints it acts on."""
    u = np.asarray(eq.u, dtype=float)
    if not np.any(u):
        return "no torque"
    acting = [name for name, v in zip(("tau1", "tau2"), u, strict=True) if v]
    actuation = {("tau1",): "shoulder only (pendubot)", ("tau2",): "elbow only (acrobot)"}.get(tuple(acting), "both joints")
    return f"holding torque tau1 = {u[0]:.4g}, tau2 = {u[1]:.4g} N.m ({actuation})"


def plot_mode_shapes(model: Model, at: str | Equilibrium = "down-down", amplitude: float = 0.25) -> Figure:
    """Snapshots of each oscillatory and unstable mode about an equilibrium.

    The equilibrium is drawn in grey, the two extreme configurations
    ``x_eq +- a * shape`` in colour; ``a`` is chosen so that the largest bob
    displacement is ``amplitude`` times the total arm length.

    Parameters
    ----------
    model : Model
        The pendulum.
    at : str or Equilibrium, default "down-down"
        Equilibrium name (solved at zero torque) or a solved Equilibrium.
    amplitude : float, default 0.25
        Largest bob displacement as a fraction of L1 + L2.

    Returns
    -------
    matplotlib.figure.Figure
        One panel per oscillatory or unstable mode; the title names the
        equilibrium, the torque holding it (and the joints it acts on) and the
        key parameters (masses, lengths, springs, non-zero dampers).
    """
    eq = equilibrium(model, at) if isinstance(at, str) else at
    shown = [m for m in modes(model, eq) if m.kind in ("oscillatory", "unstable")]
    reach = model.params.L1 + model.params.L2
    base = _chain(model, eq.x)
    n = max(len(shown), 1)
    width = max(3.2 * n, 7.5)
    # Square panels plus room for the two-line suptitle, the panel titles and the axis labels.
    fig, axes = plt.subplots(1, n, figsize=(width, width / n + 1.5), squeeze=False, layout="constrained")
    for ax, m in zip(axes[0], shown, strict=False):
        dx = np.zeros(model.nx)
        dx[: model.nq] = m.shape
        probe = 1e-4
        disp = np.abs(_chain(model, eq.x + probe * dx) - base).max() / probe  # linear response per unit amplitude
        a = amplitude * reach / disp if disp > 0 else 0.0
        # Spring modes move along the links: draw the extremes side by side so they do not hide each other.
        shift = 0.45 * reach if m.spring_share >= 0.5 else 0.0
        ax.plot(base[:, 0], base[:, 1], "-o", color="0.6", lw=3, ms=7, label="equilibrium")
        for sign, color in ((1, "tab:blue"), (-1, "tab:orange")):
            c = _chain(model, eq.x + sign * a * dx)
            c[:, 0] -= sign * shift
            ax.plot(c[:, 0], c[:, 1], "-o", color=color, lw=1.8, ms=6, label=f"{'+' if sign > 0 else '-'} shape")
            ax.plot(-sign * shift, 0, "k^", ms=8)
        lim = 1.35 * reach
        ax.set_xlim(-lim, lim)
        ax.set_ylim(-lim, lim)
        ax.set_aspect("equal")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.set_title(_title(m) + ("\n(extremes drawn side by side)" if shift else ""), fontsize=9)
        ax.grid(alpha=0.3)
    axes[0][0].legend(fontsize=7, loc="lower left")
    fig.suptitle(
        f"{model.kind} double pendulum, modes at {eq.name} ({eq.stability}); {_torque_line(eq)}\n{_params_line(model)}",
        fontsize=10,
    )
    return fig


def plot_frequency_vs_stiffness(k_values: Sequence[float] | None = None, **params: float) -> Figure:
    """Elastic down-down natural frequencies against spring stiffness k1 = k2 = k, log axes.

    The pendular modes approach the rigid pendulum's (dashed) as k grows; the
    spring modes climb as sqrt(k), on the analytic lines of the radial
    two-mass problem (dotted).

    Parameters
    ----------
    k_values : sequence of float, optional
        Stiffnesses [N/m]; default 40 values from 10 to 1e5 N/m.
    **params : float
        Other elastic parameters.

    Returns
    -------
    matplotlib.figure.Figure
        Log-log chart of natural frequency [rad/s] against k [N/m].
    """
    k = np.logspace(1, 5, 40) if k_values is None else np.asarray(k_values, dtype=float)
    data = stiffness_sweep(k, **params)
    fig, ax = plt.subplots(figsize=(7.0, 4.8))
    for j, name in enumerate(("in-phase", "anti-phase")):
        ax.loglog(data["k"], data["pendular"][:, j], "-", color=f"C{j}", lw=2, label=f"elastic pendular {name}")
        ax.axhline(data["rigid"][j], color=f"C{j}", ls="--", lw=1, label=f"rigid pendular {name}")
        ax.loglog(
            data["k"], data["spring"][:, j], "-", color=f"C{j + 2}", lw=3.5, alpha=0.7, label=f"elastic spring stretch {name}"
        )
    # Radial two-mass problem of the hanging chain: omega^2 = eig(M^-1 K) with K = k I, so omega ~ sqrt(k).
    m1, m2 = params.get("m1", 1.0), params.get("m2", 1.0)
    M = np.array([[m1 + m2, m2], [m2, m2]])
    coef = np.sqrt(np.sort(np.linalg.eigvals(np.linalg.inv(M)).real))
    for c in coef:
        ax.loglog(data["k"], c * np.sqrt(data["k"]), ":", color="0.15", lw=1.2)
    ax.plot([], [], ":", color="0.15", label=r"analytic $\sqrt{k\,\mathrm{eig}(M^{-1})}$")
    ax.set_xlabel("spring stiffness k1 = k2 [N/m]")
    ax.set_ylabel("natural frequency [rad/s]")
    ax.set_title("Modes at down-down: pendular modes converge to rigid, spring modes climb as sqrt(k)", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    return fig


def save_mode_figures(model: Model, directory: str | Path, at: Sequence[str | Equilibrium], **sweep_params: Any) -> list[Path]:
    """Write mode-shape snapshots per equilibrium (and, for the elastic model, the stiffness chart) as PNG.

    Parameters
    ----------
    model : Model
        The pendulum.
    directory : str or Path
        Output directory, created if missing.
    at : sequence of str or Equilibrium
        Equilibria; one file ``modes_<kind>_<name>.png`` each (see
        :func:`plot_mode_shapes`).
    **sweep_params
        Keywords of :func:`plot_frequency_vs_stiffness` (``k_values`` or
        elastic parameters) overriding the model's m1, m2, L1, L2, g; used
        for the elastic model only.

    Returns
    -------
    list of Path
        Files written, the stiffness chart
        ``modes_frequency_vs_stiffness.png`` last (elastic model only).
    """
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for eq in at:
        fig = plot_mode_shapes(model, eq)
        written.append(save_figure(fig, out / f"modes_{model.kind}_{eq if isinstance(eq, str) else eq.name}.png", dpi=110))
    if model.kind == "elastic":
        shared = {n: getattr(model.params, n) for n in ("m1", "m2", "L1", "L2", "g")}
        fig = plot_frequency_vs_stiffness(**{**shared, **sweep_params})
        written.append(save_figure(fig, out / "modes_frequency_vs_stiffness.png", dpi=110))
    return written
