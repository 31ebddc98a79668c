"""Online re-planning from any state: a swing-up solved from the current state, tracked by TVLQR, caught by LQR."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from .._inputs import checked
from ..model.model import INPUT_NAMES
from ..model.robot import joint_rates
from .global_swingup import GlobalSwingUp, global_controller
from .lqr import wrap_state_error

if TYPE_CHECKING:
    from .tracking import TVLQRTracker

__all__ = [
    "REPLAN_DEFAULTS",
    "ReplanningSwingUp",
    "replanning_controller",
    "plan_swingup",
    "nearest_upright",
    "upright_goals",
    "MOVING_RATE",
]


@checked(n_intervals="intervals", replan_error="error_level")
@dataclass
class ReplanningSwingUp:
    """Global swing-up by online re-planning: an optimal swing-up from the current state, tracked by TVLQR.

    A plan (direct collocation, :func:`~pendulab.control.swingup.solve_transcription`, effort-optimal over
    ``horizon`` seconds to the nearest upright branch, torque limit ``u_max``) is solved whenever the
    controller has none, after a gap in its calls (the protocol's reset: it is not told, it sees time
    jump), when the state leaves the plan's tube (tracking cost ``e' e`` above ``replan_error``), or when the
    plan ends outside the catch. TVLQR (:func:`~pendulab.control.tracking.tvlqr`) tracks it; near upright
    the catch LQR of ``fallback`` takes over with hysteresis. While no plan is available (a failed solve,
    retried every ``retry`` seconds) the state-based ``fallback`` (:class:`GlobalSwingUp`) acts.

    **Real time.** A solve takes 0.1-2 s of wall time, far beyond a 2 ms period. With ``plan_delay = 0``
    the simulation pauses for it (idealised: as if planning were instantaneous). With ``plan_delay = d > 0``
    the plan starts from the state *predicted* ``d`` seconds ahead (the model driven by ``fallback``, which
    also acts meanwhile), so a background solver that finishes within ``d`` realises the same behaviour in
    real time; the delay costs ``d`` seconds of every swing-up.

    Attributes
    ----------
    fallback : GlobalSwingUp
        State-based controller (pumping + catch) and the catch test.
    actuation : str
        ``"pendubot"`` or ``"acrobot"``.
    horizon : float
        Plan horizon [s].
    n_intervals : int
        Collocation intervals of a plan.
    plan_delay : float
        Prediction horizon of the plan's start [s] (0: plan from the current state).
    replan_error : float
        Leave a plan when the wrapped tracking error ``|x - x_ref|^2`` exceeds this.
    retry : float
        Wait before re-trying a failed solve [s].
    min_time : bool
        Try a time-optimal plan (free horizon in [0.3, ``horizon``]) first, the effort-optimal one on failure.
    max_iter : int
        IPOPT iteration cap of one solve (deterministic, unlike a wall-time budget); a capped solve counts as failed.
    max_solve_time : float
        Safety wall-time budget of one solve [s] (only a stuck solve should hit it: results then depend on load).
    velocity_limit : float or None
        Bound on both joint rates of every plan [rad/s] (:func:`plan_swingup`); None: unbounded. The
        hardware protocol resets the robot at 20 rad/s (:mod:`pendulab.evaluate.realai.v3_hardware`).
    plan_times : list of float
        Wall time of each solve [s] (diagnostics).
    n_failed : int
        Solves that failed.

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.control import ReplanningSwingUp, as_feedback, global_controller
    >>> ctrl = ReplanningSwingUp(global_controller("pendubot"), "pendubot", horizon=1.5, n_intervals=40)
    >>> model = ctrl.fallback.model
    >>> x0 = np.array([2.27, 2.61, -6.87, -6.67])  # thrown: a state a reset may leave behind
    >>> traj = pl.simulate(model, x0, 3.0, dt=ctrl.sample_time, u=as_feedback(ctrl, model))
    >>> ctrl.fallback.caught, len(ctrl.plan_times), ctrl.n_failed  # one plan to the nearest upright, then the catch
    (True, 1, 0)
    """

    fallback: GlobalSwingUp
    actuation: str
    horizon: float = 1.5
    n_intervals: int = 40
    plan_delay: float = 0.0
    replan_error: float = 1.0
    retry: float = 0.1
    max_iter: int = 150
    min_time: bool = False
    max_solve_time: float = 60.0
    velocity_limit: float | None = None
    # Counters of the controller's own life, not inputs.
    plan_times: list[float] = field(default_factory=list, init=False)
    n_failed: int = field(default=0, init=False)
    _tracker: object = field(default=None, init=False, repr=False)
    _t_plan: float = field(default=0.0, init=False, repr=False)
    _t_last: float | None = field(default=None, init=False, repr=False)
    _t_retry: float = field(default=-math.inf, init=False, repr=False)

    @property
    def sample_time(self) -> float:
        """[s] (the fallback's)."""
        return self.fallback.sample_time

    @property
    def input_names(self) -> tuple[str, ...]:
        """The driven torque."""
        return self.fallback.input_names

    def reset(self) -> None:
        """Forget the plan and the catch."""
        self.fallback.reset()
        self._tracker, self._t_last, self._t_retry = None, None, -math.inf

    def _predict(self, t: float, x: np.ndarray, duration: float) -> np.ndarray:
        """The state ``duration`` ahead under ``fallback`` (RK4 at the sample time on the design model)."""
        fb = self.fallback
        f, p, h = fb._rhs, fb._p, fb.sample_time
        j = INPUT_NAMES.index(fb.input_names[0])
        saved = fb.caught
        for _ in range(round(duration / h)):
            u = [0.0, 0.0]
            u[j] = float(fb(t, x)[0])
            k1 = f(x, u, p)
            k2 = f(x + 0.5 * h * k1, u, p)
            k3 = f(x + 0.5 * h * k2, u, p)
            k4 = f(x + h * k3, u, p)
            x = x + h * (k1 + 2.0 * (k2 + k3) + k4) / 6.0
        fb.caught = saved
        return x

    def _plan(self, t: float, x: np.ndarray) -> None:
        import time as _time

        t0 = _time.perf_counter()
        start = self._predict(t, x, self.plan_delay) if self.plan_delay > 0 else np.array(x, dtype=float)
        self._tracker = plan_swingup(
            self.fallback,
            self.actuation,
            start,
            horizon=self.horizon,
            n_intervals=self.n_intervals,
            min_time=self.min_time,
            max_iter=self.max_iter,
            max_solve_time=self.max_solve_time,
            velocity_limit=self.velocity_limit,
        )
        if self._tracker is not None:
            self._t_plan = t + self.plan_delay
        else:
            self.n_failed += 1
            self._t_retry = t + self.retry
        self.plan_times.append(_time.perf_counter() - t0)

    def __call__(self, t: float, x: np.ndarray) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        fb = self.fallback
        gap = self._t_last is not None and t - self._t_last > 1.5 * fb.sample_time
        self._t_last = t
        if gap:
            self._tracker, fb.caught, self._t_retry = None, False, -math.inf
        v = fb.cost(x)
        if fb.caught and v > fb.release_level:
            fb.caught = False
        elif not fb.caught and v < fb.catch_level:
            fb.caught = True
        if fb.caught:
            self._tracker = None
            return np.clip(fb.balance(t, x), -fb.u_max, fb.u_max)
        tr = self._tracker
        if tr is not None:
            tau = t - self._t_plan
            if tau >= 0.0:
                if tau >= tr.horizon:
                    tr = self._tracker = None  # ended outside the catch: plan again
                else:
                    k = min(int(tau / fb.sample_time + 1e-6), len(tr.x_ref) - 1)
                    e = wrap_state_error(x - tr.x_ref[k], fb.model.state_names)
                    if float(e @ e) > self.replan_error:
                        tr = self._tracker = None
        if tr is None and t >= self._t_retry:
            self._plan(t, x)
            tr = self._tracker
        if tr is not None and t - self._t_plan >= 0.0:
            j = INPUT_NAMES.index(fb.input_names[0])
            u = float(tr(t - self._t_plan, x)[j])
            return np.array([min(max(u, -fb.u_max), fb.u_max)])
        return np.array([fb.pump(x)])


def nearest_upright(start: np.ndarray) -> tuple[float, float, float, float]:
    """The upright equilibrium on the branch (``pi + 2 pi k`` per absolute angle) nearest to ``start``.

    Parameters
    ----------
    start : ndarray, shape (4,) or longer
        State whose angles (theta1, theta2 [rad]) come first.

    Returns
    -------
    tuple of float
        (theta1, theta2 [rad], 0, 0): the nearest upright state at rest.
    """
    two_pi = 2.0 * math.pi
    return (
        math.pi + two_pi * round((float(start[0]) - math.pi) / two_pi),
        math.pi + two_pi * round((float(start[1]) - math.pi) / two_pi),
        0.0,
        0.0,
    )


#: A joint rate below this [rad/s] counts as no motion when choosing goals ahead of it (:func:`upright_goals`).
MOVING_RATE: float = 1.0


def upright_goals(start: np.ndarray) -> list[tuple[int, int]]:
    """Upright branches a swing-up from ``start`` may aim at: the nearest, then those ahead of each moving joint.

    A reset hands over at 5-30 rad/s; reversing that motion to reach the nearest upright costs time that going on
    to the next branch does not (v3 hand-overs of training seeds 10-11: band entry 0.36-0.60 s ahead of the
    motion against 0.70-0.98 s to the nearest branch). Which branch wins depends on the state, so the plan library
    solves each candidate and keeps the fastest closed loop.

    Parameters
    ----------
    start : ndarray, shape (4,)
        State (absolute angles) [rad, rad/s].

    Returns
    -------
    list of (int, int)
        Offsets ``(d1, d2)`` in turns from the nearest branch (:func:`nearest_upright`), ``(0, 0)`` first; a joint
        moving faster than :data:`MOVING_RATE` adds the branch one turn ahead in its direction.

    Raises
    ------
    ValueError
        ``start`` not a finite state of shape (4,).
    """
    x = np.asarray(start, dtype=float)
    if x.shape != (4,) or not np.all(np.isfinite(x)):
        raise ValueError(f"start must be a finite state of shape (4,), got {np.asarray(start).tolist()!r}")
    ahead = [(0, int(math.copysign(1.0, w))) if abs(w) > MOVING_RATE else (0,) for w in x[2:4]]
    return sorted({(d1, d2) for d1 in ahead[0] for d2 in ahead[1]}, key=lambda d: (abs(d[0]) + abs(d[1]), d))


def plan_swingup(
    fallback: GlobalSwingUp,
    actuation: str,
    start: np.ndarray,
    *,
    horizon: float,
    n_intervals: int,
    min_time: bool,
    max_iter: int = 150,
    max_solve_time: float = 60.0,
    velocity_limit: float | None = None,
    goal_offset: tuple[int, int] = (0, 0),
) -> TVLQRTracker | None:
    """The re-planner's plan: a swing-up from ``start`` to an upright branch, with its TVLQR gains.

    Direct collocation (Radau, ``n_intervals``): time-optimal with a free horizon in [0.3, ``horizon``] first
    when ``min_time``, effort-optimal over ``horizon`` otherwise or on failure; IPOPT capped at ``max_iter``.
    The tracker is designed at the fallback's sample time and torque limit.

    Parameters
    ----------
    fallback : GlobalSwingUp
        Supplies the design model, sample time and torque limit.
    actuation : {"pendubot", "acrobot"}
        Driven joint.
    start : ndarray, shape (4,)
        Start state (absolute angles) [rad, rad/s].
    horizon : float
        Plan horizon (the free horizon's upper bound) [s].
    n_intervals : int
        Collocation intervals.
    min_time : bool
        Try the time-optimal plan first.
    max_iter : int
        IPOPT iteration cap per solve.
    max_solve_time : float
        Wall-time safety budget per solve [s].
    velocity_limit : float, optional
        Bound on both joint rates over the plan [rad/s] (``SwingUpProblem.velocity_limit``); raised to the start's
        joint rates when they exceed it (the start must stay feasible). None: unbounded.
    goal_offset : (int, int)
        The goal's branch in turns from the nearest upright (:func:`upright_goals`); (0, 0): the nearest.

    Returns
    -------
    TVLQRTracker or None
        None when every attempt failed.

    Raises
    ------
    ValueError
        ``goal_offset`` not two integers.
    """
    from .swingup import SwingUpProblem, solve_transcription
    from .tracking import tvlqr

    if len(goal_offset) != 2 or not all(isinstance(d, (int, np.integer)) for d in goal_offset):
        raise ValueError(f"goal_offset must be two whole turns (d1, d2), got {goal_offset!r}")
    x0 = tuple(float(v) for v in start)
    near = nearest_upright(np.asarray(x0))
    goal = (near[0] + 2.0 * math.pi * goal_offset[0], near[1] + 2.0 * math.pi * goal_offset[1], 0.0, 0.0)
    vmax = None if velocity_limit is None else max(float(velocity_limit), float(np.max(np.abs(joint_rates(x0)))))
    attempts: list[dict[str, object]] = []
    if min_time:  # time-optimal first (bang-bang within 90 % of the limit), free horizon up to ``horizon``
        attempts.append(dict(horizon=0.8 * horizon, free_horizon=True, horizon_bounds=(0.3, horizon), objective="time"))
    attempts.append(dict(horizon=horizon))
    for kw in attempts:
        pb = SwingUpProblem(fallback.model, actuation, fallback.u_max, x0=x0, goal=goal, velocity_limit=vmax, **kw)
        try:
            res = solve_transcription(
                pb,
                "radau",
                N=n_intervals,
                tolerance=None,
                refine=False,
                ipopt_options={"print_level": 0, "sb": "yes", "max_iter": max_iter},
                max_wall_time=max_solve_time,
            )
        except (ValueError, RuntimeError):
            continue
        if res.success:
            return tvlqr(res, dt=fallback.sample_time)
    return None


#: Plan horizon [s] and collocation intervals per task. Pendubot: the shortest horizon at which 10 of 10 random
#: reset-like states (uniform configuration, rates in +-3 rad/s) solved within 150 IPOPT iterations (1.0 s: 7/10).
#: Acrobot: 1.5 s solved 9/10 but failed often in the protocol (v3 seed 2: 0.369); 2.0 s: 9/10, no failure in
#: the protocol run, seed 2: 0.582 (benchmarks/results/v3.md).
#: Third entry: try a time-optimal plan first (v3 seeds 0-2: pendubot 0.747 against 0.717 effort-optimal only,
#: acrobot 0.636 against 0.610).
REPLAN_DEFAULTS: dict[str, tuple[float, int, bool]] = {"pendubot": (1.2, 40, True), "acrobot": (2.0, 30, True)}


@checked(global_controller)
def replanning_controller(
    task: str,
    *,
    plan_delay: float = 0.0,
    horizon: float | None = None,
    min_time: bool | None = None,
    velocity_limit: float | None = None,
    **options: float,
) -> ReplanningSwingUp:
    """The re-planning global swing-up on a RealAIGym leaderboard task's plant (2 ms, 6 N.m).

    Parameters
    ----------
    task : {"pendubot", "acrobot"}
        Leaderboard task.
    plan_delay : float
        Start each plan from the state predicted this far ahead [s] (0: idealised instantaneous planning).
    horizon : float, optional
        Plan horizon [s]; default :data:`REPLAN_DEFAULTS`.
    min_time : bool, optional
        Try a time-optimal plan first (see :class:`ReplanningSwingUp`); default :data:`REPLAN_DEFAULTS`.
    velocity_limit : float, optional
        Bound on both link rates of every plan [rad/s]; None: unbounded.
    **options : float
        Overrides of the fallback (:func:`global_swingup`).

    Returns
    -------
    ReplanningSwingUp

    Raises
    ------
    ValueError
        Unknown task, negative ``plan_delay`` or non-positive ``horizon``.

    Examples
    --------
    >>> import pendulab as pl
    >>> from pendulab.control import as_feedback, replanning_controller
    >>> ctrl = replanning_controller("pendubot")  # plans from the current state, 2 ms TVLQR, LQR catch
    >>> model = ctrl.fallback.model
    >>> traj = pl.simulate(model, model.state(), 2.0, dt=ctrl.sample_time, u=as_feedback(ctrl, model))
    >>> ctrl.fallback.caught, ctrl.n_failed  # upright after one time-optimal plan
    (True, 0)
    """
    fb = global_controller(task, **options)
    delay = float(plan_delay)
    if not (math.isfinite(delay) and delay >= 0.0):
        raise ValueError(f"plan_delay must be a finite non-negative time [s], got {plan_delay!r}")
    h_default, n_int, mt_default = REPLAN_DEFAULTS[task]
    h = h_default if horizon is None else float(horizon)
    mt = mt_default if min_time is None else bool(min_time)
    return ReplanningSwingUp(fb, task, horizon=h, n_intervals=n_int, plan_delay=delay, min_time=mt, velocity_limit=velocity_limit)
