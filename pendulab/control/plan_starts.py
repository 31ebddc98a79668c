"""Start states of the v3 plan library: the states the protocol's reset PID hands over, simulated from upright.

v3's reset (``pendulab.evaluate.realai.v3_definition``: PID kp 10, ki 0.1, kd 1 at its own 1 ms step, each joint
saturated at 6 N.m, plus gravity compensation, for 0.2 s) starts wherever the pendulum is. A controller that
balances between resets is upright then, so the hand-over is a function of the drawn configuration and the
upright branch; where the PID saturates for the whole 0.2 s, different draws hand over the same state.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from .._checks import bounded_int
from ..model.model import Model
from ..model.pycode import to_python

__all__ = ["DEFAULT_BRANCHES", "reset_handover", "library_starts", "rest_starts"]

#: Upright branches the resets leave from, as (k1, k2): absolute angles ``(pi + 2 pi k1, pi + 2 pi k2)``.
DEFAULT_BRANCHES: tuple[tuple[int, int], ...] = ((0, 0), (-1, -1), (0, -1), (-1, 0))
#: Reset PID of the protocol (kp, ki, kd), its step [s], length [s] and saturation [N.m] (evaluate/realai/v3_definition).
_PID = (10.0, 0.1, 1.0, 0.001, 0.2, 6.0)


def _rk4(f: Callable, x: np.ndarray, u: Sequence[float], p: list[float], h: float) -> np.ndarray:
    k1 = f(x, u, p)
    k2 = f(x + 0.5 * h * k1, u, p)
    k3 = f(x + 0.5 * h * k2, u, p)
    k4 = f(x + h * k3, u, p)
    return x + h * (k1 + 2.0 * (k2 + k3) + k4) / 6.0


def reset_handover(model: Model, x_pre: np.ndarray, goal: np.ndarray, sample_time: float = 0.002) -> np.ndarray:
    """The state a v3 reset hands over: the protocol's PID (+ gravity compensation) for 0.2 s from ``x_pre``.

    A fresh PID (no integral or derivative history: the protocol's history only adds a one-step kick).

    Parameters
    ----------
    model : Model
        Rigid model (absolute angles).
    x_pre : ndarray, shape (4,)
        State when the reset starts (absolute angles) [rad, rad/s].
    goal : ndarray, shape (2,)
        Drawn configuration in the protocol's relative angles ``(q1, q2 = th2 - th1)`` [rad].
    sample_time : float
        Simulation step [s].

    Returns
    -------
    ndarray, shape (4,)
        State at the hand-over (absolute angles).
    """
    kp, ki, kd, pid_dt, length, sat = _PID
    f = to_python(model.functions["rhs"])
    p = [float(v) for v in model.p]
    prm = model.params
    a1, a2 = prm.m1 * prm.g * prm.lc1 + prm.m2 * prm.g * prm.L1, prm.m2 * prm.g * prm.lc2
    x = np.array(x_pre, dtype=float)
    errs: list[np.ndarray] = []
    timer = 0.0
    while timer <= length:
        q = np.array([x[0], x[1] - x[0]])
        errs.append(np.asarray(goal, dtype=float) - q)
        u = kp * errs[-1] + ki * np.sum(errs, axis=0) * pid_dt
        if len(errs) > 2:
            u = u + kd * (errs[-1] - errs[-2]) / pid_dt
        s12 = math.sin(q[0] + q[1])
        u = np.clip(np.clip(u, -sat, sat) + [a1 * math.sin(q[0]) + a2 * s12, a2 * s12], -sat, sat)
        x = _rk4(f, x, u, p, sample_time)
        timer += sample_time
    return x


def library_starts(model: Model, n_grid: int, branches: Sequence[tuple[int, int]] = DEFAULT_BRANCHES) -> np.ndarray:
    """Plan starts: hanging at rest, then the hand-over states of an ``n_grid`` x ``n_grid`` grid of drawn configurations.

    Parameters
    ----------
    model : Model
        Design model.
    n_grid : int
        Grid points per relative angle (cell centres of ``[-pi, pi)``).
    branches : sequence of (int, int)
        Upright branches ``(k1, k2)`` the resets leave from.

    Returns
    -------
    ndarray, shape (1 + len(branches) n_grid^2, 4)
        Start states (absolute angles) [rad, rad/s].

    Raises
    ------
    ValueError
        ``n_grid`` outside [1, 64] or an empty ``branches``.
    """
    n = bounded_int("n_grid", n_grid, low=1, high=64, why="plans per angle of the library grid")
    if len(branches) == 0:
        raise ValueError(f"branches must name at least one upright branch (k1, k2), got {branches!r}")
    g = -math.pi + (np.arange(n) + 0.5) * 2.0 * math.pi / n
    starts = [np.zeros(4)]
    for k1, k2 in branches:
        up = np.array([math.pi + 2.0 * math.pi * int(k1), math.pi + 2.0 * math.pi * int(k2), 0.0, 0.0])
        for q1 in g:
            for q2 in g:
                starts.append(reset_handover(model, up, np.array([q1, q2])))
    return np.array(starts)


def rest_starts(n_grid: int) -> np.ndarray:
    """Plan starts at rest on an ``n_grid`` x ``n_grid`` grid of configurations: the hardware protocol's hand-overs.

    The ICRA 2025 hardware final's reset (``pendulab.evaluate.realai.v3_hardware``: PID kp 2, kd 0.3 at a 1 ms
    step, for at least 1 s) brings the robot near a configuration drawn uniformly in ``[-pi, pi)^2`` and
    nearly to rest, whatever state it started from: the hand-over is the drawn configuration at rest.

    Parameters
    ----------
    n_grid : int
        Grid points per relative angle (cell centres of ``[-pi, pi)``).

    Returns
    -------
    ndarray, shape (n_grid^2, 4)
        Start states (absolute angles ``theta1 = q1``, ``theta2 = q1 + q2``) [rad], rates 0 [rad/s].

    Raises
    ------
    ValueError
        ``n_grid`` outside [1, 64].
    """
    n = bounded_int("n_grid", n_grid, low=1, high=64, why="plans per angle of the library grid")
    g = -math.pi + (np.arange(n) + 0.5) * 2.0 * math.pi / n
    return np.array([[q1, q1 + q2, 0.0, 0.0] for q1 in g for q2 in g])
