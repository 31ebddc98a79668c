"""The energy balance of a run: work done by the held torques and energy dissipated by the dampers.

``E(t) - E(0) = W(t) - D(t)``; the defect of this balance measures the
integration error of a forced or damped run (summaries and energy figures).
"""

from __future__ import annotations

import numpy as np

from ..model.model import Model
from .trajectory import Trajectory

__all__ = ["energy_flows", "trajectory_energy_flows"]


def energy_flows(model: Model, t: np.ndarray, x: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Work done by held torques and energy dissipated by the dampers, accumulated along a trajectory.

    The energy balance of a run is ``E(t) - E(0) = W(t) - D(t)``; its defect
    measures the integration error of a forced or damped run.

    Parameters
    ----------
    model : Model
        The pendulum.
    t : ndarray, shape (N,)
        Uniform grid [s] the torques are held on.
    x : ndarray, shape (N, nx)
        States on ``t``.
    u : ndarray, shape (N-1, nu) or (N, nu)
        Torques [N.m] held over each interval (a last row is ignored).

    Returns
    -------
    work : ndarray, shape (N,)
        Work [J] delivered by the torques from 0 to ``t[k]``: exact for held
        torques (``tau1 dtheta1 + tau2 (dtheta2 - dtheta1)`` per interval, by
        :meth:`Model.power_in` at the mean rates).
    dissipated : ndarray, shape (N,)
        Energy [J] dissipated by the dampers (:meth:`Model.dissipation`) from 0
        to ``t[k]``: trapezoid rule with the Euler-Maclaurin end correction
        (``- h^2/12 (P'(t_k) - P'(0))``, ``P'`` by finite differences), error
        O(h^4) while the dissipated power is smooth.
    """
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    n = len(t)
    zero = np.zeros(n)
    if n < 2:
        return zero, zero.copy()
    h = float(t[1] - t[0])
    names = model.state_names
    th = [names.index("theta1"), names.index("theta2")]
    om = [names.index("omega1"), names.index("omega2")]
    mean_rates = x[:-1].copy()
    mean_rates[:, om] = (x[1:, th] - x[:-1, th]) / h
    U = np.asarray(u, dtype=float)[: n - 1]
    work = np.concatenate([[0.0], np.cumsum(np.atleast_1d(model.power_in(mean_rates, U)) * h)])
    p = np.atleast_1d(model.dissipation(x))
    if not np.any(p):
        return work, zero.copy()
    dissipated = np.concatenate([[0.0], np.cumsum(0.5 * h * (p[1:] + p[:-1]))])
    if n >= 3:
        dp = np.gradient(p, h, edge_order=2)
        dissipated -= h * h / 12.0 * (dp - dp[0])
    return work, dissipated


def trajectory_energy_flows(model: Model, traj: Trajectory) -> tuple[np.ndarray, np.ndarray]:
    """Input work and dissipated energy [J] accumulated along a trajectory of :func:`~pendulab.integrate.simulate.simulate`.

    Parameters
    ----------
    model : Model
        The model the trajectory is of.
    traj : Trajectory
        A run; when its input was held on a finer grid than the output grid (a
        :class:`~pendulab.integrate.simulate.TimeInput`), the flows the run recorded on that grid
        (``stats["input_work"]``, ``stats["dissipated"]``), else :func:`energy_flows`
        on the output grid with ``traj.u`` held over each interval.

    Returns
    -------
    work, dissipated : ndarray, shape (N,)
        From 0 to each output time [J]; the energy balance is ``E - E[0] = work - dissipated``.
    """
    if "input_work" in traj.stats and "dissipated" in traj.stats:
        return np.asarray(traj.stats["input_work"], dtype=float), np.asarray(traj.stats["dissipated"], dtype=float)
    return energy_flows(model, traj.t, traj.x, traj.u)
