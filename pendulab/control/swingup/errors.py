"""A posteriori error estimate of a swing-up plan: every interval re-integrated independently.

A plan is a grid ``t`` (N + 1,), states ``x`` on it and torques ``u`` held on
each of the N intervals. Its *defect* on interval k is how far the true
dynamics, started from the plan's state ``x[k]`` with the plan's torque
``u[k]``, end from the plan's next state ``x[k + 1]``. Integrating each
interval from the plan's own state (not open loop from the start) measures the
local error of the transcription, free of the chaotic amplification of an
open-loop replay.

Each state's defect is divided by that state's largest magnitude over the plan
(``scale``), so angles, rates and spring lengths are judged on one relative
footing; the plan *passes* when the worst relative defect is within the
tolerance. This is the metric of the issue and the default (``scale="state"``).

One alternative scale is offered, as an explicit option (``scale="bob-speed"``):
the defect of the spring rates ``v1, v2`` [m/s] of an elastic model is divided
by ``max(max |v_i|, max_j |r_j omega_j|)`` over the plan: the bobs' largest
tangential speed, unless the spring's own rate is larger (both are velocities
of the same point masses). A stiff
spring's own rate stays tiny along any plan, so relative to itself a spring
ringing of micrometres counts as a large error; against the bob speed it is
judged like the motion it perturbs. All other states keep their own scale; for
a rigid model both options are the same. Results state which scale they used
(:attr:`ErrorEstimate.scale_kind`).

The re-integration uses the fast path, :func:`pendulab.simulate`: with
``method="auto"`` the integrator is chosen once per plan (the rule of
:mod:`pendulab.integrate.auto`, applied at the start state) and used for every
interval; one call per interval costs ~0.15-0.3 ms on the rigid model
(``benchmarks/results/swingup.md``).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any, Protocol

import numpy as np

from ..._inputs import checked
from ...integrate import SimulationError, simulate
from ...integrate.auto import choose_method
from ...model.model import Model

__all__ = ["ErrorEstimate", "estimate_error", "estimate_error_arrays", "SCALE_FLOOR", "SCALES", "rescale"]

#: Smallest per-state normalisation [state units: rad, m, rad/s, m/s]. A state that stays at
#: zero over a plan (an unexcited coordinate) would otherwise divide by zero; below this
#: magnitude its defect is judged in absolute terms.
SCALE_FLOOR = 1e-3
#: Per-state normalisations of the relative defect: ``state`` (each state's own largest magnitude,
#: the default) and ``bob-speed`` (spring rates against the bobs' largest speed; module notes).
SCALES: tuple[str, ...] = ("state", "bob-speed")


class PlanTrajectory(Protocol):
    """What :func:`estimate_error` reads from a plan (a :class:`~pendulab.control.swingup.solve.SwingUpResult`).

    Attributes
    ----------
    problem : SwingUpProblem
        Gives the model (``problem.model``).
    t : ndarray, shape (N + 1,)
        Grid times [s].
    x : ndarray, shape (N + 1, nx)
        States on the grid.
    u : ndarray, shape (N, 2)
        Held torques [N.m].
    """

    problem: Any
    t: np.ndarray
    x: np.ndarray
    u: np.ndarray


@dataclass(frozen=True)
class ErrorEstimate:
    """Relative per-interval defects of a plan under independent re-integration.

    Attributes
    ----------
    defects : ndarray, shape (N, nx)
        Relative defect per interval and state:
        ``|x_sim(t[k+1]; x[k], u[k]) - x[k+1]| / scale`` (dimensionless); inf
        where the integrator failed on that interval.
    interval_worst : ndarray, shape (N,)
        Worst relative defect of each interval over the states.
    worst : float
        Worst relative defect of the plan.
    tolerance : float
        Relative tolerance the plan is judged against.
    passed : bool
        ``worst <= tolerance``.
    method : str
        Integrator used (a key of :data:`pendulab.METHODS`; ``auto`` resolved).
    scale : ndarray, shape (nx,)
        Per-state normalisation: that state's largest magnitude over the plan,
        floored at :data:`SCALE_FLOOR` [state units].
    absolute : ndarray, shape (N, nx)
        The defects in state units [rad, m, rad/s, m/s] (``defects * scale``).
    state_names : tuple of str
        Names of the nx states (for messages and plots).
    scale_kind : str
        Which normalisation ``scale`` is (an entry of :data:`SCALES`).

    Examples
    --------
    >>> from pendulab.control import swing_up
    >>> from pendulab.control.swingup.tasks import load_task
    >>> res = swing_up(load_task("acrobot").problem, N=40)  # error estimate at the default tolerance 1e-3
    >>> est = res.error
    >>> est.passed, est.defects.shape  # relative defect per interval and state
    (True, (50, 4))
    >>> print(est.summary())
    error estimate (...): worst relative defect 1.0...e-04 (interval 19, omega1) vs tolerance 1.0e-03: pass
    """

    defects: np.ndarray
    interval_worst: np.ndarray
    worst: float
    tolerance: float
    passed: bool
    method: str
    scale: np.ndarray
    absolute: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)), repr=False)
    state_names: tuple[str, ...] = ()
    scale_kind: str = "state"

    @property
    def worst_interval(self) -> int:
        """Index of the interval with the worst defect (-1 for an empty plan)."""
        return int(np.argmax(self.interval_worst)) if self.interval_worst.size else -1

    @property
    def worst_state(self) -> str:
        """Name (or index, without names) of the state with the worst defect."""
        if not self.defects.size:
            return ""
        j = int(np.argmax(self.defects[self.worst_interval]))
        return self.state_names[j] if self.state_names else str(j)

    def summary(self) -> str:
        """One line for logs and the CLI.

        Returns
        -------
        str
            Worst relative defect, where it occurs, the tolerance and pass/fail.
        """
        verdict = "pass" if self.passed else "FAIL"
        how = self.method if self.scale_kind == "state" else f"{self.method}, spring rates against the bob speed"
        return (
            f"error estimate ({how}): worst relative defect {self.worst:.2e} "
            f"(interval {self.worst_interval}, {self.worst_state}) vs tolerance {self.tolerance:.1e}: {verdict}"
        )


@checked()
def estimate_error(
    result: PlanTrajectory,
    *,
    tolerance: float = 1e-3,
    model: Model | None = None,
    method: str = "auto",
    rtol: float = 1e-10,
    atol: float = 1e-10,
    t: Any = None,
    x: Any = None,
    u: Any = None,
    scale: str = "state",
) -> ErrorEstimate:
    """Re-integrate every interval of a plan and compare with the plan's next state.

    Parameters
    ----------
    result : SwingUpResult or PlanTrajectory
        The plan (its grid ``t``, states ``x``, held torques ``u``).
    tolerance : float
        Relative tolerance of the pass/fail verdict (dimensionless, > 0).
    model : Model or None
        Model to check against (default: the plan's own). It must have the
        plan's state layout; to check a rigid plan against an elastic model,
        lift the states first and pass them as ``x``.
    method : str
        ``"auto"`` or a key of :data:`pendulab.METHODS`.
    rtol, atol : float
        Tolerances of the re-integration (keep them well below ``tolerance``).
    t : array_like, shape (N + 1,), or None
        Grid override [s] (default ``result.t``).
    x : array_like, shape (N + 1, nx), or None
        State override (default ``result.x``), e.g. a rigid plan lifted to the elastic model.
    u : array_like, shape (N, 2), or None
        Torque override [N.m] (default ``result.u``).
    scale : {"state", "bob-speed"}
        Normalisation of the defects: each state's largest magnitude (the
        default), or for the spring rates of an elastic model the bobs'
        largest speed (module notes).

    Returns
    -------
    ErrorEstimate
        Relative defects per interval and state, the worst one and the verdict.

    Raises
    ------
    ValueError
        Bad shapes, non-finite values, a non-increasing grid, a state size
        that does not match ``model``, a non-positive tolerance or an unknown ``scale``.

    Examples
    --------
    >>> from pendulab.control import estimate_error, swing_up
    >>> from pendulab.control.swingup.tasks import load_task
    >>> problem = load_task("pendubot").problem
    >>> for N in (20, 40):  # one solve each, without the solver's own estimate
    ...     est = estimate_error(swing_up(problem, N=N, tolerance=None), tolerance=1e-2)
    ...     print(N, f"worst {est.worst:.0e} in {est.worst_state}:", "pass" if est.passed else "fail")
    20 worst 1e-01 in omega2: fail
    40 worst 4e-03 in omega2: pass
    """
    return estimate_error_arrays(
        result.problem.model if model is None else model,
        result.t if t is None else t,
        result.x if x is None else x,
        result.u if u is None else u,
        tolerance=tolerance,
        method=method,
        rtol=rtol,
        atol=atol,
        scale=scale,
    )


@checked()
def estimate_error_arrays(
    model: Model,
    t: Any,
    x: Any,
    u: Any,
    *,
    tolerance: float = 1e-3,
    method: str = "auto",
    rtol: float = 1e-10,
    atol: float = 1e-10,
    scale: str = "state",
) -> ErrorEstimate:
    """The error estimate of a plan given as arrays (see :func:`estimate_error`).

    Parameters
    ----------
    model : Model
        Model whose dynamics the plan must satisfy.
    t : array_like, shape (N + 1,)
        Grid times [s], strictly increasing (non-uniform allowed).
    x : array_like, shape (N + 1, nx)
        Plan states on the grid, in ``model.state_names`` order.
    u : array_like, shape (N, 2)
        Torques (tau1, tau2) held on each interval [N.m].
    tolerance : float
        Relative tolerance of the verdict (dimensionless, > 0).
    method : str
        ``"auto"`` (resolved once, at ``x[0]``) or a key of :data:`pendulab.METHODS`.
    rtol, atol : float
        Tolerances of the re-integration.
    scale : {"state", "bob-speed"}
        Normalisation of the defects (see :func:`estimate_error`).

    Returns
    -------
    ErrorEstimate
        Relative defects per interval and state, the worst one and the verdict.

    Raises
    ------
    ValueError
        Bad shapes, non-finite values, a non-increasing grid, a state size
        that does not match ``model``, a non-positive tolerance or an unknown ``scale``.

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.control import estimate_error_arrays
    >>> model = pl.rigid()
    >>> traj = pl.simulate(model, model.state(theta1=1.0), 2.0, dt=0.05, u=[0.5, 0.0])
    >>> estimate_error_arrays(model, traj.t, traj.x, traj.u[:-1], tolerance=1e-6).passed  # a true solution
    True
    >>> x = traj.x.copy()
    >>> x[10, 2] += 0.01  # a 0.01 rad/s kink in omega1 at t = 0.5 s
    >>> est = estimate_error_arrays(model, traj.t, x, traj.u[:-1], tolerance=1e-6)
    >>> est.passed, est.worst_interval, est.worst_state
    (False, 9, 'omega1')
    """
    if scale not in SCALES:
        raise ValueError(f"scale must be one of {list(SCALES)}, got {scale!r}")
    t, x, u = _check_plan(model, t, x, u)
    tolerance = float(tolerance)
    if not (np.isfinite(tolerance) and tolerance > 0.0):
        raise ValueError(f"tolerance must be a positive finite number, got {tolerance!r}")
    N = t.size - 1
    if method == "auto":
        # One choice per plan: the rule's eigenvalue test costs more than one interval's integration.
        method = choose_method(model, x[0], u[0], rtol, atol).method
    h = np.diff(t)
    absolute = np.empty((N, x.shape[1]))
    for k in range(N):
        try:
            seg = simulate(model, x[k], h[k], dt=h[k], method=method, rtol=rtol, atol=atol, u=u[k])
            absolute[k] = np.abs(seg.x[-1] - x[k + 1])
        except SimulationError:
            # An interval the integrator cannot cross is certainly not resolved by the plan.
            absolute[k] = np.inf
    norm = _scale(model, x, scale)
    defects = absolute / norm
    interval_worst = defects.max(axis=1)
    worst = float(interval_worst.max())
    return ErrorEstimate(
        defects=defects,
        interval_worst=interval_worst,
        worst=worst,
        tolerance=tolerance,
        passed=bool(worst <= tolerance),
        method=method,
        scale=norm,
        absolute=absolute,
        state_names=tuple(model.state_names),
        scale_kind=scale,
    )


def rescale(estimate: ErrorEstimate, model: Model, x: Any, scale: str) -> ErrorEstimate:
    """The same estimate under another normalisation (no re-integration: the absolute defects are kept).

    Parameters
    ----------
    estimate : ErrorEstimate
        An estimate of the plan with states ``x``.
    model : Model
        The model it was computed on.
    x : array_like, shape (N + 1, nx)
        The plan's states (they set the scale).
    scale : {"state", "bob-speed"}
        The normalisation wanted.

    Returns
    -------
    ErrorEstimate
        Defects, worst and verdict under ``scale`` (same tolerance and integrator).

    Raises
    ------
    ValueError
        Unknown ``scale`` or ``x`` that does not match the estimate.
    """
    if scale not in SCALES:
        raise ValueError(f"scale must be one of {list(SCALES)}, got {scale!r}")
    x = np.asarray(x, dtype=float)
    if x.shape != (estimate.absolute.shape[0] + 1, model.nx) or estimate.absolute.shape[1] != model.nx:
        raise ValueError(f"x must have shape {(estimate.absolute.shape[0] + 1, model.nx)} to match the estimate, got {x.shape}")
    norm = _scale(model, x, scale)
    defects = estimate.absolute / norm
    interval_worst = defects.max(axis=1)
    worst = float(interval_worst.max())
    return replace(
        estimate,
        defects=defects,
        interval_worst=interval_worst,
        worst=worst,
        passed=bool(worst <= estimate.tolerance),
        scale=norm,
        scale_kind=scale,
    )


def _scale(model: Model, x: np.ndarray, kind: str) -> np.ndarray:
    """Per-state normalisation of the defects (the one definition; module notes)."""
    norm = np.maximum(np.max(np.abs(x), axis=0), SCALE_FLOOR)
    if kind == "bob-speed" and model.kind == "elastic":
        # State order (DESIGN.md): theta1, theta2, r1, r2, omega1, omega2, v1, v2.
        norm[6:8] = np.maximum(norm[6:8], float(np.max(np.abs(x[:, 2:4] * x[:, 4:6]))))
    return norm


def _check_plan(model: Model, t: Any, x: Any, u: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    if not isinstance(model, Model):
        raise TypeError(f"model must be a pendulab Model, got {type(model).__name__}")
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    u = np.asarray(u, dtype=float)
    if t.ndim != 1 or t.size < 2:
        raise ValueError(f"t must be a 1-D grid of at least 2 times, got shape {t.shape}")
    N = t.size - 1
    if x.shape != (N + 1, model.nx):
        raise ValueError(f"x must have shape (len(t), nx) = ({N + 1}, {model.nx}) for this model, got {x.shape}")
    if u.shape != (N, 2):
        raise ValueError(f"u must have shape (N, 2) = ({N}, 2) (one held torque pair per interval), got {u.shape}")
    for name, arr in (("t", t), ("x", x), ("u", u)):
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"{name} must be finite, got NaN or inf")
    if np.any(np.diff(t) <= 0.0):
        raise ValueError("t must be strictly increasing")
    return t, x, u
