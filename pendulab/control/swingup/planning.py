"""A swing-up plan proven on the task's full dynamics, and the front door :func:`swing_up`.

:func:`plan` applies the planning rule of :mod:`.rule` (which model to plan an
elastic swing-up on: rigid, rigid + quasi-static springs, or the full elastic
model; the rule and its constants are documented there), lifts the plan to the
task's state and proves it on the full dynamics; :func:`swing_up` is the same
path returning the plan's :class:`~pendulab.control.swingup.result.SwingUpResult`,
the function a user calls first for every shipped task, rigid or elastic.
:func:`pendulab.control.swingup.solve.solve_transcription` is the expert path:
one transcription of the problem as given (no planning model), with every
solver option.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ..._inputs import checked
from .errors import SCALES, ErrorEstimate, estimate_error_arrays, rescale
from .guess import Guess, lift_plan, rigid_counterpart_problem
from .mesh import oscillation_mesh
from .problem import SwingUpProblem
from .rule import (  # noqa: F401  (PLANNING, C_RIGID, C_QUASI_STATIC, elastic_error: re-exported from their old home)
    C_QUASI_STATIC,
    C_RIGID,
    ELASTIC_DEGREE,
    LEVELS,
    PLANNING,
    PlanningDecision,
    elastic_error,
    fastest_spring_frequency,
    planning_rule,
)
from .solve import SwingUpResult, solve_transcription
from .transcription import COLLOCATION

_IPOPT_OK = ("Solve_Succeeded", "Solved_To_Acceptable_Level")
#: Largest constraint violation of a valid plan (as the solver's own check) [state units].
_FEASIBILITY_TOL = 1e-6

__all__ = ["Plan", "plan", "swing_up", "solve_objective", "is_solved"]


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
        Error estimate of ``result`` on the task's full dynamics (normalised as
        ``error_scale`` of :func:`plan`); None when no plan was found.
    attempts : tuple of dict
        One per level tried: ``level``, ``worst`` (relative defect), ``worst_bob_speed``
        (the same defects with spring rates against the bob speed), ``passed``,
        ``time_s`` (solve + lift + proof [s]), ``N`` (intervals), ``degree``.
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


def _rigid_guess(guess: Any) -> Any:
    """An elastic trajectory guess projected onto the rigid state (angles and rates); names pass through."""
    if isinstance(guess, SwingUpResult):
        guess = guess.as_guess()
    if isinstance(guess, Guess) and guess.x.shape[1] == 8:
        return Guess(guess.t, guess.x[:, [0, 1, 4, 5]], guess.u)
    return guess


def is_solved(res: SwingUpResult) -> bool:
    """IPOPT converged to a point that satisfies the constraints (whatever the error estimate says).

    Parameters
    ----------
    res : SwingUpResult
        A solve.

    Returns
    -------
    bool
        Converged, feasible within the solver's own check, finite.
    """
    return bool(res.status in _IPOPT_OK and res.max_violation <= _FEASIBILITY_TOL and np.all(np.isfinite(res.x)))


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
    error_scale: str = "state",
) -> SwingUpResult:
    """The transcription-level solve with the error tolerance and mesh refinement of the solver."""
    return solve_transcription(
        problem,
        method,
        N,
        degree=degree,
        guess=guess,
        tolerance=tolerance,
        refine=refine,
        mesh=mesh,
        max_intervals=max_intervals,
        error_scale=error_scale,
    )


def solve_objective(
    problem: SwingUpProblem,
    method: str,
    N: int,
    degree: int,
    guess: Any,
    tolerance: float,
    refine: bool,
    error_scale: str = "state",
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
        Initial guess of :func:`solve_transcription`; the effort stage runs only for ``"auto"``.
    tolerance : float
        Relative error tolerance (passed to the solver when it refines).
    refine : bool
        Mesh refinement on/off (passed to the solver when it refines).
    error_scale : {"state", "bob-speed"}
        Normalisation of the error estimate (see :func:`estimate_error_arrays`).

    Returns
    -------
    SwingUpResult
        The final stage's result; ``stages`` include the effort stage (label
        prefixed ``effort:``) and ``wall_time``/``build_time`` cover both stages.
    """
    if problem.objective == "effort" or not problem.free_horizon or guess != "auto":
        return _solve(problem, method, N, degree, guess, tolerance, refine, error_scale=error_scale)
    effort = problem.replace(objective="effort", free_horizon=False)
    first = _solve(effort, method, N, degree, "auto", tolerance, False, error_scale=error_scale)
    res = _solve(problem, method, N, degree, first if first.success else "auto", tolerance, refine, error_scale=error_scale)
    stages = tuple({**s, "label": "effort: " + s["label"]} for s in first.stages) + tuple(res.stages)
    return replace(
        res,
        stages=stages,
        iterations=res.iterations + first.iterations,
        wall_time=res.wall_time + first.wall_time,
        build_time=res.build_time + first.build_time,
    )


@checked(max_intervals="intervals")
def plan(
    problem: SwingUpProblem,
    *,
    planning: str = "auto",
    tolerance: float = 1e-3,
    method: str = "radau",
    N: int | None = None,
    degree: int = 3,
    guess: str | Guess | SwingUpResult = "auto",
    refine: bool = True,
    max_intervals: int = 300,
    error_scale: str = "state",
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
        Initial intervals (default: the problem's ``intervals``) and collocation degree (of the rigid plan; the elastic
        level raises the degree, and if needed N, until the fastest spring mode is
        resolved, module notes).
    guess : str, Guess or SwingUpResult
        Initial guess of the first solve (see :func:`solve_transcription`).
    refine : bool
        Mesh refinement of the solver on/off.
    max_intervals : int
        Cap on the intervals of a mesh (elastic NLPs of 600 degree-3 intervals took
        minutes to build and ~6 GB of memory here; 300 is the default cap).
    error_scale : {"state", "bob-speed"}
        Normalisation of the proofs' error estimates (default: each state's
        largest magnitude; see :func:`estimate_error_arrays`).

    Returns
    -------
    Plan
        For an elastic problem: the first level (from the rule's choice on,
        cheapest first) whose lifted plan passes the elastic error estimate;
        the elastic level is solved at a degree and on a uniform mesh that
        resolve the fastest spring mode (p-refinement), warm-started from the rigid
        plan re-solved on that mesh and lifted quasi-statically, and h-refined
        where its estimate still misses the tolerance. A rigid problem is solved
        as it is.

    Raises
    ------
    TypeError
        ``problem`` is not a SwingUpProblem.
    ValueError
        Unknown ``planning`` name or error scale, a bad tolerance (and bad solver settings).

    Examples
    --------
    >>> from pendulab.control import plan
    >>> from pendulab.control.swingup.tasks import load_task
    >>> problem = load_task("pendubot_elastic").problem  # springs of 25 kN/m
    >>> p = plan(problem, N=40, tolerance=0.2, error_scale="bob-speed")  # a coarse 20 % plan: cheap levels qualify
    >>> p.decision.chosen, p.level, p.success
    ('rigid+quasi-static', 'rigid+quasi-static', True)
    >>> p.result.x.shape  # the rigid plan lifted to the elastic state, proven on the elastic dynamics
    (41, 8)
    >>> print(f"predicted {p.decision.predicted[p.level]:.2f}, measured {p.estimate.worst:.2f}")
    predicted 0.15, measured 0.15
    """
    if not isinstance(problem, SwingUpProblem):
        raise TypeError(f"problem must be a SwingUpProblem, got {type(problem).__name__}")
    N = problem.intervals if N is None else N
    if error_scale not in SCALES:
        raise ValueError(f"error_scale must be one of {list(SCALES)}, got {error_scale!r}")
    decision = planning_rule(problem.model, tolerance, planning)
    tol = decision.tolerance
    t0 = time.perf_counter()
    build = 0.0
    attempts: list[dict[str, Any]] = []
    model = problem.model

    def record(level: str, res: SwingUpResult, est: ErrorEstimate | None, t_start: float) -> None:
        worst = est.worst if est is not None else math.inf
        bob = rescale(est, model, res.x, "bob-speed").worst if est is not None else math.inf
        passed = bool(est is not None and est.passed and res.success)
        attempts.append(
            {
                "level": level,
                "worst": worst,
                "worst_bob_speed": bob,
                "passed": passed,
                "time_s": time.perf_counter() - t_start,
                "N": res.N,
                "degree": res.degree,
            }
        )

    def finish(res: SwingUpResult, level: str, est: ErrorEstimate | None) -> Plan:
        return Plan(res, decision, level, est, tuple(attempts), time.perf_counter() - t0 - build, build)

    if model.kind != "elastic":
        ts = time.perf_counter()
        res = solve_objective(problem, method, N, degree, guess, tol, refine, error_scale)
        build += res.build_time
        # The solver's own estimate is the proof here (same model, same scale): no second re-integration.
        est = res.error if res.error is not None and res.error.tolerance == tol else None
        if est is None and res.success:
            est = estimate_error_arrays(model, res.t, res.x, res.u, tolerance=tol, scale=error_scale)
        record("rigid", res, est, ts)
        return finish(res, "rigid", est)

    warm: Any = guess
    levels = LEVELS[LEVELS.index(decision.chosen) :]
    d_el, n_el = _elastic_discretisation(problem, method, N, degree, tol, max_intervals)
    rigid_problem = rigid_counterpart_problem(problem)
    rigid_res: SwingUpResult | None = None
    if levels[0] != "elastic" or guess == "auto":
        ts = time.perf_counter()
        # Refined (to half the tolerance, half left to the lift's modelling error) only when a rigid
        # level may be the answer; for the elastic level it is just the first warm start.
        refine_rigid = refine and levels[0] != "elastic"
        rigid_res = solve_objective(rigid_problem, method, N, degree, _rigid_guess(guess), 0.5 * tol, refine_rigid, error_scale)
        build += rigid_res.build_time
        for level in levels[:-1]:
            tl = ts if level == levels[0] else time.perf_counter()
            # A converged rigid plan that missed its share of the tolerance still lifts: the proof
            # on the elastic dynamics includes its discretisation error.
            if not is_solved(rigid_res):
                record(level, rigid_res, None, tl)
                continue
            try:
                x = lift_plan(model, level, rigid_res.t, rigid_res.x, rigid_res.u)
            except RuntimeError:  # springs too soft to carry the motion quasi-statically
                record(level, rigid_res, None, tl)
                continue
            lifted = replace(
                rigid_res, problem=problem, x=x, xc=np.zeros((0, model.nx)), message=f"{level} plan: " + rigid_res.message
            )
            est = estimate_error_arrays(model, rigid_res.t, x, rigid_res.u, tolerance=tol, scale=error_scale)
            record(level, lifted, est, tl)
            if est.passed:
                return finish(replace(lifted, success=True, error=est), level, est)
    ts = time.perf_counter()
    if rigid_res is not None and is_solved(rigid_res):
        warm = _elastic_warm_start(problem, rigid_problem, rigid_res, method, n_el, d_el)
        build += warm.build_time
    res = _solve(problem, method, n_el, d_el, warm, tol, refine, None, max(max_intervals, n_el), error_scale)
    build += res.build_time
    # The solver's own estimate (same model, same scale) is the proof.
    est = res.error if is_solved(res) else None
    record("elastic", res, est, ts)
    return finish(res, "elastic", est)


def _elastic_discretisation(
    problem: SwingUpProblem, method: str, N: int, degree: int, tol: float, max_intervals: int
) -> tuple[int, int]:
    """p-refinement of the elastic level: (degree, uniform intervals) that resolve the fastest spring mode.

    The lowest degree from the task's up to :data:`ELASTIC_DEGREE` that resolves the mode on the
    task's N intervals; if none does, :data:`ELASTIC_DEGREE` on as many intervals as the mode needs.
    """
    if method not in COLLOCATION:
        return degree, N
    omega = fastest_spring_frequency(problem.model)
    for d in range(degree, max(degree, ELASTIC_DEGREE) + 1):
        if oscillation_mesh(problem.horizon, omega, d, tol, N) == N:
            return d, N
    d = max(degree, ELASTIC_DEGREE)
    return d, min(oscillation_mesh(problem.horizon, omega, d, tol, N), max(max_intervals, N))


def _elastic_warm_start(
    problem: SwingUpProblem, rigid_problem: SwingUpProblem, rigid_res: SwingUpResult, method: str, N: int, degree: int
) -> SwingUpResult:
    """The rigid plan re-solved on the elastic level's mesh and degree, lifted to quasi-static spring lengths.

    An interpolated coarse plan is a poor start for the fine elastic NLP (pendubot_elastic:
    ~200 IPOPT iterations against ~20 from the re-solved rigid plan, docs/swingup.md).
    ``build_time`` of the result is the rigid re-solve's NLP build.
    """
    fine = replace(rigid_res, build_time=0.0)  # its build is already counted
    if (rigid_res.N, rigid_res.degree) != (N, degree) or not np.allclose(np.diff(rigid_res.t), rigid_res.horizon / rigid_res.N):
        fine = solve_transcription(rigid_problem, method, N, degree=degree, guess=rigid_res, tolerance=None)
        if not is_solved(fine):
            fine = replace(rigid_res, build_time=fine.build_time)
    try:
        x = lift_plan(problem.model, "rigid+quasi-static", fine.t, fine.x, fine.u)
    except RuntimeError:  # springs too soft to carry the motion quasi-statically: springs at rest length
        x = lift_plan(problem.model, "rigid", fine.t, fine.x, fine.u)
    return replace(fine, problem=problem, x=x, xc=np.zeros((0, problem.model.nx)), message="rigid plan lifted: " + fine.message)


#: Options of :func:`swing_up` that only the transcription-level solve has (ignored by the planner: an error there).
_TRANSCRIPTION_ONLY = ("integrator", "ipopt_options", "max_refinements", "mesh", "error_method", "max_wall_time")


@checked(max_intervals="intervals")
def swing_up(
    problem: SwingUpProblem,
    method: str = "radau",
    N: int | None = None,
    *,
    degree: int = 3,
    tolerance: float | None = 1e-3,
    planning: str = "auto",
    guess: str | Guess | SwingUpResult = "auto",
    refine: bool = True,
    max_intervals: int | None = None,
    error_scale: str = "state",
    **transcription: Any,
) -> SwingUpResult:
    """Solve a swing-up problem, rigid or elastic: the front door.

    A rigid problem is solved as it is
    (:func:`~pendulab.control.swingup.solve.solve_transcription`: transcription,
    a posteriori error estimate, mesh refinement). An elastic problem is planned
    by the planning rule (:func:`plan`: the cheapest planning model predicted to
    meet ``tolerance``, lifted and proven on the full elastic dynamics, the elastic
    level at the collocation degree its spring modes need), so every shipped task
    solves with these defaults. For the decision and the evidence call :func:`plan`;
    for one transcription of an elastic problem as given (the expert path) call
    :func:`~pendulab.control.swingup.solve.solve_transcription`.

    Parameters
    ----------
    problem : SwingUpProblem
        The problem.
    method : {"radau", "legendre", "shooting"}
        Transcription.
    N : int, optional
        Intervals of the first mesh (default: the problem's ``intervals``, 100 unless its task sets ``N``).
    degree : int
        Collocation degree (of the rigid plan of an elastic problem; the planner raises it where needed).
    tolerance : float or None
        Relative defect the plan must meet (dimensionless). None: one solve without an error
        estimate (rigid problems only: an elastic plan is always proven).
    planning : {"auto", "rigid", "quasi-static", "elastic"}
        Starting level of an elastic problem (``auto``: the rule); a rigid problem accepts ``auto`` and ``rigid``.
    guess : str, Guess or SwingUpResult
        Initial guess (see :func:`~pendulab.control.swingup.solve.solve_transcription`).
    refine : bool
        Mesh refinement on/off.
    max_intervals : int, optional
        Cap on the intervals of a refined mesh (default: the transcription's 600, the planner's 300).
    error_scale : {"state", "bob-speed"}
        Normalisation of the error estimate.
    **transcription
        Options of the transcription-level solve (``integrator``, ``ipopt_options``,
        ``max_refinements``, ``mesh``, ``error_method``, ``max_wall_time``): rigid problems only.

    Returns
    -------
    SwingUpResult
        The plan on the problem's own model (an elastic plan from a rigid level is
        lifted to the elastic state); ``success`` False with the reason in ``message``.

    Raises
    ------
    TypeError
        ``problem`` is not a SwingUpProblem, or an unknown keyword.
    ValueError
        Bad settings, or a transcription-only option (or ``tolerance=None``, a
        planning level) that does not apply to the problem's kind.
    KeyboardInterrupt
        On Ctrl-C during a solve.

    Examples
    --------
    >>> import numpy as np
    >>> from pendulab.control import swing_up
    >>> from pendulab.control.swingup.tasks import load_task
    >>> task = load_task("pendubot")  # RealAIGym pendubot: 6 N.m on the shoulder, 3 s
    >>> res = swing_up(task.problem, N=task.N)  # 40 intervals, refined where the error estimate asks
    >>> res.success, res.N, res.error.passed
    (True, 50, True)
    >>> print(f"cost {res.cost:.3f} N^2.m^2.s, peak shoulder torque {np.abs(res.u[:, 0]).max():.2f} N.m")
    cost 1.222 N^2.m^2.s, peak shoulder torque 1.65 N.m
    """
    if not isinstance(problem, SwingUpProblem):
        raise TypeError(f"problem must be a SwingUpProblem, got {type(problem).__name__}")
    N = problem.intervals if N is None else N
    unknown = sorted(set(transcription) - set(_TRANSCRIPTION_ONLY))
    if unknown:
        raise TypeError(f"swing_up() got unexpected keyword argument(s) {unknown}; options: {list(_TRANSCRIPTION_ONLY)}")
    if problem.model.kind != "elastic":
        if planning not in ("auto", "rigid"):
            raise ValueError(f"planning={planning!r} applies to elastic problems only; this problem's model is rigid")
        if max_intervals is not None:
            transcription["max_intervals"] = max_intervals
        return solve_transcription(
            problem, method, N, degree=degree, tolerance=tolerance, guess=guess, refine=refine, error_scale=error_scale,
            **transcription,
        )  # fmt: skip
    given = sorted(transcription)
    if given or tolerance is None:
        what = given if given else ["tolerance=None"]
        raise ValueError(
            f"{what} apply to the transcription-level solve only; swing_up plans an elastic problem by the planning "
            "rule (proven to a tolerance). Call pendulab.control.swingup.solve.solve_transcription for one "
            "transcription of the elastic problem as given"
        )
    return plan(
        problem, planning=planning, tolerance=tolerance, method=method, N=N, degree=degree, guess=guess, refine=refine,
        max_intervals=300 if max_intervals is None else max_intervals, error_scale=error_scale,
    ).result  # fmt: skip
