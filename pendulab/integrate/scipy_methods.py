"""SciPy ``solve_ivp`` family: RK45, DOP853, Radau, BDF, LSODA.

The right-hand side is plain Python generated from the CasADi graph
(:func:`pendulab.model.pycode.to_python`); the implicit methods get the exact
CasADi Jacobian.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import lru_cache
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp

from ..model.model import model_functions
from ..model.pycode import to_python
from .registry import MethodSpec, RunRequest, RunResult

__all__ = ["METHOD_SPECS", "run_scipy", "python_rhs"]

_IMPLICIT = {"Radau", "BDF", "LSODA"}


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
    kwargs: dict[str, Any] = {"rtol": req.rtol, "atol": req.atol}
    if req.max_step is not None:
        kwargs["max_step"] = req.max_step
    kwargs.update(req.options)

    def solve(x_start: np.ndarray, u_const: np.ndarray, t_eval: np.ndarray) -> np.ndarray:
        ul = list(u_const)

        def fun(_t: float, x: np.ndarray) -> np.ndarray:
            return rhs(x, ul, p)

        jac_kw = {}
        if plugin in _IMPLICIT:

            def jac(_t: float, x: np.ndarray) -> np.ndarray:
                return np.asarray(jac_fun(x, u_const, model.p)[0])

            jac_kw["jac"] = jac
        sol = solve_ivp(fun, (t_eval[0], t_eval[-1]), x_start, method=plugin, t_eval=t_eval, **jac_kw, **kwargs)
        counter["n_rhs"] += int(sol.nfev)
        counter["n_jac"] += int(sol.njev)
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
    counter["n_steps"] = counter["n_steps"] or None
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
