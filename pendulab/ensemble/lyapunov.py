"""Largest Lyapunov exponent by the variational equations with renormalisation (Benettin et al. 1980).

The state ``x`` and one tangent vector ``delta`` are integrated together,

    dx/dt = f(x),        d(delta)/dt = A(x) delta,     A = df/dx,

and every ``renorm_interval`` the tangent vector is divided by its norm; the
logarithms of those norms, summed and divided by the elapsed time, converge to
the largest Lyapunov exponent

    lambda_1 = lim (1/t) ln |delta(t)| / |delta(0)|      [1/s].

A first stretch ``t_transient`` (renormalised, not counted) lets the tangent
vector turn into the most unstable direction. The exponent does not depend on
the norm (Euclidean here, over states of mixed units), only its convergence does.

The physics is never typed here. Two methods, two independent routes to the
same exact Jacobian of the model's one CasADi right-hand side:

``method="taylor"`` (default; heyoka)
    The model's CasADi ``rhs`` graph is translated to a heyoka ODE system by
    :func:`pendulab.integrate.taylor.translate` (constants folded, parameters
    hoisted to runtime parameters, structural zeros specialised), and heyoka's
    :class:`heyoka.var_ode_sys` differentiates it symbolically with respect to
    the initial value of one state variable. The first-order variational
    equations of one column of the state-transition matrix are exactly
    ``d(delta)/dt = A(x) delta``; their initial value is overwritten by the
    tangent vector at every renormalisation, so the system is ``2 nx``
    equations, not the ``nx + nx**2`` of the full matrix (8 for the rigid and
    16 for the elastic model instead of 20 and 72). The compiled integrator is
    cached per structure (kind, parameters that are exactly zero, tolerance):
    a change of stiffness or mass never recompiles. Measured on this machine
    (rigid, theta1 = theta2 = 2 rad, 100 s): 8 ms; translating CasADi's
    ``jtimes`` graph of the same system instead costs 6x more per Taylor step
    (estimated) and 1.7x more to compile, so heyoka's own differentiation of
    the lean translated system is used. Compilation takes ~1 s (rigid) and ~30 s
    (elastic) once per process; heyoka's disk cache makes later processes fast.
``method="cvodes"``
    The augmented system ``[f(x); A(x) delta]`` is built in CasADi from
    ``model.symbolic`` (``A delta`` as ``casadi.jtimes``, forward-mode AD) and
    integrated interval by interval with CVODES (BDF, Newton), time-scaled so
    one integrator serves every interval length. Slower (one Python call per
    interval plus a much smaller step than a Taylor step); the independent
    cross-check, and the fallback where heyoka is not installed.

Both methods hold the inputs at zero (free motion); dampers, if the model has
any, act.

**Equal-energy initial states.** :func:`energy_matched_state` places the links
at given angles, chooses the spring lengths (``springs="quasi-static"``: zero
radial acceleration at the current angular rates, so the fast spring mode is
not excited; or ``"static"``: carrying the along-link gravity load only), and
scales the angular rates along a given direction so that the total mechanical
energy ``model.energy(x)`` (zero at the pivot height with unstretched springs,
the same zero for every model) equals the requested value to rounding.
:func:`energy_matched_states` draws random angles and directions and returns,
for a list of models, states with the *same* angles and rate direction, each
at the requested energy.
"""

from __future__ import annotations

import copy
import math
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np
from scipy.optimize import brentq

from .._checks import bounded_int, check_model, check_spring_lengths, positive_float, relative_tolerance
from ..integrate.taylor.availability import check_tolerance_floor
from ..model.model import Model
from ..model.quasistatic import quasi_static_lengths
from ..model.statics import static_spring_lengths

__all__ = [
    "LyapunovEstimate",
    "LYAPUNOV_METHODS",
    "SPRING_STARTS",
    "largest_lyapunov",
    "energy_matched_state",
    "energy_matched_states",
    "variational_taylor_system",
]

#: Integration methods of :func:`largest_lyapunov`.
LYAPUNOV_METHODS: tuple[str, ...] = ("taylor", "cvodes")
#: Largest number of renormalisations (transient included) of one estimate: the arrays t, running and
#: log_growth hold 8 bytes per renormalisation each, and each one is a Python round trip.
MAX_RENORM = 10_000_000
#: Default step budget of one estimate (integrator steps, transient included; as ``simulate``'s ``max_steps``).
DEFAULT_MAX_STEPS = 10_000_000
#: Taylor steps per propagation slice: Ctrl-C and the budgets are checked between slices.
_SLICE_STEPS = 2000
#: Spring-length choices of the energy-matched initial states.
SPRING_STARTS: tuple[str, ...] = ("quasi-static", "static")


@dataclass(frozen=True)
class LyapunovEstimate:
    """The largest Lyapunov exponent of one trajectory and how it converged.

    Attributes
    ----------
    value : float
        Estimate of the largest Lyapunov exponent [1/s]: the total log growth of
        the tangent vector over ``t_total`` divided by ``t_total``.
    t : ndarray, shape (n_renorm,)
        Times of the renormalisations, counted from the end of the transient [s].
    running : ndarray, shape (n_renorm,)
        Running estimate ``sum(log_growth[:i+1]) / t[i]`` [1/s] (the convergence curve).
    log_growth : ndarray, shape (n_renorm,)
        ``ln`` of the tangent vector's growth over each interval (dimensionless).
    n_renorm : int
        Number of renormalisations counted in the estimate (transient excluded).
    method : {"taylor", "cvodes"}
    t_total, t_transient, renorm_interval : float
        Averaging time, transient and renormalisation interval [s].
    rtol : float
        Integrator tolerance.
    x_final : ndarray, shape (nx,)
        State at the end [SI].
    tangent_final : ndarray, shape (nx,)
        Unit tangent vector at the end (approximates the most unstable direction).
    n_steps : int
        Integrator steps (transient included; 0 when the method does not count them).
    energy_drift : float
        ``|E(x_final) - E(x0)|`` [J]; the accuracy check of the state part for an
        undamped model (chaos does not amplify it).
    """

    value: float
    t: np.ndarray = field(repr=False)
    running: np.ndarray = field(repr=False)
    log_growth: np.ndarray = field(repr=False)
    n_renorm: int
    method: str
    t_total: float
    t_transient: float
    renorm_interval: float
    rtol: float
    x_final: np.ndarray = field(repr=False)
    tangent_final: np.ndarray = field(repr=False)
    n_steps: int = 0
    energy_drift: float = 0.0

    @property
    def half_time_change(self) -> float:
        """``|running(t_total) - running(t_total / 2)|`` [1/s], a convergence indicator.

        Returns
        -------
        float
            Change of the running estimate over the second half of the averaging time.
        """
        i = int(np.searchsorted(self.t, 0.5 * self.t_total))
        i = min(max(i, 0), len(self.running) - 1)
        return float(abs(self.running[-1] - self.running[i]))


# -- argument checks --------------------------------------------------------------------
def _check_model(model: Any) -> Model:
    return check_model(model)


def _nonnegative_float(name: str, value: Any) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a non-negative number [s], got {value!r}") from exc
    if not math.isfinite(v) or v < 0.0:
        raise ValueError(f"{name} must be a non-negative finite number [s], got {value!r}")
    return v


def _check_tangent(model: Model, tangent0: Any, seed: int) -> np.ndarray:
    if tangent0 is None:
        d = np.random.default_rng(seed).standard_normal(model.nx)
    else:
        d = model.check_state(tangent0, "tangent0")
        if d.ndim != 1:
            raise ValueError(f"tangent0 must have shape ({model.nx},), got shape {d.shape}")
    n = float(np.linalg.norm(d))
    if n == 0.0:
        raise ValueError("tangent0 must be a non-zero vector, got all zeros")
    return d / n


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
    model = _check_model(model)
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


# -- the estimator ----------------------------------------------------------------------
def largest_lyapunov(
    model: Model,
    x0: Any,
    t_total: float,
    *,
    renorm_interval: float = 0.25,
    t_transient: float = 0.0,
    rtol: float = 1e-12,
    method: str = "taylor",
    tangent0: Any = None,
    seed: int = 0,
    max_steps: int = DEFAULT_MAX_STEPS,
    max_wall_time: float | None = None,
) -> LyapunovEstimate:
    """Largest Lyapunov exponent of the free motion from ``x0`` (Benettin's renormalisation).

    Parameters
    ----------
    model : Model
        Rigid or elastic model, at its parameters ``model.p``; inputs held at zero.
    x0 : array_like, shape (nx,)
        Initial state in ``model.state_names`` order [rad, m, rad/s, m/s].
    t_total : float
        Averaging time after the transient [s], > 0.
    renorm_interval : float, default 0.25
        Time between renormalisations of the tangent vector [s], in (0, t_total]. The
        last interval is shortened to end exactly at ``t_transient + t_total``.
    t_transient : float, default 0.0
        Time integrated first (tangent renormalised, growth not counted) so that the
        tangent vector aligns with the most unstable direction [s], >= 0.
    rtol : float, default 1e-12
        Integrator tolerance, in (0, 1): heyoka's ``tol`` (``"taylor"``), or CVODES'
        ``reltol`` and ``abstol`` (``"cvodes"``).
    method : {"taylor", "cvodes"}
        heyoka Taylor integration of heyoka's variational equations, or CVODES on the
        CasADi-built augmented system (see the module docstring).
    tangent0 : array_like, shape (nx,), optional
        Initial tangent vector (normalised here); default a random unit vector drawn
        with ``seed`` (a generic direction has a component along the most unstable one).
    seed : int, default 0
        Seed of the default tangent vector.
    max_steps : int, default 10 000 000
        Step budget of the Taylor integration (transient included), checked every 2000 steps.
    max_wall_time : float, optional
        Wall-time budget [s], checked between propagation slices (Taylor) or intervals (CVODES).

    Returns
    -------
    LyapunovEstimate
        ``value`` [1/s], the running estimate vs time, the log growth per interval,
        ``n_renorm`` and the integration's statistics.

    Raises
    ------
    TypeError
        ``model`` is not a pendulab Model.
    ValueError
        ``x0`` or ``tangent0`` of the wrong shape or non-finite; an elastic ``x0`` with a
        spring length r1 or r2 <= 0; ``tangent0`` zero; more than :data:`MAX_RENORM`
        renormalisations; ``t_total`` or ``renorm_interval`` not positive and finite;
        ``t_transient`` negative or non-finite; ``renorm_interval > t_total``; ``rtol``
        outside (0, 1); unknown ``method``.
    RuntimeError
        The integrator failed, a spring passed through zero length, or a budget was spent (the
        message names the method or budget, the time reached and the status).
    KeyboardInterrupt
        Ctrl-C, handled between propagation slices (milliseconds).
    TaylorUnavailableError
        ``method="taylor"`` without heyoka installed (an ``ImportError``).
    """
    model = _check_model(model)
    x = model.check_state(x0, "x0")
    if x.ndim != 1:
        raise ValueError(f"x0 must be one state of shape ({model.nx},), got shape {x.shape}")
    T = positive_float("t_total", t_total, "[s]")
    tau = positive_float("renorm_interval", renorm_interval, "[s]")
    t_tr = _nonnegative_float("t_transient", t_transient)
    if tau > T:
        raise ValueError(f"renorm_interval must be at most t_total = {T!r} s, got {renorm_interval!r} s")
    tol = relative_tolerance("rtol", rtol)
    if method == "taylor":
        check_tolerance_floor("rtol", tol)
    if not isinstance(method, str) or method not in _RUNNERS:
        raise ValueError(f"method must be one of {list(LYAPUNOV_METHODS)}, got {method!r}")
    check_spring_lengths(model.kind, x, "x0")
    d0 = _check_tangent(model, tangent0, seed)
    steps = bounded_int("max_steps", max_steps, low=1, high=2**62, why="the step budget of one estimate")
    wall = None if max_wall_time is None else positive_float("max_wall_time", max_wall_time, "[s]")

    n_tr = math.ceil(t_tr / tau - 1e-9) if t_tr > 0 else 0
    n = max(1, math.ceil(T / tau - 1e-9))
    if n_tr + n > MAX_RENORM:
        raise ValueError(
            f"renorm_interval = {renorm_interval!r} s gives {n_tr + n} renormalisations over t_transient + t_total = "
            f"{t_tr + T:g} s, above the limit MAX_RENORM = {MAX_RENORM} (memory and time of the estimate); "
            "choose a longer renorm_interval"
        )
    t_skip = np.minimum(tau * np.arange(1, n_tr + 1), t_tr)
    t_avg = t_tr + np.minimum(tau * np.arange(1, n + 1), T)
    times = np.concatenate([t_skip, t_avg])
    logs, xf, df, n_steps = _RUNNERS[method](model, x, d0, times, n_tr, tol, _Budget(steps, wall))
    logs = logs[n_tr:]
    t = t_avg - t_tr
    running = np.cumsum(logs) / t
    drift = abs(float(model.energy(xf)) - float(model.energy(x)))
    return LyapunovEstimate(
        value=float(running[-1]),
        t=t,
        running=running,
        log_growth=logs,
        n_renorm=int(n),
        method=method,
        t_total=T,
        t_transient=t_tr,
        renorm_interval=tau,
        rtol=tol,
        x_final=xf,
        tangent_final=df,
        n_steps=n_steps,
        energy_drift=drift,
    )


# -- energy-matched initial states ------------------------------------------------------
def _springs_at(model: Model, theta: np.ndarray, omega: np.ndarray, springs: str) -> np.ndarray:
    if springs == "static":
        return static_spring_lengths(model.params, theta)
    return quasi_static_lengths(model, theta, omega)


def _state_at(model: Model, theta: np.ndarray, omega: np.ndarray, springs: str) -> np.ndarray:
    if model.kind == "rigid":
        return np.concatenate([theta, omega])
    r = _springs_at(model, theta, omega, springs)
    return np.concatenate([theta, r, omega, np.zeros(2)])


def energy_matched_state(model: Model, energy: float, theta: Any, direction: Any, *, springs: str = "quasi-static") -> np.ndarray:
    """A state at the angles ``theta`` whose total mechanical energy is ``energy``.

    The angular rates are ``s * direction / |direction|`` with the one ``s >= 0`` that
    gives ``model.energy(x) == energy``; for the elastic model the spring rates are zero
    and the spring lengths follow ``springs``.

    Parameters
    ----------
    model : Model
        Rigid or elastic model.
    energy : float
        Requested total energy [J] (kinetic + gravity + springs; zero at the pivot
        height with unstretched springs, as :meth:`Model.energy`).
    theta : array_like, shape (2,)
        Absolute link angles [rad].
    direction : array_like, shape (2,)
        Direction of the angular rates (omega1, omega2); its length does not matter.
    springs : {"quasi-static", "static"}
        Elastic model only: lengths with zero radial acceleration at the final rates
        (:func:`pendulab.model.quasistatic.quasi_static_lengths`; no fast spring
        oscillation is excited), or lengths carrying the along-link gravity load only
        (:func:`pendulab.model.statics.static_spring_lengths`).

    Returns
    -------
    ndarray, shape (nx,)
        State with ``|model.energy(x) - energy| <= 1e-12 max(1, |energy|)``.

    Raises
    ------
    ValueError
        Bad shapes or non-finite values, a zero ``direction``, an unknown ``springs``,
        or ``energy`` below the potential energy at ``theta`` (not reachable).
    RuntimeError
        No quasi-static spring lengths (springs too soft for the motion), or the energy
        could not be matched to the tolerance.
    """
    model = _check_model(model)
    th = _pair("theta", theta)
    dv = _pair("direction", direction)
    nd = float(np.linalg.norm(dv))
    if nd == 0.0:
        raise ValueError("direction must be a non-zero (omega1, omega2) direction, got (0, 0)")
    dv = dv / nd
    if springs not in SPRING_STARTS:
        raise ValueError(f"springs must be one of {list(SPRING_STARTS)}, got {springs!r}")
    try:
        E = float(energy)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"energy must be a finite number [J], got {energy!r}") from exc
    if not math.isfinite(E):
        raise ValueError(f"energy must be a finite number [J], got {energy!r}")

    def excess(s: float) -> float:
        return float(model.energy(_state_at(model, th, s * dv, springs))) - E

    e0 = excess(0.0)
    if e0 > 0.0:
        raise ValueError(
            f"energy = {E!r} J is below the energy at rest at theta = {th.tolist()} rad ({e0 + E!r} J); "
            "choose angles with a lower potential energy"
        )
    tol = 1e-12 * max(1.0, abs(E))
    if model.kind == "rigid" or springs == "static":
        # Spring lengths independent of the rates: E(s) = E(0) + s**2 T(unit direction).
        t1 = excess(1.0) - e0
        s = math.sqrt(-e0 / t1)
    else:
        s_hi = math.sqrt(-e0 / max(excess(1.0) - e0, 1e-300))
        for _ in range(60):
            if excess(s_hi) > 0.0:
                break
            s_hi *= 2.0
        s = brentq(excess, 0.0, s_hi, xtol=1e-15, rtol=4 * np.finfo(float).eps, maxiter=200)
    x = _state_at(model, th, s * dv, springs)
    # One Newton polish along the rates (the kinetic energy is quadratic in them).
    err = float(model.energy(x)) - E
    if abs(err) > tol / 4 and s > 0.0:
        h = 1e-6 * s
        slope = (excess(s + h) - excess(s - h)) / (2 * h)
        s -= err / slope
        x = _state_at(model, th, s * dv, springs)
        err = float(model.energy(x)) - E
    if abs(err) > tol:
        raise RuntimeError(f"energy_matched_state: energy matched only to {err:.3g} J (tolerance {tol:.3g} J)")
    return model.check_state(x)


def _pair(name: str, value: Any) -> np.ndarray:
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be two numbers, got {value!r}") from exc
    if a.shape != (2,) or not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be two finite numbers, got {value!r}")
    return a


def energy_matched_states(
    models: Sequence[Model], energy: float, n: int, *, seed: int = 0, springs: str = "quasi-static"
) -> list[np.ndarray]:
    """Random states of equal energy, the same angles and rate directions for every model.

    Angles are drawn uniformly in [-pi, pi)^2 and rate directions uniformly on the
    circle (``numpy.random.default_rng(seed)``); a draw is kept when ``energy`` is above
    the rest energy at those angles for every model, so every model gets a state.

    Parameters
    ----------
    models : sequence of Model
        Models to start (rigid and/or elastic).
    energy : float
        Total energy [J] of every state (see :func:`energy_matched_state`).
    n : int
        Number of states per model, >= 1.
    seed : int, default 0
        Random seed.
    springs : {"quasi-static", "static"}
        Spring lengths of the elastic models (see :func:`energy_matched_state`).

    Returns
    -------
    list of ndarray, shape (n, nx) each
        ``out[j][i]`` is the i-th state of ``models[j]``.

    Raises
    ------
    ValueError
        ``n`` not a positive integer, an empty ``models``, or an ``energy`` below the
        potential energy of every angle tried (1000 n draws).
    """
    n = bounded_int("n", n, high=1_000_000, why="each state is found by a root search in Python")
    models = [_check_model(m) for m in models]
    if not models:
        raise ValueError("models must contain at least one Model, got none")
    rng = np.random.default_rng(seed)
    out: list[list[np.ndarray]] = [[] for _ in models]
    tries = 0
    while len(out[0]) < n:
        tries += 1
        if tries > 1000 * n:
            raise ValueError(f"energy = {energy!r} J: found only {len(out[0])} of {n} reachable angle pairs in {tries - 1} draws")
        th = rng.uniform(-np.pi, np.pi, 2)
        phi = rng.uniform(0.0, 2 * np.pi)
        dv = np.array([np.cos(phi), np.sin(phi)])
        try:
            states = [energy_matched_state(m, energy, th, dv, springs=springs) for m in models]
        except ValueError:
            continue
        for j, x in enumerate(states):
            out[j].append(x)
    return [np.array(o) for o in out]
