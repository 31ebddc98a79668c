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

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._checks import check_model, check_spring_lengths, positive_float
from .._inputs import checked
from ..integrate.taylor.availability import check_tolerance_floor
from ..model.model import Model
from .lyapunov_states import SPRING_STARTS, energy_matched_state, energy_matched_states
from .lyapunov_variational import _RUNNERS, _Budget, variational_taylor_system

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


# -- the estimator ----------------------------------------------------------------------
@checked(max_steps="step_budget")
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
    tol = float(rtol)
    if method == "taylor":
        check_tolerance_floor("rtol", tol)
    if not isinstance(method, str) or method not in _RUNNERS:
        raise ValueError(f"method must be one of {list(LYAPUNOV_METHODS)}, got {method!r}")
    check_spring_lengths(model.kind, x, "x0")
    d0 = _check_tangent(model, tangent0, seed)
    steps = int(max_steps)
    wall = None if max_wall_time is None else float(max_wall_time)

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
