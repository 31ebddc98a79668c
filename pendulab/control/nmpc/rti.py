"""Real-time-iteration NMPC at 500 Hz: one compiled Gauss-Newton SQP step per sample (controller name ``rti``).

The same tracking problem as :mod:`.controller` (track the task's offline swing-up plan, then
regulate upright; terminal cost the discrete LQR cost-to-go about the goal; hard torque bounds), solved
the real-time-iteration way (Diehl, Bock and Schloeder 2005): each sample takes exactly one Gauss-Newton
SQP step from the previous solution shifted by one sample. The whole step (linearization, condensing,
box-QP solve, update and shift; :mod:`.rti_step`) is one CasADi Function, generated as C, compiled once
and cached on disk (:mod:`.rti_build`), and called from Python through preallocated buffers.

Design (measured in ``benchmarks/results/rti.md``, explained in ``docs/rti.md``):

* sampled every 2 ms, predicting over 30 intervals of 10 ms (0.3 s): intervals longer than the
  sample keep the look-ahead of the 50 Hz NMPC at a fifth of its cost per second of horizon; the
  warm start interpolates inside the intervals;
* no hard velocity bound: the QP has torque bounds only, so it is a box QP in the condensed torques (an
  optional *soft* bound on the joint rates, ``rate_limit``, is a least-squares penalty inside the same QP),
  solved by a fixed number of primal-dual active-set iterations started from the bounds the warm start sits
  on; a call whose last iterate is not a KKT point is counted (``qp_unsolved``) and its clipped iterate applied;
* a step that returns a non-finite value never raises: it is counted in ``failures``, the LQR torque
  about the goal is applied and the next sample starts cold (from a rollout of the measured state).
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import casadi as ca
import numpy as np

from ..._checks import bounded_int, positive_float
from ..._inputs import check_input
from ...model.model import Model
from ..feedback import actuated_inputs, upright_state
from ..lqr import lqr_balance, wrap_state_error
from ..tracking import resample_reference
from .ocp import reference_window
from .rti_build import compiled_step
from .rti_step import rollout_function, rti_step_function

if TYPE_CHECKING:
    from ..swingup.tasks import Task

__all__ = ["RTIOptions", "RTIController", "rti_controller", "rti_for_task", "MAX_RTI_HORIZON"]

#: Largest number of shooting intervals: the condensed QP is dense in N m torques (cost ~ N^3 per QP iteration).
MAX_RTI_HORIZON = 200


@dataclass(frozen=True)
class RTIOptions:
    """Settings of the real-time-iteration NMPC.

    Attributes
    ----------
    horizon : int
        Shooting intervals N (prediction ``N * interval`` seconds). Set from ``intervals`` when given.
    interval : float
        Length of a shooting interval [s], at least ``sample_time``. Set to ``intervals[0]`` when given.
    intervals : tuple of float or None
        A non-uniform grid: the N interval lengths [s], each at least ``sample_time`` (best a multiple
        of it: the reference is read at the nearest sample). None: ``horizon`` intervals of ``interval``.
    sample_time : float
        Controller sample time [s] (one SQP step per sample).
    substeps : int or None
        RK4 steps per interval; default one per 10 ms of each interval (``ceil(interval / 0.01)``).
    qp_iterations : int
        Primal-dual active-set solves of the box QP (the first holds the warm start's saturated torques).
    q_angle, q_rate : float
        Stage weights on angle errors [1/rad^2] and rate errors [s^2/rad^2].
    r : float or None
        Weight of each driven torque [1/(N.m)^2]; default ``1 / u_max^2``.
    terminal_weights : tuple of float or None
        Diagonal of the terminal weight (one per state, angles first); default the discrete LQR
        cost-to-go about the goal at the last interval.
    cost_per_second : bool
        Weight each stage cost by its interval length [s] (the cost approximates an integral, as acados
        does); default False (every stage weighs the same).
    rate_limit : float or None
        Soft bound on both joint rates (``omega1``, ``omega2 - omega1``) at every node [rad/s] (declared
        ``velocity_limit``); None: no bound.
    rate_weight : float
        Penalty weight of a rate past ``rate_limit`` [s^2/rad^2] per node (declared ``weight``). Default 1e3:
        at 1e4 and above the active-set steps cycled on a swing-up from hanging (measured; docs/rti.md).
    angle_limit : float or None
        Largest joint angle the controller steers to [rad]: the measured state is compared with the reference
        moved by whole turns, at most as many as keep it within this (:func:`joint_wrapped_error`); None: the
        nearest whole turn, however far the robot has wound.
    compiled : bool
        Run the step as cached C (default) or as the uncompiled CasADi graph (same numbers, slower).
    """

    horizon: int = 30
    interval: float = 0.01
    sample_time: float = 0.002
    substeps: int | None = None
    qp_iterations: int = 20
    q_angle: float = 10.0
    q_rate: float = 1.0
    r: float | None = None
    compiled: bool = True
    intervals: tuple[float, ...] | None = None
    terminal_weights: tuple[float, ...] | None = None
    cost_per_second: bool = False
    rate_limit: float | None = None
    rate_weight: float = 1e3
    angle_limit: float | None = None

    def __post_init__(self) -> None:
        if self.intervals is not None:
            if isinstance(self.intervals, str) or np.ndim(self.intervals) != 1 or len(self.intervals) == 0:
                raise TypeError(f"intervals must be a non-empty sequence of interval lengths [s], got {self.intervals!r}")
            grid = tuple(positive_float(f"intervals[{k}]", v, "[s]") for k, v in enumerate(self.intervals))
            object.__setattr__(self, "intervals", grid)
            object.__setattr__(self, "horizon", len(grid))
            object.__setattr__(self, "interval", grid[0])
        if self.terminal_weights is not None:
            if isinstance(self.terminal_weights, str) or np.ndim(self.terminal_weights) != 1:
                raise TypeError(f"terminal_weights must be a sequence of weights, got {self.terminal_weights!r}")
            tw = tuple(positive_float(f"terminal_weights[{k}]", v) for k, v in enumerate(self.terminal_weights))
            object.__setattr__(self, "terminal_weights", tw)
        object.__setattr__(
            self, "horizon", bounded_int("horizon", self.horizon, low=1, high=MAX_RTI_HORIZON, why="the condensed QP is dense")
        )
        object.__setattr__(
            self, "qp_iterations", bounded_int("qp_iterations", self.qp_iterations, low=1, high=100, why="a fixed per-call cost")
        )
        if self.substeps is not None:
            object.__setattr__(self, "substeps", bounded_int("substeps", self.substeps, high=100, why="RK4 steps are unrolled"))
        for name, unit in (("interval", "[s]"), ("sample_time", "[s]"), ("q_angle", ""), ("q_rate", "")):
            object.__setattr__(self, name, positive_float(name, getattr(self, name), unit))
        if self.r is not None:
            object.__setattr__(self, "r", positive_float("r", self.r))
        if self.rate_limit is not None:
            object.__setattr__(self, "rate_limit", check_input("velocity_limit", self.rate_limit, "rate_limit"))
        object.__setattr__(self, "rate_weight", check_input("weight", self.rate_weight, "rate_weight"))
        if self.angle_limit is not None:
            object.__setattr__(self, "angle_limit", check_input("angle_limit", self.angle_limit))
        if self.sample_time > min(self.grid) * (1 + 1e-9):
            raise ValueError(
                f"sample_time must be at most interval (the shortest, {min(self.grid)!r} s: the warm start shifts "
                f"inside each interval), got {self.sample_time!r}"
            )
        for name in ("compiled", "cost_per_second"):
            if not isinstance(getattr(self, name), bool):
                raise TypeError(f"{name} must be True or False, got {getattr(self, name)!r}")

    @property
    def grid(self) -> tuple[float, ...]:
        """The N interval lengths [s] (``intervals``, or ``horizon`` times ``interval``)."""
        return self.intervals if self.intervals is not None else (self.interval,) * self.horizon

    @property
    def prediction(self) -> float:
        """Prediction horizon [s] (sum of the intervals)."""
        return float(sum(self.grid))

    @property
    def steps_per_interval(self) -> int:
        """RK4 steps per interval actually used (of the first interval on a non-uniform grid)."""
        return self.grid_steps[0]

    @property
    def grid_steps(self) -> tuple[int, ...]:
        """RK4 steps of each interval actually used."""
        if self.substeps is not None:
            return (self.substeps,) * self.horizon
        return tuple(max(1, math.ceil(h / 0.01 - 1e-9)) for h in self.grid)


def joint_wrapped_error(dx: np.ndarray, ref: np.ndarray | None = None, angle_limit: float | None = None) -> np.ndarray:
    """A state difference (absolute angles first) with the *joint* angle differences wrapped into [-pi, pi).

    The shoulder angle and the elbow's relative angle ``theta2 - theta1`` are wrapped, as the robot's joints
    are. Wrapping the two absolute angles apart would hand a hanging robot a goal a whole turn of the elbow
    away whenever the two differences sit on opposite sides of pi (both are ~pi there, so noise decides).
    With ``angle_limit``, the whole turns are limited so that the target joint angle (``ref`` moved by them)
    stays within ``+-angle_limit``: a robot wound past it is steered back, not on to the next upright
    (a real robot has a winding limit; RealAIGym's hardware resets at 3.5 pi).

    Parameters
    ----------
    dx : ndarray, shape (nx,)
        ``x - ref``, ``theta1, theta2`` first (rigid and elastic states alike) [rad, rad, ...].
    ref : ndarray, shape (nx,), optional
        The reference the difference is taken to (needed with ``angle_limit``).
    angle_limit : float, optional
        Largest target joint angle [rad]; None: no limit.

    Returns
    -------
    ndarray, shape (nx,)
        The same difference, joint angles wrapped; the other entries unchanged.
    """
    d = np.array([dx[0], dx[1] - dx[0]])
    turns = np.round(d / (2 * np.pi))
    if angle_limit is not None and ref is not None:
        qr = np.array([ref[0], ref[1] - ref[0]])
        # the largest number of turns n (towards 0) with |qr + 2 pi n| <= angle_limit
        hi = np.floor((angle_limit - qr) / (2 * np.pi) + 1e-12)
        lo = np.ceil((-angle_limit - qr) / (2 * np.pi) - 1e-12)
        turns = np.clip(turns, np.minimum(lo, 0.0), np.maximum(hi, 0.0))
    e1, e2 = d - 2 * np.pi * turns
    out = np.array(dx, dtype=float)
    out[0], out[1] = e1, e1 + e2
    return out


@dataclass
class RTIController:
    """One compiled real-time iteration per sample (build with :func:`rti_controller` or :func:`rti_for_task`).

    Attributes
    ----------
    model : Model
        Plant and prediction model (rigid or elastic).
    options : RTIOptions
        Settings.
    input_names : tuple of str
        Driven torques, in output order.
    u_max : float
        Torque bound [N.m].
    x_ref : ndarray, shape (K, nx)
        Reference states on the sample grid.
    u_ref : ndarray, shape (K, m)
        Reference torques on the sample grid [N.m].
    goal : ndarray, shape (nx,)
        Held after the reference (upright at rest by default).
    graph : casadi.Function
        The uncompiled step (:func:`~.rti_step.rti_step_function`).
    step : casadi.Function
        What runs: the compiled step, or ``graph`` with ``compiled=False``.
    K_lqr : ndarray, shape (m, nx)
        Discrete LQR gain about ``goal`` at the interval (fallback torque).
    solve_times : list of float
        Wall time of each call [s] (checks, reference window, warm start and step).
    failures, qp_unsolved : int
        Calls with a non-finite step (fallback applied); calls whose QP iterate was not a KKT point (clipped, applied).
    """

    model: Model
    options: RTIOptions
    input_names: tuple[str, ...]
    u_max: float
    x_ref: np.ndarray
    u_ref: np.ndarray
    goal: np.ndarray
    graph: ca.Function
    step: ca.Function
    K_lqr: np.ndarray
    solve_times: list[float] = field(default_factory=list)
    failures: int = 0
    qp_unsolved: int = 0

    def __post_init__(self) -> None:
        N, nx, m = self.options.horizon, self.model.nx, len(self.input_names)
        # Row k of a (N+1, nx) C-ordered array is column k of CasADi's column-major (nx, N+1) matrix.
        self._in = [np.zeros(nx), np.zeros((N + 1, nx)), np.zeros((N, m)), np.zeros((N + 1, nx)), np.zeros((N, m))]
        self._out = [np.zeros(m), np.zeros((N + 1, nx)), np.zeros((N, m)), np.zeros((N + 1, nx)), np.zeros((N, m)), np.zeros(3)]
        self._buf, self._eval = self.step.buffer()
        for i, a in enumerate(self._in):
            self._buf.set_arg(i, memoryview(a))
        for i, a in enumerate(self._out):
            self._buf.set_res(i, memoryview(a))
        self._nodes = np.concatenate([[0.0], np.cumsum(self.options.grid)])  # node times [s]
        self._offsets = np.round(self._nodes / self.options.sample_time).astype(int)
        self._k_prev = -1
        self._warm = False
        self._rollout = rollout_function(self.model, self.input_names, self.options.grid, self.options.grid_steps)

    @property
    def sample_time(self) -> float:
        """Sample period [s]."""
        return self.options.sample_time

    def reset(self) -> None:
        """Forget the warm start and the statistics before a new run."""
        self.reset_warm_start()
        self.solve_times = []
        self.failures = self.qp_unsolved = 0

    def reset_warm_start(self) -> None:
        """Start the next call cold (from a rollout of the reference torques), keeping the statistics."""
        self._k_prev, self._warm = -1, False

    def set_reference(self, x_ref: np.ndarray, u_ref: np.ndarray, goal: np.ndarray | None = None) -> None:
        """Track another reference from the next call on; that call's time 0 is the reference's first sample.

        Parameters
        ----------
        x_ref : array_like, shape (K, nx)
            States on the sample grid [rad, rad/s].
        u_ref : array_like, shape (K, m) or (K - 1, m)
            Driven torques on the sample grid [N.m].
        goal : array_like, shape (nx,), optional
            Held after the reference; default the current :attr:`goal`.

        Raises
        ------
        ValueError
            Shapes that do not match, non-finite values, or an empty reference.
        """
        x_ref = self.model.check_state(np.asarray(x_ref, dtype=float), "x_ref")
        m = len(self.input_names)
        u_ref = np.asarray(u_ref, dtype=float)
        if x_ref.ndim != 2 or len(x_ref) == 0:
            raise ValueError(f"x_ref must have shape (K, {self.model.nx}) with K >= 1, got {x_ref.shape}")
        if u_ref.ndim != 2 or u_ref.shape[1] != m or len(u_ref) not in (len(x_ref), len(x_ref) - 1):
            raise ValueError(f"u_ref must have shape ({len(x_ref)}, {m}) or ({len(x_ref) - 1}, {m}), got {u_ref.shape}")
        if not np.all(np.isfinite(u_ref)):
            raise ValueError("u_ref must be finite")
        if goal is not None:
            goal = self.model.check_state(np.asarray(goal, dtype=float), "goal")
            if goal.ndim != 1:
                raise ValueError(f"goal must be one state of shape ({self.model.nx},), got {goal.shape}")
            self.goal = goal
        self.x_ref, self.u_ref = x_ref, u_ref
        self.reset_warm_start()

    def window(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """Reference at the shooting nodes of the window starting at sample ``k`` (the goal after the reference).

        Parameters
        ----------
        k : int
            Sample index (time ``k * sample_time``).

        Returns
        -------
        xr : ndarray, shape (N+1, nx)
        ur : ndarray, shape (N, m)
        """
        idx = k + self._offsets
        return reference_window(self.x_ref, idx, self.goal), reference_window(self.u_ref, idx[:-1], 0.0)

    def __call__(self, t: float, x: np.ndarray) -> np.ndarray:
        """One real-time iteration from the measured state: the torques to apply now.

        Parameters
        ----------
        t : float
            Time since the start of the run [s] (selects the reference window).
        x : array_like, shape (nx,)
            Measured plant state [rad, rad/s].

        Returns
        -------
        ndarray, shape (m,)
            Torques [N.m] for ``input_names``, within the torque bound.

        Raises
        ------
        ValueError
            A negative or non-finite ``t``, or an ``x`` that is not a finite state of shape (nx,) (a bad
            measurement; a failed step never raises, it is counted in :meth:`stats`).
        """
        start = time.perf_counter()
        x = self.model.check_state(x, "x")
        if x.ndim != 1:
            raise ValueError(f"x must be one state of shape ({self.model.nx},), got shape {x.shape}")
        try:
            t = float(t)
        except (TypeError, ValueError):
            raise ValueError(f"t must be a time >= 0 [s], got {t!r}") from None
        if not (math.isfinite(t) and t >= 0.0):
            raise ValueError(f"t must be a finite time >= 0 [s] (the controller's clock starts at 0), got {t!r}")
        k = int(math.floor(t / self.options.sample_time + 1e-6))
        x0, X, U, XR, UR = self._in
        XR[:], UR[:] = self.window(k)
        x0[:] = XR[0] + joint_wrapped_error(x - XR[0], XR[0], self.options.angle_limit)
        self._guess(k)
        self._eval()
        u0, Xn, Un, _, _, info = self._out
        if not (np.all(np.isfinite(u0)) and np.all(np.isfinite(Xn)) and np.all(np.isfinite(Un))):
            self.failures += 1
            self._warm = False
            u = -self.K_lqr @ wrap_state_error(x0 - self.goal, self.model.state_names)
        else:
            self._warm, self._k_prev = True, k
            self.qp_unsolved += int(info[0] < 0.5)
            u = u0.copy()
        self.solve_times.append(time.perf_counter() - start)
        return np.clip(u, -self.u_max, self.u_max)

    def _guess(self, k: int) -> None:
        """Write the start guess of the step: the last solution shifted to sample ``k``, or (cold) the reference
        torques and the states they lead to from ``x0`` (:func:`~.rti_step.rollout_function`)."""
        x0, X, U, XR, UR = self._in
        _, Xn, Un, Xs, Us, _ = self._out
        s = k - self._k_prev
        if not self._warm or s < 0:
            U[:] = UR
            X[:] = np.asarray(self._rollout(x0, UR.T)).T
            if not np.all(np.isfinite(X)):
                X[:] = XR
        elif s == 1:  # the usual case: the step already returned the trajectory one sample later
            X[:], U[:] = Xs, Us
        elif s == 0:
            X[:], U[:] = Xn, Un
        else:
            nodes = self._nodes
            at = np.minimum(nodes + s * self.options.sample_time, nodes[-1])
            X[:] = np.column_stack([np.interp(at, nodes, Xn[:, i]) for i in range(X.shape[1])])
            Ug = np.vstack([Un, Un[-1:]])
            U[:] = np.column_stack([np.interp(at[:-1], nodes, Ug[:, i]) for i in range(U.shape[1])])
        X[0] = x0

    def stats(self) -> dict[str, float | int | str]:
        """Per-call statistics of the run so far.

        Returns
        -------
        dict
            ``solver`` ("rti"), ``n_calls``, ``solve_time_median``, ``solve_time_max`` [s] (nan before the
            first call), ``iterations_median`` and ``iterations_max`` (1: one SQP step per call), ``failures``,
            ``qp_unsolved`` (counts of calls) and ``compiled``.
        """
        ts = np.asarray(self.solve_times)
        n = len(ts)
        return {
            "solver": "rti",
            "n_calls": n,
            "solve_time_median": float(np.median(ts)) if n else float("nan"),
            "solve_time_max": float(ts.max()) if n else float("nan"),
            "iterations_median": 1.0 if n else float("nan"),
            "iterations_max": 1 if n else 0,
            "failures": int(self.failures),
            "qp_unsolved": int(self.qp_unsolved),
            "compiled": bool(self.options.compiled),
        }


def _check_options(options: RTIOptions | None, changes: dict[str, Any]) -> RTIOptions:
    unknown = sorted(set(changes) - set(RTIOptions.__dataclass_fields__))
    if unknown:
        raise TypeError(f"unknown RTI option(s) {unknown}; expected some of {sorted(RTIOptions.__dataclass_fields__)}")
    base = options if options is not None else RTIOptions()
    return RTIOptions(**{**base.__dict__, **changes})


def rti_controller(
    model: Model,
    *,
    actuation: str | Sequence[str] = "full",
    u_max: float = 20.0,
    reference: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
    goal: np.ndarray | None = None,
    options: RTIOptions | None = None,
    cache_directory: Path | None = None,
    **option_changes: Any,
) -> RTIController:
    """Build a real-time-iteration NMPC tracking ``reference`` (if any), then holding ``goal``.

    Parameters
    ----------
    model : Model
        Plant and prediction model, rigid or elastic (an elastic one is predicted with all 8 states, RK4 steps
        of at most 10 ms and at least ``h omega_fast`` per interval).
    actuation : {"full", "pendubot", "acrobot"} or sequence of input names
        Driven torques.
    u_max : float
        Torque bound [N.m].
    reference : (t, x, u), optional
        Times [s] shape (K,), states shape (K, nx) (or (K, 4) rigid states for an elastic model: the spring lengths
        are taken quasi-static), torques (tau1, tau2) [N.m] shape (K, 2) or (K-1, 2).
        None: regulation about ``goal``.
    goal : ndarray, shape (nx,), optional
        State held after the reference; default upright at rest.
    options : RTIOptions, optional
        Settings (default :class:`RTIOptions`).
    cache_directory : Path, optional
        Cache folder of the compiled step; default :func:`pendulab.native.cache_dir`.
    **option_changes
        :class:`RTIOptions` fields overriding ``options``.

    Returns
    -------
    RTIController

    Raises
    ------
    TypeError
        ``model`` is not a Model, or unknown option names.
    ValueError
        Bad options, torque limit, actuation, goal or reference shapes.
    CompilerNotFoundError (RuntimeError)
        ``compiled=True``, the step is not cached and no C compiler is found.
    """
    if not isinstance(model, Model):
        raise TypeError(f"model must be a pendulab Model, got {type(model).__name__}")
    opts = _check_options(options, option_changes)
    if model.kind == "elastic" and opts.substeps is None:
        opts = _check_options(opts, {"substeps": _elastic_substeps(model, opts.grid)})
    u_max = positive_float("u_max", u_max, "[N.m]")
    names = actuated_inputs(actuation)
    cols = [("tau1", "tau2").index(n) for n in names]
    goal = upright_state(model) if goal is None else model.check_state(goal, "goal")
    if goal.ndim != 1:
        raise ValueError(f"goal must be a single state of shape ({model.nx},), got {goal.shape}")
    if reference is None:
        x_ref, u_ref = goal[None, :], np.zeros((1, len(names)))
    else:
        t, xs, us = reference
        us = np.asarray(us, dtype=float)
        if us.ndim != 2 or us.shape[1] != 2:
            raise ValueError(f"reference torques must have shape (K, 2) (tau1, tau2), got {us.shape}")
        xs = np.asarray(xs, dtype=float)
        if model.kind == "elastic" and xs.ndim == 2 and xs.shape[1] == 4:  # a rigid plan: quasi-static spring lengths
            from .build import _lift_quasi_static

            xs = _lift_quasi_static(model, xs, us)
        xs = model.check_state(xs, "reference states")
        if xs.ndim != 2:
            raise ValueError(f"reference states must have shape (K, {model.nx}), got {xs.shape}")
        _, x_ref, u_full = resample_reference(t, xs, us, opts.sample_time, model)
        u_ref = u_full[:, cols]
    Q = _stage_weights(model, opts)
    R = np.eye(len(names)) * (opts.r if opts.r is not None else 1.0 / u_max**2)
    top = lqr_balance(model, names, Q, R, opts.grid[-1], at=goal)
    P = top.P if opts.terminal_weights is None else np.diag(opts.terminal_weights)
    if P.shape != Q.shape:
        raise ValueError(f"terminal_weights must have {model.nx} entries (one per state), got {len(opts.terminal_weights)}")
    build: dict[str, Any] = {
        "N": opts.horizon, "interval": opts.interval, "substeps": opts.steps_per_interval,
        "shift": opts.sample_time / opts.interval, "Q": Q, "R": R, "P": P, "u_max": u_max,
        "qp_iterations": opts.qp_iterations,
    }  # fmt: skip
    if opts.intervals is not None:  # the uniform build (and its cache key) stays as it was
        build.update(interval=list(opts.grid), substeps=list(opts.grid_steps), shift=[opts.sample_time / h for h in opts.grid])
    if opts.cost_per_second:
        build["stage_scale"] = list(opts.grid)
    if opts.rate_limit is not None:
        build.update(rate_limit=opts.rate_limit, rate_weight=opts.rate_weight)
    graph = rti_step_function(model, names, **build)
    if opts.compiled:
        meta = {**{k: np.asarray(v).tolist() for k, v in build.items()}, "model_p": np.asarray(model.p).tolist(), "inputs": names}
        step = compiled_step(graph, meta, directory=cache_directory)
    else:
        step = graph
    return RTIController(model, opts, names, u_max, x_ref, u_ref, goal, graph, step, top.K)


def _stage_weights(model: Model, opts: RTIOptions) -> np.ndarray:
    """Diagonal stage weight: ``q_angle`` on the angles, ``q_rate`` on the angular rates; an elastic model's spring
    lengths 100 [1/m^2] and their rates 0.1 [s^2/m^2] (the 8-state NMPC's weights, :mod:`.build`)."""
    fixed = {"r": 100.0, "v": 0.1, "t": opts.q_angle, "o": opts.q_rate}
    return np.diag([fixed[name[0]] for name in model.state_names])


def _elastic_substeps(model: Model, grid: Sequence[float]) -> int:
    """RK4 steps per interval for an elastic prediction: one per 10 ms, and at least ``h omega_fast`` (stability)."""
    from .build import _substeps

    return max(max(1, math.ceil(h / 0.01 - 1e-9), _substeps(model, h, None)) for h in grid)


def rti_for_task(task: Task | str, **options: Any) -> tuple[RTIController, np.ndarray]:
    """RTI NMPC that tracks the task's optimized swing-up at 500 Hz and then balances; and the task's start state.

    Parameters
    ----------
    task : Task or str
        Swing-up task (rigid or elastic), or its name (``pendubot``).
    **options
        :class:`RTIOptions` fields (``horizon``, ``interval``, ``sample_time``...) and ``cache_directory``.

    Returns
    -------
    controller : RTIController
        Saturated at the task's torque limit.
    x0 : ndarray, shape (nx,)
        The task's start state.

    Raises
    ------
    ValueError
        The swing-up plan failed, or bad options (checked before planning).
    TypeError
        ``task`` is neither a Task nor a name; unknown option names.
    FileNotFoundError
        Unknown task name.
    """
    from ..swingup.tasks import resolve_task
    from .factories import plan_swingup

    task = resolve_task(task)
    cache_directory = options.pop("cache_directory", None)
    opts = _check_options(None, options)  # before the (costly) plan
    pb = task.problem
    res = plan_swingup(pb, method=task.method, N=task.N, degree=task.degree)
    ctrl = rti_controller(
        task.model, actuation=pb.actuation, u_max=pb.torque_limit, reference=(res.t, res.x, res.u), options=opts,
        cache_directory=cache_directory,
    )  # fmt: skip
    return ctrl, np.asarray(pb.start, dtype=float)
