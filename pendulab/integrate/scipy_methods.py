"""SciPy ``solve_ivp`` family: RK45, DOP853, Radau, BDF, LSODA.

The right-hand side is plain Python generated from the CasADi graph
(:func:`pendulab.model.pycode.to_python`); the implicit methods get the exact
CasADi Jacobian.

Options are the solver's own keywords (``first_step``, ``max_step``; LSODA also
``min_step``), checked before the run. The run's budget
(:class:`~pendulab.integrate.registry.Budget`) is kept by a subclass of the
solver that counts every step (``stats["n_steps"]``) and a wrapper of the RHS
that watches the wall time; both stop the run with a private exception that the
runner turns into a :class:`~pendulab.integrate.registry.SimulationError`.
A ``KeyboardInterrupt`` propagates unchanged.
"""

from __future__ import annotations

import inspect
import time
from collections.abc import Callable
from functools import cache, lru_cache
from typing import TYPE_CHECKING, Any

import numpy as np

from ..model.model import model_functions
from ..model.pycode import to_python
from .registry import MethodSpec, RunRequest, RunResult

if TYPE_CHECKING:
    from scipy.integrate import OdeSolver

__all__ = ["METHOD_SPECS", "run_scipy", "python_rhs", "solver_options"]

_IMPLICIT = {"Radau", "BDF", "LSODA"}


def _solver_class(name: str) -> type[OdeSolver]:
    """SciPy's solver class ``name``; scipy.integrate is imported here, on first use, because the method
    registry imports this module and everything that only looks a method up (e.g. the flip-map CLI's
    ensemble) paid 0.4-0.8 s for it."""
    import scipy.integrate

    return getattr(scipy.integrate, name)


#: Solver keywords the runner sets itself (or that would change the meaning of its exact Jacobian).
_MANAGED = ("self", "fun", "t0", "y0", "t_bound", "rtol", "atol", "vectorized", "jac", "jac_sparsity", "lband", "uband")


@cache
def solver_options(name: str) -> tuple[str, ...]:
    """Options a user may pass to a SciPy method: the solver's keywords the runner does not set.

    Parameters
    ----------
    name : str
        ``"RK45"``, ``"DOP853"``, ``"Radau"``, ``"BDF"`` or ``"LSODA"``.

    Returns
    -------
    tuple of str
        E.g. ``("first_step", "max_step")`` (LSODA adds ``min_step``).
    """
    params = inspect.signature(_solver_class(name).__init__).parameters.values()
    keep = (p.name for p in params if p.kind is p.POSITIONAL_OR_KEYWORD or p.kind is p.KEYWORD_ONLY)
    return tuple(sorted(n for n in keep if n not in _MANAGED))


#: A run whose time advances less than _STALL_FRACTION of its horizon over _STALL_STEPS steps has stalled.
_STALL_STEPS = 10_000
_STALL_FRACTION = 1e-9


class _BudgetExhaustedError(Exception):
    """Raised inside solve_ivp by the step counter or the RHS wrapper; caught by the runner."""

    def __init__(self, which: str, t: float) -> None:
        super().__init__(which)
        self.which = which
        self.t = t


def _counting(base: type[OdeSolver], req: RunRequest, counter: dict[str, Any]) -> type[OdeSolver]:
    """A subclass of ``base`` counting steps over the run and stopping at the step or wall budget."""
    budget = req.budget
    horizon = req.t_final
    mark = {"n": 0, "t": float(req.t[0])}

    class Counted(base):  # type: ignore[misc, valid-type]
        def step(self):  # noqa: ANN202 - OdeSolver.step
            if counter["n_steps"] >= budget.max_steps:
                raise _BudgetExhaustedError("steps", float(self.t))
            if budget.wall_exceeded():
                raise _BudgetExhaustedError("wall", float(self.t))
            message = super().step()
            counter["n_steps"] += 1
            if counter["n_steps"] - mark["n"] >= _STALL_STEPS:
                # Steps that no longer move time (e.g. a state growing without bound under huge torques)
                # would spend the whole step budget for nothing: stop early and say why.
                if abs(float(self.t) - mark["t"]) < _STALL_FRACTION * horizon:
                    raise req.fail(
                        float(self.t),
                        f"the step size collapsed: t advanced {abs(float(self.t) - mark['t']):.3g} s in the last "
                        f"{_STALL_STEPS} steps",
                    )
                mark["n"], mark["t"] = counter["n_steps"], float(self.t)
            return message

    Counted.__name__ = Counted.__qualname__ = f"Counted{base.__name__}"
    return Counted


@lru_cache(maxsize=8)
def python_rhs(kind: str) -> Callable[..., np.ndarray]:
    """The model's right-hand side as plain Python ``f(x, u, p) -> xdot`` (NumPy, no CasADi call).

    Parameters
    ----------
    kind : {"rigid", "elastic"}
        Model kind.

    Returns
    -------
    callable
        ``f(x, u, p)`` with sequences of lengths nx, 2 and np; returns an ndarray of shape (nx,).
    """
    return to_python(model_functions(kind)["rhs"])


def run_scipy(req: RunRequest) -> RunResult:
    """Runner of the SciPy family.

    Parameters
    ----------
    req : RunRequest
        A validated run.

    Returns
    -------
    RunResult
        States, held inputs and ``solve_ivp``'s counters.

    Raises
    ------
    SimulationError
        ``solve_ivp`` did not reach the end of an interval.
    """
    model, spec, t = req.model, req.spec, req.t
    plugin = spec.settings["plugin"]
    rhs = python_rhs(model.kind)
    p = model.p.tolist()
    jac_fun = model.functions["jac_rhs"]
    counter: dict[str, Any] = {"n_rhs": 0, "n_jac": 0, "n_steps": 0}
    accepted = solver_options(plugin)
    unknown = sorted(set(req.options) - set(accepted))
    if unknown:
        raise ValueError(
            f"method {spec.name!r}: unknown option(s) {unknown} for scipy.integrate.{plugin}; expected some of "
            f"{list(accepted)} or the budget options ['max_steps', 'max_wall_time'] (rtol, atol and the Jacobian "
            "are set from simulate's arguments)"
        )
    kwargs: dict[str, Any] = {"rtol": req.rtol, "atol": req.atol}
    if req.max_step is not None:
        kwargs["max_step"] = req.max_step
    kwargs.update(req.options)
    from scipy.integrate import solve_ivp

    solver = _counting(_solver_class(plugin), req, counter)
    budget = req.budget

    def solve(x_start: np.ndarray, u_const: np.ndarray, t_eval: np.ndarray) -> np.ndarray:
        ul = list(u_const)

        if budget.max_wall_time is None:

            def fun(_t: float, x: np.ndarray) -> np.ndarray:
                return rhs(x, ul, p)

        else:
            deadline = budget.start + budget.max_wall_time

            def fun(_t: float, x: np.ndarray) -> np.ndarray:
                # A step of an implicit method can take many evaluations: watch the clock here too.
                if time.perf_counter() > deadline:
                    raise _BudgetExhaustedError("wall", float(_t))
                return rhs(x, ul, p)

        jac_kw = {}
        if plugin in _IMPLICIT:

            def jac(_t: float, x: np.ndarray) -> np.ndarray:
                return np.asarray(jac_fun(x, u_const, model.p)[0])

            jac_kw["jac"] = jac
        before = counter["n_steps"]
        try:
            sol = solve_ivp(fun, (t_eval[0], t_eval[-1]), x_start, method=solver, t_eval=t_eval, **jac_kw, **kwargs)
        except _BudgetExhaustedError as exc:
            raise req.budget_error(exc.t, counter["n_steps"], exc.which) from None
        counter["n_rhs"] += int(sol.nfev)
        counter["n_jac"] += int(sol.njev)
        if counter["n_steps"] == before:  # a solver that does not go through step() (none today)
            counter["n_steps"] += int(getattr(sol, "nsteps", 0) or 0)
        if sol.status != 0 or sol.y.shape[1] != len(t_eval):
            t_end = float(sol.t[-1]) if sol.t.size else float(t_eval[0])
            raise req.fail(t_end, sol.message)
        return sol.y.T

    if req.constant_input:
        X = solve(req.x0, req.schedule[0], t)
        U = req.schedule
    else:
        X = np.empty((len(t), model.nx))
        U = np.empty((req.n_intervals, model.nu))
        X[0] = req.x0
        for k in range(req.n_intervals):
            U[k] = req.schedule[k] if req.schedule is not None else req.feedback_input(float(t[k]), X[k])
            X[k + 1] = solve(X[k], U[k], t[k : k + 2])[-1]
    return RunResult(X, U, counter)


def _spec(name: str, description: str) -> MethodSpec:
    return MethodSpec(name, "scipy", description, run_scipy, False, {"plugin": name})


#: The SciPy methods.
METHOD_SPECS: tuple[MethodSpec, ...] = (
    _spec("RK45", "SciPy Dormand-Prince 5(4)"),
    _spec("DOP853", "SciPy Dormand-Prince 8(5,3)"),
    _spec("Radau", "SciPy Radau IIA (order 5), exact Jacobian"),
    _spec("BDF", "SciPy BDF, exact Jacobian"),
    _spec("LSODA", "SciPy LSODA (Adams/BDF switching), exact Jacobian"),
)
