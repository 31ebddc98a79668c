"""One swing-up episode end to end: plan (on the model the task needs), prove, replay, track with TVLQR + LQR, score.

Used by the ``pendulab swingup`` command, the example and the benchmarks.
:func:`closed_loop_success_rate` tracks the *same* plan from randomized starts
near the task's start: the tracker is what has to absorb a perturbed start
(re-planning per start would test the planner, which the benchmark does
separately), and one plan for all starts costs one solve instead of twenty.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ..._checks import bounded_int, positive_float, relative_tolerance
from ..._inputs import checked
from ...integrate import simulate
from ...integrate.trajectory import Trajectory
from ..tracking import TVLQRTracker, tvlqr
from .check import HeightCheck, ReplayReport, height_success, replay
from .errors import ErrorEstimate
from .guess import Guess
from .iterations import wall_time_budget
from .planning import Plan, is_solved, plan
from .solve import SwingUpResult
from .tasks import Task, resolve_task
from .transcription import INTERVALS_WHY, MAX_INTERVALS

__all__ = ["Episode", "run_episode", "SuccessRate", "closed_loop_success_rate", "tracking_torque"]


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
    plan : Plan or None
        The planning decision, the levels tried and the error estimate on the
        task's dynamics (None for episodes built by hand).
    """

    task: Task
    result: SwingUpResult
    replay: ReplayReport | None
    controller: TVLQRTracker | None
    closed_loop: Trajectory | None
    height: HeightCheck | None
    x0: np.ndarray
    plan: Plan | None = None

    @property
    def error(self) -> ErrorEstimate | None:
        """Error estimate of the plan on the task's own dynamics (None without a plan)."""
        if self.plan is not None and self.plan.estimate is not None:
            return self.plan.estimate
        return getattr(self.result, "error", None)

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
            solve and build times [s], the IPOPT time of the final mesh alone
            ``final_mesh_solve_time_s``, horizon [s], cost); the planning
            model (``planning_*``: requested, rule's choice, level used, spring
            and pendular frequencies [rad/s], levels tried); the error estimate
            (``error_*``: worst relative defect, tolerance, passed, method, the
            per-interval worst defects and the grid ``mesh_t_s``); mesh
            refinements; the torque margin; the replay defects when replayed;
            and, when a closed loop ran, ``success``,
            ``swing_up_time_s``, ``height_threshold_m``, ``max_torque_Nm``,
            ``torque_limit_Nm``, ``control_energy_N2m2s`` (integral of
            ``tau1^2 + tau2^2``), ``final_state_error`` (inf-norm) and the
            tracking torque's departure from the plan (:func:`tracking_torque`).
            Otherwise ``success`` is False.
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
            "torque_margin": self.task.problem.margin,
            "plan_torque_limit_Nm": self.task.problem.plan_torque_limit,
            "refinements": max(len(getattr(r, "mesh_history", ())) - 1, 0),
            "final_mesh_solve_time_s": round(float(getattr(r, "solve_time", float("nan"))), 4),
        }
        if self.plan is not None:
            d = self.plan.decision
            out.update(
                {
                    "planning_requested": d.requested,
                    "planning_rule_choice": d.chosen,
                    "planning_model": self.plan.level,
                    "planning_reason": d.reason,
                    "spring_frequency_rad_s": d.spring_frequency if np.isfinite(d.spring_frequency) else None,
                    "pendular_frequency_rad_s": d.pendular_frequency,
                    "planning_predicted_error": d.predicted,
                    "planning_attempts": [dict(a) for a in self.plan.attempts],
                    "plan_time_s": round(self.plan.wall_time, 4),
                    "plan_build_time_s": round(self.plan.build_time, 4),
                }
            )
        est = self.error
        if est is not None:
            out.update(
                {
                    "error_worst": est.worst,
                    "error_tolerance": est.tolerance,
                    "error_passed": est.passed,
                    "error_method": est.method,
                    "error_worst_interval": est.worst_interval,
                    "error_worst_state": est.worst_state,
                    "error_interval_worst": est.interval_worst.tolist(),
                    "mesh_t_s": np.asarray(r.t).tolist(),
                }
            )
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
                    **tracking_torque(cl, r, out.get("spring_frequency_rad_s")),
                }
            )
        else:
            out["success"] = False
        return out


def tracking_torque(closed_loop: Trajectory, result: SwingUpResult, spring_frequency: float | None) -> dict[str, Any]:
    """How the closed loop's torque departs from the plan's over the plan's horizon, and why.

    Parameters
    ----------
    closed_loop : Trajectory
        The tracked closed loop (uniform output grid).
    result : SwingUpResult
        The plan.
    spring_frequency : float or None
        The springs' rate w_s [rad/s] (elastic tasks), or None.

    Returns
    -------
    dict
        ``tracking_torque_rms_Nm`` (RMS of closed-loop minus plan torque of the driven joint
        over the horizon), ``tracking_torque_frequency_Hz`` (the dominant frequency of that
        difference) and ``tracking_torque_note`` (its cause, in words).

    Notes
    -----
    On the elastic tasks the difference rings at the springs' modes (measured on
    ``pendubot_elastic``: 0.55 N.m RMS, spectrum 11-27 Hz against spring modes of 20
    and 24 Hz). The task's springs are undamped (c = 0): every held torque step
    excites them, the link rates carry the ringing, and the tracker's rate feedback
    returns it as torque. It is not the spring weights (zeroing them changed the RMS
    by < 1 %) nor the sample time (0.005 / 0.002 / 0.001 s: 0.548 / 0.544 / 0.539 N.m).
    """
    t = closed_loop.t
    inside = t <= result.horizon
    driven = int(np.argmax(np.max(np.abs(closed_loop.u[inside]), axis=0)))
    diff = closed_loop.u[inside, driven] - np.asarray(result.u_at(t[inside])).reshape(inside.sum(), -1)[:, driven]
    spectrum = np.abs(np.fft.rfft(diff - diff.mean()))
    freqs = np.fft.rfftfreq(diff.size, float(t[1] - t[0]))
    rms, peak = float(np.sqrt(np.mean(diff**2))), float(freqs[int(np.argmax(spectrum))])
    nyquist = 0.5 / float(t[1] - t[0])
    note = f"the tracker's corrections, dominant at {peak:.1f} Hz"
    if peak >= 0.8 * nyquist:
        note = (
            f"sample-to-sample alternation at {peak:.1f} Hz, near the output step's Nyquist frequency {nyquist:.0f} Hz: "
            "the sampled tracker's high gains on the fast states overcorrect from one sample to the next"
        )
    elif spring_frequency is not None and 0.5 <= 2 * np.pi * peak / spring_frequency <= 2.0:
        note = (
            f"ringing of the spring modes ({spring_frequency / (2 * np.pi):.1f} Hz): the held torque steps excite the "
            "springs, the link rates carry their vibration and the tracker's rate feedback returns it as torque"
        )
    return {"tracking_torque_rms_Nm": rms, "tracking_torque_frequency_Hz": peak, "tracking_torque_note": note}


def run_episode(
    task: Task | str,
    *,
    method: str | None = None,
    N: int | None = None,
    guess: str | Guess | SwingUpResult = "auto",
    x0: np.ndarray | None = None,
    do_replay: bool = True,
    tolerance: float | None = None,
    refine: bool = True,
    planning: str | None = None,
    max_wall_time: float | None = None,
    stage: Callable[[str], Any] | None = None,
) -> Episode:
    """Plan the task, prove the plan, replay it, track it in closed loop and score the episode.

    Parameters
    ----------
    task : Task or str
        The task or its name (``pendubot``; ``swingup_pendubot`` is an alias).
    method, N : optional
        Override the task's transcription and (initial) number of intervals.
    guess : str, Guess or SwingUpResult
        Initial guess (see :func:`swing_up`).
    x0 : array_like, shape (nx,), optional
        Start of the closed loop (a perturbed start); default the problem's start.
    do_replay : bool
        Run the (slower) open-loop replay check.
    tolerance : float, optional
        Relative defect the plan must meet (default the task's ``tolerance``).
    refine : bool
        Mesh refinement until the tolerance is met (False: one solve, estimate reported).
    planning : {"auto", "rigid", "quasi-static", "elastic"}, optional
        Planning model of an elastic task (default the task's ``planning``). A
        planning model other than the task's own on a rigid task is an error.
    max_wall_time : float, optional
        Wall-time budget of the planning [s]: IPOPT stops at its next iteration once it
        is spent and the episode reports a failed plan saying so. None: no budget.
    stage : callable, optional
        ``stage(description)`` before each step after planning (replay, closed-loop simulation): progress.

    Returns
    -------
    Episode
        From :func:`pendulab.control.swingup.planning.plan`. When no valid plan
        was found, only ``task``, ``result``, ``x0`` and ``plan`` are set.
        Otherwise the TVLQR tracker (sample time ``task.dt``) is simulated with
        CVODES from ``x0`` over ``task.t_final`` and scored with
        :func:`height_success`. A plan that solved but misses the tolerance
        without refinement (``refine=False``) is still tracked and reported.

    Raises
    ------
    ValueError
        Bad overrides (unknown planning name, a planning model on a rigid task,
        a tolerance outside (0, 1), N outside [2, MAX_INTERVALS]).
    TypeError
        ``task`` is neither a Task nor a name.
    """
    task = resolve_task(task)
    if N is not None:
        N = bounded_int("N", N, low=2, high=MAX_INTERVALS, why=INTERVALS_WHY)
    if tolerance is not None:
        tolerance = relative_tolerance("tolerance", tolerance)
    if planning is not None and planning != "auto" and task.model.kind != "elastic" and planning != "rigid":
        raise ValueError(
            f"planning={planning!r} applies to elastic tasks only; task {task.name!r} is rigid (planned on its own model)"
        )
    if max_wall_time is not None:
        max_wall_time = positive_float("max_wall_time", max_wall_time, "[s]")
    with wall_time_budget(max_wall_time) as budget:
        pl_ = plan(
            task.problem,
            planning=task.planning if planning is None else planning,
            tolerance=task.tolerance if tolerance is None else tolerance,
            method=method or task.method,
            N=N or task.N,
            degree=task.degree,
            guess=guess,
            refine=refine,
        )
    if budget.exceeded:
        stopped = replace(
            pl_.result, success=False, message=pl_.result.message + f"; stopped by the wall-time budget {max_wall_time:g} s"
        )
        pl_ = replace(pl_, result=stopped)
    res = pl_.result
    start = task.problem.start if x0 is None else task.model.check_state(x0, "x0")
    # Without refinement a converged plan that misses the tolerance is still tracked (and reported as failed).
    if not (res.success or (not refine and is_solved(res))):
        return Episode(task, res, None, None, None, None, start, pl_)
    if stage is not None and do_replay:
        stage("replaying the plan open loop")
    rep = replay(res) if do_replay else None
    ctrl = tvlqr(res if res.success else replace(res, success=True), dt=task.dt)
    if stage is not None:
        stage(f"closed-loop simulation (TVLQR + LQR, {task.t_final:g} s, CVODES)")
    cl = simulate(task.model, start, task.t_final, dt=task.dt, method="cvodes", rtol=1e-8, atol=1e-8, u=ctrl)
    hc = height_success(cl, task.rest_lengths, task.success_fraction)
    return Episode(task, res, rep, ctrl, cl, hc, start, pl_)


@dataclass(frozen=True)
class SuccessRate:
    """Closed-loop success of one plan from randomized starts.

    Attributes
    ----------
    successes : int
        Starts whose closed loop met the height criterion.
    starts : int
        Number of starts.
    x0 : ndarray, shape (starts, nx)
        The starts.
    success : ndarray of bool, shape (starts,)
        Per start.
    t_up : ndarray, shape (starts,)
        Swing-up time per start [s] (nan when it failed).
    angle_spread, rate_spread : float
        Half-widths of the uniform start perturbation [rad], [rad/s].

    Examples
    --------
    >>> from pendulab.control import closed_loop_success_rate
    >>> rate = closed_loop_success_rate("pendubot", starts=2, seed=1, angle_spread=0.2, rate_spread=0.5)
    >>> rate.x0.shape, rate.success.tolist(), rate.rate  # a SuccessRate: the starts and their verdicts
    ((2, 4), [True, True], 1.0)
    """

    successes: int
    starts: int
    x0: np.ndarray
    success: np.ndarray
    t_up: np.ndarray
    angle_spread: float
    rate_spread: float

    @property
    def rate(self) -> float:
        """Fraction of successful starts."""
        return self.successes / self.starts


@checked(angle_spread="spread", rate_spread="spread")
def closed_loop_success_rate(
    task: Task | str,
    starts: int = 20,
    seed: int = 0,
    *,
    episode: Episode | None = None,
    angle_spread: float = 0.05,
    rate_spread: float = 0.1,
) -> SuccessRate:
    """Track one plan of the task from randomized starts near its start and count the successes.

    Parameters
    ----------
    task : Task or str
        The task or its name.
    starts : int
        Number of randomized starts, in [1, 100000].
    seed : int
        Seed of :func:`numpy.random.default_rng`.
    episode : Episode, optional
        An episode of ``task`` whose plan and tracker are reused (default: one
        is planned with the task's settings).
    angle_spread : float
        Uniform perturbation of both angles, +- this [rad].
    rate_spread : float
        Uniform perturbation of both angular rates, +- this [rad/s].

    Returns
    -------
    SuccessRate
        Per start: closed loop (TVLQR + LQR, CVODES at 1e-8, sample time
        ``task.dt``) over ``task.t_final`` scored with :func:`height_success`.
        Zero successes when no plan was found.

    Raises
    ------
    ValueError
        ``starts`` out of range, negative spreads, or an episode of another task.
    TypeError
        ``task`` is neither a Task nor a name.

    Examples
    --------
    >>> import numpy as np
    >>> from pendulab.control import closed_loop_success_rate
    >>> rate = closed_loop_success_rate("acrobot", starts=3, seed=0)  # one plan, tracked from 3 perturbed starts
    >>> rate.successes, rate.starts, rate.rate
    (3, 3, 1.0)
    >>> np.round(rate.t_up, 1)  # swing-up time of each start [s]
    array([1.8, 1.8, 1.8])
    """
    task = resolve_task(task)
    starts = int(starts)
    if not (angle_spread >= 0.0 and rate_spread >= 0.0):
        raise ValueError(f"angle_spread and rate_spread must be >= 0, got {angle_spread!r} and {rate_spread!r}")
    if episode is not None and episode.task.name != task.name:
        raise ValueError(f"episode is of task {episode.task.name!r}, not {task.name!r}")
    ep = episode if episode is not None else run_episode(task, do_replay=False)
    rng = np.random.default_rng(seed)
    model, nq = task.model, task.model.nq
    x0s = np.tile(task.problem.start, (int(starts), 1))
    x0s[:, 0:2] += rng.uniform(-angle_spread, angle_spread, (starts, 2))
    x0s[:, nq : nq + 2] += rng.uniform(-rate_spread, rate_spread, (starts, 2))
    ok = np.zeros(starts, dtype=bool)
    t_up = np.full(starts, np.nan)
    if ep.controller is not None:
        for i, x0 in enumerate(x0s):
            cl = simulate(model, x0, task.t_final, dt=task.dt, method="cvodes", rtol=1e-8, atol=1e-8, u=ep.controller)
            hc = height_success(cl, task.rest_lengths, task.success_fraction)
            ok[i], t_up[i] = hc.success, hc.t_up
    return SuccessRate(int(ok.sum()), int(starts), x0s, ok, t_up, float(angle_spread), float(rate_spread))
