"""Checks of a swing-up against the real dynamics and the task's success criterion.

* :func:`replay` integrates the optimal torques with the native high-accuracy
  integrator (``pendulab.simulate``, CVODES) - per interval from each grid
  state (the local defect of the transcription, free of chaotic
  amplification; the same computation as :func:`.errors.estimate_error`, in
  state units) and open loop over the whole horizon (what happens without
  feedback). Uniform and non-uniform grids alike.
* :func:`height_success` applies the benchmark criterion: the end effector
  rises above ``fraction * (L1 + L2)`` and stays there to the end.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...integrate import simulate
from ...integrate.trajectory import Trajectory
from ...model.model import Model
from .errors import estimate_error_arrays
from .solve import SwingUpResult

__all__ = ["ReplayReport", "replay", "height_success", "HeightCheck"]


@dataclass(frozen=True)
class ReplayReport:
    """Optimal trajectory vs the native integrator.

    Attributes
    ----------
    interval_defect : float
        Max over intervals and states of |x_sim(t_k+1; x_k, u_k) - x_k+1| [state units].
    interval_defects : ndarray, shape (N,)
        Per-interval max defect.
    open_loop : Trajectory
        The optimal torques replayed open loop from the start (output grid = NLP grid).
    max_deviation : float
        Max over the horizon of the open-loop state deviation from the optimum (inf-norm).
    final_deviation : float
        Open-loop deviation at T (inf-norm).
    method : str
        Integrator used.
    """

    interval_defect: float
    interval_defects: np.ndarray
    open_loop: Trajectory
    max_deviation: float
    final_deviation: float
    method: str


def replay(result: SwingUpResult, method: str = "cvodes", rtol: float = 1e-10, atol: float = 1e-10) -> ReplayReport:
    """Replay the optimal torques through ``pendulab.simulate``.

    Parameters
    ----------
    result : SwingUpResult
    method : str
        Any ``pendulab.METHODS`` entry; the default CVODES at 1e-10 is the reference.
    rtol, atol : float
        Integrator tolerances.

    Returns
    -------
    ReplayReport
        Per-interval defects (each interval integrated from the optimal grid
        state with its held torque) and the open-loop replay from the start
        on the NLP grid, with its deviation from the optimum.
    """
    model = result.problem.model
    # Defects: one integration per interval from the optimal grid state (the torque jumps there).
    est = estimate_error_arrays(model, result.t, result.x, result.u, method=method, rtol=rtol, atol=atol)
    defects = est.absolute.max(axis=1)
    ol = _open_loop(model, result, method, rtol, atol)
    dev = np.max(np.abs(ol.x - result.x), axis=1)
    return ReplayReport(float(defects.max()), defects, ol, float(dev.max()), float(dev[-1]), method)


def _open_loop(model: Model, result: SwingUpResult, method: str, rtol: float, atol: float) -> Trajectory:
    """The torques replayed from the start, sampled on the plan's grid (uniform or not)."""
    h = np.diff(result.t)
    if np.allclose(h, h[0], rtol=1e-12, atol=0.0):
        return simulate(model, result.x[0], result.horizon, dt=h[0], method=method, rtol=rtol, atol=atol, u=result.u)
    # A non-uniform grid: chain one run per interval (simulate's output grid is uniform).
    x = np.empty_like(result.x)
    x[0] = result.x[0]
    for k in range(result.N):
        x[k + 1] = simulate(model, x[k], h[k], dt=h[k], method=method, rtol=rtol, atol=atol, u=result.u[k]).x[-1]
    u = np.vstack([result.u, result.u[-1:]])
    y = np.asarray(model.outputs(x, u), dtype=float)
    return Trajectory(
        result.t.copy(), x, u, y, model.state_names, model.input_names, model.output_names, method, stats={"chained": True}
    )


@dataclass(frozen=True)
class HeightCheck:
    """Outcome of the height criterion on one episode.

    Attributes
    ----------
    success : bool
        End effector above the threshold from ``t_up`` to the end.
    t_up : float
        Swing-up time: start of the final stretch above the threshold [s] (nan if never).
    threshold : float
        Height threshold [m] (y up, pivot at 0).
    height : ndarray, shape (K,)
        End-effector height y2 over the episode [m].
    """

    success: bool
    t_up: float
    threshold: float
    height: np.ndarray


def height_success(traj: Trajectory, rest_lengths: tuple[float, float], fraction: float = 0.9) -> HeightCheck:
    """Benchmark criterion: y2 > fraction * (L1 + L2) from some time on until the end.

    Parameters
    ----------
    traj : Trajectory
        Episode (needs output ``y2``).
    rest_lengths : (float, float)
        L1, L2 [m] (rest lengths for the elastic model).
    fraction : float
        Fraction of the full reach (0.9 in the acrobot/pendubot benchmarks).

    Returns
    -------
    HeightCheck
        Success if ``y2`` is above the threshold at the last sample; ``t_up``
        is then the first time of the final stretch above it [s].
    """
    y2 = traj["y2"]
    thr = fraction * (rest_lengths[0] + rest_lengths[1])
    above = y2 > thr
    if not above[-1]:
        return HeightCheck(False, float("nan"), thr, y2)
    below = np.flatnonzero(~above)
    k = 0 if below.size == 0 else int(below[-1]) + 1
    return HeightCheck(True, float(traj.t[k]), thr, y2)
