"""Open-loop simulation of the robot under a record's measured torques (joint coordinates).

Shared by the output-error fit and the validation: a fixed-step RK4 on the record's own uniform
grid, the torque held over each step (the robot's loop holds it between commands), built as
CasADi Functions from :func:`pendulab.model.robot.robot_rhs` so whole batches of windows run in
one call.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from functools import cache

import casadi as ca
import numpy as np

from ..model.robot import robot_rhs
from .preprocess import Prepared
from .regressor import FIXED_NAMES, STANDARD_NAMES, _robot_vector

__all__ = ["joint_rhs", "rollout", "prediction_errors", "open_loop_segments", "HORIZONS"]

#: Validation horizons [s] (the identification issue's).
HORIZONS: tuple[float, ...] = (0.1, 0.25, 0.5, 1.0)

_J = np.array([[1.0, 0.0], [-1.0, 1.0]])  # joint rates = J @ absolute rates
_JINV = np.linalg.inv(_J)


@cache
def joint_rhs() -> ca.Function:
    """Forward dynamics in joint coordinates with the standard parameters.

    Returns
    -------
    casadi.Function
        ``f(x, tau, pi, fixed) -> xdot``: ``x = (q1, q2, q1', q2')``, ``tau`` the torque *reading*
        (the offsets ``o`` of ``pi`` are taken off), ``pi`` the values of :data:`STANDARD_NAMES`,
        ``fixed`` of :data:`FIXED_NAMES`.
    """
    x, tau = ca.SX.sym("x", 4), ca.SX.sym("tau", 2)
    pi, fixed = ca.SX.sym("pi", len(STANDARD_NAMES)), ca.SX.sym("fixed", len(FIXED_NAMES))
    xa = ca.vertcat(_JINV @ x[:2], _JINV @ x[2:])
    xd = robot_rhs()(xa, tau - pi[-2:], _robot_vector(pi, fixed))
    out = ca.vertcat(x[2:], _J @ xd[2:])
    return ca.Function("joint_rhs", [x, tau, pi, fixed], [out], ["x", "tau", "pi", "fixed"], ["xdot"])


@cache
def rollout(steps: int, h: float) -> ca.Function:
    """``steps`` RK4 steps of length ``h`` under a held torque per step.

    Parameters
    ----------
    steps : int
        Number of steps.
    h : float
        Step [s].

    Returns
    -------
    casadi.Function
        ``F(x0, U, pi, fixed) -> X``: ``x0`` shape (4,), ``U`` shape (2, steps) torque readings,
        ``X`` shape (4, steps), the state after each step.
    """
    f = joint_rhs()
    x, u = ca.MX.sym("x", 4), ca.MX.sym("u", 2)
    pi, fixed = ca.MX.sym("pi", len(STANDARD_NAMES)), ca.MX.sym("fixed", len(FIXED_NAMES))
    k1 = f(x, u, pi, fixed)
    k2 = f(x + h / 2 * k1, u, pi, fixed)
    k3 = f(x + h / 2 * k2, u, pi, fixed)
    k4 = f(x + h * k3, u, pi, fixed)
    step = ca.Function("rk4", [x, u, pi, fixed], [x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)])
    return step.mapaccum("rollout", steps, [0], [0])


def prediction_errors(
    prep: Prepared,
    pi: np.ndarray,
    fixed: Mapping[str, float],
    horizons: Sequence[float] = HORIZONS,
    start_every: float = 0.1,
) -> np.ndarray:
    """Open-loop prediction error of both joint angles from measured states along a record.

    From every ``start_every`` seconds (within the usable samples), the model starts at the
    record's filtered state and runs under the measured torques; the error is the predicted minus
    the measured (unfiltered) angle ``h`` seconds later.

    Parameters
    ----------
    prep : Prepared
        The record.
    pi : numpy.ndarray, shape (13,)
        Standard parameters of the model.
    fixed : mapping of str to float
        Values of :data:`FIXED_NAMES`.
    horizons : sequence of float, default :data:`HORIZONS`
        Horizons [s].
    start_every : float, default 0.1
        Spacing of the starts [s].

    Returns
    -------
    numpy.ndarray, shape (len(horizons), n_starts, 2)
        Errors [rad] per horizon, start and joint.

    Raises
    ------
    ValueError
        A horizon not positive, or longer than the record's usable part.
    """
    dt = prep.dt
    k_h = np.array([int(round(h / dt)) for h in horizons])
    if (k_h < 1).any():
        raise ValueError(f"horizons must be at least one sample ({dt:.3g} s), got {list(horizons)}")
    usable = np.flatnonzero(prep.use)
    first, last = usable[0], usable[-1]
    starts = np.arange(first, last - k_h.max() + 1, max(1, int(round(start_every / dt))))
    if starts.size == 0:
        raise ValueError(f"record {prep.name!r} is shorter than the longest horizon {max(horizons)} s")
    steps = int(k_h.max())
    U = np.stack([prep.tau[s : s + steps].T for s in starts], axis=0)  # (n, 2, steps)
    x0 = prep.state(starts).T
    fx = np.array([float(fixed[k]) for k in FIXED_NAMES])
    F = rollout(steps, dt).map(starts.size)
    X = np.asarray(F(x0, np.hstack(list(U)), pi, fx)).reshape(4, starts.size, steps)
    errs = [X[:2, :, k - 1].T - prep.q_measured[starts + k] for k in k_h]
    return np.stack(errs)


def open_loop_segments(
    prep: Prepared, pi: np.ndarray, fixed: Mapping[str, float], every: float, length: float
) -> list[tuple[np.ndarray, np.ndarray]]:
    """Open-loop predictions of ``length`` seconds started from the measured state every ``every`` seconds.

    Parameters
    ----------
    prep : Prepared
        A prepared record (its measured torques drive the predictions).
    pi : numpy.ndarray, shape (15,)
        Standard parameters and torque offsets (:func:`~pendulab.identify.validation.standard_vector`).
    fixed : mapping of str to float
        Values of :data:`~pendulab.identify.regressor.FIXED_NAMES`.
    every, length : float
        Spacing of the starts and length of each prediction [s].

    Returns
    -------
    list of (numpy.ndarray, numpy.ndarray)
        Per start: times, shape (steps,) [s], and predicted joint angles, shape (2, steps) [rad]; all
        segments in one mapped CasADi rollout.
    """
    steps = int(round(length / prep.dt))
    usable = np.flatnonzero(prep.use)
    starts = np.arange(usable[0], usable[-1] - steps, int(round(every / prep.dt)))
    fx = np.array([float(fixed[k]) for k in FIXED_NAMES])
    U = np.hstack([prep.tau[s : s + steps].T for s in starts])
    X = np.asarray(rollout(steps, prep.dt).map(starts.size)(prep.state(starts).T, U, pi, fx)).reshape(4, starts.size, steps)
    return [(prep.t[s + 1 : s + steps + 1], X[:2, i, :]) for i, s in enumerate(starts)]
