"""``swing_up``: solve a :class:`SwingUpProblem` with IPOPT and report honestly.

The default initial guess (``"auto"``) needs no tuning: a straight line from
start to goal; if IPOPT fails from there, a homotopy from the fully actuated
to the under-actuated problem (the passive joint's torque bound shrinks to
zero, each stage warm-started from the last). Elastic problems are first
solved on their rigid point-mass counterpart and lifted with quasi-static
spring lengths.

A failed solve is a result with ``success=False``, IPOPT's return status and
a readable message, never an exception and never a trajectory passed off as
optimal.

An interrupt (Ctrl-C) is never a failed solve: CasADi catches the
``KeyboardInterrupt`` raised inside IPOPT's callbacks and returns as if IPOPT
had failed, which would start the next homotopy stage. :func:`swing_up`
watches SIGINT while it runs and raises ``KeyboardInterrupt`` as soon as the
interrupted IPOPT run returns, without starting another.
"""

from __future__ import annotations

import contextlib
import signal
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .guess import Guess, energy_guess, lift_to_elastic, linear_guess, rigid_counterpart
from .problem import SwingUpProblem
from .transcription import COLLOCATION, Transcription, get_transcription

__all__ = ["SwingUpResult", "swing_up", "GUESSES"]

#: Named initial-guess strategies accepted by :func:`swing_up`.
GUESSES: tuple[str, ...] = ("auto", "linear", "energy", "homotopy")
_IPOPT_OK = ("Solve_Succeeded", "Solved_To_Acceptable_Level")
#: A "successful" solution must satisfy its constraints to this level (defects in state units).
_FEASIBILITY_TOL = 1e-6
#: Passive-torque bound (fraction of the torque limit) of each homotopy stage.
_HOMOTOPY = (1.0, 0.3, 0.1, 0.03, 0.0)
_WARM_IPOPT = {"mu_strategy": "monotone", "mu_init": 1e-3}


@dataclass(frozen=True)
class SwingUpResult:
    """Outcome of :func:`swing_up`.

    Attributes
    ----------
    problem : SwingUpProblem
    method : str
        Transcription (``radau``, ``legendre``, ``shooting``).
    N, degree : int
        Intervals and collocation degree (0 for shooting).
    success : bool
        IPOPT converged *and* the solution satisfies dynamics and bounds.
    status : str
        IPOPT's return status of the final stage (e.g. ``Solve_Succeeded``,
        ``Infeasible_Problem_Detected``).
    message : str
        Human-readable summary; says why when ``success`` is False.
    iterations : int
        IPOPT iterations, summed over all stages.
    wall_time : float
        Solve time incl. guesses and homotopy stages [s] (NLP building excluded).
    build_time : float
        Time spent building the NLP(s) this call (0 when cached) [s].
    t : ndarray, shape (N + 1,)
        Grid times [s].
    x : ndarray, shape (N + 1, nx)
        States on the grid.
    u : ndarray, shape (N, 2)
        Torques (tau1, tau2) held on each interval [N.m].
    cost : float
        Objective value.
    max_violation : float
        Largest constraint (defect/continuity) violation.
    stages : tuple of dict
        One entry per IPOPT run: label, status, iterations, time.
    xc : ndarray, shape (N * degree, nx)
        Collocation-point states (empty for shooting).
    """

    problem: SwingUpProblem
    method: str
    N: int
    degree: int
    success: bool
    status: str
    message: str
    iterations: int
    wall_time: float
    build_time: float
    t: np.ndarray
    x: np.ndarray
    u: np.ndarray
    cost: float
    max_violation: float
    stages: tuple[dict[str, Any], ...] = ()
    xc: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)), repr=False)

    @property
    def horizon(self) -> float:
        """Final time T [s]."""
        return float(self.t[-1])

    def u_at(self, t: float | np.ndarray) -> np.ndarray:
        """Held torque at time(s) ``t`` (zero-order hold).

        Parameters
        ----------
        t : float or array_like, shape (K,)
            Times [s]; before 0 the first torque, from T on the last.

        Returns
        -------
        ndarray, shape (2,) or (K, 2)
            Torques (tau1, tau2) [N.m] of the interval containing each time.
        """
        ts = np.asarray(t, dtype=float)
        k = np.clip(np.searchsorted(self.t, ts, side="right") - 1, 0, self.N - 1)
        return self.u[k]

    def x_at(self, t: float | np.ndarray) -> np.ndarray:
        """State at time(s) ``t`` by cubic Hermite interpolation with the model's f(x, u).

        Parameters
        ----------
        t : float or array_like, shape (K,)
            Times [s]; clipped to [0, T], so outside it the end states are returned.

        Returns
        -------
        ndarray, shape (nx,) or (K, nx)
            Interpolated states (scalar ``t`` gives one state).
        """
        ts = np.asarray(t, dtype=float)
        scalar = ts.ndim == 0
        ts = np.clip(np.atleast_1d(ts), 0.0, self.horizon)
        k = np.clip(np.searchsorted(self.t, ts, side="right") - 1, 0, self.N - 1)
        h = self.t[k + 1] - self.t[k]
        s = ((ts - self.t[k]) / h)[:, None]
        model = self.problem.model
        f0 = model.rhs(self.x[k], self.u[k])
        f1 = model.rhs(self.x[k + 1], self.u[k])
        h00, h10, h01, h11 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s, -2 * s**3 + 3 * s**2, s**3 - s**2
        out = h00 * self.x[k] + h10 * h[:, None] * f0 + h01 * self.x[k + 1] + h11 * h[:, None] * f1
        return out[0] if scalar else out

    def as_guess(self) -> Guess:
        """This solution as an initial guess for another solve.

        Returns
        -------
        Guess
            The grid ``t``, states ``x`` and held torques ``u`` (shape (N, 2)).
        """
        return Guess(self.t, self.x, self.u)


def swing_up(
    problem: SwingUpProblem,
    method: str = "radau",
    N: int = 100,
    *,
    degree: int = 3,
    integrator: str = "rk",
    guess: str | Guess | SwingUpResult = "auto",
    ipopt_options: dict[str, Any] | None = None,
) -> SwingUpResult:
    """Solve a swing-up problem by direct collocation or multiple shooting with IPOPT.

    Parameters
    ----------
    problem : SwingUpProblem
    method : {"radau", "legendre", "shooting"}
        Transcription (see :mod:`pendulab.control.swingup.transcription`).
    N : int
        Number of control intervals (torques are held on each).
    degree : int
        Collocation polynomial degree.
    integrator : {"rk", "cvodes"}
        Integrator of multiple shooting (see :func:`get_transcription`).
    guess : {"auto", "linear", "energy", "homotopy"}, Guess or SwingUpResult
        Initial guess: ``auto`` = linear, falling back to the homotopy (and,
        for elastic models, starting from the rigid counterpart's solution);
        ``linear`` / ``energy`` = that guess alone; ``homotopy`` = always the
        full -> under-actuated homotopy; or an explicit trajectory.
    ipopt_options : dict or None
        Extra IPOPT options.

    Returns
    -------
    SwingUpResult
        ``success`` False (with IPOPT's status and a message) when IPOPT fails
        or its answer violates dynamics or bounds.

    Raises
    ------
    ValueError
        Unknown method/guess name, bad N or degree.
    KeyboardInterrupt
        On SIGINT (Ctrl-C), also when it arrives inside an IPOPT iteration;
        no further stage is started.
    """
    with _watch_interrupt() as interrupt:
        return _swing_up(problem, method, N, degree, integrator, guess, ipopt_options, interrupt)


def _swing_up(
    problem: SwingUpProblem,
    method: str,
    N: int,
    degree: int,
    integrator: str,
    guess: str | Guess | SwingUpResult,
    ipopt_options: dict[str, Any] | None,
    interrupt: _Interrupt,
) -> SwingUpResult:
    if isinstance(guess, str) and guess not in GUESSES:
        raise ValueError(f"guess must be one of {list(GUESSES)}, a Guess or a SwingUpResult, got {guess!r}")
    if not isinstance(guess, (str, Guess, SwingUpResult)):
        raise ValueError(f"guess must be one of {list(GUESSES)}, a Guess or a SwingUpResult, got {type(guess).__name__}")
    warm = isinstance(guess, (Guess, SwingUpResult)) or (guess in ("auto", "homotopy") and problem.model.kind == "elastic")
    if warm:
        # From a good guess a small, monotone barrier parameter keeps IPOPT near it (fewer
        # iterations, lower-cost local optima on the elastic tasks: benchmarks/results/swingup.md).
        ipopt_options = {**_WARM_IPOPT, **(ipopt_options or {})}
    tb = time.perf_counter()
    tr = get_transcription(problem, method, N, degree, integrator, ipopt_options)
    build = time.perf_counter() - tb
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
        rigid_res = swing_up(rigid_counterpart(problem), method, N, degree=degree, integrator=integrator, guess=guess)
        build_extra += rigid_res.build_time
        stages.extend({**s, "label": "rigid: " + s["label"]} for s in rigid_res.stages)
        g = lift_to_elastic(problem, rigid_res.t, rigid_res.x, np.vstack([rigid_res.u, rigid_res.u[-1:]]))
    else:
        g = linear_guess(problem)
    w0 = _guess_vector(tr, problem, g)

    out = None
    if guess != "homotopy":
        out = _run(tr, problem, w0, 0.0, "direct", stages, interrupt)
    if guess == "homotopy" or (guess == "auto" and not _ok(out)):
        w = w0
        for frac in _HOMOTOPY:
            out = _run(tr, problem, w, frac, f"passive {frac:g}x limit", stages, interrupt)
            # Keep going from the last iterate even after a failed stage: later stages often recover.
            w = out["w"]
    return _result(tr, problem, out, stages, time.perf_counter() - t_start, build + build_extra)


def _guess_vector(tr: Transcription, problem: SwingUpProblem, g: Guess) -> np.ndarray:
    T = problem.horizon
    grid = np.linspace(0.0, T, tr.N + 1)
    X = g.states_at(grid, T)
    if tr.n_coll:
        tc = (grid[:-1, None] + (T / tr.N) * tr.collocation_times()[None, :]).ravel()
        Xc = g.states_at(tc, T)
    else:
        Xc = np.zeros((0, tr.nx))
    U = g.inputs_at(grid[:-1], T)
    lb, ub = problem.torque_bounds()
    return tr.join(X, Xc, np.clip(U, lb, ub), T)


class _Interrupt:
    """Whether a SIGINT arrived while :func:`swing_up` ran (set by :func:`_watch_interrupt`)."""

    def __init__(self) -> None:
        self.hit = False

    def handler(self, previous: Any) -> Any:
        def on_sigint(signum: int, frame: Any) -> None:
            if not callable(previous):  # SIG_DFL: would end the process; interrupt instead
                self.hit = True
                raise KeyboardInterrupt
            try:
                previous(signum, frame)  # the caller's handler (Python's default raises KeyboardInterrupt)
            except KeyboardInterrupt:
                self.hit = True
                raise

        return on_sigint

    def check(self, message: str = "") -> None:
        """Raise ``KeyboardInterrupt`` when a SIGINT arrived or CasADi's message names one.

        IPOPT's own status does not tell: CasADi reports an interrupted run as
        ``NonIpopt_Exception_Thrown``, like any other exception in a callback.
        """
        if self.hit or "KeyboardInterrupt" in message:
            raise KeyboardInterrupt


@contextlib.contextmanager
def _watch_interrupt() -> Iterator[_Interrupt]:
    # Signal handlers can only be installed from the main thread; elsewhere only CasADi's message tells.
    flag = _Interrupt()
    if threading.current_thread() is not threading.main_thread():
        yield flag
        return
    previous = signal.getsignal(signal.SIGINT)
    if previous in (signal.SIG_IGN, None):
        yield flag
        return
    signal.signal(signal.SIGINT, flag.handler(previous))
    try:
        yield flag
    finally:
        signal.signal(signal.SIGINT, previous)


def _run(
    tr: Transcription, problem: SwingUpProblem, w0: np.ndarray, passive: float, label: str, stages: list, interrupt: _Interrupt
) -> dict:
    lb, ub = problem.torque_bounds(passive_fraction=passive)
    t0 = time.perf_counter()
    try:
        out = tr.solve(problem, w0, lb, ub)
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


def _result(tr: Transcription, problem: SwingUpProblem, out: dict, stages: list, wall: float, build: float) -> SwingUpResult:
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
        t=np.linspace(0.0, T, tr.N + 1),
        x=X.copy(),
        u=U.copy(),
        cost=float(out["f"]),
        max_violation=violation,
        stages=tuple(stages),
        xc=Xc.copy(),
    )
