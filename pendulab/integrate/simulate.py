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
A :class:`TimeInput` (a torque given as a function of time, e.g. a scene's
``[input.sine]``) is instead held on a finer *input grid* whose step divides
the output step and is at most ``TimeInput.max_hold``, sampled at the middle of
each hold: the run does not depend on the output step, and a fast sine is not
aliased away by a coarse output grid.
Fixed-step methods take ``dt / ceil(dt / max_step)`` equal steps per output
interval (default ``max_step`` 1e-3 s); ``rtol``/``atol`` do not apply to them.

Every run has a work budget (options ``max_steps``, default 1 000 000, and
``max_wall_time``, default none), checked here once and honoured by every family
(see :func:`simulate`); an exhausted budget is a
:class:`~pendulab.integrate.registry.SimulationError`, never a hang.
"""

from __future__ import annotations

import math
import signal
import threading
import time
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager, nullcontext
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._checks import BUDGETS, bounded_int, check_model, positive_float, within_budget
from .._inputs import checked
from ..model.model import Model
from .auto import choose_method
from .energy import energy_flows, trajectory_energy_flows  # noqa: F401  (re-exported: their old home)
from .methods import METHODS
from .registry import DEFAULT_FIXED_STEP, DEFAULT_MAX_STEPS, Budget, MethodSpec, RunRequest, SimulationError, failure_hint
from .trajectory import Trajectory

__all__ = [
    "simulate",
    "time_grid",
    "input_schedule",
    "InputSpec",
    "BUDGET_OPTIONS",
    "TimeInput",
    "MAX_INPUT_INTERVALS",
]

#: Options of every method, handled by the front end (not passed to the solver).
BUDGET_OPTIONS: tuple[str, ...] = ("max_steps", "max_wall_time")
#: Families whose runner takes the step budget as its own ``options["max_steps"]``.
_NATIVE_BUDGET_FAMILIES = ("taylor", "compiled")

#: Largest number of hold intervals of a :class:`TimeInput` run (a typo in a frequency must not allocate gigabytes).
MAX_INPUT_INTERVALS = 5_000_000


@dataclass(frozen=True)
class TimeInput:
    """Torques given as a function of time only, held on an input grid fine enough for them.

    :func:`simulate` splits each output interval into ``ceil(h / max_hold)``
    equal holds (``h`` the output step) and holds ``func`` at the middle of each:
    an input defined in time, so that the horizon, the output step and the
    method can change freely without aliasing the input.

    Attributes
    ----------
    func : callable
        ``func(t) -> ndarray``: times ``t`` [s], shape (M,), to torques
        (tau1, tau2) [N.m], shape (M, nu); vectorised.
    max_hold : float
        Largest hold [s] (e.g. 1 / (100 f) for a sine of frequency f: the held
        sine's fundamental is then within 1.7e-4 of the true amplitude).
    """

    func: Callable[[np.ndarray], Any]
    max_hold: float

    def hold_grid(self, t: np.ndarray) -> np.ndarray:
        """The input grid of an output grid ``t``: each output interval split into equal holds <= ``max_hold``.

        Parameters
        ----------
        t : ndarray, shape (N,)
            Uniform output grid [s].

        Returns
        -------
        ndarray, shape ((N - 1) * s + 1,)
            Uniform input grid [s] containing ``t`` (every ``s``-th point), ``s = ceil((t[1] - t[0]) / max_hold)``.

        Raises
        ------
        ValueError
            ``max_hold`` not a positive number, or more than :data:`MAX_INPUT_INTERVALS` holds.
        """
        max_hold = positive_float("u.max_hold", self.max_hold, "[s]")
        h = float(t[1] - t[0])
        sub = max(1, math.ceil(h / max_hold - 1e-9))
        n = bounded_int(
            "number of input holds (output intervals x holds per interval)",
            (len(t) - 1) * sub,
            high=MAX_INPUT_INTERVALS,
            why=f"the input is held for at most {max_hold:.3g} s; shorten the horizon or lower the input frequency",
        )
        return np.linspace(0.0, float(t[-1]), n + 1)

    def sample(self, model: Model, t: np.ndarray) -> np.ndarray:
        """``func`` at times ``t``, checked.

        Parameters
        ----------
        model : Model
            The pendulum (input count and names).
        t : ndarray, shape (M,)
            Times [s].

        Returns
        -------
        ndarray, shape (M, nu)
            Torques [N.m].

        Raises
        ------
        ValueError
            ``func`` returned a wrong shape or non-finite torques.
        """
        value = np.asarray(self.func(np.asarray(t, dtype=float)), dtype=float)
        if value.shape != (len(t), model.nu):
            raise ValueError(f"u.func(t) must return shape ({len(t)}, {model.nu}) for {len(t)} times, got {value.shape}")
        return model.check_input(value, "u.func(t)")


InputSpec = None | float | np.ndarray | Callable[[float, np.ndarray], Any] | TimeInput


#: Default budget of output points of one run: 5e6 rows of states, inputs and outputs (about 0.7 GB for the
#: elastic model); ``PENDULAB_MAX_OUTPUT_POINTS`` raises it for a deliberately large run.
MAX_OUTPUT_POINTS: int = BUDGETS["output_points"].default  # 5_000_000, in the one table of budgets


@checked()
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

    Raises
    ------
    BudgetError
        ``N`` beyond :data:`MAX_OUTPUT_POINTS` (environment variable ``PENDULAB_MAX_OUTPUT_POINTS``
        overrides it), checked before anything is allocated.

    Examples
    --------
    >>> from pendulab.integrate import time_grid
    >>> time_grid(1.0, 0.3)  # the step shrinks to 0.25 s so the grid ends exactly at t_final
    array([0.  , 0.25, 0.5 , 0.75, 1.  ])
    >>> time_grid(10.0, 0.01).shape
    (1001,)
    >>> time_grid(1e12, 0.01)  # 1e14 points: refused before anything is allocated
    Traceback (most recent call last):
        ...
    pendulab._checks.BudgetError: ...
    """
    return _uniform_grid(t_final, dt)


#: The last grid built, read-only, by (t_final, dt): runs in a row mostly share their grid (a sweep of starts).
_LAST_GRID: tuple[float, float, np.ndarray] = (0.0, 0.0, np.zeros(0))


def _uniform_grid(t_final: float, dt: float) -> np.ndarray:
    """:func:`time_grid` of arguments already checked (simulate's hot path: no second check of its inputs)."""
    global _LAST_GRID
    points = t_final / dt + 1.0
    within_budget("output points (t_final / dt + 1)", points, BUDGETS["output_points"].env, MAX_OUTPUT_POINTS)
    last_t, last_dt, last = _LAST_GRID  # one tuple, swapped whole: safe to read from any thread
    if t_final == last_t and dt == last_dt:
        return last.copy()
    n = max(1, math.ceil(t_final / dt - 1e-9))
    # np.linspace(0, t_final, n + 1) to the bit (its arange times step, end set exactly) without its ~3 us of Python.
    t = np.arange(n + 1, dtype=float)
    t *= t_final / n
    t[-1] = t_final
    kept = t.copy()
    kept.setflags(write=False)
    _LAST_GRID = (t_final, dt, kept)
    return t


def input_schedule(model: Model, u: InputSpec, t: np.ndarray) -> np.ndarray | None:
    """Piecewise-constant torques per interval of the grid the input is held on.

    Parameters
    ----------
    model : Model
        The pendulum (input count and names).
    u : None, array_like, callable or TimeInput
        As in :func:`simulate`.
    t : ndarray, shape (N,)
        The grid the input is held on [s]: the output grid, or for a
        :class:`TimeInput` its input grid (:meth:`TimeInput.hold_grid`).

    Returns
    -------
    ndarray, shape (N-1, nu), or None
        Held torques [N.m] (a :class:`TimeInput` at the middle of each
        interval); None for a callable (feedback).

    Raises
    ------
    ValueError
        Wrong shape, non-finite values or a scalar.

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.integrate import input_schedule, time_grid
    >>> model, t = pl.rigid(), time_grid(1.0, 0.25)  # 5 output times, 4 intervals
    >>> input_schedule(model, [0.5, 0.0], t)  # a constant torque, held on every interval [N.m]
    array([[0.5, 0. ],
           [0.5, 0. ],
           [0.5, 0. ],
           [0.5, 0. ]])
    >>> ramp = np.column_stack([np.arange(5.0), np.zeros(5)])  # sampled at the 5 output times
    >>> input_schedule(model, ramp, t)  # each held from its output time: the last row is not used
    array([[0., 0.],
           [1., 0.],
           [2., 0.],
           [3., 0.]])
    >>> input_schedule(model, lambda t, x: [-x[2], 0.0], t) is None  # feedback: evaluated during the run
    True
    """
    if isinstance(u, TimeInput):
        return u.sample(model, 0.5 * (t[1:] + t[:-1]))
    if callable(u):
        return None
    n_int = len(t) - 1
    if u is None:
        return np.zeros((n_int, model.nu))
    arr = np.asarray(u, dtype=float) if not np.isscalar(u) else None
    if arr is None or arr.ndim == 0:
        raise ValueError(
            f"u must be None, shape ({model.nu},), shape (N, {model.nu}), a callable u(t, x) or a TimeInput; got {u!r}"
        )
    arr = model.check_input(arr, "u")
    if arr.ndim == 1:
        return np.tile(arr, (n_int, 1))
    if arr.shape[0] in (n_int, n_int + 1):
        return arr[:n_int]
    raise ValueError(
        f"sampled u must have one row per output time ({n_int + 1}) or per interval ({n_int}), got {arr.shape[0]} rows; "
        "an input defined in time (e.g. a sine) that should follow another horizon or output step is a "
        "pendulab.integrate.simulate.TimeInput"
    )


@checked()
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
    u : None, array_like, callable or TimeInput
        Torques (tau1, tau2) [N.m]: None (zero), shape (2,) constant, shape
        (N, 2) or (N-1, 2) sampled on the output grid (held), a callable
        ``u(t, x) -> (2,)`` evaluated at each output time and held over the step,
        or a :class:`TimeInput` (a function of time held on a finer input grid;
        ``stats["input_hold"]`` is its hold [s], and when it is finer than the
        output step, ``Trajectory.u`` holds the input's value at the output times
        and ``stats["input_work"]``, ``stats["dissipated"]`` the energy flows [J]
        of :func:`~pendulab.integrate.energy.energy_flows` on the input grid, shape (N,)).
    max_step : float, optional
        Largest internal step [s]; the step of the fixed-step methods
        (default 1e-3 s there).
    options : mapping, optional
        Extra options passed to the method: CasADi integrator options (checked
        against the plugin's option list), ``solve_ivp`` solver options
        (e.g. ``first_step``; checked against the solver's keywords), the
        Taylor/compiled options. Two **budget options** apply to every method:

        ``max_steps`` : int, default 1 000 000
            Step budget of the whole run. SciPy: accepted steps, counted at
            every step. CasADi CVODES/IDAS: SUNDIALS' ``max_num_steps`` per
            output interval (100 000 by default); a ``max_steps`` given by the
            user also bounds the total, checked between output intervals (the
            run then goes one output interval per call: CVODES restarts at
            each output time). Fixed-step methods and collocation:
            the step count is known in advance; a run above the budget is
            refused before it starts. Compiled: step attempts (accepted +
            rejected) over the run. Taylor: heyoka's ``max_steps`` of each
            propagation (per run of equal inputs, per interval under feedback).
        ``max_wall_time`` : float [s], default none
            Wall-time budget. SciPy: checked at every RHS evaluation. CasADi:
            the run is integrated one output interval per call (CVODES restarts
            at each output time) and checked between calls. Other families:
            checked between their calls (at every output time under feedback);
            a single whole-grid C call is bounded by the step budget only.

        An exhausted budget raises :class:`SimulationError` naming the steps
        taken, the time reached and the stiffness hint.

    Returns
    -------
    Trajectory

    Raises
    ------
    TypeError
        ``model`` is not a pendulab Model.
    ValueError
        Bad arguments (shape, non-finite, unknown method, non-positive times),
        an option the method does not accept (the message lists those it does),
        a bad budget option.
    SimulationError
        The integrator failed or a budget ran out; names the method, time
        reached and a hint.
    KeyboardInterrupt
        Ctrl-C during the run (never reported as a solver failure).

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> model = pl.rigid()
    >>> x0 = model.state(theta1=2.0, theta2=2.0)  # released from rest above horizontal: chaotic motion
    >>> traj = pl.simulate(model, x0, 10.0, rtol=1e-12, atol=1e-12)
    >>> traj.method, traj.x.shape  # method="auto" picks Taylor series for this non-stiff motion
    ('taylor', (1001, 4))
    >>> bool(abs(model.energy(traj.x[-1]) - model.energy(x0)) < 1e-9)  # no damping: energy conserved [J]
    True

    A constant torque on a damped pendulum: it settles where :func:`pendulab.equilibrium` says.

    >>> damped = pl.rigid(b1=5.0, b2=5.0)
    >>> traj = pl.simulate(damped, damped.rest_state(), 30.0, method="cvodes", u=[1.0, 0.0])
    >>> held = pl.equilibrium(damped, "down-down", u=[1.0, 0.0])
    >>> print(f"theta1 {traj['theta1'][-1]:.4f} rad, equilibrium {held.x[0]:.4f} rad")
    theta1 0.0510 rad, equilibrium 0.0510 rad
    """
    check_model(model)
    auto = isinstance(method, str) and method.lower() == "auto"
    spec = None if auto else METHODS.resolve(method)
    x0 = model.check_start(x0, "x0")
    if x0.ndim != 1:
        raise ValueError(f"x0 must have shape ({model.nx},), got {x0.shape}")
    t_final = float(t_final)
    dt = float(dt)
    rtol = float(rtol)
    atol = float(atol)
    if max_step is not None:
        max_step = float(max_step)
    t = _uniform_grid(t_final, dt)
    # A TimeInput is held on its own input grid (the output grid refined); every other input on the output grid.
    t_run = u.hold_grid(t) if isinstance(u, TimeInput) else t
    sub = (len(t_run) - 1) // (len(t) - 1)
    schedule = input_schedule(model, u, t_run)
    choice = None
    if auto:
        choice = choose_method(model, x0, schedule[0] if schedule is not None else np.zeros(model.nu), rtol, atol)
        spec = METHODS[choice.method]
    opts, budget = _budget(spec, options)
    _check_fixed_step_budget(spec, t_run, max_step, budget)
    request = RunRequest(
        model=model,
        spec=spec,
        x0=x0,
        t=t_run,
        schedule=schedule,
        feedback=u if callable(u) and not isinstance(u, TimeInput) else None,
        rtol=rtol,
        atol=atol,
        max_step=max_step,
        options=opts,
        budget=budget,
        unforced=u is None,
    )
    # A runner whose native code lets Ctrl-C through as KeyboardInterrupt needs no watch (~10 us of a ~0.5 ms run).
    watch = nullcontext() if spec.settings.get("passes_interrupts") else _interrupt_watch(budget)
    with watch:
        start = budget.start = time.perf_counter()
        try:
            result = spec.runner(request)
        except Exception:
            if budget.interrupted:  # a solver stopped by Ctrl-C is not a solver failure
                raise KeyboardInterrupt from None
            raise
        wall = time.perf_counter() - start
    X, U, stats = result.x, result.u, dict(result.stats)
    # A finite sum proves every state finite (one reduction); a non-finite one is rechecked element-wise (overflow).
    if not (math.isfinite(X.sum()) or np.all(np.isfinite(X))):
        k = int(np.argmax(~np.all(np.isfinite(X), axis=1)))
        raise SimulationError(
            spec.name, float(t_run[max(k - 1, 0)]), t_final, "the state became non-finite", failure_hint(model.kind)
        )
    # Two column minima (no temporary array); the offending row is searched only on failure.
    if model.kind == "elastic" and not min(X[:, 2].min(), X[:, 3].min()) > 0.0:
        # A spring that reaches zero length puts a bob on its joint: the model's polar coordinates break down.
        k, j = np.argwhere(X[:, 2:4] <= 0.0)[0]
        raise SimulationError(
            spec.name,
            float(t_run[max(k - 1, 0)]),
            t_final,
            f"spring length r{j + 1} reached {X[k, 2 + j]:.3g} m <= 0 (a bob passed through its joint)",
            "stiffer springs (larger k) or a gentler start keep the springs extended",
        )
    if isinstance(u, TimeInput):
        stats["input_hold"] = float(t_run[1] - t_run[0])
    if sub > 1:
        # The input changes within an output interval: keep the energy flows of the input grid (the output
        # grid would alias them) and report the input's value at each output time.
        work, dissipated = energy_flows(model, t_run, X, U)
        stats["input_work"], stats["dissipated"] = work[::sub], dissipated[::sub]
        X = X[::sub]
        U_full = u.sample(model, t)
    elif u is None:  # no torque: the held schedule is zeros, and so is its last row
        U_full = np.zeros((len(t), model.nu))
    else:
        U_full = np.concatenate((U, U[-1:]))
    # A family with compiled code of its own may evaluate the outputs too (Taylor: a heyoka cfunc, ~10x NumPy).
    evaluate = spec.settings.get("outputs")
    Y = evaluate(model, X, U_full) if evaluate is not None else model.outputs(X, U_full)
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


def _budget(spec: MethodSpec, options: Mapping[str, Any] | None) -> tuple[dict[str, Any], Budget]:
    """Split the budget options off the method's options; map the step budget into the families that take it."""
    if options is not None and not isinstance(options, Mapping):
        raise ValueError(f"options must be a mapping of option names to values, got {options!r}")
    opts = dict(options or {})
    explicit = "max_steps" in opts
    max_steps = opts.pop("max_steps", DEFAULT_MAX_STEPS)
    if isinstance(max_steps, bool) or not isinstance(max_steps, (int, np.integer)) or not 1 <= max_steps <= 2**31 - 1:
        raise ValueError(
            f"method {spec.name!r}: option max_steps must be an integer in [1, 2**31 - 1] (the step budget), got {max_steps!r}"
        )
    wall = opts.pop("max_wall_time", None)
    if wall is not None:
        if isinstance(wall, bool) or not isinstance(wall, (int, float, np.integer, np.floating)):
            raise ValueError(f"option max_wall_time must be a positive number of seconds, got {wall!r}")
        wall = positive_float("option max_wall_time", wall, "[s]")
    if spec.family in _NATIVE_BUDGET_FAMILIES:
        opts["max_steps"] = int(max_steps)
    return opts, Budget(max_steps=int(max_steps), max_wall_time=wall, explicit_steps=explicit)


def _check_fixed_step_budget(spec: MethodSpec, t: np.ndarray, max_step: float | None, budget: Budget) -> None:
    """Fixed-step methods know their step count in advance: refuse a run above the budget before it starts."""
    if not spec.fixed_step:
        return
    h = float(t[1] - t[0])
    n_sub = max(1, math.ceil(h / (max_step or DEFAULT_FIXED_STEP) - 1e-9))
    n_steps = (len(t) - 1) * n_sub
    if n_steps > budget.max_steps:
        raise SimulationError(
            spec.name,
            0.0,
            float(t[-1]),
            f"the run needs {n_steps} fixed steps ({len(t) - 1} output intervals x {n_sub} steps of {h / n_sub:.3g} s), "
            f"above the step budget options max_steps = {budget.max_steps}; refused before starting",
            "raise options={'max_steps': ...}, take a larger max_step, or use an error-controlled method",
            n_steps=0,
        )


@contextmanager
def _interrupt_watch(budget: Budget) -> Iterator[None]:
    """Record a SIGINT in ``budget.interrupted`` while the run lasts (main thread only).

    Solvers that run Python's signal check inside C (CasADi) turn the resulting
    ``KeyboardInterrupt`` into their own failure (e.g. CVODES' ``CV_RHSFUNC_FAIL``);
    the flag lets the front end and the runners re-raise ``KeyboardInterrupt``.
    The previous handler still runs (and raises ``KeyboardInterrupt`` as usual).
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.getsignal(signal.SIGINT)
    if previous is None or previous is signal.SIG_IGN:  # installed outside Python, or ignored: leave it alone
        yield
        return

    def handler(signum: int, frame: Any) -> None:
        budget.interrupted = True
        if callable(previous):
            previous(signum, frame)
        else:  # SIG_DFL
            raise KeyboardInterrupt

    try:
        signal.signal(signal.SIGINT, handler)
    except ValueError:  # not allowed here (e.g. an embedded interpreter)
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
