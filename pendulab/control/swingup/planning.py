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
    Plan on the full elastic model, warm-started from the quasi-static lift of
    the rigid plan. p-refinement first: the lowest collocation degree (from the
    task's up to :data:`ELASTIC_DEGREE`) that resolves the fastest spring mode
    on the task's N intervals, else :data:`ELASTIC_DEGREE` on a uniform mesh
    fine enough for it (:func:`pendulab.control.swingup.mesh.oscillation_mesh`:
    Radau of degree d follows an undamped mode within 1e-3 per interval up to
    ``h w`` = 1.41, 2.54, 3.83, 5.2, 6.7 for d = 3 ... 7), then h-refinement
    where the estimate still misses the tolerance. The warm start is the rigid plan
    re-solved on that mesh and degree (a coarse plan interpolated onto it cost
    the elastic NLP ~200 IPOPT iterations instead of ~20).

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
the modelling error of the lift. The constants bound the measured ratios on
``swingup_pendubot_elastic`` with springs of 1e3 ... 1e9 N/m (one rigid plan lifted;
benchmarks/results/swingup.md, "Planning rule"): rigid 1.1 ... 4.2, quasi-static
5 ... 14. They order the attempts; the proof decides.

Proofs use the error estimate's default normalisation (each state's largest
magnitude over the plan, the issue's metric); ``error_scale="bob-speed"``
judges the spring rates against the bobs' speed instead (the one definition is
in :mod:`.errors`). The constants above were fitted with the bob-speed scale:
under the default scale a quasi-statically lifted plan of very stiff springs
can fail its proof (each step of the held torque rings the springs with rates
far above the quasi-static ones) and the elastic level takes over.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ...analysis.modes import modes
from ...model.model import Model
from .errors import SCALES, ErrorEstimate, estimate_error_arrays, rescale
from .guess import Guess, lift_plan, rigid_counterpart
from .mesh import oscillation_mesh
from .problem import SwingUpProblem
from .solve import SwingUpResult, swing_up
from .transcription import COLLOCATION

_IPOPT_OK = ("Solve_Succeeded", "Solved_To_Acceptable_Level")
#: Largest constraint violation of a valid plan (as the solver's own check) [state units].
_FEASIBILITY_TOL = 1e-6

__all__ = [
    "PLANNING",
    "LEVELS",
    "C_RIGID",
    "C_QUASI_STATIC",
    "ELASTIC_DEGREE",
    "PlanningDecision",
    "Plan",
    "planning_rule",
    "plan",
    "elastic_error",
    "solve_objective",
]

#: Planning choices accepted in task files and by :func:`plan` (``quasi-static`` = ``rigid+quasi-static``).
PLANNING: tuple[str, ...] = ("auto", "rigid", "quasi-static", "elastic")
#: Planning levels, cheapest first.
LEVELS: tuple[str, ...] = ("rigid", "rigid+quasi-static", "elastic")
#: Predicted relative error of a rigid plan on the elastic dynamics per unit of w_p / w_s.
C_RIGID = 4.0
#: Predicted relative error of a quasi-statically lifted rigid plan per unit of (w_p / w_s)^2.
C_QUASI_STATIC = 15.0
#: Highest collocation degree of the elastic level's p-refinement (beyond it, more intervals).
ELASTIC_DEGREE = 7
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
        Highest pendular abs(lambda) at hanging and upright [rad/s].
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


def _frequencies(model: Model) -> tuple[float, float]:
    """Highest pendular abs(lambda) and lowest spring frequency [rad/s] at hanging and upright."""
    pend, spring = 0.0, math.inf
    for at in ("down-down", "up-up"):
        for md in modes(model, at):
            if md.spring_share >= 0.5 and md.kind == "oscillatory":
                spring = min(spring, md.omega_n)
            elif md.spring_share < 0.5:
                pend = max(pend, md.omega_n)
    return pend, spring


def _fastest_spring(model: Model) -> float:
    """Highest spring-mode frequency [rad/s] at hanging and upright (0 without springs)."""
    return max(
        (md.omega_n for at in ("down-down", "up-up") for md in modes(model, at) if md.spring_share >= 0.5),
        default=0.0,
    )


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


def elastic_error(model: Model, t: np.ndarray, x: np.ndarray, u: np.ndarray, tolerance: float = 1e-3) -> ErrorEstimate:
    """Error estimate of a plan on ``model`` with spring rates judged against the bob speed.

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
        :func:`estimate_error_arrays` with ``scale="bob-speed"`` (the definition lives there).

    Raises
    ------
    ValueError
        Bad shapes or values (from :func:`estimate_error_arrays`).
    """
    return estimate_error_arrays(model, t, x, u, tolerance=tolerance, scale="bob-speed")


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
    """swing_up with the error tolerance and mesh refinement of the solver."""
    return swing_up(
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
        Initial guess of :func:`swing_up`; the effort stage runs only for ``"auto"``.
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
        Initial intervals and collocation degree (of the rigid plan; the elastic
        level raises the degree, and if needed N, until the fastest spring mode is
        resolved, module notes).
    guess : str, Guess or SwingUpResult
        Initial guess of the first solve (see :func:`swing_up`).
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
    """
    if not isinstance(problem, SwingUpProblem):
        raise TypeError(f"problem must be a SwingUpProblem, got {type(problem).__name__}")
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
    rigid_problem = rigid_counterpart(problem)
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
            if not _solved(rigid_res):
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
    if rigid_res is not None and _solved(rigid_res):
        warm = _elastic_warm_start(problem, rigid_problem, rigid_res, method, n_el, d_el)
        build += warm.build_time
    res = _solve(problem, method, n_el, d_el, warm, tol, refine, None, max(max_intervals, n_el), error_scale)
    build += res.build_time
    # The solver's own estimate (same model, same scale) is the proof.
    est = res.error if _solved(res) else None
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
    omega = _fastest_spring(problem.model)
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
        fine = swing_up(rigid_problem, method, N, degree=degree, guess=rigid_res, tolerance=None)
        if not _solved(fine):
            fine = replace(rigid_res, build_time=fine.build_time)
    try:
        x = lift_plan(problem.model, "rigid+quasi-static", fine.t, fine.x, fine.u)
    except RuntimeError:  # springs too soft to carry the motion quasi-statically: springs at rest length
        x = lift_plan(problem.model, "rigid", fine.t, fine.x, fine.u)
    return replace(fine, problem=problem, x=x, xc=np.zeros((0, problem.model.nx)), message="rigid plan lifted: " + fine.message)
