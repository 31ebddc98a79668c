"""From a measured record to samples a regression can use: uniform grid, zero-phase derivatives, saturation.

Decisions (each measured on RealAIGym's C.1 records, see ``docs/identification.md``):

* **Non-uniform stamps** (2.0-3.7 ms on the robot) are resampled onto a uniform grid at the
  record's median interval by linear interpolation; the few long intervals are far shorter than
  the motion's time scales (the excitation is below 5 Hz). Records sampled differently (A.0's
  sys-id runs at 2 ms beside one at 1.5 ms) are fitted together on one grid,
  :func:`common_interval`: the coarsest record's, so no record is given samples finer than its own.
* **Zero-phase differentiation**: the angles pass a zero-phase Butterworth low-pass (4th order,
  applied forwards and backwards, so no lag between angles, rates, accelerations and torques),
  then central differences give rates and accelerations. The torque passes the *same* filter for
  the regression, so both sides of ``tau = Y(q, q', q'') pi`` see the same attenuation.
* **Quantization**: the encoders step by ``2 pi / 2^14``-ish (C.1: 3.8e-4 rad) and the torque
  reading by 5.9e-3 N.m. Differentiating a staircase twice gives spikes; the low-pass removes
  them (the quantization noise left after the filter is reported, :attr:`Prepared.quantum`).
* **Saturation**: samples whose input torque reaches the stated limit are dropped from the
  regression together with a filter length around them (a saturated reading is not the torque
  that acted); a record more than half saturated is refused.
* **Edges**: a filter length at each end is dropped (the filter's start-up transient).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.signal import butter, sosfiltfilt

from .records import Record, RecordError

__all__ = ["Prepared", "prepare", "quantum", "common_interval", "DEFAULT_CUTOFF_HZ", "GRID_TOLERANCE"]

#: Default low-pass cutoff [Hz]: above the excitation's band, below the quantization noise (see the module docstring).
DEFAULT_CUTOFF_HZ = 8.0

#: Largest fraction of a record's samples that may be saturated.
MAX_SATURATED_FRACTION = 0.5

#: Records whose median intervals agree to this fraction keep their own grids (the output-error fit's tolerance).
GRID_TOLERANCE = 0.01


@dataclass(frozen=True)
class Prepared:
    """A record on a uniform grid with zero-phase derivatives.

    Attributes
    ----------
    name : str
        The record's name.
    t : numpy.ndarray, shape (n,)
        Uniform time grid [s].
    q, qd, qdd : numpy.ndarray, shape (n, 2)
        Filtered joint angles [rad], rates [rad/s] and accelerations [rad/s^2].
    tau_filtered : numpy.ndarray, shape (n, 2)
        Input torque through the same filter [N.m] (for the regression).
    tau : numpy.ndarray, shape (n, 2)
        Input torque resampled, not filtered [N.m] (for simulation).
    q_measured : numpy.ndarray, shape (n, 2)
        Angles resampled, not filtered [rad] (what prediction errors are measured against).
    use : numpy.ndarray of bool, shape (n,)
        Samples the regression may use (not an edge, not near saturation).
    quantum : numpy.ndarray, shape (2, 2)
        Quantization steps found in the record: rows angles / torques, columns joints.
    """

    name: str
    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    tau_filtered: np.ndarray
    tau: np.ndarray
    q_measured: np.ndarray
    use: np.ndarray
    quantum: np.ndarray

    @property
    def dt(self) -> float:
        """Grid interval [s]."""
        return float(self.t[1] - self.t[0])

    def state(self, i: int | np.ndarray) -> np.ndarray:
        """Filtered joint state ``(q1, q2, q1', q2')`` at sample(s) ``i``.

        Parameters
        ----------
        i : int or array of int
            Sample indices.

        Returns
        -------
        numpy.ndarray, shape (4,) or (len(i), 4)
            Joint angles [rad] and rates [rad/s].
        """
        return np.concatenate([self.q[i], self.qd[i]], axis=-1)


def quantum(x: np.ndarray) -> float:
    """The quantization step of a signal: the smallest gap between the distinct values it takes.

    Parameters
    ----------
    x : numpy.ndarray, shape (n,)
        Samples.

    Returns
    -------
    float
        The step, or 0.0 for a signal with fewer than two distinct values.
    """
    values = np.unique(np.round(np.asarray(x, dtype=float), 12))
    gaps = np.diff(values)
    gaps = gaps[gaps > 1e-9]  # gaps below 1e-9 are the float noise of a scaled integer reading, not steps
    return float(gaps.min()) if gaps.size else 0.0


def common_interval(records: Sequence[Record]) -> float | None:
    """The grid interval records must share to be fitted together, or None if their own grids agree.

    Parameters
    ----------
    records : sequence of Record
        The records (at least one).

    Returns
    -------
    float or None
        None if every record's median interval is within :data:`GRID_TOLERANCE` of the others'
        (each keeps its own grid); else the largest median interval [s].

    Raises
    ------
    ValueError
        No records.
    """
    if not records:
        raise ValueError("common_interval needs at least one record")
    medians = np.array([float(np.median(np.diff(r.t))) for r in records])
    if medians.max() <= medians.min() * (1.0 + GRID_TOLERANCE):
        return None
    return float(medians.max())


def prepare(
    record: Record,
    cutoff_hz: float = DEFAULT_CUTOFF_HZ,
    torque_limit: tuple[float, float] = (np.inf, np.inf),
    dt: float | None = None,
) -> Prepared:
    """Resample, filter and differentiate one record (see the module docstring).

    Parameters
    ----------
    record : Record
        The measured record.
    cutoff_hz : float, default :data:`DEFAULT_CUTOFF_HZ`
        Low-pass cutoff [Hz], below half the sampling rate.
    torque_limit : tuple of float, default (inf, inf)
        Per joint, the magnitude at which the input torque saturates [N.m].
    dt : float, optional
        Grid interval [s]; default the record's median interval (:func:`common_interval` gives the
        one of several records fitted together).

    Returns
    -------
    Prepared
        The prepared samples.

    Raises
    ------
    ValueError
        ``cutoff_hz`` not positive or not below half the sampling rate; ``torque_limit`` not two
        positive numbers; ``dt`` not positive or longer than a tenth of the record.
    RecordError
        The record is too short for the filter, or more than half its samples are saturated.
    """
    if dt is None:
        dt = float(np.median(np.diff(record.t)))
    elif not (np.isfinite(dt) and 0.0 < dt <= 0.1 * record.duration):
        raise ValueError(f"dt must be in (0, {0.1 * record.duration:.4g}] s (a tenth of {record.name!r}), got {dt!r}")
    dt = float(dt)
    nyquist = 0.5 / dt
    if not (np.isfinite(cutoff_hz) and 0.0 < cutoff_hz < nyquist):
        raise ValueError(
            f"cutoff_hz must be in (0, {nyquist:.4g}) Hz (half the sampling rate of {record.name!r}), got {cutoff_hz!r}"
        )
    limit = np.asarray(torque_limit, dtype=float)
    if limit.shape != (2,) or not (limit > 0).all():
        raise ValueError(f"torque_limit must be two positive numbers [N.m], got {torque_limit!r}")
    n = int(np.floor(record.duration / dt + 1e-9)) + 1  # 1e-9: a duration of exactly k intervals keeps its last sample
    t = np.arange(n) * dt
    edge = int(np.ceil(2.0 / (cutoff_hz * dt)))  # two periods of the cutoff: the filter's start-up transient
    if n <= 4 * edge:
        raise RecordError(
            f"record {record.name!r}: {record.duration:.4g} s is too short for a {cutoff_hz} Hz filter; "
            f"need > {4 * edge * dt:.3g} s"
        )

    def resample(a: np.ndarray) -> np.ndarray:
        return np.column_stack([np.interp(t, record.t, a[:, j]) for j in range(a.shape[1])])

    q_raw, tau_raw = resample(record.q), resample(record.tau)
    sos = butter(4, cutoff_hz, fs=1.0 / dt, output="sos")
    q = sosfiltfilt(sos, q_raw, axis=0)
    qd = np.gradient(q, dt, axis=0)
    qdd = np.gradient(qd, dt, axis=0)
    tau_f = sosfiltfilt(sos, tau_raw, axis=0)

    saturated = (np.abs(tau_raw) >= 0.999 * limit).any(axis=1)
    if saturated.mean() > MAX_SATURATED_FRACTION:
        raise RecordError(
            f"record {record.name!r}: {100 * saturated.mean():.0f} % of the samples reach the torque limit {limit.tolist()} N.m; "
            f"at most {100 * MAX_SATURATED_FRACTION:.0f} % may be saturated"
        )
    near = np.convolve(saturated.astype(float), np.ones(2 * edge + 1), mode="same") > 0
    use = ~near
    use[:edge] = use[-edge:] = False
    q_step = [quantum(record.q[:, j]) for j in range(2)]
    tau_step = [quantum(record.tau[:, j]) for j in range(2)]
    return Prepared(
        name=record.name, t=t, q=q, qd=qd, qdd=qdd, tau_filtered=tau_f, tau=tau_raw, q_measured=q_raw, use=use,
        quantum=np.array([q_step, tau_step]),
    )  # fmt: skip
