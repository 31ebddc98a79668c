"""The two integration routes of :func:`pendulab.ensemble.lyapunov.largest_lyapunov`: the state and one
tangent vector, renormalised at given times, by heyoka's variational equations (``"taylor"``) or by
CVODES on the CasADi-built augmented system (``"cvodes"``); compiled integrators cached per structure.

See :mod:`pendulab.ensemble.lyapunov` for the method and the measurements.
"""

from __future__ import annotations

import copy
import math
import threading
import time
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from .._checks import check_model
from .._inputs import checked
from ..model.model import Model

__all__ = ["variational_taylor_system"]

#: Taylor steps per propagation slice: Ctrl-C and the budgets are checked between slices.
_SLICE_STEPS = 2000


# -- Taylor (heyoka) --------------------------------------------------------------------
_VAR_CACHE: dict[Any, tuple[Any, Any, int]] = {}  # structure key -> (var_ode_sys, pars function, n pars)
_TAYLOR_CACHE: dict[Any, Any] = {}  # structure key -> compiled taylor_adaptive (copied per run)
_TAYLOR_LOCK = threading.RLock()


def _variational(model: Model, tol: float) -> tuple[Any, Any]:
    """The structure key and the cached entry's pieces: (key, (vsys, pars function)) — no compilation."""
    from ..integrate.taylor import structure_key, translate
    from ..integrate.taylor.availability import heyoka_module

    hy = heyoka_module()
    key = structure_key(model.kind, model.p, (0, 1), tol)
    with _TAYLOR_LOCK:
        found = _VAR_CACHE.get(key)
        if found is None:
            system = translate(
                model.functions["rhs"], zero_params=key.zero_params, zero_inputs=key.zero_inputs, state_names=model.state_names
            )
            first_state = system.sys[0][0]
            # d/d(x_0(0)) of the solution: one column of the state-transition matrix, i.e. the tangent
            # equations d(delta)/dt = A(x) delta; the column's initial value is overwritten at every renormalisation.
            vsys = hy.var_ode_sys(system.sys, [first_state], order=1)
            found = (vsys, system.pars, system.n_pars)
            _VAR_CACHE[key] = found
    return key, found


def _taylor_integrator(model: Model, tol: float) -> tuple[Any, np.ndarray]:
    """A fresh copy of the compiled (state + one tangent vector) integrator and its runtime parameters."""
    from ..integrate.taylor.availability import heyoka_module

    hy = heyoka_module()
    key, (vsys, pars_of, n_pars) = _variational(model, tol)
    with _TAYLOR_LOCK:
        ta = _TAYLOR_CACHE.get(key)
        if ta is None:
            ta = hy.taylor_adaptive(vsys, [0.0] * model.nx, pars=[0.0] * n_pars, tol=tol, compact_mode=False)
            _TAYLOR_CACHE[key] = ta
    return copy.copy(ta), np.asarray(pars_of(np.zeros(model.nu), model.p))


@checked()
def variational_taylor_system(model: Model, tol: float = 1e-12) -> tuple[list, np.ndarray]:
    """The heyoka ODE system ``[(x, f(x)), ..., (delta, A(x) delta)]`` integrated by ``method="taylor"``.

    Parameters
    ----------
    model : Model
        Rigid or elastic model (its structural zeros are specialised).
    tol : float
        Tolerance of the integrator (part of the cache key; the system does not depend on it).

    Returns
    -------
    sys : list of (heyoka.expression, heyoka.expression)
        ``2 nx`` pairs; the last ``nx`` are the tangent equations.
    pars : ndarray
        The runtime parameter values at ``model.p`` (see :func:`pendulab.integrate.taylor.translate`).

    Raises
    ------
    TaylorUnavailableError
        heyoka is not installed (an ``ImportError``).
    """
    model = check_model(model)
    _, (vsys, pars_of, _) = _variational(model, float(tol))
    return list(vsys.sys), np.asarray(pars_of(np.zeros(model.nu), model.p))


def _run_taylor(
    model: Model, x0: np.ndarray, d0: np.ndarray, times: np.ndarray, n_skip: int, rtol: float, budget: _Budget
) -> tuple:
    from ..integrate.taylor.availability import heyoka_module

    hy = heyoka_module()
    nx = model.nx
    ta, pars = _taylor_integrator(model, rtol)
    ta.time = 0.0
    ta.state[:nx] = x0
    ta.state[nx:] = d0
    ta.pars[:] = pars
    logs = np.empty(len(times))
    n_steps = 0
    step_limit, time_limit = hy.taylor_outcome.step_limit, hy.taylor_outcome.time_limit
    for i, t in enumerate(times):
        while True:  # slices of at most _SLICE_STEPS steps: a SIGINT is handled between two slices
            res = ta.propagate_until(float(t), max_steps=_SLICE_STEPS)
            n_steps += int(res[3])
            budget.check(n_steps, ta.time, float(times[-1]))
            if res[0] != step_limit:
                break
        if res[0] != time_limit or not np.all(np.isfinite(ta.state)):
            raise RuntimeError(
                f"largest_lyapunov: method 'taylor' (heyoka) stopped at t = {ta.time:.6g} s of {times[-1]:.6g} s "
                f"with status {res[0]} (state finite: {bool(np.all(np.isfinite(ta.state)))})"
            )
        _check_springs(model, ta.state[:nx], ta.time)
        norm = float(np.linalg.norm(ta.state[nx:]))
        logs[i] = math.log(norm)
        ta.state[nx:] /= norm
    return logs, np.array(ta.state[:nx]), np.array(ta.state[nx:]), n_steps


def _check_springs(model: Model, x: np.ndarray, t: float) -> None:
    """simulate's rule: a spring through zero length ends the run (the polar coordinates break down)."""
    if model.kind == "elastic" and not np.all(np.asarray(x)[2:4] > 0.0):
        raise RuntimeError(
            f"largest_lyapunov: spring length reached {np.asarray(x)[2:4].tolist()} m <= 0 at t = {t:.6g} s "
            "(a bob passed through its joint); stiffer springs or a gentler start keep the springs extended"
        )


@dataclass
class _Budget:
    """Step and wall-time budget of one estimate."""

    max_steps: int
    max_wall_time: float | None
    start: float = field(default_factory=time.perf_counter)

    def check(self, n_steps: int, t: float, t_end: float) -> None:
        if n_steps > self.max_steps:
            raise RuntimeError(
                f"largest_lyapunov: step budget exhausted (max_steps = {self.max_steps}) at t = {t:.6g} s of {t_end:.6g} s"
            )
        if self.max_wall_time is not None and time.perf_counter() - self.start > self.max_wall_time:
            raise RuntimeError(
                f"largest_lyapunov: wall-time budget exhausted (max_wall_time = {self.max_wall_time:g} s) "
                f"at t = {t:.6g} s of {t_end:.6g} s"
            )


# -- CVODES (CasADi) --------------------------------------------------------------------
_CVODES_CACHE: dict[tuple[str, float], ca.Function] = {}


def _cvodes_integrator(model: Model, rtol: float) -> ca.Function:
    """CVODES over s in [0, 1] of ``dz/ds = h [f(x); A(x) delta]`` with parameters ``[p; h]``."""
    key = (model.kind, rtol)
    with _TAYLOR_LOCK:
        F = _CVODES_CACHE.get(key)
        if F is None:
            sym = model.symbolic
            delta = ca.SX.sym("delta", model.nx)
            h = ca.SX.sym("h")
            xdot = ca.substitute(sym.xdot, sym.u, ca.SX.zeros(sym.u.shape))
            ode = h * ca.vertcat(xdot, ca.jtimes(xdot, sym.x, delta))
            dae = {"x": ca.vertcat(sym.x, delta), "p": ca.vertcat(sym.p, h), "ode": ode}
            opts = {"reltol": rtol, "abstol": rtol, "max_num_steps": 10**7}
            F = ca.integrator("lyapunov_cvodes", "cvodes", dae, 0.0, 1.0, opts)
            _CVODES_CACHE[key] = F
    return F


def _run_cvodes(
    model: Model, x0: np.ndarray, d0: np.ndarray, times: np.ndarray, n_skip: int, rtol: float, budget: _Budget
) -> tuple:
    nx = model.nx
    F = _cvodes_integrator(model, rtol)
    z = np.concatenate([x0, d0])
    logs = np.empty(len(times))
    t_prev = 0.0
    for i, t in enumerate(times):
        try:
            z = np.asarray(F(x0=z, p=np.concatenate([model.p, [t - t_prev]]))["xf"]).ravel()
        except RuntimeError as exc:
            raise RuntimeError(
                f"largest_lyapunov: method 'cvodes' failed between t = {t_prev:.6g} s and {t:.6g} s: {exc}"
            ) from exc
        if not np.all(np.isfinite(z)):
            raise RuntimeError(f"largest_lyapunov: method 'cvodes' reached a non-finite state by t = {t:.6g} s")
        _check_springs(model, z[:nx], float(t))
        budget.check(0, float(t), float(times[-1]))
        norm = float(np.linalg.norm(z[nx:]))
        logs[i] = math.log(norm)
        z[nx:] /= norm
        t_prev = float(t)
    return logs, z[:nx].copy(), z[nx:].copy(), 0


_RUNNERS = {"taylor": _run_taylor, "cvodes": _run_cvodes}
