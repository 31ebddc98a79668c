"""What the real robot's sensing and loop timing look like, measured from its records.

The v3-hardware protocol (:mod:`pendulab.evaluate.realai.v3_hardware`) feeds its controllers what RealAIGym's
design C.1 robot gives them; every number comes from the measured records here, none is assumed:

* **encoder quantization**: the T-motor's position reply steps by a fixed increment; it is the smallest
  non-zero change between consecutive samples, and every other change is a whole multiple of it;
* **velocity noise**: the motor's velocity reply against a smoothed derivative of the position
  (Savitzky-Golay, cubic, 21 samples = 42 ms), taken where that derivative is slow (< 0.5 rad/s: there the
  smoother's own error, which grows with acceleration, is negligible); the residual's standard deviation and
  its lag-1 autocorrelation (about -0.45: the reply is close to a difference of quantized positions, whose
  noise alternates in sign from sample to sample);
* **loop intervals**: the differences of the record's time stamps (the 2 ms loop and its overruns);
* **torque reading**: its step (the smallest non-zero change of the readings) and its noise, the reading
  minus a Savitzky-Golay smoothing of it (quadratic, 11 samples = 22 ms).

Only the excitation records may be measured (:data:`~pendulab.identify.datasets.C1_EXCITATION`): the blind
records (:data:`~pendulab.identify.datasets.C1_BLIND`) are refused, as they are for identification.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cache
from typing import Any

import numpy as np
from scipy.signal import savgol_filter

from .datasets import C1_BLIND, C1_EXCITATION, c1_record
from .records import Record

__all__ = ["SensingModel", "measure_sensing", "c1_sensing", "VELOCITY_WINDOW", "TORQUE_WINDOW", "SLOW_RATE"]

#: Savitzky-Golay window [samples] (cubic) of the position derivative the velocity reply is compared with.
VELOCITY_WINDOW: int = 21
#: Savitzky-Golay window [samples] (quadratic) of the smoothing the torque reading's noise is measured against.
TORQUE_WINDOW: int = 11
#: The velocity noise is measured where the smoothed position derivative is below this [rad/s].
SLOW_RATE: float = 0.5
#: Samples dropped at each end of a record (where the Savitzky-Golay windows are one-sided).
_EDGE: int = 25


@dataclass(frozen=True)
class SensingModel:
    """The robot's measured sensing and loop timing.

    Attributes
    ----------
    position_step : float
        Encoder quantization step of the joint angles [rad].
    position_multiple_error : float
        Largest deviation of a position change from a whole multiple of ``position_step`` [steps]
        (close to 0: the increments are quantized).
    velocity_noise : tuple of float
        Standard deviation of the velocity reply's noise, joints 1 and 2 (joint rates, ``q2`` relative) [rad/s].
    velocity_correlation : tuple of float
        Lag-1 autocorrelation of that noise, joints 1 and 2 [-].
    torque_step : float
        Step of the torque reading [N.m].
    torque_noise : tuple of float
        Standard deviation of the torque reading's noise, joints 1 and 2 [N.m].
    intervals : ndarray, shape (n,)
        Every loop interval of the measured records [s] (the distribution the protocol draws from).
    records : tuple of str
        Names of the records measured.
    """

    position_step: float
    position_multiple_error: float
    velocity_noise: tuple[float, float]
    velocity_correlation: tuple[float, float]
    torque_step: float
    torque_noise: tuple[float, float]
    intervals: np.ndarray = field(repr=False)
    records: tuple[str, ...] = ()

    def interval_stats(self) -> dict[str, float]:
        """Summary of the loop-interval distribution.

        Returns
        -------
        dict of str to float
            ``median``, ``min``, ``max``, ``p99``, ``p999`` [s], ``overrun_fraction`` (intervals above 2.05 ms)
            and ``n`` (number of intervals).
        """
        iv = np.asarray(self.intervals, dtype=float)
        return {
            "n": float(iv.size),
            "median": float(np.median(iv)),
            "min": float(iv.min()),
            "max": float(iv.max()),
            "p99": float(np.percentile(iv, 99.0)),
            "p999": float(np.percentile(iv, 99.9)),
            "overrun_fraction": float(np.mean(iv > 0.00205)),
        }

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready values (the interval distribution as its summary).

        Returns
        -------
        dict
            The attributes, units in the key names' docs (:class:`SensingModel`).
        """
        return {
            "position_step": self.position_step,
            "position_multiple_error": self.position_multiple_error,
            "velocity_noise": list(self.velocity_noise),
            "velocity_correlation": list(self.velocity_correlation),
            "torque_step": self.torque_step,
            "torque_noise": list(self.torque_noise),
            "intervals": self.interval_stats(),
            "records": list(self.records),
        }


def _step(changes: np.ndarray) -> tuple[float, float]:
    """Quantization step of a signal from its changes: the smallest non-zero change, refined over the changes up to 5
    steps; and the largest deviation of any change from a whole multiple of it [steps]."""
    d = np.abs(np.asarray(changes, dtype=float)).ravel()
    d = d[d > 0.0]
    if d.size == 0:
        raise ValueError("the records never change: no quantization step to measure")
    first = float(d.min())
    mult = np.round(d / first)
    small = (mult >= 1) & (mult <= 5)
    step = float(np.median(d[small] / mult[small]))
    dev = float(np.max(np.abs(d / step - np.round(d / step))))
    return step, dev


def measure_sensing(records: Sequence[Record]) -> SensingModel:
    """Measure the sensing and loop timing of a robot from its records.

    Parameters
    ----------
    records : sequence of Record
        Records with measured rates (``qd``) and the *measured* torque as ``tau``
        (:data:`~pendulab.identify.records.REALAIGYM_COLUMNS`), each longer than ``2 * 25 + 21`` samples.

    Returns
    -------
    SensingModel
        The measured values (see the module docstring for the methods).

    Raises
    ------
    ValueError
        No records, a record without rates or too short, a C.1 blind-test record
        (:data:`~pendulab.identify.datasets.C1_BLIND`), or signals that never change.
    """
    recs = list(records)
    if not recs:
        raise ValueError("records: measure_sensing needs at least one record")
    blind = [r.name for r in recs if r.name in C1_BLIND]
    if blind:
        raise ValueError(f"records: {blind} are the C.1 blind test (C1_BLIND); never measure anything on them")
    for r in recs:
        if r.qd is None:
            raise ValueError(f"records: {r.name!r} has no measured rates (qd); the velocity noise needs them")
        if len(r.t) < 2 * _EDGE + VELOCITY_WINDOW:
            raise ValueError(f"records: {r.name!r} has {len(r.t)} samples, fewer than {2 * _EDGE + VELOCITY_WINDOW}")
    pos_step, pos_dev = _step(np.concatenate([np.diff(r.q, axis=0).ravel() for r in recs]))
    # the torque readings of a record, sorted: neighbouring distinct values differ by whole steps
    tau_step, _ = _step(np.concatenate([np.diff(np.unique(r.tau[:, j])) for r in recs for j in range(2)]))
    vel_res: list[list[np.ndarray]] = [[], []]
    vel_pairs: list[list[np.ndarray]] = [[], []]
    tau_res: list[list[np.ndarray]] = [[], []]
    for r in recs:
        h = float(np.median(np.diff(r.t)))
        sl = slice(_EDGE, len(r.t) - _EDGE)
        for j in range(2):
            deriv = savgol_filter(r.q[:, j], VELOCITY_WINDOW, 3, deriv=1, delta=h)
            res = (r.qd[:, j] - deriv)[sl]
            slow = np.abs(deriv[sl]) < SLOW_RATE
            vel_res[j].append(res[slow])
            both = slow[1:] & slow[:-1]
            vel_pairs[j].append(np.column_stack([res[:-1][both], res[1:][both]]))
            tau_res[j].append((r.tau[:, j] - savgol_filter(r.tau[:, j], TORQUE_WINDOW, 2))[sl])
    v_std = tuple(float(np.std(np.concatenate(vel_res[j]))) for j in range(2))
    v_rho = tuple(float(np.corrcoef(np.concatenate(vel_pairs[j]).T)[0, 1]) for j in range(2))
    t_std = tuple(float(np.std(np.concatenate(tau_res[j]))) for j in range(2))
    intervals = np.concatenate([np.diff(r.t) for r in recs])
    return SensingModel(
        position_step=pos_step,
        position_multiple_error=pos_dev,
        velocity_noise=(v_std[0], v_std[1]),
        velocity_correlation=(v_rho[0], v_rho[1]),
        torque_step=tau_step,
        torque_noise=(t_std[0], t_std[1]),
        intervals=intervals,
        records=tuple(r.name for r in recs),
    )


@cache
def c1_sensing() -> SensingModel:
    """Design C.1's sensing and timing, measured on its eight excitation records (never the blind test).

    Returns
    -------
    SensingModel
        :func:`measure_sensing` of :data:`~pendulab.identify.datasets.C1_EXCITATION`.
    """
    return measure_sensing([c1_record(s) for s in C1_EXCITATION])


def ma1_coefficients(std: float, correlation: float) -> tuple[float, float]:
    """Coefficients ``(c0, c1)`` of ``n_k = c0 e_k + c1 e_{k-1}`` (``e`` unit white noise) with the given std and lag-1
    autocorrelation (clipped to the MA(1) range [-0.5, 0.5]).

    Parameters
    ----------
    std : float
        Standard deviation of ``n`` (>= 0).
    correlation : float
        Lag-1 autocorrelation of ``n``.

    Returns
    -------
    tuple of float
        ``c0, c1`` (same unit as ``std``).
    """
    rho = min(0.5, max(-0.5, float(correlation)))
    a = 0.0 if abs(rho) < 1e-12 else (1.0 - math.sqrt(max(0.0, 1.0 - 4.0 * rho * rho))) / (2.0 * rho)
    c0 = float(std) / math.sqrt(1.0 + a * a)
    return c0, a * c0
