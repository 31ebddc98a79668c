"""Which model to plan an elastic swing-up on, and a plan proven on the full elastic dynamics.

Model no more than the task needs (DESIGN.md, principle 4) - the rule of the
scene hierarchy (:mod:`pendulab.bench.hierarchy`), restated here because
``control`` may not import ``bench``: *the cheapest model whose error is within
the tolerance wins; the full elastic model is the reference and always
qualifies.* Levels, cheapest first:

``rigid``
    Plan on the rigid point-mass counterpart; the springs are taken as rigid
    links (r = L, v = 0).
``rigid+quasi-static``
    Plan on the rigid counterpart; the springs follow at their quasi-static
    lengths r*(theta, omega, u) (:func:`pendulab.model.quasistatic.quasi_static_lengths`:
    gravity, centrifugal and torque load, zero radial acceleration), v = dr*/dt.
``elastic``
    Plan on the full elastic model (with mesh refinement), warm-started from the
    quasi-static lift of the rigid plan.

The error of a level is *predicted* from the modes (screening) and then
*measured* (the proof): the lifted plan is checked interval by interval on the
full elastic dynamics (:func:`pendulab.control.swingup.errors.estimate_error_arrays`).
A level that fails its proof hands over to the next one, so the decision never
rests on the prediction alone.

Prediction, with ``w_p`` the highest pendular and ``w_s`` the lowest spring
frequency (modes at hanging and upright, :func:`pendulab.analysis.modes.modes`)
and ``eps = w_p / w_s``:

* rigid: a spring not at its loaded length oscillates about it; the spring force
  of that oscillation is set by the load (not by k), and its effect on the
  angular rates over one interval averages out as ``1 / w_s``:
  error ~ ``C_RIGID * eps``;
* rigid+quasi-static: the lengths carry the load; what remains is the next
  order of the slow-manifold expansion: error ~ ``C_QUASI_STATIC * eps**2``.

The rigid plan is refined to half the tolerance, leaving the other half to
the modelling error of the lift. The constants were fitted on ``swingup_pendubot_elastic`` (rigid plan, N = 100,
springs 2.5e4 ... 1e9 N/m; docs/swingup.md gives the table); they order the
attempts, the proof decides.

Spring rates are judged against the bobs' speed scale: a stiff spring's own rate
is nearly zero along any plan, so relative to itself every micrometre of
oscillation would count as a 100 % error. The defect of ``v1, v2`` is divided by
``max(|v| over the plan, max_i |r_i omega_i| over the plan)`` (a bob's tangential
speed; both are velocities of the same point mass, in m/s).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ...analysis.modes import modes
from ...model.model import Model
from ...model.quasistatic import quasi_static_lengths
from .errors import ErrorEstimate, estimate_error_arrays
from .guess import Guess, rigid_counterpart
from .mesh import refine_mesh
from .problem import SwingUpProblem
from .solve import SwingUpResult, swing_up

_IPOPT_OK = ("Solve_Succeeded", "Solved_To_Acceptable_Level")
#: Largest constraint violation of a valid plan (as the solver's own check) [state units].
_FEASIBILITY_TOL = 1e-6

__all__ = [
    "PLANNING",
    "LEVELS",
    "C_RIGID",
    "C_QUASI_STATIC",
    "PlanningDecision",
    "Plan",
    "planning_rule",
    "plan",
    "lift_plan",
    "elastic_error",
    "solve_objective",
]

#: Planning choices accepted in task files and by :func:`plan` (``quasi-static`` = ``rigid+quasi-static``).
PLANNING: tuple[str, ...] = ("auto", "rigid", "quasi-static", "elastic")
#: Planning levels, cheapest first.
LEVELS: tuple[str, ...] = ("rigid", "rigid+quasi-static", "elastic")
#: Predicted relative error of a rigid plan on the elastic dynamics per unit of w_p / w_s.
C_RIGID = 3.0
#: Predicted relative error of a quasi-statically lifted rigid plan per unit of (w_p / w_s)^2.
C_QUASI_STATIC = 5.0
_LEVEL_OF = {"rigid": "rigid", "quasi-static": "rigid+quasi-static", "elastic": "elastic"}


@dataclass(frozen=True)
class PlanningDecision:
    """The planning-model rule applied to one elastic model.

    Attributes
    ----------
    requested : str
        What was asked (one of :data:`PLANNING`).
    chosen : str
        Level the rule starts from (one of :data:`LEVELS`; always ``rigid`` for a rigid model).
    pendular_frequency : float
        Highest pendular |lambda| at hanging and upright [rad/s].
    spring_frequency : float
        Lowest spring-mode frequency at hanging and upright [rad/s] (inf for a rigid model).
    predicted : dict of str to float
        Predicted relative error of each level on the elastic dynamics (dimensionless).
    tolerance : float
        Relative tolerance (dimensionless).
    reason : str
        One line: why this level.
    """

    requested: str
    chosen: str
    pendular_frequency: float
    spring_frequency: float
    predicted: dict[str, float]
    tolerance: float
    reason: str

    @property
    def separation(self) -> float:
        """Frequency ratio ``spring_frequency / pendular_frequency`` (inf for a rigid model)."""
        return self.spring_frequency / self.pendular_frequency


@dataclass(frozen=True)
class Plan:
    """A swing-up plan for the task's own (elastic or rigid) problem, with the evidence.

    Attributes
    ----------
    result : SwingUpResult
        The plan on the task's problem: for a rigid-level plan the rigid solution
        lifted to the elastic state (``xc`` empty), so that
        :func:`pendulab.control.tracking.tvlqr` tracks it on the elastic model.
        ``success`` is False when no level met the tolerance (``message`` says why).
    decision : PlanningDecision
        The rule's decision.
    level : str
        Level that produced ``result`` (one of :data:`LEVELS`).
    estimate : ErrorEstimate or None
        Error estimate of ``result`` on the task's full dynamics (spring rates
        against the bob speed scale, see the module notes); None when no plan was found.
    attempts : tuple of dict
        One per level tried: ``level``, ``worst`` (relative defect), ``passed``,
        ``time_s`` (solve + lift + proof [s]), ``N`` (intervals).
    wall_time : float
        Total time of :func:`plan` excluding NLP builds [s].
    build_time : float
        NLP build time spent in this call [s].
    """

    result: SwingUpResult
    decision: PlanningDecision
    level: str
    estimate: ErrorEstimate | None
    attempts: tuple[dict[str, Any], ...]
    wall_time: float
    build_time: float

    @property
    def success(self) -> bool:
        """A plan was found and its error estimate meets the tolerance."""
        return bool(self.result.success and self.estimate is not None and self.estimate.passed)


def _frequencies(model: Model) -> tuple[float, float]:
    """Highest pendular |lambda| and lowest spring frequency [rad/s] at hanging and upright."""
    pend, spring = 0.0, math.inf
    for at in ("down-down", "up-up"):
        for md in modes(model, at):
            if md.spring_share >= 0.5 and md.kind == "oscillatory":
                spring = min(spring, md.omega_n)
            elif md.spring_share < 0.5:
                pend = max(pend, md.omega_n)
    return pend, spring


def _rigid_guess(guess: Any) -> Any:
    """An elastic trajectory guess projected onto the rigid state (angles and rates); names pass through."""
    if isinstance(guess, SwingUpResult):
        guess = guess.as_guess()
    if isinstance(guess, Guess) and guess.x.shape[1] == 8:
        return Guess(guess.t, guess.x[:, [0, 1, 4, 5]], guess.u)
    return guess


def _solved(res: SwingUpResult) -> bool:
    """IPOPT converged to a point that satisfies the constraints (whatever the error estimate says)."""
    return bool(res.status in _IPOPT_OK and res.max_violation <= _FEASIBILITY_TOL and np.all(np.isfinite(res.x)))


def _check_tolerance(tolerance: Any) -> float:
    try:
        tol = float(tolerance)
    except (TypeError, ValueError):
        raise TypeError(f"tolerance must be a number (relative defect), got {type(tolerance).__name__}") from None
    if not (math.isfinite(tol) and tol > 0.0):
        raise ValueError(f"tolerance must be a positive finite relative defect, got {tolerance!r}")
    return tol


def planning_rule(model: Model, tolerance: float = 1e-3, planning: str = "auto") -> PlanningDecision:
    """Pick the cheapest planning model predicted to meet ``tolerance`` on the elastic dynamics.

    Parameters
    ----------
    model : Model
        The task's model (elastic; a rigid model is planned on as it is).
    tolerance : float
        Relative defect the plan must meet on the full dynamics (dimensionless, > 0).
    planning : {"auto", "rigid", "quasi-static", "elastic"}
        ``auto`` applies the rule; the others force a starting level (the proof
        still runs, and a failed level still hands over to the next one).

    Returns
    -------
    PlanningDecision
        The starting level, the frequencies and the predicted errors.

    Raises
    ------
    TypeError
        ``model`` is not a Model or ``tolerance`` is not a number.
    ValueError
        Unknown ``planning`` name or a non-positive tolerance.
    """
    if not isinstance(model, Model):
        raise TypeError(f"model must be a pendulab Model, got {type(model).__name__}")
    if planning not in PLANNING:
        raise ValueError(f"planning must be one of {list(PLANNING)}, got {planning!r}")
    tol = _check_tolerance(tolerance)
    if model.kind != "elastic":
        pend, _ = _frequencies(model)
        return PlanningDecision(planning, "rigid", pend, math.inf, {}, tol, "rigid model: planned on as it is")
    pend, spring = _frequencies(model)
    eps = pend / spring
    predicted = {"rigid": C_RIGID * eps, "rigid+quasi-static": C_QUASI_STATIC * eps**2, "elastic": 0.0}
    if planning != "auto":
        chosen = _LEVEL_OF[planning]
        reason = f"requested {planning!r}"
    else:
        chosen = next(level for level in LEVELS if predicted[level] <= tol)
        head = f"springs {spring / pend:.3g}x faster than the pendulum (w_s = {spring:.4g}, w_p = {pend:.4g} rad/s): "
        cheaper = ", ".join(f"{k} {predicted[k]:.2g}" for k in LEVELS[: LEVELS.index(chosen)])
        if chosen == "elastic":
            reason = head + f"no cheaper model predicted within tolerance {tol:.1e} ({cheaper})"
        else:
            reason = head + f"{chosen} predicted {predicted[chosen]:.2g} <= tolerance {tol:.1e}"
            reason += f" ({cheaper})" if cheaper else ""
    return PlanningDecision(planning, chosen, pend, spring, predicted, tol, reason)


def lift_plan(model: Model, level: str, t: np.ndarray, x_rigid: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Lift a rigid plan to elastic states for one planning level.

    Parameters
    ----------
    model : Model
        The elastic model.
    level : {"rigid", "rigid+quasi-static"}
        ``rigid``: springs at rest length, v = 0. ``rigid+quasi-static``:
        quasi-static lengths under the mean of the torques held before and after
        each node (the torque jumps there), v = dr/dt by second-order differences.
    t : ndarray, shape (K,)
        Grid times [s].
    x_rigid : ndarray, shape (K, 4)
        Rigid states (theta1, theta2, omega1, omega2).
    u : ndarray, shape (K - 1, 2)
        Torques held on the intervals [N.m].

    Returns
    -------
    ndarray, shape (K, 8)
        Elastic states (theta1, theta2, r1, r2, omega1, omega2, v1, v2).

    Raises
    ------
    ValueError
        Not an elastic model, an unknown level, or mismatched shapes.
    RuntimeError
        No quasi-static lengths at some node (springs too soft for the motion).
    """
    if not isinstance(model, Model) or model.kind != "elastic":
        raise ValueError("model must be an elastic pendulab Model to lift a rigid plan onto")
    t, x_rigid, u = np.asarray(t, float), np.asarray(x_rigid, float), np.asarray(u, float)
    K = t.size
    if x_rigid.shape != (K, 4) or u.shape != (K - 1, 2):
        raise ValueError(f"x_rigid must have shape ({K}, 4) and u ({K - 1}, 2), got {x_rigid.shape} and {u.shape}")
    theta, omega = x_rigid[:, :2], x_rigid[:, 2:]
    if level == "rigid":
        r = np.tile([model.params.L1, model.params.L2], (K, 1))
        v = np.zeros((K, 2))
    elif level == "rigid+quasi-static":
        u_node = np.vstack([u[:1], 0.5 * (u[1:] + u[:-1]), u[-1:]])
        r = np.array([quasi_static_lengths(model, theta[k], omega[k], u_node[k]) for k in range(K)])
        v = np.gradient(r, t, axis=0)
    else:
        raise ValueError(f"level must be 'rigid' or 'rigid+quasi-static' to lift a rigid plan, got {level!r}")
    return np.column_stack([theta, r, omega, v])


def elastic_error(model: Model, t: np.ndarray, x: np.ndarray, u: np.ndarray, tolerance: float = 1e-3) -> ErrorEstimate:
    """Error estimate of a plan on ``model`` with spring rates judged against the bob speed scale.

    Parameters
    ----------
    model : Model
        Model the plan must satisfy (rigid models: the plain estimate).
    t : ndarray, shape (N + 1,)
        Grid [s].
    x : ndarray, shape (N + 1, nx)
        States on the grid.
    u : ndarray, shape (N, 2)
        Held torques [N.m].
    tolerance : float
        Relative tolerance of the verdict.

    Returns
    -------
    ErrorEstimate
        As :func:`estimate_error_arrays`, with ``scale`` of v1, v2 raised to
        ``max_i |r_i omega_i|`` over the plan [m/s] when that is larger.

    Raises
    ------
    ValueError
        Bad shapes or values (from :func:`estimate_error_arrays`).
    """
    est = estimate_error_arrays(model, t, x, u, tolerance=tolerance)
    if model.kind != "elastic":
        return est
    x = np.asarray(x, float)
    speed = float(np.max(np.abs(x[:, 2:4] * x[:, 4:6])))
    scale = est.scale.copy()
    scale[6:8] = np.maximum(scale[6:8], speed)
    defects = est.absolute / scale
    worst_k = defects.max(axis=1)
    worst = float(worst_k.max())
    return replace(est, defects=defects, interval_worst=worst_k, worst=worst, passed=bool(worst <= est.tolerance), scale=scale)


def _solve(
    problem: SwingUpProblem,
    method: str,
    N: int,
    degree: int,
    guess: Any,
    tolerance: float,
    refine: bool,
    mesh: np.ndarray | None = None,
    max_intervals: int = 600,
) -> SwingUpResult:
    """swing_up with the error tolerance and mesh refinement of the solver."""
    return swing_up(
        problem, method, N, degree=degree, guess=guess, tolerance=tolerance, refine=refine, mesh=mesh, max_intervals=max_intervals
    )


def solve_objective(
    problem: SwingUpProblem, method: str, N: int, degree: int, guess: Any, tolerance: float, refine: bool
) -> SwingUpResult:
    """Solve one problem; a free-horizon ``time``/``mix`` objective from an ``effort`` solution at the guessed horizon.

    Minimum-time optima ride the torque bound almost everywhere; from a straight
    line IPOPT wanders (hundreds of iterations, homotopy fallbacks). The fixed-
    horizon effort problem is easy and its solution is a good guess of the swing.

    Parameters
    ----------
    problem : SwingUpProblem
    method : str
        Transcription.
    N, degree : int
        Intervals and collocation degree.
    guess : str, Guess or SwingUpResult
        Initial guess of :func:`swing_up`; the effort stage runs only for ``"auto"``.
    tolerance : float
        Relative error tolerance (passed to the solver when it refines).
    refine : bool
        Mesh refinement on/off (passed to the solver when it refines).

    Returns
    -------
    SwingUpResult
        The final stage's result; ``stages`` include the effort stage (label
        prefixed ``effort:``) and ``wall_time``/``build_time`` cover both stages.
    """
    if problem.objective == "effort" or not problem.free_horizon or guess != "auto":
        return _solve(problem, method, N, degree, guess, tolerance, refine)
    effort = problem.replace(objective="effort", free_horizon=False)
    first = _solve(effort, method, N, degree, "auto", tolerance, False)
    res = _solve(problem, method, N, degree, first if first.success else "auto", tolerance, refine)
    stages = tuple({**s, "label": "effort: " + s["label"]} for s in first.stages) + tuple(res.stages)
    return replace(
        res,
        stages=stages,
        iterations=res.iterations + first.iterations,
        wall_time=res.wall_time + first.wall_time,
        build_time=res.build_time + first.build_time,
    )


def plan(
    problem: SwingUpProblem,
    *,
    planning: str = "auto",
    tolerance: float = 1e-3,
    method: str = "radau",
    N: int = 100,
    degree: int = 3,
    guess: str | Guess | SwingUpResult = "auto",
    refine: bool = True,
    max_intervals: int = 300,
) -> Plan:
    """Plan a swing-up on the cheapest adequate model and prove it on the problem's full dynamics.

    Parameters
    ----------
    problem : SwingUpProblem
        The task's problem (elastic or rigid).
    planning : {"auto", "rigid", "quasi-static", "elastic"}
        Starting level (``auto``: :func:`planning_rule`).
    tolerance : float
        Relative defect the plan must meet (dimensionless, > 0).
    method : str
        Transcription.
    N, degree : int
        Initial intervals and collocation degree.
    guess : str, Guess or SwingUpResult
        Initial guess of the first solve (see :func:`swing_up`).
    refine : bool
        Mesh refinement of the solver on/off.
    max_intervals : int
        Cap on the intervals of a refined mesh (elastic NLPs of 600 intervals took
        minutes to build and ~6 GB of memory here; 300 is the default cap).

    Returns
    -------
    Plan
        For an elastic problem: the first level (from the rule's choice on,
        cheapest first) whose lifted plan passes the elastic error estimate;
        the elastic level is solved with refinement, warm-started from the
        quasi-static lift on the rigid plan's mesh split where the lift misses
        the tolerance (refined on the full model only where needed). A rigid
        problem is solved as it is.

    Raises
    ------
    TypeError
        ``problem`` is not a SwingUpProblem.
    ValueError
        Unknown ``planning`` name or a bad tolerance (and bad solver settings).
    """
    if not isinstance(problem, SwingUpProblem):
        raise TypeError(f"problem must be a SwingUpProblem, got {type(problem).__name__}")
    decision = planning_rule(problem.model, tolerance, planning)
    tol = decision.tolerance
    t0 = time.perf_counter()
    build = 0.0
    attempts: list[dict[str, Any]] = []
    model = problem.model

    def record(level: str, res: SwingUpResult, est: ErrorEstimate | None, t_start: float) -> None:
        worst = est.worst if est is not None else math.inf
        passed = bool(est is not None and est.passed and res.success)
        attempts.append({"level": level, "worst": worst, "passed": passed, "time_s": time.perf_counter() - t_start, "N": res.N})

    def finish(res: SwingUpResult, level: str, est: ErrorEstimate | None) -> Plan:
        return Plan(res, decision, level, est, tuple(attempts), time.perf_counter() - t0 - build, build)

    if model.kind != "elastic":
        ts = time.perf_counter()
        res = solve_objective(problem, method, N, degree, guess, tol, refine)
        build += res.build_time
        # The solver's own estimate is the proof here (same model, same scale): no second re-integration.
        est = res.error if res.error is not None and res.error.tolerance == tol else None
        if est is None and res.success:
            est = elastic_error(model, res.t, res.x, res.u, tol)
        record("rigid", res, est, ts)
        return finish(res, "rigid", est)

    warm: Any = guess
    mesh: np.ndarray | None = None
    levels = LEVELS[LEVELS.index(decision.chosen) :]
    if levels[0] != "elastic" or guess == "auto":
        # The rigid plan is the rigid levels' answer and the elastic level's warm start.
        ts = time.perf_counter()
        # Half the error budget for the rigid plan's discretisation, half for the modelling (the lift).
        rigid_res = solve_objective(rigid_counterpart(problem), method, N, degree, _rigid_guess(guess), 0.5 * tol, refine)
        build += rigid_res.build_time
        for level in LEVELS[:-1]:
            tl = ts if level == levels[0] else time.perf_counter()
            # A converged rigid plan that missed its share of the tolerance still lifts: the proof
            # on the elastic dynamics includes its discretisation error, and it is a good warm start.
            if not _solved(rigid_res):
                if level in levels:
                    record(level, rigid_res, None, tl)
                continue
            try:
                x = lift_plan(model, level, rigid_res.t, rigid_res.x, rigid_res.u)
            except RuntimeError:  # springs too soft to carry the motion quasi-statically
                if level in levels:
                    record(level, rigid_res, None, tl)
                continue
            lifted = replace(
                rigid_res, problem=problem, x=x, xc=np.zeros((0, model.nx)), message=f"{level} plan: " + rigid_res.message
            )
            needed = level in levels or (refine and level == "rigid+quasi-static")
            est = elastic_error(model, rigid_res.t, x, rigid_res.u, tol) if needed else None
            if level == "rigid+quasi-static":
                warm = lifted
                if refine and est is not None:
                    # The elastic solve starts on the rigid plan's mesh, split where the lift misses the tolerance.
                    mesh, _ = refine_mesh(lifted.mesh, est.interval_worst, tol, max(degree, 1), max_intervals=max_intervals)
            if level not in levels:
                continue
            record(level, lifted, est, tl)
            if est.passed:
                return finish(replace(lifted, success=True, error=est), level, est)
    ts = time.perf_counter()
    res = _solve(problem, method, N if mesh is None else mesh.size, degree, warm, tol, refine, mesh, max_intervals)
    build += res.build_time
    # A plan IPOPT solved feasibly but the solver rejected on its own estimate (spring rates against
    # their own, tiny, magnitude) is judged here like every other level: against the bob speed scale.
    solved = _solved(res)
    est = elastic_error(model, res.t, res.x, res.u, tol) if solved else None
    record("elastic", res, est, ts)
    if est is not None and est.passed and not res.success:
        res = replace(res, success=True, message=f"{res.message}; accepted: {est.summary()} (spring rates against the bob speed)")
    elif res.success and est is not None and not est.passed:
        res = replace(
            res,
            success=False,
            message=f"{res.message}; error estimate {est.worst:.2e} above tolerance {tol:.1e} on the elastic dynamics",
        )
    return finish(res, "elastic", est)
