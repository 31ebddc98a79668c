"""Figures of flip maps: one map (:func:`plot_flip_map`) or several side by side on one colour scale
(:func:`plot_flip_map_compare`). matplotlib is imported when a figure is drawn.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .._io import atomic_path
from .flipmap_result import FlipMap

__all__ = ["plot_flip_map", "plot_flip_map_compare"]


def _save(fig: Any, path: str | Path) -> None:
    """Save a PNG atomically: an interrupted run never leaves a truncated image."""
    # Constrained layout sizes the panels; with equal-aspect images it can still leave the x-labels
    # outside the canvas (seen with --k 3000), so the saved area is the tight box of every artist.
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=150, bbox_inches="tight", pad_inches=0.08)


def _draw(fmap: FlipMap, ax: Any, *, cmap: str, vmin: float, vmax: float, show_threshold: bool) -> Any:
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm

    colours = plt.get_cmap(cmap).with_extremes(bad="white")
    data = np.ma.masked_invalid(fmap.t_flip.T)  # rows = theta2 (vertical axis)
    h1 = fmap.theta1[1] - fmap.theta1[0] if fmap.theta1.size > 1 else 1.0
    h2 = fmap.theta2[1] - fmap.theta2[0] if fmap.theta2.size > 1 else 1.0
    extent = (fmap.theta1[0] - h1 / 2, fmap.theta1[-1] + h1 / 2, fmap.theta2[0] - h2 / 2, fmap.theta2[-1] + h2 / 2)
    im = ax.imshow(
        data,
        origin="lower",
        extent=extent,
        cmap=colours,
        norm=LogNorm(vmin=vmin, vmax=vmax),
        interpolation="nearest",
        aspect="equal",
    )
    if show_threshold and fmap.skipped is not None and fmap.skipped.any() and fmap.theta1.size > 2:
        ax.contour(fmap.theta1, fmap.theta2, fmap.skipped.T.astype(float), levels=[0.5], colors="0.55", linewidths=0.6)
    ticks = [-math.pi, -math.pi / 2, 0.0, math.pi / 2, math.pi]
    # Plain Unicode, not mathtext: the first mathtext label of a process builds its parser (~0.2 s of a
    # whole flip-map command that is measured against 2 s).
    labels = ["\u2212\u03c0", "\u2212\u03c0/2", "0", "\u03c0/2", "\u03c0"]
    for setter, lim in ((ax.set_xticks, extent[:2]), (ax.set_yticks, extent[2:])):
        keep = [(t, s) for t, s in zip(ticks, labels, strict=True) if lim[0] - 1e-9 <= t <= lim[1] + 1e-9]
        if keep:
            setter([t for t, _ in keep], [s for _, s in keep])
    ax.set_xlabel("\u03b8\u2081 at release [rad]")
    ax.set_ylabel("\u03b8\u2082 at release [rad]")
    return im


def _plain_ticks(cbar: Any) -> None:
    """Colour-bar ticks as plain numbers (0.3, 1, 4), not 3 x 10^-1."""
    from matplotlib.ticker import FuncFormatter

    def minor(v: float, _pos: int) -> str:  # label 2, 3, 5 per decade only: no overlapping labels
        lead = f"{v:.0e}"[0]
        return f"{v:g}" if lead in "235" else ""

    cbar.ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _pos: f"{v:g}"))
    cbar.ax.yaxis.set_minor_formatter(FuncFormatter(minor))


def _limits(maps: Sequence[FlipMap]) -> tuple[float, float]:
    finite = [m.t_flip[np.isfinite(m.t_flip)] for m in maps]
    finite = [f for f in finite if f.size]
    vmax = max(m.t_max for m in maps)
    vmin = min(float(f.min()) for f in finite) if finite else vmax / 100
    return max(vmin, vmax * 1e-4), vmax


def _title(fmap: FlipMap) -> str:
    if fmap.kind == "elastic":
        k1, k2 = fmap.params.get("k1", float("nan")), fmap.params.get("k2", float("nan"))
        stiff = f"k = {k1:g} N/m" if k1 == k2 else f"k1 = {k1:g}, k2 = {k2:g} N/m"
        return f"elastic double pendulum ({stiff})"
    return "rigid double pendulum"


def plot_flip_map(
    fmap: FlipMap,
    path: str | Path | None = None,
    *,
    ax: Any = None,
    cmap: str = "viridis",
    title: str | None = None,
    show_threshold: bool = True,
) -> Any:
    """The classic flip-map picture: time to the first flip, log colour scale, no flip in white.

    Parameters
    ----------
    fmap : FlipMap
        The map.
    path : str or Path, optional
        Save the figure there (PNG, 150 dpi).
    ax : matplotlib Axes, optional
        Draw into these axes instead of a new figure.
    cmap : str
        Matplotlib colour map of the flip time (log scale, ``vmin`` the fastest
        flip, ``vmax = t_max``).
    title : str, optional
        Axes title (default: model, grid, horizon).
    show_threshold : bool
        Draw the energy boundary ``V0 = V_flip`` as a thin grey line (the points
        outside cannot flip).

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    import matplotlib.pyplot as plt

    fig = ax.figure if ax is not None else plt.figure(figsize=(6.6, 5.4), layout="constrained")
    ax = ax if ax is not None else fig.add_subplot()
    vmin, vmax = _limits([fmap])
    im = _draw(fmap, ax, cmap=cmap, vmin=vmin, vmax=vmax, show_threshold=show_threshold)
    _plain_ticks(fig.colorbar(im, ax=ax, label="time to first flip [s]"))
    n1, n2 = fmap.t_flip.shape
    ax.set_title(title or f"{_title(fmap)}: {n1} x {n2} released at rest, white = no flip in {fmap.t_max:g} s", fontsize=9)
    if path is not None:
        _save(fig, path)
    return fig


def plot_flip_map_compare(
    maps: Sequence[FlipMap],
    path: str | Path | None = None,
    *,
    cmap: str = "viridis",
    show_threshold: bool = True,
) -> Any:
    """Flip maps side by side (e.g. rigid and elastic) on one shared colour scale.

    Parameters
    ----------
    maps : sequence of FlipMap
        Maps to show, left to right.
    path : str or Path, optional
        Save the figure there (PNG, 150 dpi).
    cmap : str
        Matplotlib colour map.
    show_threshold : bool
        Draw each map's energy boundary.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.

    Raises
    ------
    ValueError
        ``maps`` is empty.
    """
    import matplotlib.pyplot as plt

    if not maps:
        raise ValueError("maps must hold at least one FlipMap, got none")
    fig, axes = plt.subplots(1, len(maps), figsize=(5.0 * len(maps) + 1.2, 5.0), layout="constrained", squeeze=False)
    vmin, vmax = _limits(maps)
    im = None
    for fmap, ax in zip(maps, axes[0], strict=True):
        im = _draw(fmap, ax, cmap=cmap, vmin=vmin, vmax=vmax, show_threshold=show_threshold)
        frac = float(np.mean(fmap.flipped))
        ax.set_title(f"{_title(fmap)}\n{frac:.1%} flip within {fmap.t_max:g} s", fontsize=9)
    for ax in axes[0][1:]:
        ax.set_ylabel("")
    _plain_ticks(fig.colorbar(im, ax=list(axes[0]), label="time to first flip [s]", shrink=0.9))
    fig.suptitle("Double pendulum released at rest: white = no flip", fontsize=10)
    if path is not None:
        _save(fig, path)
    return fig
