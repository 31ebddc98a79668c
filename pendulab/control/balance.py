"""Closed-loop balancing simulations and a region-of-attraction estimate by bisection.

The controller is sampled-data: :func:`pendulab.simulate` holds the torque
over each output step (``dt``), exactly like a co-simulation master would.
Saturation ``|tau| <= u_max`` is applied inside the feedback.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._inputs import checked
from ..integrate import SimulationError, simulate
from ..integrate.trajectory import Trajectory
from ..model.model import Model
from .lqr import LQRDesign, wrap_state_error

__all__ = ["simulate_balance", "balanced", "ROAResult", "region_of_attraction", "format_roa", "DEFAULT_DIRECTIONS"]

#: Perturbation directions in (theta1, theta2); amplitudes are the Euclidean norm [rad].
DEFAULT_DIRECTIONS: Mapping[str, tuple[float, float]] = {
    "theta1": (1.0, 0.0),
    "theta2": (0.0, 1.0),
    "in-phase": (1.0, 1.0),
    "anti-phase": (1.0, -1.0),
}


def _sample_time(design: LQRDesign, dt: float | None) -> float:
    if dt is None:
        return design.dt if design.dt is not None else 0.01
    if design.dt is not None and not math.isclose(dt, design.dt, rel_tol=1e-9):
        raise ValueError(f"dt = {dt!r} s differs from the discrete design's sample time {design.dt!r} s")
    if not (np.isfinite(dt) and dt > 0):
        raise ValueError(f"dt must be a positive sample time in seconds, got {dt!r}")
    return float(dt)


@checked()
def simulate_balance(
    model: Model,
    design: LQRDesign,
    x0: Any,
    t_final: float = 5.0,
    dt: float | None = None,
    u_max: float | None = None,
    method: str = "cvodes",
    rtol: float = 1e-8,
    atol: float = 1e-8,
) -> Trajectory:
    """Simulate the nonlinear model under the LQR feedback (sampled, optionally saturated).

    Parameters
    ----------
    model : Model
        Must be the model the design was made for (same kind).
    design : LQRDesign
    x0 : array_like, shape (nx,)
        Initial state.
    t_final : float
        Horizon [s].
    dt : float, optional
        Controller sample time [s] = output step; default the design's ``dt``
        or 0.01 s for a continuous design.
    u_max : float, optional
        Torque limit [N.m] on each actuated joint.
    method, rtol, atol
        Integrator settings (see :func:`pendulab.simulate`).

    Returns
    -------
    Trajectory
        Closed-loop states on the uniform grid of step ``dt``; the torque is
        held over each step.

    Raises
    ------
    ValueError
        ``design`` is for another model kind, or ``dt`` is not positive or
        differs from a discrete design's sample time.
    SimulationError
        The integrator failed (see :func:`pendulab.simulate`).

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.control import balanced, lqr_balance, simulate_balance
    >>> model = pl.rigid()
    >>> design = lqr_balance(model, "pendubot", dt=0.01)
    >>> x0 = design.x_eq + [0.0, 0.1, 0.0, 0.0]  # elbow link 0.1 rad off
    >>> for u_max in (10.0, 5.0):  # torque limit [N.m]; the design asks for 12.6 N.m at first
    ...     traj = simulate_balance(model, design, x0, t_final=5.0, u_max=u_max)
    ...     print(u_max, float(np.abs(traj.u[:, 0]).max()), balanced(design, traj.x[-1]))
    10.0 10.0 True
    5.0 5.0 False
    """
    if design.kind != model.kind:
        raise ValueError(f"design is for the {design.kind} model, got a {model.kind} model")
    return simulate(
        model, x0, t_final, dt=_sample_time(design, dt), method=method, rtol=rtol, atol=atol, u=design.controller(u_max)
    )


@checked(tol="settle_tol")
def balanced(design: LQRDesign, x: Any, tol: float = 1e-2) -> bool:
    """True when the angles and angular velocities are within ``tol`` of the equilibrium.

    Spring coordinates are not judged: at vertical equilibria the torques cannot
    reach them to first order, and undamped springs keep ringing.

    Parameters
    ----------
    design : LQRDesign
        Provides the equilibrium ``x_eq`` and the state names.
    x : array_like, shape (nx,)
        State to judge; angles are compared modulo 2 pi.
    tol : float
        Threshold on each angle error [rad] and angular velocity error [rad/s].

    Returns
    -------
    bool
        True when all errors are finite and every theta/omega error is below ``tol``.

    Examples
    --------
    >>> import pendulab as pl
    >>> from pendulab.control import balanced, lqr_balance
    >>> design = lqr_balance(pl.rigid())
    >>> up = design.x_eq  # (pi, pi, 0, 0)
    >>> balanced(design, up + [0.005, 0.0, 0.0, 0.0]), balanced(design, up + [0.05, 0.0, 0.0, 0.0])
    (True, False)
    >>> balanced(design, up + [2 * np.pi, -2 * np.pi, 0.0, 0.0])  # angles are compared modulo 2 pi
    True
    """
    dx = wrap_state_error(np.asarray(x, dtype=float) - design.x_eq, design.state_names)
    judged = [i for i, n in enumerate(design.state_names) if n.startswith(("theta", "omega"))]
    return bool(np.all(np.isfinite(dx)) and np.max(np.abs(dx[judged])) < tol)


@dataclass(frozen=True)
class ROAResult:
    """Largest converging perturbation along one direction.

    Attributes
    ----------
    direction : str
    vector : ndarray, shape (2,)
        Unit perturbation of (theta1, theta2).
    amplitude : float
        Largest amplitude [rad] found to converge (a lower bound within ``tol``).
    reached_max : bool
        True when even ``amplitude_max`` converged.
    simulations : int

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.control import lqr_balance, region_of_attraction
    >>> model = pl.rigid()
    >>> design = lqr_balance(model, "full")
    >>> (row,) = region_of_attraction(model, design, {"in-phase": (1.0, 1.0)}, u_max=20.0, t_final=3.0, tol=0.05)
    >>> row.direction, np.round(row.vector, 3), row.reached_max  # unit (theta1, theta2) direction
    ('in-phase', array([0.707, 0.707]), False)
    >>> print(f"{row.amplitude:.3f} rad in {row.simulations} simulations")
    0.736 rad in 6 simulations
    """

    direction: str
    vector: np.ndarray
    amplitude: float
    reached_max: bool
    simulations: int


@checked(tol="settle_tol")
def region_of_attraction(
    model: Model,
    design: LQRDesign,
    directions: Mapping[str, Sequence[float]] | None = None,
    u_max: float | None = None,
    t_final: float = 5.0,
    dt: float | None = None,
    amplitude_max: float = math.pi / 2,
    tol: float = 0.01,
    settle_tol: float = 1e-2,
    progress: Callable[[str], None] | None = None,
) -> list[ROAResult]:
    """Estimate the region of attraction along a few angle directions by bisection.

    Each trial starts at rest at ``x_eq + a * d`` (springs at their equilibrium
    lengths) and counts as converged when :func:`balanced` holds at ``t_final``.
    Assumes the converging set is an interval along each direction.

    Parameters
    ----------
    model, design
    directions : mapping of name to (d_theta1, d_theta2), optional
        Default ``DEFAULT_DIRECTIONS``; vectors are normalized.
    u_max : float, optional
        Torque limit [N.m].
    t_final : float
        Horizon of each trial [s].
    dt : float, optional
        Controller sample time [s].
    amplitude_max : float
        Upper end of the search [rad].
    tol : float
        Bisection stops when the bracket is narrower than this [rad].
    settle_tol : float
        Convergence threshold on angles [rad] and angular velocities [rad/s].
    progress : callable(str), optional
        Called with a one-line status after each trial (the CLI prints it).

    Returns
    -------
    list of ROAResult
        One per direction, in the order of ``directions``.

    Raises
    ------
    ValueError
        Non-positive ``amplitude_max`` or ``tol``, or a direction that is not
        a finite non-zero 2-vector.

    Examples
    --------
    >>> import pendulab as pl
    >>> from pendulab.control import lqr_balance, region_of_attraction
    >>> model = pl.rigid()
    >>> design = lqr_balance(model, "full")
    >>> (row,) = region_of_attraction(model, design, {"theta1": (1.0, 0.0)}, u_max=20.0, t_final=3.0, tol=0.05)
    >>> print(f"{row.direction}: caught from {row.amplitude:.2f} rad ({row.simulations} simulations)")
    theta1: caught from 0.88 rad (6 simulations)
    """
    if not (amplitude_max > 0 and tol > 0):
        raise ValueError(f"amplitude_max and tol must be positive, got {amplitude_max!r} and {tol!r}")
    dirs = DEFAULT_DIRECTIONS if directions is None else directions
    results = []
    for name, vec in dirs.items():
        d = np.asarray(vec, dtype=float).ravel()
        if d.shape != (2,) or not np.all(np.isfinite(d)) or np.linalg.norm(d) == 0:
            raise ValueError(f"direction {name!r} must be a non-zero (d_theta1, d_theta2), got {vec!r}")
        d = d / np.linalg.norm(d)
        count = 0

        def converges(a: float, d: np.ndarray = d, name: str = name) -> bool:
            nonlocal count
            count += 1
            x0 = design.x_eq.copy()
            x0[:2] += a * d
            try:
                traj = simulate_balance(model, design, x0, t_final, dt=dt, u_max=u_max)
                ok = balanced(design, traj.x[-1], settle_tol)
            except SimulationError:
                ok = False
            if progress is not None:
                progress(f"{design.kind} {design.actuation} {name}: a = {a:.4f} rad -> {'ok' if ok else 'falls'}")
            return ok

        if converges(amplitude_max):
            results.append(ROAResult(name, d, amplitude_max, True, count))
            continue
        lo, hi = 0.0, amplitude_max
        while hi - lo > tol:
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if converges(mid) else (lo, mid)
        results.append(ROAResult(name, d, lo, False, count))
    return results


def format_roa(rows: Sequence[ROAResult], title: str = "") -> str:
    """Plain-text table of region-of-attraction estimates.

    Parameters
    ----------
    rows : sequence of ROAResult
        As returned by :func:`region_of_attraction`.
    title : str
        Optional first line.

    Returns
    -------
    str
        One line per direction: largest converging amplitude [rad] and [deg]
        (prefixed ``>=`` when ``amplitude_max`` converged) and the number of
        simulations.

    Examples
    --------
    >>> import pendulab as pl
    >>> from pendulab.control import format_roa, lqr_balance, region_of_attraction
    >>> model = pl.rigid()
    >>> directions = {"theta1": (1.0, 0.0), "anti-phase": (1.0, -1.0)}
    >>> rows = region_of_attraction(model, lqr_balance(model), directions, u_max=20.0, t_final=3.0, tol=0.05)
    >>> print(format_roa(rows, title="rigid, full actuation, |tau| <= 20 N.m"))
    rigid, full actuation, |tau| <= 20 N.m
    direction    largest converging [rad]   [deg]  sims
    theta1                          0.884    50.6     6
    anti-phase  >=                  1.571    90.0     1
    """
    lines = [title] if title else []
    lines.append(f"{'direction':<11} {'largest converging [rad]':>25} {'[deg]':>7} {'sims':>5}")
    for r in rows:
        bound = ">=" if r.reached_max else "  "
        lines.append(f"{r.direction:<11} {bound:>2}{r.amplitude:>23.3f} {math.degrees(r.amplitude):>7.1f} {r.simulations:>5}")
    return "\n".join(lines)
