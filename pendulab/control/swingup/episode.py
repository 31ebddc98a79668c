"""One swing-up episode end to end: solve, replay, track with TVLQR + LQR, score.

Used by the ``pendulab swingup`` command, the example and the benchmarks.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ...integrate import simulate
from ...integrate.trajectory import Trajectory
from ..tracking import TVLQRTracker, tvlqr
from .check import HeightCheck, ReplayReport, height_success, replay
from .guess import Guess
from .solve import SwingUpResult, swing_up
from .tasks import Task

__all__ = ["Episode", "run_episode"]


@dataclass(frozen=True)
class Episode:
    """Everything one episode produced.

    Attributes
    ----------
    task : Task
    result : SwingUpResult
    replay : ReplayReport or None
        None when the solve failed.
    controller : TVLQRTracker or None
    closed_loop : Trajectory or None
        Native closed-loop simulation over the episode (controller held at ``task.dt``).
    height : HeightCheck or None
    x0 : ndarray, shape (nx,)
        Start state of the closed loop (may differ from the problem's start).
    """

    task: Task
    result: SwingUpResult
    replay: ReplayReport | None
    controller: TVLQRTracker | None
    closed_loop: Trajectory | None
    height: HeightCheck | None
    x0: np.ndarray

    @property
    def success(self) -> bool:
        """Solved, and the closed loop meets the height criterion."""
        return bool(self.result.success and self.height is not None and self.height.success)

    def summary(self) -> dict[str, Any]:
        """Flat, JSON-friendly summary (SI units).

        Returns
        -------
        dict
            Task, model, actuation and solver figures (status, iterations,
            solve and build times [s], horizon [s], cost); the replay defects
            when replayed; and, when a closed loop ran, ``success``,
            ``swing_up_time_s``, ``height_threshold_m``, ``max_torque_Nm``,
            ``torque_limit_Nm``, ``control_energy_N2m2s`` (integral of
            ``tau1^2 + tau2^2``) and ``final_state_error`` (inf-norm). Otherwise
            ``success`` is False.
        """
        r = self.result
        out: dict[str, Any] = {
            "task": self.task.name,
            "model": self.task.model.kind,
            "actuation": self.task.problem.actuation,
            "method": r.method,
            "N": r.N,
            "solve_success": r.success,
            "ipopt_status": r.status,
            "iterations": r.iterations,
            "solve_time_s": round(r.wall_time, 4),
            "build_time_s": round(r.build_time, 4),
            "horizon_s": r.horizon,
            "cost": r.cost,
            "message": r.message,
        }
        if self.replay is not None:
            out["replay_interval_defect"] = self.replay.interval_defect
            out["replay_open_loop_max_deviation"] = self.replay.max_deviation
        if self.closed_loop is not None and self.height is not None:
            cl = self.closed_loop
            u = cl.u[:-1]
            dt = np.diff(cl.t)
            out.update(
                {
                    "success": self.success,
                    "swing_up_time_s": self.height.t_up,
                    "height_threshold_m": self.height.threshold,
                    "max_torque_Nm": float(np.max(np.abs(cl.u))),
                    "torque_limit_Nm": self.task.problem.torque_limit,
                    "control_energy_N2m2s": float(np.sum(np.sum(u**2, axis=1) * dt)),
                    "final_state_error": float(np.max(np.abs(cl.x[-1] - self.task.problem.target))),
                }
            )
        else:
            out["success"] = False
        return out


def run_episode(
    task: Task,
    *,
    method: str | None = None,
    N: int | None = None,
    guess: str | Guess | SwingUpResult = "auto",
    x0: np.ndarray | None = None,
    do_replay: bool = True,
) -> Episode:
    """Solve the task, replay the optimum, track it in closed loop and score the episode.

    Parameters
    ----------
    task : Task
    method, N : optional
        Override the task's transcription and number of intervals.
    guess : str, Guess or SwingUpResult
        Initial guess (see :func:`swing_up`).
    x0 : array_like, shape (nx,), optional
        Start of the closed loop (a perturbed start); default the problem's start.
    do_replay : bool
        Run the (slower) open-loop replay check.

    Returns
    -------
    Episode
        When the solve fails, only ``task``, ``result`` and ``x0`` are set.
        Otherwise the TVLQR tracker (sample time ``task.dt``) is simulated with
        CVODES from ``x0`` over ``task.t_final`` and scored with
        :func:`height_success`.
    """
    res = swing_up(task.problem, method or task.method, N or task.N, degree=task.degree, guess=guess)
    start = task.problem.start if x0 is None else task.model.check_state(x0, "x0")
    if not res.success:
        return Episode(task, res, None, None, None, None, start)
    rep = replay(res) if do_replay else None
    ctrl = tvlqr(res, dt=task.dt)
    cl = simulate(task.model, start, task.t_final, dt=task.dt, method="cvodes", rtol=1e-8, atol=1e-8, u=ctrl)
    hc = height_success(cl, task.rest_lengths, task.success_fraction)
    return Episode(task, res, rep, ctrl, cl, hc, start)
