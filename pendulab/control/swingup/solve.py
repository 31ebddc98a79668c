"""``solve_transcription``: solve a :class:`SwingUpProblem` with IPOPT and report honestly (the expert path).

The default initial guess (``"auto"``) needs no tuning: a straight line from
start to goal; if IPOPT fails from there, a homotopy from the fully actuated
to the under-actuated problem (the passive joint's torque bound shrinks to
zero, each stage warm-started from the last). Elastic problems are first
solved on their rigid point-mass counterpart and lifted with quasi-static
spring lengths.

Every plan is then checked a posteriori (:mod:`.errors`: each interval
re-integrated by the fast path, relative defect per state) and, with
``refine=True``, the mesh is refined where the estimate exceeds the tolerance
(:mod:`.mesh`: h-refinement) and the NLP re-solved warm from the previous
solution, until the estimate meets the tolerance or a cap is hit.

A failed solve is a result with ``success=False``, IPOPT's return status and
a readable message, never an exception and never a trajectory passed off as
optimal.

An interrupt (Ctrl-C) is never a failed solve: CasADi catches the
``KeyboardInterrupt`` raised inside IPOPT's callbacks and returns as if IPOPT
had failed, which would start the next homotopy stage. :func:`solve_transcription`
watches SIGINT while it runs and raises ``KeyboardInterrupt`` as soon as the
interrupted IPOPT run returns, without starting another.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ..._inputs import checked
from .errors import SCALES, ErrorEstimate, estimate_error
from .guess import Guess, energy_guess, lift_to_elastic, linear_guess, rigid_counterpart_problem
from .iterations import SigintWatch, wall_time_budget, watch_sigint
from .mesh import collocation_states, parent_intervals, refine_mesh
from .problem import SwingUpProblem
from .result import SwingUpResult
from .transcription import COLLOCATION, Transcription, _build, get_transcription

__all__ = ["SwingUpResult", "solve_transcription", "GUESSES"]

#: Named initial-guess strategies accepted by :func:`solve_transcription`.
GUESSES: tuple[str, ...] = ("auto", "linear", "energy", "homotopy")
_IPOPT_OK = ("Solve_Succeeded", "Solved_To_Acceptable_Level")
#: A "successful" solution must satisfy its constraints to this level (defects in state units).
_FEASIBILITY_TOL = 1e-6
#: Passive-torque bound (fraction of the torque limit) of each homotopy stage.
_HOMOTOPY = (1.0, 0.3, 0.1, 0.03, 0.0)
_WARM_IPOPT = {"mu_strategy": "monotone", "mu_init": 1e-3}


@checked(max_intervals="intervals")
def solve_transcription(
    problem: SwingUpProblem,
    method: str = "radau",
    N: int | None = None,
    *,
    degree: int = 3,
    integrator: str = "rk",
    guess: str | Guess | SwingUpResult = "auto",
    ipopt_options: dict[str, Any] | None = None,
    tolerance: float | None = 1e-3,
    refine: bool = True,
    max_refinements: int = 4,
    max_intervals: int = 600,
    mesh: Any = None,
    error_method: str = "auto",
    error_scale: str = "state",
    max_wall_time: float | None = None,
) -> SwingUpResult:
    """Solve a swing-up problem by direct collocation or multiple shooting with IPOPT, check and refine it.

    The expert path: one transcription of the problem as given, with every
    solver option. The front door is :func:`pendulab.control.swing_up`, which
    applies the planning rule to elastic problems (a stiff elastic task solved
    here directly at degree 3, N = 100 refines to the interval cap and fails).

    Parameters
    ----------
    problem : SwingUpProblem
    method : {"radau", "legendre", "shooting"}
        Transcription (see :mod:`pendulab.control.swingup.transcription`).
    N : int, optional
        Number of control intervals of the first mesh, torques held on each (default: the
        problem's ``intervals``, 100 unless its task sets ``N``).
    degree : int
        Collocation polynomial degree (the same on every interval: h-refinement only).
    integrator : {"rk", "cvodes"}
        Integrator of multiple shooting (see :func:`get_transcription`).
    guess : {"auto", "linear", "energy", "homotopy"}, Guess or SwingUpResult
        Initial guess: ``auto`` = linear, falling back to the homotopy (and,
        for elastic models, starting from the rigid counterpart's solution);
        ``linear`` / ``energy`` = that guess alone; ``homotopy`` = always the
        full -> under-actuated homotopy; or an explicit trajectory.
    ipopt_options : dict or None
        Extra IPOPT options.
    tolerance : float or None
        Relative tolerance of the a posteriori error estimate (worst
        per-interval defect / the state's largest magnitude; see
        :func:`~pendulab.control.swingup.errors.estimate_error`). A plan
        whose estimate exceeds it is not a success. None: no estimate and no
        refinement (a single solve, judged by IPOPT and the constraints only).
    refine : bool
        Refine the mesh (split intervals whose defect exceeds ``tolerance``)
        and re-solve warm from the previous solution until the estimate meets
        the tolerance or a cap is hit. False: a single solve on the first mesh.
    max_refinements : int
        Cap on the number of refinements (re-solves) after the first solve.
    max_intervals : int
        Cap on the number of intervals of a refined mesh.
    mesh : array_like, shape (N,), or None
        Interval fractions of the first mesh (positive, normalised to sum 1);
        None = uniform.
    error_method : str
        Integrator of the error estimate: ``"auto"`` or a key of :data:`pendulab.METHODS`.
    error_scale : {"state", "bob-speed"}
        Normalisation of the error estimate (see
        :func:`~pendulab.control.swingup.errors.estimate_error`; default: each
        state's largest magnitude).
    max_wall_time : float, optional
        Wall-time budget [s] of the whole call (solves and refinements): IPOPT is
        stopped at its next iteration once it is spent, and the result is a failure
        saying so. None: no budget.

    Returns
    -------
    SwingUpResult
        ``success`` False (with IPOPT's status and a message) when IPOPT
        fails, its answer violates dynamics or bounds, the error estimate
        exceeds ``tolerance`` when the refinement stops (the message gives
        the estimate, the tolerance and the cap that was hit), or the
        wall-time budget ran out.

    Raises
    ------
    TypeError
        ``problem`` is not a SwingUpProblem.
    ValueError
        Unknown method/guess name, bad N, degree, mesh, tolerance, caps or error scale.
    KeyboardInterrupt
        On SIGINT (Ctrl-C), also when it arrives inside an IPOPT iteration;
        no further stage is started.

    Examples
    --------
    >>> from pendulab.control import solve_transcription
    >>> from pendulab.control.swingup.tasks import load_task
    >>> problem = load_task("pendubot").problem
    >>> res = solve_transcription(problem, "legendre", N=40)  # Gauss-Legendre collocation, refined to tolerance 1e-3
    >>> res.success, res.method, [h["N"] for h in res.mesh_history]  # 40 intervals, refined once
    (True, 'legendre', [40, 50])
    >>> print(f"cost {res.cost:.3f} N^2.m^2.s, worst relative defect {res.error.worst:.0e}")
    cost 1.223 N^2.m^2.s, worst relative defect 6e-05
    """
    if not isinstance(problem, SwingUpProblem):
        raise TypeError(f"problem must be a SwingUpProblem, got {type(problem).__name__}")
    if tolerance is not None and not (isinstance(tolerance, (int, float)) and np.isfinite(tolerance) and tolerance > 0):
        raise ValueError(f"tolerance must be a positive number or None, got {tolerance!r}")
    if not (isinstance(max_refinements, (int, np.integer)) and max_refinements >= 0):
        raise ValueError(f"max_refinements must be an integer >= 0, got {max_refinements!r}")
    if not (isinstance(max_intervals, (int, np.integer)) and max_intervals >= 2):
        raise ValueError(f"max_intervals must be an integer >= 2, got {max_intervals!r}")
    if error_scale not in SCALES:
        raise ValueError(f"error_scale must be one of {list(SCALES)}, got {error_scale!r}")
    if max_wall_time is not None:
        max_wall_time = float(max_wall_time)
    int(max_intervals)
    settings = _Settings(method, problem.intervals if N is None else N, degree, integrator, ipopt_options)
    with watch_sigint() as interrupt, wall_time_budget(max_wall_time) as budget:
        res = _solve_transcription(problem, settings, guess, mesh, interrupt, tolerance, refine, max_refinements, max_intervals,
                        (error_method, error_scale))  # fmt: skip
    if budget.exceeded:
        res = replace(
            res, success=False, message=res.message + f"; stopped by the wall-time budget max_wall_time={max_wall_time:g} s"
        )
    return res


def _solve_transcription(
    problem: SwingUpProblem,
    settings: _Settings,
    guess: Any,
    mesh: Any,
    interrupt: SigintWatch,
    tolerance: float | None,
    refine: bool,
    max_refinements: int,
    max_intervals: int,
    error: tuple[str, str],
) -> SwingUpResult:
    """One solve on the first mesh, then the a posteriori check and the refinements."""
    t_start = time.perf_counter()
    res = _solve_mesh(problem, settings, guess, mesh, interrupt)
    if tolerance is None:
        return res
    return _check_and_refine(
        problem, settings, res, float(tolerance), refine, max_refinements, max_intervals, error, interrupt, t_start
    )


@dataclass(frozen=True)
class _Settings:
    method: str
    N: int
    degree: int
    integrator: str
    ipopt_options: dict[str, Any] | None


def _estimate(res: SwingUpResult, tolerance: float, error: tuple[str, str]) -> tuple[ErrorEstimate | None, float]:
    t0 = time.perf_counter()
    if not np.all(np.isfinite(res.x)) or not np.all(np.isfinite(res.u)):
        return None, time.perf_counter() - t0
    return estimate_error(res, tolerance=tolerance, method=error[0], scale=error[1]), time.perf_counter() - t0


def _check_and_refine(
    problem: SwingUpProblem,
    settings: _Settings,
    res: SwingUpResult,
    tolerance: float,
    refine: bool,
    max_refinements: int,
    max_intervals: int,
    error: tuple[str, str],
    interrupt: SigintWatch,
    t_start: float,
) -> SwingUpResult:
    history: list[dict[str, Any]] = []
    stages = list(res.stages)
    build = res.build_time
    iterations = res.iterations
    # Error model e ~ h^(q + 1) with q one below the asymptotic rate (Radau(d) local error ~ h^(d + 1), RK4 ~ h^5):
    # from coarse meshes the defect falls slower, as the optimum moves with the mesh (free horizon: 0.16 -> 0.057
    # -> 0.030 -> 0.032 over N = 20 -> 60 with q = d; pendubot task, mix objective).
    order = max(1, settings.degree - 1) if settings.method in COLLOCATION else 3
    while True:
        est, t_est = _estimate(res, tolerance, error)
        history.append(_history_entry(res, est, t_est))
        passed = est is not None and est.passed
        if not res.success or passed or not refine:
            break
        if len(history) > max_refinements:
            break
        new_mesh, pieces = refine_mesh(res.mesh, est.interval_worst, tolerance, order, max_intervals=max_intervals)
        if new_mesh.size == res.N:  # at the interval cap: nothing left to split
            break
        res = _solve_refined(problem, settings, res, new_mesh, pieces, interrupt)
        stages.extend({**s, "label": f"refine {len(history)} (N={res.N}): " + s["label"]} for s in res.stages)
        build += res.build_time
        iterations += res.iterations
    message = res.message
    success = res.success and passed
    if est is not None:
        message += "; " + est.summary()
    if res.success and not passed:
        n_ref = len(history) - 1
        if not refine:
            why = "refinement off (refine=False)"
        elif n_ref >= max_refinements:
            why = f"cap max_refinements={max_refinements} reached"
        else:
            why = f"cap max_intervals={max_intervals} reached"
        worst = float("nan") if est is None else est.worst
        message += f"; plan rejected: error estimate {worst:.2e} > tolerance {tolerance:.1e} after {n_ref} refinements, {why}"
    return replace(
        res,
        success=success,
        message=message,
        iterations=iterations,
        stages=tuple(stages),
        wall_time=time.perf_counter() - t_start - build,
        build_time=build,
        error=est,
        mesh_history=tuple(history),
        solve_time=res.wall_time,
    )


def _history_entry(res: SwingUpResult, est: ErrorEstimate | None, t_est: float) -> dict[str, Any]:
    return {
        "N": res.N,
        "worst": float("nan") if est is None else est.worst,
        "passed": bool(est is not None and est.passed),
        "status": res.status,
        "iterations": res.iterations,
        "solve_time": res.wall_time,
        "estimate_time": t_est,
        "build_time": res.build_time,
    }


def _solve_refined(
    problem: SwingUpProblem,
    settings: _Settings,
    prev: SwingUpResult,
    mesh: np.ndarray,
    pieces: np.ndarray,
    interrupt: SigintWatch,
) -> SwingUpResult:
    """Re-solve on a refined mesh, warm from the previous solution transferred exactly."""
    options = {**_WARM_IPOPT, **(settings.ipopt_options or {})}
    tr, build = _transcription(problem, settings.method, mesh.size, settings.degree, settings.integrator, options)
    t_start = time.perf_counter()
    T = prev.horizon
    grid = tr.grid(T, mesh)
    parent = parent_intervals(pieces)
    if tr.n_coll and prev.xc.shape[0] == prev.N * prev.degree and prev.method == tr.method:
        states = lambda tq: collocation_states(prev.t, prev.x, prev.xc, prev.degree, prev.method, tq)  # noqa: E731
    else:
        states = prev.x_at
    X = states(grid)
    X[0], X[-1] = prev.x[0], prev.x[-1]
    if tr.n_coll:
        tc = (grid[:-1, None] + np.diff(grid)[:, None] * tr.collocation_times()[None, :]).ravel()
        Xc = states(tc)
    else:
        Xc = np.zeros((0, tr.nx))
    w0 = tr.join(X, Xc, prev.u[parent], T)
    stages: list[dict[str, Any]] = []
    out = _run(tr, problem, w0, 0.0, "warm", stages, interrupt, mesh)
    return _result(tr, problem, out, stages, time.perf_counter() - t_start, build, mesh)


def _solve_mesh(
    problem: SwingUpProblem, settings: _Settings, guess: str | Guess | SwingUpResult, mesh: Any, interrupt: SigintWatch
) -> SwingUpResult:
    """One solve on one mesh with the guess strategy ``guess`` (no error estimate)."""
    method, N, degree, integrator, ipopt_options = (
        settings.method,
        settings.N,
        settings.degree,
        settings.integrator,
        settings.ipopt_options,
    )
    if isinstance(guess, str) and guess not in GUESSES:
        raise ValueError(f"guess must be one of {list(GUESSES)}, a Guess or a SwingUpResult, got {guess!r}")
    if not isinstance(guess, (str, Guess, SwingUpResult)):
        raise ValueError(f"guess must be one of {list(GUESSES)}, a Guess or a SwingUpResult, got {type(guess).__name__}")
    warm = isinstance(guess, (Guess, SwingUpResult)) or (guess in ("auto", "homotopy") and problem.model.kind == "elastic")
    if warm:
        # From a good guess a small, monotone barrier parameter keeps IPOPT near it (fewer
        # iterations, lower-cost local optima on the elastic tasks: benchmarks/results/swingup.md).
        ipopt_options = {**_WARM_IPOPT, **(ipopt_options or {})}
    tr, build = _transcription(problem, method, N, degree, integrator, ipopt_options)
    mesh = tr.fractions(mesh)
    t_start = time.perf_counter()
    stages: list[dict[str, Any]] = []
    build_extra = 0.0

    if isinstance(guess, SwingUpResult):
        g = guess.as_guess()
    elif isinstance(guess, Guess):
        g = guess
    elif guess == "energy":
        g = energy_guess(problem)
    elif guess in ("auto", "homotopy") and problem.model.kind == "elastic":
        # The rigid plan is only a guess here: no estimate, no refinement.
        rigid_res = _solve_mesh(rigid_counterpart_problem(problem), replace(settings, ipopt_options=None), guess, mesh, interrupt)
        build_extra += rigid_res.build_time
        stages.extend({**s, "label": "rigid: " + s["label"]} for s in rigid_res.stages)
        g = lift_to_elastic(problem, rigid_res.t, rigid_res.x, np.vstack([rigid_res.u, rigid_res.u[-1:]]))
    else:
        g = linear_guess(problem)
    w0 = _guess_vector(tr, problem, g, mesh)

    out = None
    if guess != "homotopy":
        out = _run(tr, problem, w0, 0.0, "direct", stages, interrupt, mesh)
    if guess == "homotopy" or (guess == "auto" and not _ok(out)):
        w = w0
        for frac in _HOMOTOPY:
            out = _run(tr, problem, w, frac, f"passive {frac:g}x limit", stages, interrupt, mesh)
            # Keep going from the last iterate even after a failed stage: later stages often recover.
            w = out["w"]
    return _result(tr, problem, out, stages, time.perf_counter() - t_start, build + build_extra, mesh)


def _transcription(
    problem: SwingUpProblem, method: str, N: int, degree: int, integrator: str, ipopt_options: dict[str, Any] | None
) -> tuple[Transcription, float]:
    """The cached NLP and the time spent building it in this call (exactly 0 on a cache hit)."""
    misses = _build.cache_info().misses
    tr = get_transcription(problem, method, N, degree, integrator, ipopt_options)
    return tr, (tr.build_time if _build.cache_info().misses > misses else 0.0)


def _guess_vector(tr: Transcription, problem: SwingUpProblem, g: Guess, mesh: np.ndarray) -> np.ndarray:
    T = problem.horizon
    grid = tr.grid(T, mesh)
    X = g.states_at(grid, T)
    if tr.n_coll:
        tc = (grid[:-1, None] + np.diff(grid)[:, None] * tr.collocation_times()[None, :]).ravel()
        Xc = g.states_at(tc, T)
    else:
        Xc = np.zeros((0, tr.nx))
    U = g.inputs_at(grid[:-1], T)
    lb, ub = problem.torque_bounds()
    return tr.join(X, Xc, np.clip(U, lb, ub), T)


def _run(
    tr: Transcription,
    problem: SwingUpProblem,
    w0: np.ndarray,
    passive: float,
    label: str,
    stages: list,
    interrupt: SigintWatch,
    mesh: np.ndarray | None = None,
) -> dict:
    lb, ub = problem.torque_bounds(passive_fraction=passive)
    t0 = time.perf_counter()
    try:
        out = tr.solve(problem, w0, lb, ub, mesh)
    except RuntimeError as exc:  # function evaluation errors (NaN, integrator failure) end up here
        interrupt.check(str(exc))  # ... and interrupts CasADi turned into errors
        out = {"w": w0, "f": float("nan"), "g": np.array([np.inf]), "stats": {"return_status": f"Error: {exc}", "iter_count": 0}}
    # CasADi catches a KeyboardInterrupt raised in IPOPT's callbacks and returns (status
    # NonIpopt_Exception_Thrown): stop here, do not start another stage from an interrupted one.
    interrupt.check(str(out["stats"].get("return_status", "")))
    stats = out["stats"]
    iters = int(stats.get("iter_count", 0))
    stages.append(
        {
            "label": label,
            "status": str(stats.get("return_status", "unknown")),
            # IPOPT leaves iter_count unset when it stops before iterating (e.g. a missing linear solver).
            "iterations": iters if 0 <= iters <= 10**7 else 0,
            "time": time.perf_counter() - t0,
        }
    )
    return out


def _ok(out: dict | None) -> bool:
    if out is None:
        return False
    status = str(out["stats"].get("return_status", ""))
    return status in _IPOPT_OK and np.max(np.abs(out["g"]), initial=0.0) <= _FEASIBILITY_TOL


def _result(
    tr: Transcription, problem: SwingUpProblem, out: dict, stages: list, wall: float, build: float, mesh: np.ndarray | None = None
) -> SwingUpResult:
    X, Xc, U, T = tr.split(out["w"])
    T = problem.horizon if T is None else T
    status = stages[-1]["status"]
    violation = float(np.max(np.abs(out["g"]), initial=0.0))
    slb, sub = problem.state_bounds()
    tlb, tub = problem.torque_bounds()
    # Bounds are IPOPT-hard but relaxed by bound_relax_factor (1e-8): allow that much.
    bound_err = max(
        float(np.max(np.maximum(slb - X, X - sub), initial=0.0)),
        float(np.max(np.maximum(tlb - U, U - tub), initial=0.0)),
    )
    converged = status in _IPOPT_OK
    feasible = violation <= _FEASIBILITY_TOL and bound_err <= 1e-6
    success = converged and feasible
    iters = sum(s["iterations"] for s in stages)
    if success:
        message = f"{tr.method} N={tr.N}: IPOPT {status} after {iters} iterations, cost {out['f']:.6g}, T = {T:.4g} s"
    elif converged:
        message = (
            f"{tr.method} N={tr.N}: IPOPT reported {status} but the solution violates constraints "
            f"(defect {violation:.2e}, bounds {bound_err:.2e}); not a valid trajectory"
        )
    else:
        message = (
            f"{tr.method} N={tr.N}: IPOPT failed with status {status} after {iters} iterations "
            f"(constraint violation {violation:.2e}); the swing-up may be infeasible with torque limit "
            f"{problem.torque_limit:g} N.m in {T:.4g} s - try a longer horizon, a larger limit or another guess"
        )
    return SwingUpResult(
        problem=problem,
        method=tr.method,
        N=tr.N,
        degree=tr.degree if tr.method in COLLOCATION else 0,
        success=success,
        status=status,
        message=message,
        iterations=iters,
        wall_time=wall,
        build_time=build,
        t=tr.grid(T, mesh),
        x=X.copy(),
        u=U.copy(),
        cost=float(out["f"]),
        max_violation=violation,
        stages=tuple(stages),
        xc=Xc.copy(),
        solve_time=wall,
    )
