"""Time-varying LQR tracking: the one TVLQR tracker (:class:`TVLQRTracker`) and its design.

The tracker is sampled-data (zero-order hold at the sample time), as in
``pendulab.simulate`` with a callable input and in a co-simulation master, so
it is designed in discrete time: each sample interval is linearized with the
exact CasADi Jacobians and discretized exactly for the hold, and the Riccati
recursion (:func:`pendulab.control.lqr.discrete_tvlqr`) runs backward from
the cost-to-go of the discrete LQR that balances at the reference's end
(:func:`pendulab.control.lqr.lqr_balance`, same weights), which then takes over.

* :func:`tvlqr_tracker` tracks any reference ``(t, x, u)`` (resampled to the
  sample grid by :func:`resample_reference`, linearized at its samples);
* :func:`tvlqr` tracks an optimized swing-up (linearized at the middle of
  each sample interval of the collocation polynomial);
* :func:`default_weights` are the weights both use when none are given.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from .._inputs import checked
from ..model.model import INPUT_NAMES, Model
from .feedback import LinearStateFeedback, actuated_inputs, as_feedback, energy_swingup, upright_state
from .lqr import UncontrollableError, discrete_tvlqr, lqr_balance, weight_matrix, wrap_state_error

if TYPE_CHECKING:  # typing only: the swing-up package builds on this module
    from .swingup.solve import SwingUpResult

__all__ = [
    "TVLQRTracker",
    "default_weights",
    "tvlqr",
    "tvlqr_tracker",
    "resample_reference",
    "swingup_reference",
    "load_reference_csv",
]


@checked()
@dataclass
class TVLQRTracker:
    """Track a reference with time-varying gains, then hand over to ``final``: the one TVLQR tracker.

    ``u = u_ref[k] - K[k] (x - x_ref[k])`` (angles wrapped) on sample ``k``, the
    last reference sample at or before ``t`` (a time a hair, 1e-6 of a sample,
    before a grid time belongs to it: masters accumulate time in floating
    point). After the reference, ``final`` (e.g. LQR balance) takes over.
    Build it with :func:`pendulab.control.tracking.tvlqr_tracker` (any
    reference) or :func:`pendulab.control.tracking.tvlqr` (an optimized swing-up).

    Attributes
    ----------
    model : Model
        Plant the gains were designed for.
    t_ref : ndarray, shape (N,)
        Reference times [s], increasing.
    x_ref : ndarray, shape (N, nx)
        Reference states.
    u_ref : ndarray, shape (N-1, m) or (N, m)
        Reference torques [N.m] for ``input_names``.
    K : ndarray, shape (N-1, m, nx) or (N, m, nx)
        Gains [N.m per state unit].
    sample_time : float
        Sample period [s].
    input_names : tuple of str
        The torques driven (m of them); a passive torque in the list gets zero rows.
    final : SampledController or None
        Used after ``t_ref[-1]``; holds ``u_ref[-1]`` if None.
    u_max : float or None
        Symmetric torque limit [N.m].

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.control import swingup_reference, tvlqr_tracker
    >>> model = pl.rigid()
    >>> tracker = tvlqr_tracker(model, *swingup_reference(model, 0.01, 4.0), 0.01)  # a TVLQRTracker
    >>> tracker.horizon, tracker.K.shape, type(tracker.final).__name__  # 400 gains, then LQR balance
    (4.0, (400, 2, 4), 'LinearStateFeedback')
    >>> k = 100  # at a reference sample, on the reference, the torque is the reference torque
    >>> bool(np.allclose(tracker(tracker.t_ref[k], tracker.x_ref[k]), tracker.u_ref[k]))
    True
    """

    model: Model
    t_ref: np.ndarray
    x_ref: np.ndarray
    u_ref: np.ndarray
    K: np.ndarray
    sample_time: float
    input_names: tuple[str, ...] = INPUT_NAMES
    final: Any = None
    u_max: float | None = None

    def __post_init__(self) -> None:
        self.t_ref = np.asarray(self.t_ref, dtype=float)
        self.x_ref = np.asarray(self.x_ref, dtype=float)
        self.u_ref = np.asarray(self.u_ref, dtype=float).reshape(len(self.u_ref), -1)
        self.K = np.asarray(self.K, dtype=float)
        n, m = len(self.t_ref), len(self.input_names)
        if n < 2 or np.any(np.diff(self.t_ref) <= 0):
            raise ValueError(f"t_ref must be increasing with at least 2 samples, got {self.t_ref[:5]!r}...")
        if self.x_ref.shape != (n, self.model.nx):
            raise ValueError(f"x_ref must have shape ({n}, {self.model.nx}), got {self.x_ref.shape}")
        if self.u_ref.shape[0] not in (n - 1, n) or self.u_ref.shape[1] != m:
            raise ValueError(f"u_ref must have shape ({n}, {m}) or ({n - 1}, {m}), got {self.u_ref.shape}")
        if self.K.ndim != 3 or self.K.shape[0] not in (n - 1, n) or self.K.shape[1:] != (m, self.model.nx):
            raise ValueError(f"K must have shape ({n - 1}, {m}, {self.model.nx}), got {self.K.shape}")

    @property
    def horizon(self) -> float:
        """End of the reference [s]; ``final`` acts from then on."""
        return float(self.t_ref[-1])

    def reset(self) -> None:
        """Reset the final controller."""
        if self.final is not None:
            self.final.reset()

    def __call__(self, t: float, x: np.ndarray) -> np.ndarray:
        """Torques [N.m] for ``input_names`` at time ``t`` [s] and state ``x``, shape (m,)."""
        k = int(np.searchsorted(self.t_ref, t + 1e-6 * self.sample_time, side="right")) - 1
        if k >= min(len(self.K), len(self.u_ref), len(self.t_ref) - 1):
            u = np.asarray(self.final(t, x), dtype=float) if self.final is not None else self.u_ref[-1].copy()
        else:
            k = max(k, 0)
            u = self.u_ref[k] - self.K[k] @ wrap_state_error(np.asarray(x, dtype=float) - self.x_ref[k], self.model.state_names)
        return u if self.u_max is None else np.clip(u, -self.u_max, self.u_max)


@checked(torque_limit="u_max")
def default_weights(model: Model, torque_limit: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """State weight Q and per-torque input weight r used when none are given.

    Angles 10 /rad^2, link rates 1 /(rad/s)^2; spring lengths 100 /m^2 and
    rates 0.1 /(m/s)^2 (springs are stiff and need little control); r makes a
    torque at the limit cost as much as a 1/sqrt(10) rad angle error (r = 1
    without a limit).

    Parameters
    ----------
    model : Model
        Rigid or elastic pendulum.
    torque_limit : float, optional
        Torque limit [N.m].

    Returns
    -------
    Q : ndarray, shape (nx, nx)
        Diagonal state weight.
    r : ndarray, shape ()
        Weight of each driven torque [1/(N.m)^2].

    Examples
    --------
    >>> import pendulab as pl
    >>> from pendulab.control import default_weights
    >>> model = pl.elastic()
    >>> Q, r = default_weights(model, torque_limit=6.0)
    >>> dict(zip(model.state_names, np.diag(Q).tolist()))
    {'theta1': 10.0, 'theta2': 10.0, 'r1': 100.0, 'r2': 100.0, 'omega1': 1.0, 'omega2': 1.0, 'v1': 0.1, 'v2': 0.1}
    >>> round(float(r), 4)  # 1 / 6^2: a torque at the limit costs as much as a 0.32 rad angle error
    0.0278
    """
    q = {"theta": 10.0, "omega": 1.0, "r": 100.0, "v": 0.1}
    Q = np.diag([q[n.rstrip("0123456789")] for n in model.state_names])
    r = 1.0 if torque_limit is None else 1.0 / float(torque_limit) ** 2
    return Q, np.array(r)


def _weights(model: Model, m: int, Q: Any, R: Any, torque_limit: float | None) -> tuple[np.ndarray, np.ndarray]:
    Qd, rd = default_weights(model, torque_limit)
    Qm = weight_matrix(Qd if Q is None else Q, model.nx, "Q", definite=False)
    if R is None:
        R = rd
    Rm = np.atleast_2d(np.asarray(R, dtype=float)) * (np.eye(m) if np.ndim(R) == 0 else 1.0)
    return Qm, weight_matrix(Rm, m, "R", definite=True)


def _design(
    model: Model,
    t_s: np.ndarray,
    x_s: np.ndarray,
    u_s: np.ndarray,
    x_lin: np.ndarray,
    goal: np.ndarray,
    sample_time: float,
    names: tuple[str, ...],
    out_names: tuple[str, ...],
    Q: Any,
    R: Any,
    u_max: float | None,
) -> TVLQRTracker:
    """Gains along a reference on the sample grid, and the tracker that applies them."""
    cols = [INPUT_NAMES.index(n) for n in names]
    Qm, Rm = _weights(model, len(cols), Q, R, u_max)
    try:
        top = lqr_balance(model, names, Qm, Rm, sample_time, at=goal)
    except UncontrollableError as exc:
        raise ValueError(f"the reference's end is not stabilisable with the torques {list(names)}: {exc}") from exc
    M = len(t_s) - 1
    K = discrete_tvlqr(model, x_lin, u_s[:M], sample_time, Qm, Rm, top.P, actuation=names)
    # Scatter onto the controller's outputs: a passive torque in out_names gets zero gains and zero reference.
    rows = [out_names.index(n) for n in names]
    K_out = np.zeros((M, len(out_names), model.nx))
    K_out[:, rows] = K
    K_top = np.zeros((len(out_names), model.nx))
    K_top[rows] = top.K
    u_ref = u_s[:M][:, [INPUT_NAMES.index(n) for n in out_names]]
    u_eq = top.u_eq[[INPUT_NAMES.index(n) for n in out_names]]
    final = LinearStateFeedback(model, K_top, goal, u_eq, sample_time, out_names, u_max, top.P, "discrete")
    return TVLQRTracker(model, t_s, x_s, u_ref, K_out, sample_time, out_names, final=final, u_max=u_max)


@checked()
def tvlqr(
    result: SwingUpResult,
    dt: float = 0.01,
    Q: np.ndarray | None = None,
    R: np.ndarray | float | None = None,
) -> TVLQRTracker:
    """Time-varying LQR along an optimized swing-up, handing over to balancing LQR at the goal.

    The tracker drives both torques (a passive joint gets zero), so it is also
    a plain feedback ``u(t, x) -> (tau1, tau2)`` for :func:`pendulab.simulate`.

    Parameters
    ----------
    result : SwingUpResult
        A successful swing-up (its goal must be an equilibrium with zero torque).
    dt : float
        Controller sample time [s]; the NLP interval should be a multiple of it.
    Q : ndarray, shape (nx, nx), optional
        State weight (default :func:`default_weights`).
    R : float or ndarray, shape (m, m), optional
        Weight on the driven torques (default :func:`default_weights` at the torque limit).

    Returns
    -------
    TVLQRTracker
        Saturated at the problem's torque limit.

    Raises
    ------
    ValueError
        The result failed, ``dt`` is not positive, or the goal is not
        stabilisable with the driven torques.

    Examples
    --------
    >>> import pendulab as pl
    >>> from pendulab.control import swing_up, tvlqr
    >>> from pendulab.control.swingup.check import height_success
    >>> from pendulab.control.swingup.tasks import load_task
    >>> task = load_task("pendubot")
    >>> ctrl = tvlqr(swing_up(task.problem, N=task.N), dt=task.dt)  # TVLQR along the plan, then LQR balance
    >>> traj = pl.simulate(task.model, task.problem.start, task.t_final, dt=task.dt, u=ctrl)
    >>> check = height_success(traj, task.rest_lengths)
    >>> check.success, round(check.t_up, 2)  # end effector above 90 % of L1 + L2 from t_up on
    (True, 1.61)
    """
    if not result.success:
        raise ValueError(f"result must be a successful swing-up to track, got status {result.status!r}")
    if not (isinstance(dt, (int, float)) and math.isfinite(dt) and dt > 0):
        raise ValueError(f"dt must be a positive sample time [s], got {dt!r}")
    pb = result.problem
    model = pb.model
    M = max(1, int(round(result.horizon / dt)))
    t_s = np.arange(M + 1) * dt
    x_s = result.x_at(t_s)
    x_s[-1] = pb.target
    # The torque of a sample is the one held at its middle (robust to grid round-off); the ZOH
    # discretization of an interval is linearized at its middle too.
    u_s = result.u_at(t_s + 0.5 * dt)
    x_lin = result.x_at(t_s[:M] + 0.5 * dt)
    names = actuated_inputs(pb.actuation)
    return _design(model, t_s, x_s, u_s, x_lin, pb.target, float(dt), names, INPUT_NAMES, Q, R, pb.torque_limit)


@checked()
def tvlqr_tracker(
    model: Model,
    t: np.ndarray,
    x: np.ndarray,
    u: np.ndarray,
    sample_time: float,
    *,
    u_max: float | None = 20.0,
    actuation: str | Sequence[str] = "full",
    Q: Any = None,
    R: Any = None,
) -> TVLQRTracker:
    """TVLQR tracking of any reference (e.g. a swing-up), handing over to discrete LQR balance upright.

    Parameters
    ----------
    model : Model
        Design model.
    t : ndarray, shape (N,)
        Reference times [s], increasing from 0 (any grid).
    x : ndarray, shape (N, nx)
        Reference states.
    u : ndarray, shape (N, 2) or (N-1, 2)
        Full reference torques (tau1, tau2) [N.m], held from ``t[k]``.
    sample_time : float
        Controller sample time [s]; the reference is resampled to it (:func:`resample_reference`).
    u_max : float or None
        Torque limit [N.m] (also scales the default input weight).
    actuation : {"full", "pendubot", "acrobot"} or sequence of input names
        The torques driven (the tracker outputs only those).
    Q, R : array_like, optional
        Weights (default :func:`default_weights`).

    Returns
    -------
    TVLQRTracker

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.control import as_feedback, swingup_reference, tvlqr_tracker
    >>> model = pl.rigid()
    >>> t, x, u = swingup_reference(model, 0.01, 4.0)  # any (t, x, u) reference
    >>> tracker = tvlqr_tracker(model, t, x, u, 0.01, u_max=20.0)
    >>> x0 = x[0] + [0.1, -0.1, 0.0, 0.0]  # a perturbed start
    >>> traj = pl.simulate(model, x0, 6.0, dt=0.01, u=as_feedback(tracker, model))
    >>> np.round(np.cos(traj.x[-1, :2]), 3)  # tracked, then balanced upright
    array([-1., -1.])
    """
    h = float(sample_time)
    ts, xs, us = resample_reference(t, x, u, h, model)
    xs = model.check_state(xs, "x_ref")
    names = actuated_inputs(actuation)
    return _design(model, ts, xs, us, xs[:-1], upright_state(model), h, names, names, Q, R, u_max)


@checked()
def swingup_reference(
    model: Model, sample_time: float, t_final: float, *, x0: np.ndarray | None = None, u_max: float = 20.0
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A swing-up reference from the native energy-pumping loop: ``(t, x_ref, u_ref)``.

    Simulates :func:`~pendulab.control.feedback.energy_swingup` on ``model``
    (tolerances 1e-10) with the output grid equal to the sample grid. Stands in
    for an optimized swing-up when none is at hand; any reference on the sample
    grid can be tracked the same way.

    Parameters
    ----------
    model : Model
        Rigid or elastic pendulum.
    sample_time : float
        Controller sample time and output step [s].
    t_final : float
        Horizon [s].
    x0 : ndarray, shape (nx,), optional
        Start state; default hanging with theta1 = 0.1 rad.
    u_max : float
        Torque limit [N.m] of the swing-up.

    Returns
    -------
    t : ndarray, shape (N,)
        Sample times [s].
    x_ref : ndarray, shape (N, nx)
        Closed-loop states.
    u_ref : ndarray, shape (N, 2)
        Torques (tau1, tau2) [N.m] held from each sample.

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.control import swingup_reference
    >>> t, x, u = swingup_reference(pl.rigid(), 0.01, 5.0, u_max=20.0)  # energy pumping + LQR, 10 ms samples
    >>> t.shape, x.shape, u.shape
    ((501,), (501, 4), (501, 2))
    >>> np.round(np.cos(x[-1, :2]), 3), float(np.abs(u).max())  # ends upright; torques within the limit
    (array([-1., -1.]), 20.0)
    """
    from ..integrate import simulate

    ctrl = energy_swingup(model, sample_time, u_max=u_max)
    x0 = model.state(theta1=0.1) if x0 is None else x0
    traj = simulate(model, x0, t_final, dt=sample_time, u=as_feedback(ctrl, model), rtol=1e-10, atol=1e-10)
    return traj.t, traj.x, traj.u


@checked()
def resample_reference(
    t: np.ndarray, x: np.ndarray, u: np.ndarray, sample_time: float, model: Model | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Put a reference ``(t, x, u)`` on the uniform sample grid ``k h <= t[-1]`` (k = 0, 1, 2, and so on).

    Torques are zero-order held (the value of the last reference knot at or
    before each sample), so a reference whose knots are a multiple of ``h``
    apart keeps its torques exactly. States between knots are interpolated by
    cubic Hermite with the slopes ``f(x, u)`` of ``model`` (a coarse optimized
    trajectory stays close to a solution: linear interpolation would cut
    corners and the tracker would fight them), or linearly without a model.

    Parameters
    ----------
    t : ndarray, shape (N,)
        Increasing times [s], starting at 0.
    x : ndarray, shape (N, nx)
    u : ndarray, shape (N, 2) or (N-1, 2)
        Torques held from ``t[k]`` [N.m].
    sample_time : float
        [s].
    model : Model, optional
        Gives the Hermite slopes.

    Returns
    -------
    t_s, x_s, u_s : ndarrays, shapes (M,), (M, nx), (M, 2)
        Sample times [s], states and held torques [N.m].

    Raises
    ------
    ValueError
        Non-positive ``sample_time``; times not increasing from 0 or fewer
        than 2; row counts of ``x`` or ``u`` not matching ``t``; or a reference
        shorter than one sample.

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.control import resample_reference
    >>> model = pl.rigid()
    >>> coarse = pl.simulate(model, model.state(theta1=0.3), 1.0, dt=0.1)  # knots every 0.1 s
    >>> fine = pl.simulate(model, model.state(theta1=0.3), 1.0, dt=0.01)
    >>> for slopes in (None, model):  # linear interpolation, or cubic Hermite with the slopes f(x, u)
    ...     t, x, u = resample_reference(coarse.t, coarse.x, coarse.u, 0.01, slopes)
    ...     print(x.shape, f"angle error {np.abs(x - fine.x)[:, :2].max():.0e} rad")
    (101, 4) angle error 8e-03 rad
    (101, 4) angle error 7e-05 rad
    """
    h = float(sample_time)
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    u = np.asarray(u, dtype=float)
    if t.ndim != 1 or len(t) < 2 or np.any(np.diff(t) <= 0) or abs(t[0]) > 1e-12:
        raise ValueError(f"reference times must increase from 0 with at least 2 samples, got {t[:3]!r}...")
    if x.shape[0] != len(t) or u.shape[0] not in (len(t), len(t) - 1):
        raise ValueError(f"reference x must have {len(t)} rows and u {len(t)} or {len(t) - 1}, got {x.shape}, {u.shape}")
    n = int(np.floor(t[-1] / h + 1e-9))
    if n < 1:
        raise ValueError(f"reference ({t[-1]:g} s) is shorter than one sample ({h:g} s)")
    ts = np.arange(n + 1) * h
    k = np.clip(np.searchsorted(t, ts + 1e-9 * h, side="right") - 1, 0, len(u) - 1)
    if model is None:
        xs = np.column_stack([np.interp(ts, t, x[:, j]) for j in range(x.shape[1])])
        return ts, xs, u[k]
    j = np.minimum(k, len(t) - 2)  # interval of each sample
    dt = t[j + 1] - t[j]
    s = ((ts - t[j]) / dt)[:, None]
    f0, f1 = model.rhs(x[j], u[j]), model.rhs(x[j + 1], u[j])
    h00, h10, h01, h11 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s, -2 * s**3 + 3 * s**2, s**3 - s**2
    xs = h00 * x[j] + h10 * dt[:, None] * f0 + h01 * x[j + 1] + h11 * dt[:, None] * f1
    return ts, xs, u[k]


def load_reference_csv(path: str, model: Model) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Read a reference ``(t, x, u)`` from a CSV with a header naming ``t``, the model's states and ``tau1, tau2``.

    Trajectory CSVs (``Trajectory.to_csv``, ``pendulab cosim``, ``pendulab simulate``) and the
    optimal trajectory of ``pendulab swingup`` (``optimal.csv``) have these columns.

    Parameters
    ----------
    path : str
        CSV file; other columns are ignored.
    model : Model
        Names the state columns to read (``model.state_names``).

    Returns
    -------
    t : ndarray, shape (N,)
        Times [s].
    x : ndarray, shape (N, nx)
        States in ``model.state_names`` order.
    u : ndarray, shape (N, 2)
        Torques (tau1, tau2) [N.m].

    Raises
    ------
    ValueError
        A required column is missing or there are fewer than 2 data rows.

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.control import as_feedback, energy_swingup, load_reference_csv, tvlqr_tracker
    >>> model = pl.rigid()
    >>> swing = pl.simulate(model, model.state(theta1=0.1), 5.0, dt=0.01, u=as_feedback(energy_swingup(model, 0.01), model))
    >>> path = swing.to_csv("swingup.csv")  # columns t, theta1, ..., tau1, tau2, ...
    >>> t, x, u = load_reference_csv("swingup.csv", model)
    >>> t.shape, x.shape, u.shape
    ((501,), (501, 4), (501, 2))
    >>> tracker = tvlqr_tracker(model, t, x, u, 0.01)  # track it with time-varying LQR
    >>> tracker.horizon
    5.0
    """
    import csv

    with open(path, newline="") as fh:
        reader = csv.reader(fh)
        header = [h.strip() for h in next(reader)]
        rows = np.array([[float(v) for v in row] for row in reader if row])
    need = ("t",) + model.state_names + INPUT_NAMES
    missing = [n for n in need if n not in header]
    if missing or rows.ndim != 2 or len(rows) < 2:
        raise ValueError(
            f"reference {path!r} must be a CSV with a header containing {list(need)} and at least 2 rows; missing {missing}"
        )
    col = {n: header.index(n) for n in need}
    return (
        rows[:, col["t"]],
        rows[:, [col[n] for n in model.state_names]],
        rows[:, [col[n] for n in INPUT_NAMES]],
    )
