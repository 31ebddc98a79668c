"""The measurement model of a closed loop: the controller sees a delayed, noisy copy of the plant's state.

One model for every pipeline that feeds a controller or an estimator (the scorecard's perturbed episode,
:func:`pendulab.cosim.cosim`, the Gymnasium environment): at each controller sample the true state ``x_k`` goes in,
``y_k = x_{k-n}`` comes out (the start state while ``k < n``), with Gaussian noise of standard deviation
``velocity_noise`` added to the measured link rates ``omega1, omega2`` (RealAIGym's velocity-measurement noise; the
angles, spring lengths and stretch rates are measured exactly).
"""

from __future__ import annotations

import math
from collections import deque
from typing import Any

import numpy as np

from .._checks import bounded_int

__all__ = ["MeasurementModel", "MAX_DELAY_SAMPLES"]

#: Longest delay [samples] of a measurement model (it keeps one state per sample of delay).
MAX_DELAY_SAMPLES = 100_000


class MeasurementModel:
    """Delay (whole samples) and Gaussian noise on the link rates between a plant and its controller.

    Parameters
    ----------
    velocity_noise : float
        Standard deviation [rad/s] of the noise added to ``omega1, omega2``, >= 0.
    delay : int
        Measurement delay [samples of the caller's loop], in [0, :data:`MAX_DELAY_SAMPLES`].
    seed : int or sequence of int, optional
        Seed of the noise generator that :meth:`reset` starts afresh when it is given no generator
        (so every run with the same seed draws the same noise).

    Attributes
    ----------
    velocity_noise : float
    delay : int
    seed : int, sequence of int or None

    Raises
    ------
    ValueError
        A negative or non-finite ``velocity_noise``, a ``delay`` that is not a whole number of samples in range.
    """

    def __init__(self, velocity_noise: float = 0.0, delay: int = 0, *, seed: Any = None) -> None:
        try:
            sigma = float(velocity_noise)
        except (TypeError, ValueError):
            sigma = math.nan
        if isinstance(velocity_noise, bool) or not (math.isfinite(sigma) and sigma >= 0.0):
            raise ValueError(f"velocity_noise must be a finite standard deviation >= 0 [rad/s], got {velocity_noise!r}")
        self.velocity_noise = sigma
        self.delay = bounded_int(
            "delay [samples]", delay, low=0, high=MAX_DELAY_SAMPLES, why="the measurement model keeps one state per sample"
        )
        self.seed = seed
        self._rng: np.random.Generator = np.random.default_rng(seed)
        self._hist: deque[np.ndarray] = deque(maxlen=self.delay + 1)

    @property
    def is_exact(self) -> bool:
        """True when the measurement is the state itself (no delay, no noise)."""
        return self.delay == 0 and self.velocity_noise == 0.0

    def reset(self, x0: Any, rng: np.random.Generator | None = None) -> None:
        """Start a run at ``x0``: the delay line holds the start state; the noise restarts.

        Parameters
        ----------
        x0 : array_like, shape (nx,)
            Start state (what a delayed measurement shows before the delay has passed).
        rng : numpy.random.Generator, optional
            Generator to draw the noise from (shared with the caller's other random draws); default a new
            generator from ``seed``.
        """
        x = np.array(x0, dtype=float).reshape(-1)
        self._rng = np.random.default_rng(self.seed) if rng is None else rng
        self._hist = deque([x] * (self.delay + 1), maxlen=self.delay + 1)

    def __call__(self, x: Any) -> np.ndarray:
        """The measurement of this sample: the state ``delay`` samples ago, rates noisy.

        Parameters
        ----------
        x : array_like, shape (nx,)
            True state now (rigid: ``theta1, theta2, omega1, omega2``; elastic: ``theta1, theta2, r1, r2,
            omega1, omega2, v1, v2``).

        Returns
        -------
        ndarray, shape (nx,)
            Measured state (a new array).
        """
        self._hist.append(np.array(x, dtype=float).reshape(-1))
        y = self._hist[0].copy()
        if self.velocity_noise > 0.0:
            nq = y.size // 2
            y[nq : nq + 2] += self.velocity_noise * self._rng.standard_normal(2)
        return y

    def __repr__(self) -> str:
        return f"MeasurementModel(velocity_noise={self.velocity_noise!r}, delay={self.delay!r}, seed={self.seed!r})"
