"""Native simulation: one front end over CasADi and SciPy integrators.

Methods (``METHODS``):

* CasADi: ``cvodes`` (= ``cvodes-bdf``), ``cvodes-adams``, ``idas``,
  ``collocation`` (= ``collocation-radau``), ``collocation-legendre``, ``rk``
  (classical RK4). The whole output grid is integrated in one call whenever the
  input is known in advance (none, constant or sampled).
* SciPy ``solve_ivp``: ``RK45``, ``DOP853``, ``Radau``, ``BDF``, ``LSODA``; the
  right-hand side is plain Python generated from the CasADi graph and the
  implicit methods get the exact CasADi Jacobian.

Inputs are zero-order held on the output grid: a sampled array gives the
torque on each interval, a callable ``u(t, x)`` is a sampled-data feedback
evaluated at each output time (the same semantics as a co-simulation master).

Collocation and ``rk`` are fixed-step: their step is ``max_step`` (default
1e-3 s, at most the output step); ``rtol``/``atol`` do not apply to them.
The same holds for the Butcher-tableau methods of ``fixed_step.py`` (``forward-euler``,
``rk4``, ``implicit-euler``, ``implicit-midpoint``, ``gauss4``, ``radau3``):
``dt / ceil(dt / max_step)`` equal steps per output interval.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import casadi as ca
import numpy as np
from scipy.integrate import solve_ivp

from .._checks import positive_float
from .fixed_step import FIXED_METHODS, run_fixed
from .model import Model
from .pycode import to_python
from .trajectory import Trajectory

__all__ = ["simulate", "METHODS", "SimulationError", "InputSpec"]

InputSpec = None | float | np.ndarray | Callable[[float, np.ndarray], Any]


class SimulationError(RuntimeError):
    """An integrator failed; the message names method, time reached and a hint."""

    def __init__(self, method: str, t_reached: float, t_final: float, reason: str, hint: str = "") -> None:
        self.method = method
        self.t_reached = t_reached
        self.t_final = t_final
        msg = f"method {method!r} failed at t = {t_reached:.6g} s of {t_final:.6g} s: {reason}"
        if hint:
            msg += f" (hint: {hint})"
        super().__init__(msg)


@dataclass(frozen=True)
class MethodSpec:
    """One entry of the method registry."""

    name: str
    family: str  # "casadi" or "scipy"
    plugin: str  # CasADi plugin or SciPy method name
    fixed_step: bool
    options: Mapping[str, Any]
    description: str


_RADAU = "Radau IIA collocation, degree 3 (order 5), fixed step"
_LEGENDRE = "Gauss-Legendre collocation, degree 3 (order 6), fixed step"
METHODS: Mapping[str, MethodSpec] = {
    m.name: m
    for m in (
        MethodSpec("cvodes", "casadi", "cvodes", False, {"linear_multistep_method": "bdf"}, "SUNDIALS CVODES, BDF"),
        MethodSpec("cvodes-bdf", "casadi", "cvodes", False, {"linear_multistep_method": "bdf"}, "SUNDIALS CVODES, BDF"),
        MethodSpec("cvodes-adams", "casadi", "cvodes", False, {"linear_multistep_method": "adams"}, "CVODES, Adams-Moulton"),
        MethodSpec("idas", "casadi", "idas", False, {}, "SUNDIALS IDAS (BDF, DAE form)"),
        MethodSpec("collocation", "casadi", "collocation", True, {"collocation_scheme": "radau"}, _RADAU),
        MethodSpec("collocation-radau", "casadi", "collocation", True, {"collocation_scheme": "radau"}, _RADAU),
        MethodSpec("collocation-legendre", "casadi", "collocation", True, {"collocation_scheme": "legendre"}, _LEGENDRE),
        MethodSpec("rk", "casadi", "rk", True, {}, "classical Runge-Kutta 4, fixed step"),
        MethodSpec("RK45", "scipy", "RK45", False, {}, "SciPy Dormand-Prince 5(4)"),
        MethodSpec("DOP853", "scipy", "DOP853", False, {}, "SciPy Dormand-Prince 8(5,3)"),
        MethodSpec("Radau", "scipy", "Radau", False, {}, "SciPy Radau IIA (order 5), exact Jacobian"),
        MethodSpec("BDF", "scipy", "BDF", False, {}, "SciPy BDF, exact Jacobian"),
        MethodSpec("LSODA", "scipy", "LSODA", False, {}, "SciPy LSODA (Adams/BDF switching), exact Jacobian"),
        # Fixed-step Butcher-tableau methods iterated inside CasADi (see fixed_step.py).
        *(MethodSpec(n, "fixed", n, True, {}, m.description) for n, m in FIXED_METHODS.items()),
    )
}
_IMPLICIT_SCIPY = {"Radau", "BDF", "LSODA"}
_DEFAULT_FIXED_STEP = 1e-3
_STIFF_HINT = "stiff springs need an implicit method such as 'cvodes', 'Radau' or 'collocation'"


def _resolve_method(method: str) -> MethodSpec:
    if not isinstance(method, str):
        raise ValueError(f"method must be a string, got {method!r}")
    if method in METHODS:
        return METHODS[method]
    by_lower = {k.lower(): v for k, v in METHODS.items()}
    if method.lower() in by_lower:
        return by_lower[method.lower()]
    raise ValueError(f"unknown method {method!r}; expected one of {list(METHODS)}")


def time_grid(t_final: float, dt: float) -> np.ndarray:
    """Uniform output grid from 0 to ``t_final`` with step at most ``dt``, shape (N,)."""
    n = max(1, math.ceil(t_final / dt - 1e-9))
    return np.linspace(0.0, t_final, n + 1)


def _input_schedule(model: Model, u: InputSpec, t: np.ndarray) -> np.ndarray | None:
    """Piecewise-constant inputs per interval, shape (N-1, nu); None for a callable."""
    if callable(u):
        return None
    n_int = len(t) - 1
    if u is None:
        return np.zeros((n_int, model.nu))
    arr = np.asarray(u, dtype=float) if not np.isscalar(u) else None
    if arr is None or arr.ndim == 0:
        raise ValueError(f"u must be None, shape ({model.nu},), shape (N, {model.nu}) or a callable u(t, x); got {u!r}")
    arr = model.check_input(arr, "u")
    if arr.ndim == 1:
        return np.tile(arr, (n_int, 1))
    if arr.shape[0] in (n_int, n_int + 1):
        return arr[:n_int]
    raise ValueError(
        f"sampled u must have one row per output time ({n_int + 1}) or per interval ({n_int}), got {arr.shape[0]} rows"
    )


def _eval_feedback(model: Model, u: Callable[[float, np.ndarray], Any], t: float, x: np.ndarray) -> np.ndarray:
    value = u(t, x.copy())
    try:
        return model.check_input(np.asarray(value, dtype=float).reshape(model.nu), "u(t, x)")
    except ValueError as exc:
        raise ValueError(f"feedback u(t, x) at t = {t:.6g} s returned an invalid torque: {exc}") from exc


@lru_cache(maxsize=64)
def _casadi_integrator(kind: str, plugin: str, grid: tuple[float, ...], opts_key: tuple) -> ca.Function:
    from .builders import build_elastic, build_rigid

    sym = build_rigid() if kind == "rigid" else build_elastic()
    dae = {"x": sym.x, "u": sym.u, "p": sym.p, "ode": sym.xdot}
    return ca.integrator("pendulab_" + plugin, plugin, dae, 0.0, list(grid), _thaw(opts_key))


_MAPPING = "__mapping__"


def _freeze(opts: Mapping[str, Any]) -> tuple:
    """Hashable form of integrator options (cache key); nested dicts (e.g. ``jit_options``) included."""

    def value(v: Any) -> Any:
        if isinstance(v, Mapping):
            return (_MAPPING, _freeze(v))
        if isinstance(v, (list, tuple)):
            return tuple(value(x) for x in v)
        return v

    return tuple(sorted((k, value(v)) for k, v in opts.items()))


def _thaw(key: tuple) -> dict:
    """Inverse of ``_freeze`` (sequences come back as lists)."""

    def value(v: Any) -> Any:
        if isinstance(v, tuple) and len(v) == 2 and v[0] == _MAPPING:
            return _thaw(v[1])
        if isinstance(v, tuple):
            return [value(x) for x in v]
        return v

    return {k: value(v) for k, v in key}


def _casadi_options(
    spec: MethodSpec, h: float, rtol: float, atol: float, max_step: float | None, extra: Mapping[str, Any]
) -> dict:
    # Non-finite states are reported as a SimulationError; CasADi's per-step warnings are noise.
    opts: dict[str, Any] = {"show_eval_warnings": False, **spec.options}
    if spec.fixed_step:
        # CasADi 3.8 takes one step per output-grid interval and ignores
        # number_of_finite_elements when given a grid: the caller refines the grid.
        opts["number_of_finite_elements"] = 1
        if spec.plugin == "collocation":
            opts.setdefault("interpolation_order", 3)
    else:
        opts.update({"reltol": rtol, "abstol": atol, "max_num_steps": 100000})
        if max_step is not None:
            opts["max_step_size"] = max_step
    opts.update(extra)
    return opts


def _run_casadi(model, spec, x0, t, sched, u_fun, rtol, atol, max_step, extra):
    h = t[1] - t[0]
    opts = _casadi_options(spec, h, rtol, atol, max_step, extra)
    n_int = len(t) - 1
    # Fixed-step methods: n_sub internal steps per output interval.
    n_sub = 1
    if spec.fixed_step:
        n_sub = max(1, math.ceil(h / (max_step or _DEFAULT_FIXED_STEP) - 1e-9))
    stats: dict[str, Any] = {"n_rhs": 0, "n_steps": 0}
    # A whole-grid CVODES call carries its multistep history across the jumps of a sampled
    # input: it misses the requested accuracy by 10-100x and can fail with repeated error-test
    # failures. Restart it at each output interval instead (IDAS and the fixed-step methods are exact).
    restart = spec.plugin == "cvodes" and sched is not None and not np.all(sched == sched[0])
    if sched is not None and not restart:
        fine = np.linspace(0.0, t[-1], n_int * n_sub + 1)
        F = _casadi_integrator(model.kind, spec.plugin, tuple(fine[1:].tolist()), _freeze(opts))
        try:
            xf = np.asarray(F(x0=x0, u=np.repeat(sched, n_sub, axis=0).T, p=model.p)["xf"]).T
        except RuntimeError:
            # The whole-grid call does not say where it failed: redo the run interval by
            # interval, which either reports the failing interval or completes the run.
            stats["whole_grid_retry"] = True
        else:
            _collect_casadi_stats(F, spec, stats, n_int * n_sub)
            return np.vstack([x0, xf[n_sub - 1 :: n_sub]]), sched, stats
    return _run_casadi_intervals(model, spec, x0, t, sched, u_fun, opts, n_sub, stats)


def _run_casadi_intervals(model, spec, x0, t, sched, u_fun, opts, n_sub, stats):
    """One integrator call per output interval (feedback, restarts, failure location)."""
    h = float(t[1] - t[0])
    n_int = len(t) - 1
    F = _casadi_integrator(model.kind, spec.plugin, tuple(np.linspace(0, h, n_sub + 1)[1:].tolist()), _freeze(opts))
    X = np.empty((len(t), model.nx))
    U = np.empty((n_int, model.nu))
    X[0] = x0
    for k in range(n_int):
        U[k] = sched[k] if sched is not None else _eval_feedback(model, u_fun, t[k], X[k])
        try:
            X[k + 1] = np.asarray(F(x0=X[k], u=np.tile(U[k], (n_sub, 1)).T, p=model.p)["xf"])[:, -1]
        except RuntimeError as exc:
            raise SimulationError(spec.name, float(t[k]), float(t[-1]), _short(exc), _STIFF_HINT) from None
        if not np.all(np.isfinite(X[k + 1])):
            raise SimulationError(spec.name, float(t[k]), float(t[-1]), "the state became non-finite", _STIFF_HINT)
        _collect_casadi_stats(F, spec, stats, n_sub)
    return X, U, stats


def _collect_casadi_stats(F: ca.Function, spec: MethodSpec, stats: dict, n_steps: int) -> None:
    s = F.stats()
    if spec.fixed_step:
        # RK4: 4 evaluations a step; collocation solves a Newton system (no plain RHS count).
        stats["n_steps"] += n_steps
        stats["n_rhs"] += 4 * n_steps if spec.plugin == "rk" else 0
    else:
        stats["n_steps"] += int(s.get("nsteps", 0))
        stats["n_rhs"] += int(s.get("nfevals", 0))
        stats["n_jac"] = stats.get("n_jac", 0) + int(s.get("n_call_jacF", 0))
        stats["n_error_test_failures"] = stats.get("n_error_test_failures", 0) + int(s.get("netfails", 0))


def _short(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return text[-1] if text else type(exc).__name__


@lru_cache(maxsize=8)
def _python_rhs(kind: str) -> Callable[..., np.ndarray]:
    from .model import _functions

    return to_python(_functions(kind)["rhs"])


def _run_scipy(model, spec, x0, t, sched, u_fun, rtol, atol, max_step, extra):
    rhs = _python_rhs(model.kind)
    p = model.p.tolist()
    jac_fun = model.functions["jac_rhs"]
    counter = {"n_rhs": 0, "n_jac": 0, "n_steps": 0}
    kwargs: dict[str, Any] = {"rtol": rtol, "atol": atol}
    if max_step is not None:
        kwargs["max_step"] = max_step
    kwargs.update(extra)

    def solve(x_start, u_const, t_eval):
        ul = list(u_const)

        def fun(_t, x):
            return rhs(x, ul, p)

        jac_kw = {}
        if spec.plugin in _IMPLICIT_SCIPY:

            def jac(_t, x):
                return np.asarray(jac_fun(x, u_const, model.p)[0])

            jac_kw["jac"] = jac
        sol = solve_ivp(fun, (t_eval[0], t_eval[-1]), x_start, method=spec.plugin, t_eval=t_eval, **jac_kw, **kwargs)
        counter["n_rhs"] += int(sol.nfev)
        counter["n_jac"] += int(sol.njev)
        counter["n_steps"] += int(getattr(sol, "nsteps", 0) or 0)
        if sol.status != 0 or sol.y.shape[1] != len(t_eval):
            t_end = float(sol.t[-1]) if sol.t.size else float(t_eval[0])
            raise SimulationError(spec.name, t_end, float(t[-1]), sol.message, _STIFF_HINT)
        return sol.y.T

    if sched is not None and np.all(sched == sched[0]):
        X = solve(x0, sched[0], t)
        U = sched
    else:
        X = np.empty((len(t), model.nx))
        U = np.empty((len(t) - 1, model.nu))
        X[0] = x0
        for k in range(len(t) - 1):
            U[k] = sched[k] if sched is not None else _eval_feedback(model, u_fun, t[k], X[k])
            X[k + 1] = solve(X[k], U[k], t[k : k + 2])[-1]
    counter["n_steps"] = counter["n_steps"] or None
    return X, U, counter


def simulate(
    model: Model,
    x0: Any,
    t_final: float,
    dt: float = 0.01,
    method: str = "cvodes",
    rtol: float = 1e-8,
    atol: float = 1e-8,
    u: InputSpec = None,
    *,
    max_step: float | None = None,
    options: Mapping[str, Any] | None = None,
) -> Trajectory:
    """Integrate the model from ``x0`` over ``[0, t_final]``.

    Parameters
    ----------
    model : Model
        Rigid or elastic pendulum.
    x0 : array_like, shape (nx,)
        Initial state in ``model.state_names`` order (angles [rad], lengths [m],
        rates [rad/s], [m/s]).
    t_final : float
        Horizon [s], > 0.
    dt : float
        Output step [s]; the grid is uniform with step ``t_final / ceil(t_final / dt)``.
    method : str
        One of ``METHODS``.
    rtol, atol : float
        Error tolerances of the adaptive methods.
    u : None, array_like or callable
        Torques (tau1, tau2) [N.m]: None (zero), shape (2,) constant, shape
        (N, 2) or (N-1, 2) sampled on the output grid (held), or a callable
        ``u(t, x) -> (2,)`` evaluated at each output time and held over the step.
    max_step : float, optional
        Largest internal step [s]; the step of the fixed-step methods
        (default 1e-3 s there).
    options : mapping, optional
        Extra options passed to the CasADi integrator or ``solve_ivp``.

    Returns
    -------
    Trajectory

    Raises
    ------
    ValueError
        Bad arguments (shape, non-finite, unknown method, non-positive times).
    SimulationError
        The integrator failed; names the method, time reached and a hint.
    """
    from .model import Model as _Model

    if not isinstance(model, _Model):
        raise TypeError(f"model must be a pendulab Model, got {type(model).__name__}")
    spec = _resolve_method(method)
    x0 = model.check_state(x0, "x0")
    if x0.ndim != 1:
        raise ValueError(f"x0 must have shape ({model.nx},), got {x0.shape}")
    t_final = positive_float("t_final", t_final)
    dt = positive_float("dt", dt)
    rtol = positive_float("rtol", rtol)
    atol = positive_float("atol", atol)
    if max_step is not None:
        max_step = positive_float("max_step", max_step)
    if model.kind == "elastic" and np.any(x0[2:4] <= 0):
        raise ValueError(f"x0: spring lengths r1, r2 must be > 0 m, got {x0[2:4].tolist()}")
    t = time_grid(t_final, dt)
    sched = _input_schedule(model, u, t)
    runner = {"casadi": _run_casadi, "scipy": _run_scipy, "fixed": run_fixed}[spec.family]
    start = time.perf_counter()
    feedback = u if callable(u) else None
    X, U, stats = runner(model, spec, x0, t, sched, feedback, rtol, atol, max_step, dict(options or {}))
    wall = time.perf_counter() - start
    if not np.all(np.isfinite(X)):
        k = int(np.argmax(~np.all(np.isfinite(X), axis=1)))
        raise SimulationError(spec.name, float(t[k - 1]), t_final, "the state became non-finite", _STIFF_HINT)
    U_full = np.vstack([U, U[-1:]])
    Y = model.outputs(X, U_full)
    return Trajectory(
        t=t,
        x=X,
        u=U_full,
        y=Y,
        state_names=model.state_names,
        input_names=model.input_names,
        output_names=model.output_names,
        method=spec.name,
        success=True,
        message=f"{spec.description}: reached t = {t_final:.6g} s",
        stats={"wall_time": wall, **stats},
    )
