"""The observation pipeline of the Gymnasium environments: plant state -> measurement -> state estimate.

With ``measurement=`` (a :class:`~pendulab.evaluate.measurement.MeasurementModel`: delay in samples, Gaussian noise
on ``omega1, omega2``) the agent's observation is made from the measured state instead of the plant's; with
``estimator=`` (``"ekf"``, ``"mmae"`` or an object with ``reset`` and ``update``) from the estimator's state, which
is updated every step with the measurement and the torque held over the step. Reward, termination and
``env.state`` stay on the plant's true state.
"""

from __future__ import annotations

import copy
import inspect
from typing import Any

import numpy as np

from ..model.model import INPUT_NAMES, Model

__all__ = ["ObservationPipeline", "make_pipeline"]


class ObservationPipeline:
    """Measurement model and state estimator between a plant and an agent (one episode at a time).

    Parameters
    ----------
    measurement : MeasurementModel or None
        None: the measurement is the state.
    estimator : StateEstimator or None
        None: the observation is the measurement.

    Attributes
    ----------
    measured : ndarray, shape (nx,)
        The last measurement.
    estimate : ndarray, shape (nx,)
        The state the last observation was made from (the estimate, or the measurement without an estimator or
        once the estimate stopped being finite).
    diverged : bool
        The last estimate was not finite (the estimator diverged; the environment terminates the episode).
    """

    def __init__(self, measurement: Any, estimator: Any) -> None:
        self.measurement = measurement
        self.estimator = estimator
        self.measured = np.zeros(0)
        self.estimate = np.zeros(0)
        self.diverged = False

    def reset(self, x0: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """Start an episode at ``x0``: the delay line holds it, the estimator's prior is centred on it.

        Parameters
        ----------
        x0 : ndarray, shape (nx,)
            The plant's start state.
        rng : numpy.random.Generator
            The environment's generator (the measurement noise is drawn from it, so ``reset(seed=)`` seeds it).

        Returns
        -------
        ndarray, shape (nx,)
            The state to observe.
        """
        y = x0.copy()
        if self.measurement is not None:
            self.measurement.reset(x0, rng=rng)
            y = self.measurement(x0)
        self.measured = y
        self.estimate = y
        self.diverged = False
        if self.estimator is not None:
            _restart(self.estimator, x0)
            self.estimate = np.asarray(self.estimator.update(0.0, y, None), dtype=float).copy()
        return self.estimate

    def step(self, t: float, x: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """The state to observe after a step.

        Parameters
        ----------
        t : float
            Time [s] since the reset.
        x : ndarray, shape (nx,)
            The plant's state now.
        tau : ndarray, shape (2,)
            Torques (tau1, tau2) [N.m] held over the step that ended at ``t``.

        Returns
        -------
        ndarray, shape (nx,)
            Estimate (or measurement).
        """
        y = x.copy() if self.measurement is None else self.measurement(x)
        self.measured = y
        if self.estimator is None:
            self.estimate = y
            return y
        # A diverging estimator overflows on its way to a non-finite estimate: the env ends the episode instead.
        with np.errstate(over="ignore", invalid="ignore"):
            x_hat = np.asarray(self.estimator.update(t, y, tau), dtype=float).copy()
        self.diverged = not np.isfinite(x_hat).all()
        self.estimate = y if self.diverged else x_hat
        return self.estimate

    def copy(self) -> ObservationPipeline:
        """An independent pipeline with the same settings (one per lane of a vector environment).

        Returns
        -------
        ObservationPipeline
            Deep copies of the measurement model and the estimator.
        """
        return ObservationPipeline(copy.deepcopy(self.measurement), copy.deepcopy(self.estimator))


def _restart(estimator: Any, x0: np.ndarray) -> None:
    """``estimator.reset(x0)`` when its reset takes a start state (the EKF's does), else ``reset()``."""
    try:
        takes = bool(inspect.signature(estimator.reset).parameters)
    except (TypeError, ValueError):
        takes = False
    if takes:
        estimator.reset(x0)
    else:
        estimator.reset()


def make_pipeline(
    model: Model, dt: float, actuated: tuple[int, ...], torque_limit: float, estimator: Any, measurement: Any
) -> ObservationPipeline | None:
    """The environment's pipeline from its ``estimator`` and ``measurement`` options (None when both are None).

    Parameters
    ----------
    model : Model
        The environment's model (the design model of a named estimator).
    dt : float
        Sample time [s].
    actuated : tuple of int
        Indices of the driven torques in (tau1, tau2).
    torque_limit : float
        [N.m] of the driven torques.
    estimator : {"ekf", "mmae"}, StateEstimator or None
        Named estimators are built by :func:`~pendulab.control.robust.build_estimator` (start state: hanging at
        rest; :meth:`ObservationPipeline.reset` restarts it at each episode's start).
    measurement : MeasurementModel or None
        Delay [samples] and rate noise.

    Returns
    -------
    ObservationPipeline or None

    Raises
    ------
    ValueError
        An unknown estimator name.
    TypeError
        ``measurement`` not a MeasurementModel, ``estimator`` neither a name nor an object with reset/update.
    """
    if estimator is None and measurement is None:
        return None
    if measurement is not None:
        from ..evaluate.measurement import MeasurementModel

        if not isinstance(measurement, MeasurementModel):
            raise TypeError(
                "measurement must be a pendulab.evaluate.measurement.MeasurementModel (velocity noise, delay) or None, "
                f"got {type(measurement).__name__}"
            )
        measurement = copy.deepcopy(measurement)  # the environment owns its delay line
    est = None
    if estimator is not None:
        from ..control.robust import build_estimator

        limit = np.array([torque_limit if i in actuated else 0.0 for i in range(len(INPUT_NAMES))])
        est = build_estimator(estimator, model, dt, x0=model.rest_state(), torque_limit=limit)
    return ObservationPipeline(measurement, est)
