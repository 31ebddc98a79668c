"""Replay a measured record's torques through an FMU of the robot and through the native model.

The check that an exported FMU *is* the identified robot, on real inputs: a window of a measured
record (:class:`pendulab.identify.records.Record`) is put on a uniform grid
(:func:`pendulab.identify.preprocess.prepare`), its measured joint torques are held over each step
(as the robot's control loop held them) and drive both the FMU (co-simulation master) and
:func:`pendulab.simulate` from the record's measured start state. The two simulations must agree
to the solvers' tolerance; both are compared with the measured angles, which they follow only as
long as a chaotic open-loop prediction can (see ``benchmarks/results/identify.md``).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..identify.preprocess import prepare
from ..identify.records import Record
from ..integrate import simulate
from ..model.model import Model
from .master import cosim

__all__ = ["Replay", "TorqueReplay", "replay_record"]


class TorqueReplay:
    """A sampled "controller" that plays a torque table, one row per sample, whatever the state.

    Parameters
    ----------
    torques : array_like, shape (n, 2)
        ``(tau1, tau2)`` [N.m] held over ``[k dt, (k + 1) dt]``; the last row is held after the table ends.
    dt : float
        Sample time [s].
    """

    input_names: tuple[str, ...] = ("tau1", "tau2")

    def __init__(self, torques: Any, dt: float) -> None:
        table = np.asarray(torques, dtype=float)
        if table.ndim != 2 or table.shape[1] != 2 or table.shape[0] < 1 or not np.all(np.isfinite(table)):
            raise ValueError(f"torques must be a finite (n, 2) table [N.m], got shape {table.shape}")
        if not (math.isfinite(dt) and dt > 0.0):
            raise ValueError(f"dt must be a positive sample time [s], got {dt!r}")
        self._table = table
        self.sample_time = float(dt)

    def reset(self) -> None:
        """Nothing to forget (the table is indexed by time)."""

    def __call__(self, t: float, x: np.ndarray) -> np.ndarray:
        k = min(max(round(t / self.sample_time), 0), len(self._table) - 1)
        return self._table[k].copy()


@dataclass(frozen=True)
class Replay:
    """One replayed window.

    Attributes
    ----------
    t : numpy.ndarray, shape (n,)
        Time from the window's start [s] (uniform, step ``dt``).
    tau : numpy.ndarray, shape (n - 1, 2)
        The measured torques held over each step [N.m].
    measured : numpy.ndarray, shape (n, 2)
        Measured joint angles ``q1`` (absolute), ``q2`` (relative) [rad].
    fmu, native : numpy.ndarray, shape (n, 4)
        States ``(theta1, theta2, omega1, omega2)`` (absolute angles) of the FMU and of the native model.
    """

    t: np.ndarray
    tau: np.ndarray
    measured: np.ndarray
    fmu: np.ndarray
    native: np.ndarray

    @staticmethod
    def _joint(x: np.ndarray) -> np.ndarray:
        return np.column_stack([x[:, 0], x[:, 1] - x[:, 0]])

    def fmu_native_gap(self) -> float:
        """Largest difference of the FMU's and the native model's joint angles along the window.

        Returns
        -------
        float
            ``max |q_fmu - q_native|`` over samples and joints [rad].
        """
        return float(np.max(np.abs(self._joint(self.fmu) - self._joint(self.native))))

    def prediction_error(self, source: str = "fmu") -> np.ndarray:
        """Simulated minus measured joint angles [rad], shape (n, 2).

        Parameters
        ----------
        source : {"fmu", "native"}
            Which simulation.

        Returns
        -------
        numpy.ndarray, shape (n, 2)
            The open-loop prediction error along the window.

        Raises
        ------
        ValueError
            Another ``source``.
        """
        if source not in ("fmu", "native"):
            raise ValueError(f"source must be 'fmu' or 'native', got {source!r}")
        return self._joint(self.fmu if source == "fmu" else self.native) - self.measured


def replay_record(
    fmu_path: str | os.PathLike[str],
    model: Model,
    record: Record,
    *,
    start: float = 0.0,
    duration: float = 1.0,
    dt: float = 0.002,
    tolerance: float = 1e-10,
) -> Replay:
    """Drive the FMU and the native model with a window of a record's measured torques.

    Parameters
    ----------
    fmu_path : path-like
        A pendulab FMU (Co-Simulation) of the rigid model.
    model : Model
        The robot (``pl.rigid(plant=...)``); its parameters go to the FMU and to the native run.
    record : Record
        A measured record; its torque columns are the input.
    start : float, default 0.0
        Window start after the record's first sample [s].
    duration : float, default 1.0
        Window length [s] (a whole number of ``dt``).
    dt : float, default 0.002
        Grid and communication step [s] (the robot's loop ran at 2.0-3.7 ms).
    tolerance : float, default 1e-10
        Relative tolerance of both solvers (the FMU's embedded one and CVODES).

    Returns
    -------
    Replay
        Both simulations and the measured angles on the grid.

    Raises
    ------
    ValueError
        A non-rigid model, a window outside the record, or a bad ``dt``/``duration``.
    """
    if model.kind != "rigid":
        raise ValueError(f"a record of a rigid robot replays on a rigid model, got a {model.kind} model")
    n = round(duration / dt)
    if not (math.isfinite(duration) and n >= 1 and abs(n * dt - duration) < 1e-9 * max(1.0, duration)):
        raise ValueError(f"duration must be a positive whole number of dt = {dt} s, got {duration!r}")
    prep = prepare(record, dt=dt)
    k0 = round((start + record.t[0] - prep.t[0]) / dt)
    if start < 0.0 or k0 + n >= len(prep.t):
        raise ValueError(
            f"window [{start}, {start + duration}] s is outside record {record.name!r} ({prep.t[-1] - prep.t[0]:.3f} s long)"
        )
    window = slice(k0, k0 + n + 1)
    q, qd = prep.q[k0], prep.qd[k0]
    x0 = np.array([q[0], q[0] + q[1], qd[0], qd[0] + qd[1]])
    tau = prep.tau[k0 : k0 + n]
    params = dict(zip(model.param_names, model.p.tolist(), strict=True))
    fmu = cosim(fmu_path, TorqueReplay(tau, dt), dt, n * dt, params=params, x0=x0, tolerance=tolerance)
    native = simulate(model, x0, n * dt, dt, "cvodes", tolerance, tolerance, tau)
    return Replay(t=np.arange(n + 1) * dt, tau=tau, measured=prep.q_measured[window], fmu=fmu.x, native=native.x)
