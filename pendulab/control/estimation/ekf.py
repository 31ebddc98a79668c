"""The extended Kalman filter of a pendulab model: RK4 step, AD Jacobians, delay compensation, torque response."""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from typing import Any, Protocol, runtime_checkable

import casadi as ca
import numpy as np

from ..._checks import bounded_int, check_model
from ..._inputs import MAGNITUDE, checked
from ...analysis.linearize import linearize
from ...model.model import INPUT_NAMES, Model

__all__ = ["StateEstimator", "ExtendedKalmanFilter", "EstimationError", "delay_steps", "MAX_DELAY_STEPS", "STD_RANGE"]

#: Longest measurement delay [samples] a filter keeps a torque history for.
MAX_DELAY_STEPS: int = 200

#: Admissible non-zero standard deviations: their squares (the covariances the filter works with) and the
#: ratios of those must stay normal doubles (1e-200 squared underflows to 0, 1e200 squared overflows).
STD_RANGE: tuple[float, float] = MAGNITUDE


#: Largest magnitude of a measured state entry [rad, rad/s, m, m/s] or a torque [N.m] the filter takes: far
#: beyond any double pendulum, and small enough that their squares in the covariance update stay finite.
MAX_MAGNITUDE: float = 1e6

#: Largest ``sample_time`` times the fastest rate of the model at the prior (largest |eigenvalue| of its
#: linearization): classic RK4 is stable up to 2.78; beyond, the prediction itself diverges.
MAX_STEP_RATE: float = 2.5


class EstimationError(RuntimeError):
    """A filter step produced a non-finite estimate or covariance (or a singular innovation covariance).

    The filter is left as it was before the step: nothing non-finite is ever returned or kept.
    """


@runtime_checkable
class StateEstimator(Protocol):
    """What a controller wrapper, cosim master or gym observation pipeline needs from an estimator.

    Parameters
    ----------
    *args, **kwargs
        Not used (a ``Protocol``).

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.control import EstimatedController, ExtendedKalmanFilter, StateEstimator, balance_controller
    >>> class Encoders:  # any object with reset() and update(t, y, u) is a StateEstimator
    ...     def reset(self):
    ...         pass
    ...     def update(self, t, y, u=None):
    ...         return np.asarray(y, dtype=float)  # trust the measurement as it is
    >>> isinstance(Encoders(), StateEstimator), isinstance(ExtendedKalmanFilter(pl.rigid(), 0.01), StateEstimator)
    (True, True)
    >>> ctrl = EstimatedController(balance_controller(pl.rigid(), 0.01), Encoders())
    >>> np.round(ctrl(0.0, [np.pi + 0.01, np.pi, 0.0, 0.0]), 2)  # the LQR fed by the estimate
    array([-0.39,  0.  ])
    """

    def reset(self) -> None:
        """Forget the run: back to the prior at the start state."""

    def update(self, t: float, y: np.ndarray, u: np.ndarray | None = None) -> np.ndarray:
        """State estimate from a measurement and the torque commanded since the last call.

        Parameters
        ----------
        t : float
            Time [s].
        y : ndarray
            Measurement.
        u : ndarray, shape (2,), optional
            (tau1, tau2) [N.m] commanded over the interval that ends at ``t``; None on the first call.

        Returns
        -------
        ndarray, shape (nx,)
            Current-state estimate.
        """


@checked()
def delay_steps(delay: float, sample_time: float) -> int:
    """Samples of a measurement delay, ``int(delay / sample_time)`` as RealAIGym's simulator counts them (to 1e-9).

    Parameters
    ----------
    delay : float
        Delay [s], >= 0.
    sample_time : float
        [s].

    Returns
    -------
    int
        Whole samples of delay.

    Raises
    ------
    ValueError
        Negative or non-finite ``delay``, or more than :data:`MAX_DELAY_STEPS` samples.
    """
    d = float(delay)
    if not np.isfinite(d) or d < 0.0:
        raise ValueError(f"delay must be a finite number of seconds >= 0, got {delay!r}")
    n = int(d / sample_time + 1e-9)
    return bounded_int("delay [samples]", n, low=0, high=MAX_DELAY_STEPS, why="the filter keeps one torque per sample of delay")


def _std_vector(name: str, value: Any, n: int, *, allow_zero: bool) -> np.ndarray:
    """A vector of n standard deviations (a scalar is broadcast), checked."""
    a = np.asarray(value, dtype=float)
    if a.ndim == 0:
        a = np.full(n, float(a))
    if a.shape != (n,):
        raise ValueError(f"{name} must be a scalar or have shape ({n},), got shape {a.shape}")
    if not np.all(np.isfinite(a)) or np.any(a < 0.0) or (not allow_zero and np.any(a == 0.0)):
        what = ">= 0" if allow_zero else "> 0"
        raise ValueError(f"{name} must be finite standard deviations {what}, got {a.tolist()!r}")
    lo, hi = STD_RANGE
    nonzero = a[a != 0.0]
    if np.any(nonzero < lo) or np.any(nonzero > hi):
        raise ValueError(
            f"{name} must be standard deviations in [{lo:g}, {hi:g}]{' or 0' if allow_zero else ''} (their squares are the "
            f"filter's covariances and must stay normal doubles), got {a.tolist()!r}"
        )
    return a


def _discrete_functions(model: Model, h: float, n_dist: int, n_roll: int) -> tuple[ca.Function, ca.Function, ca.Function]:
    """One RK4 step of ``z = (x, d)`` with its Jacobian, the plain step, and a rollout of ``n_roll`` steps."""
    nx = model.nx
    p = ca.DM(model.p)
    z = ca.SX.sym("z", nx + n_dist)
    u = ca.SX.sym("u", len(INPUT_NAMES))
    x, d = z[:nx], z[nx:]
    ue = u + d if n_dist else u

    def f(xx: ca.SX) -> ca.SX:
        return model.functions["rhs"](xx, ue, p)

    k1 = f(x)
    k2 = f(x + 0.5 * h * k1)
    k3 = f(x + 0.5 * h * k2)
    k4 = f(x + h * k3)
    x_next = x + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
    z_next = ca.vertcat(x_next, d) if n_dist else x_next
    step_jac = ca.Function("ekf_step_jac", [z, u], [z_next, ca.jacobian(z_next, z)], {"cse": True})
    step = ca.Function("ekf_step", [z, u], [z_next], {"cse": True})
    roll = step.mapaccum("ekf_rollout", n_roll) if n_roll > 0 else step
    return step_jac, step, roll


class ExtendedKalmanFilter:
    """Discrete-time extended Kalman filter of a pendulab model (rigid or elastic), with delay and torque response.

    Process model: classic RK4 at ``sample_time`` with the applied torque held (as RealAIGym's simulator and
    :func:`pendulab.evaluate.realai.simulate.rk4_rollout` step), plus white process noise. With
    ``disturbance=True`` the state is augmented by ``d`` (2,) [N.m], a random-walk torque added to (tau1, tau2).

    Parameters
    ----------
    model : Model
        Design model (its parameters are used as they are).
    sample_time : float
        Filter step [s] = the interval between :meth:`update` calls.
    measured : sequence of str, optional
        Names of the measured states (default: all, in state order); ``y`` holds them in this order.
    measurement_std : float or array_like, shape (len(measured),)
        Measurement noise sigmas [state units], > 0 (angles measured exactly still need a small sigma, e.g. 1e-4).
    process_std : float or array_like, shape (nx,)
        Process noise sigmas per sample [state units], >= 0.
    delay : float
        Known measurement delay [s] of the whole state: ``y(t_k) = x(t_k - n h)``, ``n = int(delay / h)``.
    response : float
        Torque response ``k`` in (0, 2]: ``u_applied = u_last + k (u_cmd - u_last)``; 1 = applied as commanded.
    torque_limit : float or array_like, shape (2,), optional
        Limit [N.m] the plant clips applied torques to (per joint; 0 for a passive joint). Default: none.
    disturbance : bool
        Augment the state with a disturbance torque per joint.
    disturbance_std : float or array_like, shape (2,)
        Random-walk sigmas of ``d`` per sample [N.m]; 0 on a joint fixes its ``d`` at 0.
    x0 : array_like, shape (nx,), optional
        Prior mean (default: the model's rest state, hanging).
    x0_std : float or array_like, shape (nx,)
        Prior sigmas [state units].

    Raises
    ------
    TypeError
        ``model`` is not a Model.
    ValueError
        Unknown state names, wrong shapes, negative (or, for measurements, zero) sigmas, a non-positive
        ``sample_time``, a negative delay, ``response`` outside (0, 2].

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.control import ExtendedKalmanFilter
    >>> model = pl.rigid()
    >>> traj = pl.simulate(model, model.state(theta1=0.5), 2.0, dt=0.01)  # a free swing
    >>> y = traj.x + np.random.default_rng(0).normal(0.0, [1e-4, 1e-4, 0.2, 0.2], traj.x.shape)  # noisy rate sensors
    >>> ekf = ExtendedKalmanFilter(model, 0.01, measurement_std=[1e-4, 1e-4, 0.2, 0.2], x0=traj.x[0])
    >>> x_hat = np.array([ekf.update(t, yk, [0.0, 0.0]) for t, yk in zip(traj.t, y)])
    >>> rms = lambda e: np.sqrt(np.mean(e[:, 2:] ** 2))
    >>> print(f"rate error: measured {rms(y - traj.x):.2f} rad/s, estimated {rms(x_hat - traj.x):.3f} rad/s")
    rate error: measured 0.21 rad/s, estimated 0.002 rad/s
    """

    @checked()
    def __init__(
        self,
        model: Model,
        sample_time: float,
        *,
        measured: Sequence[str] | None = None,
        measurement_std: Any = 1e-3,
        process_std: Any = 1e-3,
        delay: float = 0.0,
        response: float = 1.0,
        torque_limit: Any = None,
        disturbance: bool = False,
        disturbance_std: Any = 0.05,
        x0: Any = None,
        x0_std: Any = 1e-3,
    ) -> None:
        self.model = check_model(model)
        self.sample_time = float(sample_time)
        names = model.state_names
        if measured is None:
            measured = names
        if isinstance(measured, str) or not all(isinstance(n, str) for n in measured) or len(measured) == 0:
            raise ValueError(f"measured must be a non-empty sequence of state names from {list(names)}, got {measured!r}")
        unknown = [n for n in measured if n not in names]
        if unknown or len(set(measured)) != len(measured):
            raise ValueError(f"measured must name distinct states of {list(names)}, got {list(measured)!r}")
        self.measured = tuple(measured)
        self._idx = np.array([names.index(n) for n in self.measured])
        nx, nd = model.nx, (len(INPUT_NAMES) if disturbance else 0)
        self.nz = nx + nd
        self.disturbance = bool(disturbance)
        r = _std_vector("measurement_std", measurement_std, len(self.measured), allow_zero=False)
        q = _std_vector("process_std", process_std, nx, allow_zero=True)
        qd = _std_vector("disturbance_std", disturbance_std, len(INPUT_NAMES), allow_zero=True) if nd else np.zeros(0)
        self.R = np.diag(r**2)
        self.Q = np.diag(np.concatenate([q, qd]) ** 2)
        self.H = np.zeros((len(self.measured), self.nz))
        self.H[np.arange(len(self.measured)), self._idx] = 1.0
        self._angles = np.array([i for i, n in enumerate(self.measured) if n.startswith("theta")], dtype=int)
        self.x0 = model.state() if x0 is None else model.check_state(x0, "x0").astype(float)
        rate = float(np.max(np.abs(np.linalg.eigvals(linearize(model, self.x0).A))))
        if rate * self.sample_time > MAX_STEP_RATE:
            raise ValueError(
                f"sample_time {self.sample_time:g} s is too long for the filter's RK4 prediction: the model's fastest rate "
                f"at the prior is {rate:.4g} 1/s and sample_time x rate must be <= {MAX_STEP_RATE} "
                f"(sample_time <= {MAX_STEP_RATE / rate:.3g} s)"
            )
        x0s = _std_vector("x0_std", x0_std, nx, allow_zero=False)
        self.P0 = np.diag(np.concatenate([x0s, np.full(nd, 0.5)]) ** 2)
        if torque_limit is None:
            self.torque_limit = np.full(len(INPUT_NAMES), np.inf)
        else:
            self.torque_limit = _std_vector("torque_limit", torque_limit, len(INPUT_NAMES), allow_zero=True)
        self._roll_n = 0
        self.set_hypothesis(delay_steps(delay, self.sample_time), response)
        self.reset()

    # -- configuration ------------------------------------------------------------------
    def set_hypothesis(self, n_delay: int, response: float) -> None:
        """Set the delay [samples] and torque response ``k`` the filter assumes (the bank's choice).

        Parameters
        ----------
        n_delay : int
            Measurement delay [samples], 0 ... :data:`MAX_DELAY_STEPS`.
        response : float
            Torque response ``k`` in (0, 2].

        Raises
        ------
        ValueError
            Out of range.
        """
        n = bounded_int("n_delay", n_delay, low=0, high=MAX_DELAY_STEPS, why="the filter keeps one torque per sample of delay")
        k = float(response)
        if not (np.isfinite(k) and 0.0 < k <= 2.0):
            raise ValueError(f"response must be a torque response k in (0, 2], got {response!r}")
        self.n_delay, self.response = n, k
        if n > self._roll_n or not hasattr(self, "_step_jac"):
            self._roll_n = max(n, 1)
            self._step_jac, self._step, self._roll = _discrete_functions(
                self.model, self.sample_time, self.nz - self.model.nx, self._roll_n
            )

    # -- the estimator interface ----------------------------------------------------------
    def reset(self, x0: Any = None) -> None:
        """Back to the prior (mean ``x0`` or the constructor's, zero disturbance), empty torque history.

        Parameters
        ----------
        x0 : array_like, shape (nx,), optional
            New prior mean.
        """
        x = self.x0 if x0 is None else self.model.check_state(x0, "x0").astype(float)
        self.z = np.concatenate([x, np.zeros(self.nz - self.model.nx)])
        self.P = self.P0.copy()
        self.k = 0  # updates so far
        self.u_applied = np.zeros(len(INPUT_NAMES))
        self._hist: deque[np.ndarray] = deque(maxlen=max(self.n_delay, 1) + 1)
        self.x_hat = x.copy()
        self.nis = np.nan  # normalized innovation squared of the last update

    def apply_command(self, u: Any) -> np.ndarray:
        """Record a commanded torque: the applied one after the response model and the limit.

        Parameters
        ----------
        u : array_like, shape (2,)
            Commanded (tau1, tau2) [N.m].

        Returns
        -------
        ndarray, shape (2,)
            Applied torque [N.m].

        Raises
        ------
        ValueError
            ``u`` is not two finite torques.
        """
        uc = np.asarray(u, dtype=float).reshape(-1)
        if uc.shape != (len(INPUT_NAMES),) or not np.all(np.isfinite(uc)) or np.any(np.abs(uc) > MAX_MAGNITUDE):
            raise ValueError(
                f"u must be finite torques (tau1, tau2) [N.m] of shape (2,), at most {MAX_MAGNITUDE:g} in magnitude, "
                f"got {np.asarray(u).tolist()!r}"
            )
        ua = self.u_applied + self.response * (uc - self.u_applied)
        self.u_applied = np.clip(ua, -self.torque_limit, self.torque_limit)
        self._hist.append(self.u_applied.copy())
        return self.u_applied

    def update(self, t: float, y: Any, u: Any = None) -> np.ndarray:
        """One filter step: predict over the last interval, correct with ``y``, roll forward over the delay.

        Parameters
        ----------
        t : float
            Time [s] of the measurement (for the record; the filter counts samples).
        y : array_like, shape (len(measured),) or (nx,)
            Measured states (a full state vector is accepted and the measured entries taken).
        u : array_like, shape (2,), optional
            Torques (tau1, tau2) [N.m] commanded over the interval that ends now; ``None`` on the first call.

        Returns
        -------
        ndarray, shape (nx,)
            Estimate of the current state (after delay compensation).

        Raises
        ------
        ValueError
            Wrong shape or non-finite ``y`` or ``u``.
        EstimationError
            The step produced a non-finite estimate or covariance (e.g. a measurement or torque of 1e300,
            a sample time far beyond the dynamics' time scales); the filter is restored to its state
            before the call.
        """
        ym = self._measurement(y)
        saved = (self.z.copy(), self.P.copy(), self.k, self.u_applied.copy(), list(self._hist), self.x_hat.copy(), self.nis)
        try:
            with np.errstate(over="ignore", invalid="ignore"):
                x_hat = self._step_filter(ym, u)
        except np.linalg.LinAlgError as exc:
            x_hat, reason = None, f"singular innovation covariance ({exc})"
        else:
            reason = "a non-finite estimate or covariance"
        if x_hat is None or not (np.all(np.isfinite(self.z)) and np.all(np.isfinite(self.P)) and np.all(np.isfinite(x_hat))):
            self.z, self.P, self.k, self.u_applied, hist, self.x_hat, self.nis = saved
            self._hist.clear()
            self._hist.extend(hist)
            raise EstimationError(
                f"EKF update at t = {t!r} s gave {reason} (measurement {np.asarray(ym).tolist()!r}, torque "
                f"{None if u is None else np.asarray(u, dtype=float).tolist()!r}, sample time {self.sample_time:g} s); "
                "the filter is left as before the update"
            )
        return x_hat

    def _step_filter(self, ym: np.ndarray, u: Any) -> np.ndarray:
        """The update itself (see :meth:`update`), without the output check."""
        if u is not None and self.k > 0:
            self.apply_command(u)
        n = self.n_delay
        # The measurement belongs to sample k - n; before the delay has passed it is the start state at rest.
        if self.k - n >= 1:
            u_lag = self._hist[-(n + 1)] if len(self._hist) >= n + 1 else np.zeros(len(INPUT_NAMES))
            zn, A = self._step_jac(self.z, u_lag)
            self.z = np.asarray(zn).reshape(-1)
            A = np.asarray(A)
            self.P = A @ self.P @ A.T + self.Q
        innov = ym - self.H @ self.z
        if self._angles.size:
            innov[self._angles] = (innov[self._angles] + np.pi) % (2 * np.pi) - np.pi
        S = self.H @ self.P @ self.H.T + self.R
        PHt = self.P @ self.H.T
        gain = np.linalg.solve(S, PHt.T).T
        self.z = self.z + gain @ innov
        IKH = np.eye(self.nz) - gain @ self.H
        self.P = IKH @ self.P @ IKH.T + gain @ self.R @ gain.T  # Joseph form: stays symmetric positive
        self.nis = float(innov @ np.linalg.solve(S, innov))
        self.k += 1
        m = min(n, self.k - 1, len(self._hist))
        if m > 0:
            U = np.zeros((len(INPUT_NAMES), self._roll_n))
            U[:, :m] = np.array(list(self._hist)[-m:]).T
            X = np.asarray(self._roll(self.z, U))
            self.x_hat = X[: self.model.nx, m - 1].copy()
        else:
            self.x_hat = self.z[: self.model.nx].copy()
        return self.x_hat

    @property
    def d_hat(self) -> np.ndarray:
        """Estimated disturbance torque (tau1, tau2) [N.m] (zeros without ``disturbance``)."""
        return self.z[self.model.nx :].copy() if self.disturbance else np.zeros(len(INPUT_NAMES))

    def _measurement(self, y: Any) -> np.ndarray:
        a = np.asarray(y, dtype=float).reshape(-1)
        if a.shape == (self.model.nx,) and len(self.measured) != self.model.nx:
            a = a[self._idx]
        if a.shape != (len(self.measured),) or not np.all(np.isfinite(a)) or np.any(np.abs(a) > MAX_MAGNITUDE):
            raise ValueError(
                f"y must be finite measurements of {list(self.measured)} (or a full state of {self.model.nx}), at most "
                f"{MAX_MAGNITUDE:g} in magnitude, got {np.asarray(y).tolist()!r}"
            )
        return a
