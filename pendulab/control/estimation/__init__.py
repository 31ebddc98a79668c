"""State estimation from the CasADi model: an extended Kalman filter with delay and torque-response models, and a filter bank.

* :class:`ExtendedKalmanFilter`: discrete-time EKF on the model's classic RK4 step at the sample time
  (Jacobians by CasADi AD, compiled once as CasADi Functions: no hand-typed derivatives). Measurement model:
  a chosen subset of states with Gaussian noise of given sigmas. A known measurement delay of ``n`` samples is
  handled by keeping the applied-torque history: the filter estimates the state at the measurement's time,
  then rolls the model forward over the delay with the torques already sent. A first-order torque response
  ``u_applied = u_last + k (u_cmd - u_last)`` (clipped at the torque limit) maps commands to applied torques.
  Optionally the state is augmented with a random-walk disturbance torque on each joint (offset-free
  estimation: model errors, friction, torque pulses).
* :class:`MultipleModelEstimator`: where the delay and the response ``k`` are unknown, a bank of hypotheses
  ``(n, k)`` scored by their Gaussian innovation likelihood over an identification window from the known start
  state; then the EKF of the most likely hypothesis takes over.

Both keep one small interface, :class:`StateEstimator`: ``reset()``, ``update(t, y, u) -> x_hat``, where ``u``
is the torque (tau1, tau2) commanded over the interval that ends at ``t`` (``None`` on the first call). A
controller is wrapped with :class:`pendulab.control.robust.EstimatedController`.
"""

from __future__ import annotations

from .bank import MultipleModelEstimator
from .ekf import MAX_DELAY_STEPS, EstimationError, ExtendedKalmanFilter, StateEstimator, delay_steps

__all__ = [
    "StateEstimator",
    "ExtendedKalmanFilter",
    "MultipleModelEstimator",
    "EstimationError",
    "delay_steps",
    "MAX_DELAY_STEPS",
]
