"""Geometry shared by the still figures and the animation: links, springs, runs."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..integrate.trajectory import Trajectory
from ..model.model import Model

__all__ = ["Run", "as_runs", "link_polylines", "spring_polyline", "view_limits", "RUN_COLORS", "run_colors"]

#: Line colours of the runs, in order (rigid first in the demo); repeated beyond four runs.
RUN_COLORS = ("tab:blue", "tab:red", "tab:green", "tab:purple")


def run_colors(n: int) -> list[str]:
    """Colours of ``n`` runs, cycling through :data:`RUN_COLORS`.

    Parameters
    ----------
    n : int
        Number of runs.

    Returns
    -------
    list of str
        ``n`` matplotlib colour names.
    """
    return [RUN_COLORS[i % len(RUN_COLORS)] for i in range(n)]


@dataclass(frozen=True)
class Run:
    """One simulated pendulum: its model and trajectory, with a label for legends.

    Attributes
    ----------
    label : str
        Name shown in legends and titles.
    model : Model
        The simulated pendulum (its kind selects straight links or springs).
    traj : Trajectory
        The simulation result; must have the outputs x1, y1, x2, y2.
    """

    label: str
    model: Model
    traj: Trajectory

    @cached_property
    def positions(self) -> np.ndarray:
        """x1, y1, x2, y2 [m] at every output time, shape (N, 4)."""
        return np.column_stack([self.traj[n] for n in ("x1", "y1", "x2", "y2")])


def as_runs(runs: Mapping[str, tuple[Model, Trajectory]] | list[Run] | tuple[Run, ...]) -> tuple[Run, ...]:
    """Normalize ``{label: (model, traj)}`` or a sequence of :class:`Run` to a tuple of runs.

    Parameters
    ----------
    runs : mapping of str to (Model, Trajectory), or sequence of Run
        The runs, in order.

    Returns
    -------
    tuple of Run
        The runs (a sequence of Run is returned as a tuple, unchanged).

    Raises
    ------
    ValueError
        ``runs`` is empty or a sequence with an entry that is not a Run.
    """
    if isinstance(runs, Mapping):
        out = tuple(Run(label, model, traj) for label, (model, traj) in runs.items())
    else:
        out = tuple(runs)
    if not out or not all(isinstance(r, Run) for r in out):
        raise ValueError(f"runs must be a non-empty mapping label -> (model, trajectory) or a list of Run, got {runs!r}")
    return out


def spring_polyline(p0: np.ndarray, p1: np.ndarray, coils: int = 7, width: float = 0.05) -> np.ndarray:
    """Zig-zag from ``p0`` to ``p1`` (straight ends).

    The zig-zag keeps its width and coil count, so a longer spring looks
    stretched and a shorter one compressed.

    Parameters
    ----------
    p0, p1 : array_like, shape (2,)
        End points (x, y) [m].
    coils : int, default 7
        Number of coils; the zig-zag spans the middle 70 % of the length.
    width : float, default 0.05
        Offset of the zig-zag corners from the spring axis [m].

    Returns
    -------
    ndarray, shape (M, 2)
        Polyline vertices [m], M = 2 coils + 3 (just ``p0, p1`` when they
        coincide).
    """
    p0 = np.asarray(p0, dtype=float)
    p1 = np.asarray(p1, dtype=float)
    d = p1 - p0
    length = float(np.hypot(*d))
    if length == 0.0:
        return np.vstack([p0, p1])
    along = d / length
    normal = np.array([-along[1], along[0]])
    s = np.concatenate([[0.0, 0.15], np.linspace(0.15, 0.85, 2 * coils + 1)[1:-1], [0.85, 1.0]])
    offset = np.zeros_like(s)
    offset[2:-2] = width * np.where(np.arange(len(s) - 4) % 2 == 0, 1.0, -1.0)
    return p0 + np.outer(s * length, along) + np.outer(offset, normal)


def link_polylines(model: Model, pos: np.ndarray) -> list[np.ndarray]:
    """Polylines of both links for one configuration.

    Rigid links are straight; elastic links are drawn as springs.

    Parameters
    ----------
    model : Model
        The pendulum (its kind, and an elastic model's rest lengths for the coil width).
    pos : array_like, shape (4,)
        Bob positions x1, y1, x2, y2 [m], pivot at the origin.

    Returns
    -------
    list of ndarray, shape (M, 2)
        Two polylines [m]: pivot to bob 1, bob 1 to bob 2.
    """
    origin = np.zeros(2)
    b1, b2 = np.asarray(pos[:2], dtype=float), np.asarray(pos[2:4], dtype=float)
    if model.kind == "elastic":
        # Coil width in proportion to each spring's rest length (0.05 m for a 1 m link), so short links stay readable.
        w1, w2 = 0.05 * model.params.L1, 0.05 * model.params.L2
        return [spring_polyline(origin, b1, width=w1), spring_polyline(b1, b2, width=w2)]
    return [np.vstack([origin, b1]), np.vstack([b1, b2])]


def view_limits(runs: tuple[Run, ...], margin: float = 0.15) -> tuple[tuple[float, float], tuple[float, float]]:
    """Axis limits ``(xlim, ylim)`` [m] holding the pivot and every bob of every run.

    Horizontally symmetric about the pivot; vertically from the lowest bob to
    the highest point reached (at least the pivot), so a pendulum that never
    rises above its pivot does not waste half the picture.

    Parameters
    ----------
    runs : tuple of Run
        The runs to fit.
    margin : float, default 0.15
        Space added on every side [m].

    Returns
    -------
    xlim, ylim : tuple of (float, float)
        Lower and upper axis limits [m].
    """
    pos = np.vstack([r.positions for r in runs])
    half = float(np.max(np.abs(pos[:, [0, 2]]))) + margin
    low = float(np.min(pos[:, [1, 3]])) - margin
    high = max(0.0, float(np.max(pos[:, [1, 3]]))) + margin
    return (-half, half), (low, high)
