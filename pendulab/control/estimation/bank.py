"""Unknown delay and torque response: a bank of hypotheses scored by innovation likelihood, then one EKF."""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..._inputs import checked
from ...model.model import INPUT_NAMES, Model
from .ekf import ExtendedKalmanFilter, delay_steps

__all__ = ["MultipleModelEstimator"]


class MultipleModelEstimator:
    """A bank of delay and torque-response hypotheses, picked by innovation likelihood, then one EKF.

    From the known start state ``x0`` (at rest), each response hypothesis ``k_j`` runs the model open loop with
    the torques actually commanded; hypothesis ``(n, k_j)`` predicts the measurement ``x_j(t_{i-n})``. Over the
    first ``window`` seconds the Gaussian log-likelihood of every hypothesis accumulates (measurement sigmas of
    the filter); the estimate meanwhile is the current state of the leading hypothesis. At the window's end the
    leading hypothesis is locked and the EKF (:class:`ExtendedKalmanFilter`, with that delay and response) takes
    over, started from the hypothesis' state at the measurement's time.

    Parameters
    ----------
    model : Model
        Design model.
    sample_time : float
        [s].
    delays : sequence of float
        Candidate measurement delays [s] (e.g. 0 ... 0.04 s every 2 ms).
    responses : sequence of float
        Candidate torque responses ``k`` in (0, 2].
    window : float
        Identification window [s] from the start.
    accel_std : float
        Model-error allowance [rad/s^2 or m/s^2] of the open-loop predictions: the measurement ``t`` seconds from
        the start gets ``0.5 accel_std t^2`` added to its position sigmas and ``accel_std t`` to its rate sigmas
        (the same for every hypothesis), so the early samples (the onset of motion, which fixes the delay) weigh
        most and model errors accumulated later do not pick the delay.
    **ekf_options
        Passed to :class:`ExtendedKalmanFilter` (``measured``, ``measurement_std``, ``process_std``,
        ``torque_limit``, ``disturbance``, ``x0`` ...).

    Raises
    ------
    ValueError
        Empty or invalid candidate lists, non-positive ``window``, or what the EKF raises.

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.control import MultipleModelEstimator
    >>> model = pl.rigid()
    >>> traj = pl.simulate(model, model.state(), 0.5, dt=0.01, u=[3.0, 0.0])  # a torque step from hanging at rest
    >>> y = np.vstack([traj.x[:3], traj.x[:-3]])[: len(traj.t)]  # sensors lagging 3 samples (30 ms)
    >>> bank = MultipleModelEstimator(model, 0.01, delays=[0.0, 0.01, 0.02, 0.03, 0.04], window=0.3)
    >>> for t, yk in zip(traj.t, y):
    ...     x_hat = bank.update(t, yk, [3.0, 0.0])
    >>> bank.hypothesis, bank.locked  # (delay [s], torque response k); then the EKF runs with that delay
    ((0.03, 1.0), True)
    """

    @checked()
    def __init__(
        self,
        model: Model,
        sample_time: float,
        *,
        delays: Sequence[float] = (0.0,),
        responses: Sequence[float] = (1.0,),
        window: float = 0.2,
        accel_std: float = 0.0,
        **ekf_options: Any,
    ) -> None:
        for key in ("delay", "response"):
            if key in ekf_options:
                raise ValueError(
                    f"{key} is chosen by the bank; give the candidates as {key}s=..., not {key}={ekf_options[key]!r}"
                )
        self.ekf = ExtendedKalmanFilter(model, sample_time, **ekf_options)
        h = self.ekf.sample_time
        if isinstance(delays, (int, float)) or len(delays) == 0:
            raise ValueError(f"delays must be a non-empty sequence of delays [s], got {delays!r}")
        if isinstance(responses, (int, float)) or len(responses) == 0:
            raise ValueError(f"responses must be a non-empty sequence of torque responses k, got {responses!r}")
        self.delays = np.array(sorted({delay_steps(d, h) for d in delays}), dtype=int)
        ks = [float(k) for k in responses]
        if not all(np.isfinite(k) and 0.0 < k <= 2.0 for k in ks):
            raise ValueError(f"responses must be torque responses k in (0, 2], got {list(responses)!r}")
        self.responses = np.array(ks)
        self.window_steps = max(1, int(round(float(window) / h)))
        a = float(accel_std)
        if not (np.isfinite(a) and a >= 0.0):
            raise ValueError(f"accel_std must be a finite model-error allowance >= 0 [rad/s^2], got {accel_std!r}")
        self.accel_std = a
        rate = np.array([n.startswith(("omega", "v")) for n in self.ekf.measured])
        t_w = np.arange(self.window_steps + 1) * h
        grow = np.where(rate[None, :], a * t_w[:, None], 0.5 * a * t_w[:, None] ** 2)  # (window + 1, ny)
        self._w_t = 1.0 / (np.sqrt(np.diag(self.ekf.R))[None, :] + grow) ** 2  # likelihood weights by prediction time
        self.model = model
        self.sample_time = h
        self.ekf.set_hypothesis(int(self.delays.max()), 1.0)  # compile the longest rollout once
        self._bank_step = self.ekf._step.map(len(self.responses)) if len(self.responses) > 1 else self.ekf._step
        self.reset()

    @property
    def hypothesis(self) -> tuple[float, float]:
        """The leading (or locked) hypothesis: delay [s] and torque response ``k``."""
        i, j = np.unravel_index(int(np.argmax(self.loglik)), self.loglik.shape)
        return float(self.delays[i] * self.sample_time), float(self.responses[j])

    @property
    def locked(self) -> bool:
        """True once the identification window is over and the EKF runs."""
        return self._locked

    @property
    def d_hat(self) -> np.ndarray:
        """The EKF's disturbance estimate [N.m] (zeros before the lock)."""
        return self.ekf.d_hat if self._locked else np.zeros(len(INPUT_NAMES))

    def reset(self, x0: Any = None) -> None:
        """Back to the start state (``x0`` or the constructor's), every hypothesis equally likely.

        Parameters
        ----------
        x0 : array_like, shape (nx,), optional
            Start state of this run (the hypotheses' open-loop predictions start there), as
            :meth:`ExtendedKalmanFilter.reset` takes it.
        """
        self.ekf.reset(x0)
        start = self.ekf.z[: self.model.nx].copy()  # x0, or the constructor's start state
        J = len(self.responses)
        z0 = np.concatenate([start, np.zeros(self.ekf.nz - self.model.nx)])  # zero disturbance while identifying
        self._X = np.tile(z0[:, None], (1, J))  # current open-loop states, one column per response
        self._traj: list[np.ndarray] = [self._X.copy()]  # their history, one (nx, J) per sample
        self._ua = np.zeros((len(INPUT_NAMES), J))
        self._u_cmd: list[np.ndarray] = []
        self.loglik = np.zeros((len(self.delays), J))
        self._locked = False
        self.k = 0
        self.x_hat = start

    def update(self, t: float, y: Any, u: Any = None) -> np.ndarray:
        """One step of the bank (inside the window) or of the locked EKF.

        Parameters
        ----------
        t : float
            Time [s].
        y : array_like
            Measurement (as :meth:`ExtendedKalmanFilter.update`).
        u : array_like, shape (2,), optional
            Torques commanded over the interval that ends now (``None`` on the first call).

        Returns
        -------
        ndarray, shape (nx,)
            Current-state estimate.

        Raises
        ------
        ValueError
            Wrong shape or non-finite ``y`` or ``u``.
        """
        if self._locked:
            self.x_hat = self.ekf.update(t, y, u)
            return self.x_hat
        ym = self.ekf._measurement(y)
        if u is not None and self.k > 0:
            uc = np.asarray(u, dtype=float).reshape(-1)
            if uc.shape != (len(INPUT_NAMES),) or not np.all(np.isfinite(uc)):
                raise ValueError(f"u must be finite torques (tau1, tau2) [N.m] of shape (2,), got {np.asarray(u).tolist()!r}")
            self._u_cmd.append(uc)
            lim = self.ekf.torque_limit[:, None]
            self._ua = np.clip(self._ua + self.responses[None, :] * (uc[:, None] - self._ua), -lim, lim)
            self._X = np.asarray(self._bank_step(self._X, self._ua)).reshape(self.ekf.nz, -1)
            self._traj.append(self._X.copy())
        i_now = len(self._traj) - 1
        idx = self.ekf._idx
        w = self._w_t[min(i_now, len(self._w_t) - 1)]
        for a, n in enumerate(self.delays):
            i_pred = max(i_now - n, 0)
            r = ym[:, None] - self._traj[i_pred][idx]  # (ny, J)
            self.loglik[a] -= 0.5 * (w[:, None] * r * r).sum(axis=0)  # Gaussian log-density (same sigmas for all)
        self.k += 1
        a, j = np.unravel_index(int(np.argmax(self.loglik)), self.loglik.shape)
        self.x_hat = self._X[: self.model.nx, j].copy()
        if self.k >= self.window_steps:
            self._lock(int(a), int(j))
        return self.x_hat

    def _lock(self, a: int, j: int) -> None:
        """Hand over to the EKF with hypothesis (delays[a], responses[j]), its state at the measurement's time."""
        n, k = int(self.delays[a]), float(self.responses[j])
        ekf = self.ekf
        ekf.set_hypothesis(n, k)
        i_now = len(self._traj) - 1
        ekf.reset(self._traj[max(i_now - n, 0)][: self.model.nx, j])
        ekf.k = self.k
        # Replay the applied torques of hypothesis j so the EKF's history and torque state match the bank's.
        ekf.u_applied = np.zeros(len(INPUT_NAMES))
        ekf._hist = deque(maxlen=max(n, 1) + 1)
        for uc in self._u_cmd:
            ekf.apply_command(uc)
        ekf.x_hat = self._X[: self.model.nx, j].copy()
        self._locked = True
