"""The method registry of :func:`pendulab.simulate` and the contract every runner keeps.

A *method* is a :class:`MethodSpec`: a name, a family (``"casadi"``,
``"scipy"``, ``"fixed"``; the fast-path families ``"taylor"`` and
``"compiled"`` plug in the same way) and a *runner*. The front end
(:func:`pendulab.simulate`) checks every argument once, builds a
:class:`RunRequest` and hands it to the runner, which returns a
:class:`RunResult` or raises :class:`SimulationError`. Runners never re-check
user input and never print.

The registry is assembled explicitly in :mod:`pendulab.integrate.methods`
(no registration as a side effect of an import); :func:`register_method` adds
a method at run time (tests, plug-ins).
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from ..model.model import Model

__all__ = [
    "SimulationError",
    "MethodSpec",
    "RunRequest",
    "RunResult",
    "Runner",
    "Registry",
    "STIFF_HINT",
    "RIGID_HINT",
    "failure_hint",
    "DEFAULT_FIXED_STEP",
    "DEFAULT_MAX_STEPS",
    "Budget",
]

#: Hint attached to integration failures that are most often caused by stiffness.
STIFF_HINT = "stiff springs need an implicit method such as 'cvodes', 'Radau' or 'collocation'"
#: Hint attached to failures of the rigid model (no spring, so stiffness is rarely the cause).
RIGID_HINT = "a tighter tolerance, a smaller max_step or another method (e.g. 'taylor', 'cvodes', 'Radau') may get through"


def failure_hint(kind: str) -> str:
    """The hint a failed integration of a model kind carries.

    Parameters
    ----------
    kind : {"rigid", "elastic"}
        Model kind.

    Returns
    -------
    str
        :data:`STIFF_HINT` for the elastic model (stiff springs are the usual cause), :data:`RIGID_HINT` otherwise.
    """
    return STIFF_HINT if kind == "elastic" else RIGID_HINT


#: Step [s] of the fixed-step methods when ``max_step`` is not given.
DEFAULT_FIXED_STEP = 1e-3
#: Default step budget of one :func:`pendulab.simulate` run (``options={"max_steps": ...}``).
DEFAULT_MAX_STEPS = 1_000_000


class SimulationError(RuntimeError):
    """An integrator failed; the message names the method, the time reached and a hint.

    Parameters
    ----------
    method : str
        Method name.
    t_reached : float
        Last time [s] the integration reached.
    t_final : float
        Requested horizon [s].
    reason : str
        What went wrong (solver message).
    hint : str, optional
        What to try instead.
    n_steps : int, optional
        Steps taken when the solver stopped (where known).

    Attributes
    ----------
    method, t_reached, t_final, n_steps
        As given.

    Examples
    --------
    >>> import pendulab as pl
    >>> try:
    ...     pl.simulate(pl.rigid(), [2.0, 2.0, 0.0, 0.0], 10.0, method="RK45", options={"max_steps": 50})
    ... except pl.SimulationError as err:
    ...     print(err.method, err.n_steps, round(err.t_reached, 2), err.t_final)
    ...     print(err)
    RK45 50 0.89 10.0
    method 'RK45' failed at t = 0.885997 s of 10 s: step budget exhausted: 50 steps taken, options max_steps = 50 (hint: ...)
    """

    def __init__(
        self, method: str, t_reached: float, t_final: float, reason: str, hint: str = "", n_steps: int | None = None
    ) -> None:
        self.method = method
        self.t_reached = t_reached
        self.t_final = t_final
        self.n_steps = n_steps
        msg = f"method {method!r} failed at t = {t_reached:.6g} s of {t_final:.6g} s: {reason}"
        if hint:
            msg += f" (hint: {hint})"
        super().__init__(msg)


@dataclass
class Budget:
    """The work budget of one run: a step budget and an optional wall-time budget.

    Set by :func:`pendulab.simulate` from ``options={"max_steps": ..., "max_wall_time": ...}``;
    runners check it with :meth:`RunRequest.check_budget` between their own calls (and the SciPy
    runner at every step). It also records a SIGINT seen during the run (``interrupted``), so that
    a runner can tell an interrupted solver from a failing one.

    Attributes
    ----------
    max_steps : int
        Largest number of solver steps over the whole run.
    max_wall_time : float or None
        Largest wall time [s] of the run; None: no limit.
    explicit_steps : bool
        True when the user set ``max_steps`` (the CasADi runner then also uses it as
        CVODES/IDAS' per-interval ``max_num_steps``).
    start : float
        ``time.perf_counter()`` at the start of the run.
    interrupted : bool
        A SIGINT arrived during the run.
    """

    max_steps: int = DEFAULT_MAX_STEPS
    max_wall_time: float | None = None
    explicit_steps: bool = False
    start: float = field(default_factory=time.perf_counter)
    interrupted: bool = False

    @property
    def elapsed(self) -> float:
        """Wall time [s] since :attr:`start`."""
        return time.perf_counter() - self.start

    def wall_exceeded(self) -> bool:
        """Whether a wall-time budget is set and used up.

        Returns
        -------
        bool
            True when ``max_wall_time`` is set and :attr:`elapsed` exceeds it.
        """
        return self.max_wall_time is not None and self.elapsed > self.max_wall_time


@dataclass(frozen=True)
class RunRequest:
    """Everything a runner needs, already validated by :func:`pendulab.simulate`.

    Attributes
    ----------
    model : Model
        The pendulum (its ``functions`` and parameter vector ``p``).
    spec : MethodSpec
        The method being run.
    x0 : ndarray, shape (nx,)
        Initial state.
    t : ndarray, shape (N,)
        Uniform output grid [s], ``t[0] = 0``.
    schedule : ndarray, shape (N-1, nu), or None
        Torques [N.m] held on each output interval; ``None`` when ``feedback`` is given.
    feedback : callable or None
        Sampled-data feedback ``u(t, x)``; evaluate it with :meth:`feedback_input`.
    rtol, atol : float
        Tolerances of the error-controlled methods.
    max_step : float or None
        Largest internal step [s]; the step of the fixed-step methods.
    options : mapping
        Method-specific options given by the user (without the budget options).
    budget : Budget
        Step and wall-time budget of the run.
    unforced : bool
        No torque was given: ``schedule`` is all zeros (a runner may specialise on it without scanning it).

    Examples
    --------
    What a runner receives, built by hand here to call the registered ``rk4`` runner directly
    (:func:`pendulab.simulate` builds it from its arguments):

    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.integrate import RunRequest, time_grid
    >>> model, spec, t = pl.rigid(), pl.METHODS["rk4"], time_grid(1.0, 0.1)
    >>> request = RunRequest(model, spec, model.state(theta1=0.5), t, np.zeros((10, 2)), None, 1e-8, 1e-8, 1e-3)
    >>> request.t_final, request.n_intervals, request.constant_input
    (1.0, 10, True)
    >>> result = spec.runner(request)
    >>> direct = pl.simulate(model, model.state(theta1=0.5), 1.0, dt=0.1, method="rk4")
    >>> bool(np.allclose(result.x, direct.x, rtol=0, atol=1e-12))
    True
    """

    model: Model
    spec: MethodSpec
    x0: np.ndarray
    t: np.ndarray
    schedule: np.ndarray | None
    feedback: Callable[[float, np.ndarray], Any] | None
    rtol: float
    atol: float
    max_step: float | None
    options: Mapping[str, Any] = field(default_factory=dict)
    budget: Budget = field(default_factory=Budget)
    unforced: bool = False

    @property
    def t_final(self) -> float:
        """Horizon [s]."""
        return float(self.t[-1])

    @property
    def n_intervals(self) -> int:
        """Number of output intervals, N - 1."""
        return len(self.t) - 1

    @property
    def constant_input(self) -> bool:
        """True when the input is known in advance and the same on every interval."""
        return self.schedule is not None and bool(np.all(self.schedule == self.schedule[0]))

    def feedback_input(self, t: float, x: np.ndarray) -> np.ndarray:
        """Evaluate the feedback at ``(t, x)`` and validate it.

        Parameters
        ----------
        t : float
            Time [s].
        x : ndarray, shape (nx,)
            State at ``t`` (passed to the feedback as a float copy).

        Returns
        -------
        ndarray, shape (nu,)
            Torques (tau1, tau2) [N.m].

        Raises
        ------
        ValueError
            The run has no feedback, or the feedback returned a wrong shape or
            a non-finite torque.
        SimulationError
            ``x`` is not finite: the integration diverged (e.g. a fixed step too long for stiff springs) before
            the feedback was due, so the run fails as a run; the feedback is not called with that state.
        """
        if self.feedback is None:
            raise ValueError("this run has no feedback; use the input schedule")
        # Every family's per-interval loop passes here: the wall-time budget holds for all of them.
        self.check_budget(t, None)
        state = np.array(x, dtype=float)
        if not np.isfinite(state).all():
            # Otherwise the feedback turns the diverged state into a NaN torque and the run's failure is reported
            # as the caller's bad feedback (ValueError) instead of the integration's (found by the property fuzz).
            raise self.fail(t, "the state became non-finite before the feedback was sampled (the integration diverged)")
        value = self.feedback(t, state)
        try:
            return self.model.check_input(np.asarray(value, dtype=float).reshape(self.model.nu), "u(t, x)")
        except (TypeError, ValueError) as exc:  # TypeError: not numbers at all (e.g. a dict)
            raise ValueError(f"feedback u(t, x) at t = {t:.6g} s returned an invalid torque {value!r}: {exc}") from exc

    def fail(self, t_reached: float, reason: str, hint: str | None = None) -> SimulationError:
        """Build a :class:`SimulationError` for this run (the caller raises it).

        Parameters
        ----------
        t_reached : float
            Last time [s] the integration reached.
        reason : str
            What went wrong (solver message).
        hint : str, optional
            What to try instead (default :func:`failure_hint` of the model kind); ``""`` for none.

        Returns
        -------
        SimulationError
            Error naming this run's method and horizon ``t_final``.
        """
        return SimulationError(
            self.spec.name, float(t_reached), self.t_final, reason, failure_hint(self.model.kind) if hint is None else hint
        )

    def check_budget(self, t_reached: float, n_steps: int | None) -> None:
        """Raise the budget's :class:`SimulationError` when the steps or the wall time are used up.

        Parameters
        ----------
        t_reached : float
            Time [s] the integration has reached.
        n_steps : int or None
            Steps taken so far over the run (None: not known to the caller; only the
            wall time is checked).

        Raises
        ------
        SimulationError
            Names the budget, the steps taken, the time reached and the stiffness hint.
        """
        if n_steps is not None and n_steps > self.budget.max_steps:
            raise self.budget_error(t_reached, n_steps, "steps")
        if self.budget.wall_exceeded():
            raise self.budget_error(t_reached, n_steps, "wall")

    def budget_error(self, t_reached: float, n_steps: int | None, which: str) -> SimulationError:
        """The :class:`SimulationError` of an exhausted budget (the caller raises it).

        Parameters
        ----------
        t_reached : float
            Time [s] the integration reached.
        n_steps : int or None
            Steps taken (None: unknown).
        which : {"steps", "wall"}
            The budget used up.

        Returns
        -------
        SimulationError
            With ``n_steps`` set.
        """
        b = self.budget
        taken = "an unknown number of steps" if n_steps is None else f"{n_steps} steps"
        if which == "steps":
            reason = f"step budget exhausted: {taken} taken, options max_steps = {b.max_steps}"
            hint = f"{STIFF_HINT}; or raise options={{'max_steps': ...}}"
        else:
            reason = (
                f"wall-time budget exhausted: {b.elapsed:.3g} s elapsed (options max_wall_time = {b.max_wall_time:g} s), "
                f"{taken} taken"
            )
            hint = f"{STIFF_HINT}; or raise options={{'max_wall_time': ...}}"
        return SimulationError(self.spec.name, float(t_reached), self.t_final, reason, hint, n_steps=n_steps)


@dataclass
class RunResult:
    """What a runner returns.

    Attributes
    ----------
    x : ndarray, shape (N, nx)
        States on the output grid.
    u : ndarray, shape (N-1, nu)
        Torques held on each interval [N.m].
    stats : dict
        Solver statistics (``n_steps``, ``n_rhs``, ... where the solver reports them).

    Examples
    --------
    What a runner returns: the states on the output grid, the held torques, statistics.

    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.integrate import RunRequest, time_grid
    >>> model, spec, t = pl.rigid(), pl.METHODS["rk4"], time_grid(1.0, 0.1)
    >>> result = spec.runner(RunRequest(model, spec, model.state(theta1=0.5), t, np.zeros((10, 2)), None, 1e-8, 1e-8, 1e-3))
    >>> result.x.shape, result.u.shape  # (N, nx) states, (N - 1, nu) torques
    ((11, 4), (10, 2))
    >>> result.stats["n_steps"]  # 1 ms RK4 steps over 1 s
    1000
    """

    x: np.ndarray
    u: np.ndarray
    stats: dict[str, Any] = field(default_factory=dict)


class Runner(Protocol):
    """A method family's entry point: ``runner(request) -> RunResult``.

    Any callable with this signature satisfies the protocol; the class itself
    is only a type and is never instantiated.

    Parameters
    ----------
    *args, **kwargs
        Not used (a ``Protocol`` cannot be instantiated).
    """

    def __call__(self, request: RunRequest) -> RunResult:
        """Integrate ``request`` over its grid; raise :class:`SimulationError` on failure.

        Parameters
        ----------
        request : RunRequest
            The validated run.

        Returns
        -------
        RunResult
            States on the output grid, held inputs and solver statistics.
        """


@dataclass(frozen=True)
class MethodSpec:
    """One entry of the method registry.

    Attributes
    ----------
    name : str
        Name passed as ``simulate(..., method=name)``.
    family : str
        ``"casadi"``, ``"scipy"``, ``"fixed"``, ``"taylor"`` or ``"compiled"``.
    description : str
        One line for tables and messages.
    runner : Runner
        The family's runner.
    fixed_step : bool
        True when ``rtol``/``atol`` do not apply (the step is ``max_step``).
    settings : mapping
        Family-specific settings (e.g. the CasADi plugin and its options). Keys the front end reads:
        ``"available"`` (a callable giving the reason the method cannot run here, or None), ``"outputs"``
        (``f(model, X, U) -> Y``, the outputs on the grid by the family's own compiled code) and
        ``"passes_interrupts"`` (True: the runner's native code lets Ctrl-C through as ``KeyboardInterrupt``,
        so :func:`~pendulab.integrate.simulate` installs no SIGINT watch around it).

    Examples
    --------
    >>> import pendulab as pl
    >>> spec = pl.METHODS["rk4"]
    >>> spec.name, spec.family, spec.fixed_step
    ('rk4', 'fixed', True)
    >>> sorted({s.family for s in pl.METHODS.values()})
    ['casadi', 'compiled', 'fixed', 'scipy', 'taylor']
    >>> [name for name, s in pl.METHODS.items() if s.family == "compiled"]
    ['compiled-dopri5', 'compiled-rodas4']
    >>> pl.simulate(pl.rigid(), [0.5, 0.0, 0.0, 0.0], 1.0, method=spec.name).method
    'rk4'
    """

    name: str
    family: str
    description: str
    runner: Runner = field(repr=False, compare=False)
    fixed_step: bool = False
    settings: Mapping[str, Any] = field(default_factory=dict)


class Registry(Mapping[str, MethodSpec]):
    """Read-only mapping of method name to :class:`MethodSpec`, with aliases.

    Parameters
    ----------
    specs : iterable of MethodSpec
        The methods.
    deprecated : mapping of str to str, optional
        Old name -> current name; resolving an old name warns (``DeprecationWarning``).
    """

    def __init__(self, specs: Any, deprecated: Mapping[str, str] | None = None) -> None:
        self._specs: dict[str, MethodSpec] = {}
        self._deprecated = dict(deprecated or {})
        for spec in specs:
            self.add(spec)

    def add(self, spec: MethodSpec) -> None:
        """Register a method (a name may be registered once).

        Parameters
        ----------
        spec : MethodSpec
            The method; its ``name`` must be new (and not a deprecated alias).

        Raises
        ------
        ValueError
            The name is taken.
        """
        if spec.name in self._specs or spec.name in self._deprecated:
            raise ValueError(f"method {spec.name!r} is already registered")
        self._specs[spec.name] = spec

    def __getitem__(self, name: str) -> MethodSpec:
        return self._specs[name]

    def __iter__(self):
        return iter(self._specs)

    def __len__(self) -> int:
        return len(self._specs)

    def __repr__(self) -> str:
        # what print(pl.METHODS) shows: the names, grouped by family, not an object address
        families: dict[str, list[str]] = {}
        for spec in self._specs.values():
            families.setdefault(spec.family, []).append(spec.name)
        groups = "; ".join(f"{family}: {', '.join(names)}" for family, names in families.items())
        return f"<{len(self._specs)} integration methods: {groups}>"

    def resolve(self, method: Any) -> MethodSpec:
        """Look up a method by name (case-insensitive; deprecated names warn).

        Parameters
        ----------
        method : str
            Method name, or a deprecated alias (emits ``DeprecationWarning``).

        Returns
        -------
        MethodSpec
            The registered method; an exact match wins over a case-insensitive one.

        Raises
        ------
        ValueError
            Not a string, or not a registered name.
        """
        if not isinstance(method, str):
            raise ValueError(f"method must be a string, got {method!r}")
        if method in self._deprecated:
            new = self._deprecated[method]
            warnings.warn(f"method {method!r} is deprecated; use {new!r}", DeprecationWarning, stacklevel=3)
            method = new
        if method in self._specs:
            return self._specs[method]
        by_lower = {k.lower(): v for k, v in self._specs.items()}
        if method.lower() in by_lower:
            return by_lower[method.lower()]
        raise ValueError(f"unknown method {method!r}; expected one of {list(self._specs)}")
