"""Native simulation: one front end over every integration method.

The methods live in one registry (:data:`pendulab.integrate.methods.METHODS`),
grouped by family: CasADi (``cvodes`` = ``cvodes-bdf``, ``cvodes-adams``,
``idas``, ``collocation`` = ``collocation-radau``, ``collocation-legendre``),
SciPy ``solve_ivp`` (``RK45``, ``DOP853``, ``Radau``, ``BDF``, ``LSODA``) and
fixed-step Butcher tableaus (``forward-euler``, ``rk4``, ``implicit-euler``,
``implicit-midpoint``, ``gauss4``, ``radau3``). This module checks the
arguments once and hands a :class:`~pendulab.integrate.registry.RunRequest`
to the method's runner.

Inputs are zero-order held on the output grid: a sampled array gives the
torque on each interval, a callable ``u(t, x)`` is a sampled-data feedback
evaluated at each output time (the same semantics as a co-simulation master).
Fixed-step methods take ``dt / ceil(dt / max_step)`` equal steps per output
interval (default ``max_step`` 1e-3 s); ``rtol``/``atol`` do not apply to them.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from .._checks import positive_float
from ..model.model import Model
from .auto import choose_method
from .methods import METHODS
from .registry import STIFF_HINT, RunRequest, SimulationError
from .trajectory import Trajectory

__all__ = ["simulate", "time_grid", "input_schedule", "InputSpec"]

InputSpec = None | float | np.ndarray | Callable[[float, np.ndarray], Any]


def time_grid(t_final: float, dt: float) -> np.ndarray:
    """Uniform output grid from 0 to ``t_final`` with step at most ``dt``.

    Parameters
    ----------
    t_final : float
        Horizon [s], > 0.
    dt : float
        Largest output step [s], > 0.

    Returns
    -------
    ndarray, shape (N,)
        ``N = ceil(t_final / dt) + 1`` equally spaced times [s].
    """
    n = max(1, math.ceil(t_final / dt - 1e-9))
    return np.linspace(0.0, t_final, n + 1)


def input_schedule(model: Model, u: InputSpec, t: np.ndarray) -> np.ndarray | None:
    """Piecewise-constant torques per output interval.

    Parameters
    ----------
    model : Model
        The pendulum (input count and names).
    u : None, array_like or callable
        As in :func:`simulate`.
    t : ndarray, shape (N,)
        Output grid [s].

    Returns
    -------
    ndarray, shape (N-1, nu), or None
        Held torques [N.m]; None for a callable (feedback).

    Raises
    ------
    ValueError
        Wrong shape, non-finite values or a scalar.
    """
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


def simulate(
    model: Model,
    x0: Any,
    t_final: float,
    dt: float = 0.01,
    method: str = "auto",
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
        ``"auto"`` (default: the rule of :mod:`pendulab.integrate.auto`, reported in
        ``stats["auto"]``) or a key of :data:`pendulab.METHODS` (never overridden).
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
    if not isinstance(model, Model):
        raise TypeError(f"model must be a pendulab Model, got {type(model).__name__}")
    auto = isinstance(method, str) and method.lower() == "auto"
    spec = None if auto else METHODS.resolve(method)
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
    schedule = input_schedule(model, u, t)
    choice = None
    if auto:
        choice = choose_method(model, x0, schedule[0] if schedule is not None else np.zeros(model.nu), rtol, atol)
        spec = METHODS[choice.method]
    request = RunRequest(
        model=model,
        spec=spec,
        x0=x0,
        t=t,
        schedule=schedule,
        feedback=u if callable(u) else None,
        rtol=rtol,
        atol=atol,
        max_step=max_step,
        options=dict(options or {}),
    )
    start = time.perf_counter()
    result = spec.runner(request)
    wall = time.perf_counter() - start
    X, U, stats = result.x, result.u, result.stats
    if not np.all(np.isfinite(X)):
        k = int(np.argmax(~np.all(np.isfinite(X), axis=1)))
        raise SimulationError(spec.name, float(t[k - 1]), t_final, "the state became non-finite", STIFF_HINT)
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
        stats={"wall_time": wall, **stats, **({"auto": choice.as_dict()} if choice else {})},
    )
