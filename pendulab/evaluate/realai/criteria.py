"""The RealAIGym simulation leaderboard v2 criteria and score, and the published entries.

Definitions follow ``src/python/double_pendulum/analysis/leaderboard.py`` of
github.com/dfki-ric-underactuated-lab/double_pendulum (stored copy at commit
03b4df7; the functions ``get_swingup_time``, ``get_energy``,
``get_torque_cost``, ``get_tau_smoothness``, ``get_velocity_cost`` and the
``score_version="v2"`` branch of ``leaderboard_scores``), with the weights and
normalisations of ``leaderboard/{pendubot,acrobot}/simulation_v2/create_leaderboard.py``
(commit 699c934): weights 1 on swing-up time, energy, torque cost, torque
smoothness and velocity cost (0 on max torque and integrated torque), norms
20 s, 60 J, 20 N^2 m^2 s, 0.1 N.m and 400 rad^2/s:

``S = success * (1 - (1/5) * sum_i tanh(pi * c_i / n_i))``.

Every criterion takes the trajectory in RealAIGym's convention: rows
``(t_k, q_k, u_k)`` where ``u_k`` is held over ``[t_k, t_k+1]`` and
``q2`` is the angle of link 2 *relative* to link 1 (both from hanging).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from ...control.realai.spec import HEIGHT_FRACTION, NORMS

__all__ = [
    "CRITERIA",
    "PUBLISHED",
    "to_relative",
    "swingup_time",
    "energy",
    "torque_cost",
    "torque_smoothness",
    "velocity_cost",
    "criteria",
    "score_v2",
]

#: Criterion names, in the leaderboard's order.
CRITERIA: tuple[str, ...] = ("swingup_time", "energy", "torque_cost", "torque_smoothness", "velocity_cost")

#: Published RealAIGym simulation leaderboard v2 scores, best first (criteria of each row: :mod:`.leaderboard_published`).
PUBLISHED: Mapping[str, Mapping[str, float]] = {
    "pendubot": {
        "history_sac": 0.682,
        "ar_eapo": 0.659,
        "evolsac": 0.596,
        "ilqr_riccati_lqr": 0.536,
        "ilqr_tvlqr_lqr": 0.526,
        "mcpilco": 0.480,
        "ilqr_ilqrmpc_lqr": 0.353,
    },
    "acrobot": {
        "history_sac": 0.655,
        "ar_eapo": 0.633,
        "evolsac": 0.524,
        "ilqr_tvlqr": 0.504,
        "ilqr_riccati_lqr": 0.396,
        "ilqr_ilqrmpc_lqr": 0.345,
        "mcpilco": 0.316,
    },
}


def _traj(T: np.ndarray, X: np.ndarray | None = None, U: np.ndarray | None = None) -> tuple:
    """Check and convert a trajectory (T (N,), X (N, 4), U (N, 2)); NaN or wrong shapes raise ValueError."""
    T = np.asarray(T, dtype=float)
    if T.ndim != 1 or len(T) < 2:
        raise ValueError(f"T must have shape (N,) with N >= 2, got {T.shape}")
    out = [T]
    for name, a, cols in (("X", X, 4), ("U", U, 2)):
        if a is None:
            continue
        a = np.asarray(a, dtype=float)
        if a.shape != (len(T), cols):
            raise ValueError(f"{name} must have shape ({len(T)}, {cols}), got {a.shape}")
        out.append(a)
    if not all(np.all(np.isfinite(a)) for a in out):
        raise ValueError("T, X and U must be finite (no NaN or inf)")
    return tuple(out)


def to_relative(x_abs: np.ndarray) -> np.ndarray:
    """pendulab's absolute state (theta1, theta2, omega1, omega2) -> RealAIGym's (q1, q2, dq1, dq2), q2 relative.

    Parameters
    ----------
    x_abs : array_like, shape (N, 4) or (4,)
        Absolute angles from hanging [rad] and their rates [rad/s].

    Returns
    -------
    ndarray, same shape
        ``(theta1, theta2 - theta1, omega1, omega2 - omega1)``.

    Raises
    ------
    ValueError
        The last axis is not of length 4.
    """
    x = np.array(x_abs, dtype=float)
    if x.shape[-1] != 4:
        raise ValueError(f"x_abs must have 4 columns (theta1, theta2, omega1, omega2), got shape {x.shape}")
    x[..., 1] -= x[..., 0]
    x[..., 3] -= x[..., 2]
    return x


def swingup_time(T: np.ndarray, X: np.ndarray, L1: float, L2: float) -> float:
    """Time from which the end effector stays above 0.9 (L1 + L2) (``get_swingup_time``, method "height").

    As in the leaderboard, the scan runs backwards from the second-to-last
    sample to sample 1 and stops at the first sample below the line; if the
    second-to-last sample is below, the result is ``T[-1]`` (failure).

    Parameters
    ----------
    T : array_like, shape (N,)
        Times [s].
    X : array_like, shape (N, 4)
        RealAIGym state (q1, q2 relative) [rad, rad, rad/s, rad/s].
    L1, L2 : float
        Link lengths [m].

    Returns
    -------
    float
        Swing-up time [s]; ``T[-1]`` means no swing-up.

    Raises
    ------
    ValueError
        Bad shapes or non-finite values.
    """
    T, X = _traj(T, X)
    y = -L1 * np.cos(X[:, 0]) - L2 * np.cos(X[:, 0] + X[:, 1])
    up = y > HEIGHT_FRACTION * (L1 + L2)
    index = len(T) - 1
    for i in range(len(up) - 2, 0, -1):
        if not up[i]:
            break
        index = i
    return float(T[index])


def energy(X: np.ndarray, U: np.ndarray) -> float:
    """Mechanical work of the motors, ``sum_j sum_k |(q_j[k+1] - q_j[k]) u_j[k]|`` [J] (``get_energy``).

    Parameters
    ----------
    X : array_like, shape (N, 4)
        RealAIGym state (q2 relative).
    U : array_like, shape (N, 2)
        Torques [N.m] held from each row.

    Returns
    -------
    float
        [J].

    Raises
    ------
    ValueError
        Bad shapes or non-finite values.
    """
    _, X, U = _traj(np.arange(len(X), dtype=float), X, U)
    return float(np.sum(np.abs(np.diff(X[:, :2], axis=0) * U[:-1])))


def torque_cost(T: np.ndarray, U: np.ndarray) -> float:
    """``sum_k u[k]' u[k] (t[k+1] - t[k])`` [N^2 m^2 s] (``get_torque_cost``, R = identity).

    Parameters
    ----------
    T : array_like, shape (N,)
        Times [s].
    U : array_like, shape (N, 2)
        Torques [N.m].

    Returns
    -------
    float
        [N^2 m^2 s].

    Raises
    ------
    ValueError
        Bad shapes or non-finite values.
    """
    T, U = _traj(T, None, U)
    return float(np.sum(np.sum(U[:-1] ** 2, axis=1) * np.diff(T)))


def torque_smoothness(U: np.ndarray) -> float:
    """``std(diff(u1)) + std(diff(u2))`` [N.m] (``get_tau_smoothness``; population std).

    Parameters
    ----------
    U : array_like, shape (N, 2)
        Torques [N.m].

    Returns
    -------
    float
        [N.m].

    Raises
    ------
    ValueError
        Bad shapes or non-finite values.
    """
    _, U = _traj(np.arange(len(U), dtype=float), None, U)
    return float(np.sum(np.std(np.diff(U, axis=0), axis=0)))


def velocity_cost(T: np.ndarray, X: np.ndarray) -> float:
    """``sum_k (dq1[k]^2 + dq2[k]^2) (t[k+1] - t[k])`` with dq2 relative [rad^2/s] (``get_velocity_cost``, Q = identity).

    Parameters
    ----------
    T : array_like, shape (N,)
        Times [s].
    X : array_like, shape (N, 4)
        RealAIGym state (dq2 relative).

    Returns
    -------
    float
        [rad^2/s].

    Raises
    ------
    ValueError
        Bad shapes or non-finite values.
    """
    T, X = _traj(T, X)
    return float(np.sum(np.sum(X[:-1, 2:] ** 2, axis=1) * np.diff(T)))


def criteria(T: np.ndarray, X: np.ndarray, U: np.ndarray, L1: float, L2: float) -> dict[str, float]:
    """The five v2 criteria of one run.

    Parameters
    ----------
    T : array_like, shape (N,)
        Times [s].
    X : array_like, shape (N, 4)
        RealAIGym state (q2, dq2 relative to link 1).
    U : array_like, shape (N, 2)
        Applied torques [N.m], held from each row.
    L1, L2 : float
        Link lengths [m].

    Returns
    -------
    dict of str to float
        Keys :data:`CRITERIA`.

    Raises
    ------
    ValueError
        Bad shapes or non-finite values.
    """
    T, X, U = _traj(T, X, U)
    return {
        "swingup_time": swingup_time(T, X, L1, L2),
        "energy": energy(X, U),
        "torque_cost": torque_cost(T, U),
        "torque_smoothness": torque_smoothness(U),
        "velocity_cost": velocity_cost(T, X),
    }


def score_v2(values: Mapping[str, float], success: bool) -> float:
    """The v2 RealAI score ``success * (1 - (1/5) sum_i tanh(pi c_i / n_i))``.

    Parameters
    ----------
    values : mapping of str to float
        The five criteria (keys :data:`CRITERIA`).
    success : bool
        Swing-up time before the last sample.

    Returns
    -------
    float
        In [0, 1] for non-negative criteria.

    Raises
    ------
    ValueError
        A criterion is missing or not finite.
    """
    missing = [k for k in CRITERIA if k not in values]
    if missing:
        raise ValueError(f"values lacks the criteria {missing}; expected keys {list(CRITERIA)}")
    c = [float(values[k]) for k in CRITERIA]
    if not all(math.isfinite(v) for v in c):
        raise ValueError(f"criteria must be finite, got {dict(zip(CRITERIA, c, strict=True))}")
    penalty = sum(math.tanh(math.pi * v / NORMS[k]) for k, v in zip(CRITERIA, c, strict=True)) / len(CRITERIA)
    return float(success) * (1.0 - penalty)
