"""Stabilise a swing-up: time-varying LQR along the optimum, LQR balancing at the top.

The controller is sampled-data (zero-order hold at ``dt``), as in
``pendulab.simulate`` with a callable input and in a co-simulation master, so
it is designed in discrete time: at each sample the exact CasADi Jacobians
``model.functions["jac_rhs"]`` at the nominal state and torque are discretised
exactly for the hold (matrix exponential), and the Riccati recursion runs
backward from the balancing LQR's cost-to-go at the top. After the horizon
the balancing LQR (discrete algebraic Riccati equation on the same
linearisation at the goal) takes over. Torques saturate at the limit; passive
joints get zero.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..model.model import INPUT_NAMES, Model
from .lqr import UncontrollableError, discrete_tvlqr, lqr_balance, wrap_state_error
from .swingup.solve import SwingUpResult

__all__ = ["TrackingController", "tvlqr", "default_weights"]


def default_weights(model: Model, torque_limit: float) -> tuple[np.ndarray, np.ndarray]:
    """State and input weights (Q (nx, nx), R scalar-per-actuator) used when none are given.

    Angles 10 /rad^2, link rates 1 /(rad/s)^2; spring lengths 100 /m^2 and
    rates 0.1 /(m/s)^2 (springs are stiff and need little control); R makes
    a torque at the limit cost as much as a 1/sqrt(10) rad angle error.
    """
    if model.kind == "rigid":
        q = [10.0, 10.0, 1.0, 1.0]
    else:
        q = [10.0, 10.0, 100.0, 100.0, 1.0, 1.0, 0.1, 0.1]
    return np.diag(q), np.array(1.0 / torque_limit**2)


@dataclass(frozen=True)
class TrackingController:
    """Sampled-data feedback ``u(t, x)`` -> (tau1, tau2) [N.m]; call it like a function.

    It is a :class:`pendulab.control.sampled.SampledController`, so
    :func:`pendulab.cosim.master` drives it through an FMU as well.

    Attributes
    ----------
    dt : float
        Sample time [s]; ``pendulab.simulate(..., dt=dt, u=controller)`` holds it.
    t_nom : ndarray, shape (M,)
        Sample times along the nominal trajectory [s].
    x_nom : ndarray, shape (M, nx)
    u_nom : ndarray, shape (M, 2)
    K : ndarray, shape (M, n_act, nx)
        Time-varying gains on the actuated torques.
    K_top : ndarray, shape (n_act, nx)
        Balancing gain at the goal.
    goal : ndarray, shape (nx,)
    actuated : tuple of int
    torque_limit : float
    state_names : tuple of str
        Names of the state entries (angle differences are wrapped).
    """

    dt: float
    t_nom: np.ndarray
    x_nom: np.ndarray
    u_nom: np.ndarray
    K: np.ndarray
    K_top: np.ndarray
    goal: np.ndarray
    actuated: tuple[int, ...]
    torque_limit: float
    state_names: tuple[str, ...]
    u_goal: np.ndarray = field(default_factory=lambda: np.zeros(2))

    @property
    def sample_time(self) -> float:
        """Sample time [s] (:class:`pendulab.control.sampled.SampledController` protocol)."""
        return self.dt

    @property
    def input_names(self) -> tuple[str, ...]:
        """Both torques: a passive joint gets zero (SampledController protocol)."""
        return INPUT_NAMES

    def reset(self) -> None:
        """Stateless: nothing to forget (SampledController protocol)."""

    @property
    def horizon(self) -> float:
        return float(self.t_nom[-1] + self.dt) if len(self.t_nom) else 0.0

    def __call__(self, t: float, x: np.ndarray) -> np.ndarray:
        act = list(self.actuated)
        k = int(math.floor(t / self.dt + 1e-6))
        u = np.zeros(2)
        if k < len(self.t_nom):
            u[act] = self.u_nom[k, act] - self.K[k] @ wrap_state_error(x - self.x_nom[k], self.state_names)
        else:
            u[act] = self.u_goal[act] - self.K_top @ wrap_state_error(x - self.goal, self.state_names)
        return np.clip(u, -self.torque_limit, self.torque_limit)


def tvlqr(
    result: SwingUpResult,
    dt: float = 0.01,
    Q: np.ndarray | None = None,
    R: np.ndarray | float | None = None,
) -> TrackingController:
    """Time-varying LQR along ``result`` handing over to balancing LQR at the goal.

    Parameters
    ----------
    result : SwingUpResult
        A successful swing-up (its goal must be an equilibrium with zero torque).
    dt : float
        Controller sample time [s]; the NLP interval should be a multiple of it.
    Q : ndarray, shape (nx, nx), or None
        State weight (default :func:`default_weights`).
    R : float or ndarray, shape (n_act, n_act), or None
        Input weight on the actuated torques.

    Raises
    ------
    ValueError
        If the result failed, dt is not positive, or the goal is not
        stabilisable with the actuated torques.
    """
    if not result.success:
        raise ValueError(f"result must be a successful swing-up to track, got status {result.status!r}")
    if not (isinstance(dt, (int, float)) and math.isfinite(dt) and dt > 0):
        raise ValueError(f"dt must be a positive sample time [s], got {dt!r}")
    pb = result.problem
    model = pb.model
    act = list(pb.actuated)
    Qd, Rd = default_weights(model, pb.torque_limit)
    Q = Qd if Q is None else np.asarray(Q, dtype=float)
    R = Rd if R is None else R
    R = np.atleast_2d(np.asarray(R, dtype=float)) * (np.eye(len(act)) if np.ndim(R) == 0 else 1.0)
    if Q.shape != (model.nx, model.nx):
        raise ValueError(f"Q must have shape ({model.nx}, {model.nx}), got {Q.shape}")
    if R.shape != (len(act), len(act)):
        raise ValueError(f"R must have shape ({len(act)}, {len(act)}) for actuation {pb.actuation!r}, got {R.shape}")
    goal = pb.target
    try:
        top = lqr_balance(model, pb.actuation, Q, R, dt, at=goal)
    except UncontrollableError as exc:
        raise ValueError(f"the goal is not stabilisable with actuation {pb.actuation!r}: {exc}") from exc

    M = max(1, int(round(result.horizon / dt)))
    t_nom = np.arange(M) * dt
    x_nom = result.x_at(t_nom)
    # The nominal torque of a sample is the one held at its middle (robust to grid round-off).
    u_nom = result.u_at(t_nom + 0.5 * dt)
    K = discrete_tvlqr(model, result.x_at(t_nom + 0.5 * dt), u_nom, dt, Q, R, top.P, actuation=pb.actuation)
    return TrackingController(dt, t_nom, x_nom, u_nom, K, top.K, goal, tuple(act), pb.torque_limit, model.state_names)
