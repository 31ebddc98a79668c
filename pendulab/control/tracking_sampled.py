"""Tracking a reference trajectory with time-varying LQR, sampled.

:class:`TVLQRTracker` follows any reference ``(t, x_ref, u_ref)`` on its sample
grid with time-varying gains and then hands over to a final controller (LQR
balance). :func:`tvlqr_gains` computes the gains by the backward discrete
Riccati recursion on exact ZOH discretizations along the reference;
:func:`resample_reference` puts a reference from any grid (e.g. an optimized
swing-up's collocation knots) on the sample grid; :func:`tvlqr_tracker` does
all three; :func:`load_reference_csv` reads a reference from a CSV.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._checks import positive_float
from ..model.model import INPUT_NAMES, Model
from .lqr import discrete_tvlqr, weight_matrix, wrap_state_error
from .sampled import _actuated, as_feedback, energy_swingup, lqr_balance

__all__ = [
    "TVLQRTracker",
    "tvlqr_gains",
    "resample_reference",
    "tvlqr_tracker",
    "load_reference_csv",
    "swingup_reference",
]


@dataclass
class TVLQRTracker:
    """Track a reference with time-varying gains, then hand over to ``final``.

    ``u = u_ref(t) - K(t) (x - x_ref(t))`` (angles wrapped) for ``t`` within the
    reference, where the reference is evaluated at the last reference sample at
    or before ``t`` (reference grid = sample grid gives the exact discrete law).

    Attributes
    ----------
    model : Model
    t_ref : ndarray, shape (N,)
        Reference times [s], increasing.
    x_ref : ndarray, shape (N, nx)
    u_ref : ndarray, shape (N, m) or (N-1, m)
        Reference torques [N.m] for ``input_names``.
    K : ndarray, shape (N-1, m, nx) or (N, m, nx)
        Gains.
    sample_time : float
    input_names : tuple of str
    final : SampledController or None
        Used after ``t_ref[-1]`` (e.g. LQR balance); holds ``u_ref[-1]`` if None.
    u_max : float or None
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
        self.sample_time = positive_float("sample_time", self.sample_time)

    def reset(self) -> None:
        """Reset the final controller."""
        if self.final is not None:
            self.final.reset()

    def __call__(self, t: float, x: np.ndarray) -> np.ndarray:
        # Masters accumulate time in floating point: a sample a hair before a grid time belongs to it.
        k = int(np.searchsorted(self.t_ref, t + 1e-9 * self.sample_time, side="right")) - 1
        if k >= min(len(self.K), len(self.u_ref)) or k >= len(self.t_ref) - 1:
            if self.final is not None:
                u = np.asarray(self.final(t, x), dtype=float)
            else:
                u = self.u_ref[-1].copy()
        else:
            k = max(k, 0)
            u = self.u_ref[k] - self.K[k] @ wrap_state_error(np.asarray(x, dtype=float) - self.x_ref[k], self.model.state_names)
        return u if self.u_max is None else np.clip(u, -self.u_max, self.u_max)


def tvlqr_gains(
    model: Model,
    t_ref: np.ndarray,
    x_ref: np.ndarray,
    u_ref: np.ndarray,
    *,
    Q: Any = None,
    R: Any = None,
    Qf: Any = None,
    actuation: str | Sequence[str] = "full",
) -> np.ndarray:
    """Time-varying discrete LQR gains along a reference sampled on a uniform grid.

    Each interval is linearized at ``(x_ref[k], u_ref[k])`` and discretized
    exactly with a zero-order hold of the grid step, then the discrete Riccati
    recursion (:func:`pendulab.control.lqr.discrete_tvlqr`) runs backwards from ``Qf``.

    Parameters
    ----------
    model : Model
    t_ref : ndarray, shape (N,)
        Uniform grid [s] (the controller's sample times).
    x_ref : ndarray, shape (N, nx)
    u_ref : ndarray, shape (N-1, 2) or (N, 2)
        Full torques (tau1, tau2) [N.m].
    Q, R, Qf : array_like, optional
        Weights; defaults: Q = diag(10 on angles, 1 elsewhere), R = I (m x m),
        Qf = the cost-to-go of the discrete LQR balance that takes over at the
        end (plus 1e-6 I, which keeps the uncontrollable spring block positive definite).
    actuation : {"full", "pendubot", "acrobot"} or sequence of input names
        The torques the gains drive (m of them).

    Returns
    -------
    ndarray, shape (N-1, m, nx)
    """
    t_ref = np.asarray(t_ref, dtype=float)
    x_ref = model.check_state(x_ref, "x_ref")
    u_ref = model.check_input(u_ref, "u_ref")
    cols = [INPUT_NAMES.index(n) for n in _actuated(actuation)]
    h = np.diff(t_ref)
    if len(t_ref) < 2 or np.ptp(h) > 1e-9 * max(h.max(), 1e-300) + 1e-12 or h.min() <= 0:
        raise ValueError("t_ref must be a uniform increasing grid with at least 2 samples")
    n, m = model.nx, len(cols)
    q_default = np.diag(np.where([s.startswith("theta") for s in model.state_names], 10.0, 1.0))
    Qm = weight_matrix(q_default if Q is None else Q, n, "Q", definite=False)
    Rm = weight_matrix(R, m, "R", definite=True)
    if Qf is None:
        Qfm = lqr_balance(model, float(h[0]), design="discrete", actuation=actuation).P + 1e-6 * np.eye(n)
    else:
        Qfm = np.atleast_2d(np.asarray(Qf, dtype=float))
    M = len(t_ref) - 1
    u_lin = u_ref[np.minimum(np.arange(M), len(u_ref) - 1)]
    return discrete_tvlqr(model, x_ref[:M], u_lin, float(h[0]), Qm, Rm, Qfm, actuation=_actuated(actuation))


def swingup_reference(
    model: Model, sample_time: float, t_final: float, *, x0: np.ndarray | None = None, u_max: float = 20.0
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A swing-up reference from the native energy-pumping loop: ``(t, x_ref, u_ref)``.

    Shapes (N,), (N, nx), (N, 2). Stands in for an optimized swing-up when none
    is at hand; any reference on the sample grid can be tracked the same way.
    """
    from ..integrate import simulate

    ctrl = energy_swingup(model, sample_time, u_max=u_max)
    x0 = model.state(theta1=0.1) if x0 is None else x0
    traj = simulate(model, x0, t_final, dt=sample_time, u=as_feedback(ctrl, model), rtol=1e-10, atol=1e-10)
    return traj.t, traj.x, traj.u


def resample_reference(
    t: np.ndarray, x: np.ndarray, u: np.ndarray, sample_time: float, model: Model | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Put a reference ``(t, x, u)`` on the uniform sample grid ``0, h, 2h, ... <= t[-1]``.

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
    """
    h = positive_float("sample_time", sample_time)
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
    """TVLQR tracking of any swing-up reference (e.g. an optimized one), handing over to discrete LQR balance.

    The reference ``(t, x, u)`` (u: full torques (tau1, tau2), any grid) is
    resampled to the sample grid (:func:`resample_reference`); the gains come from
    :func:`tvlqr_gains` for the torques named by ``actuation`` (a passive
    joint gets none); ``Q``, ``R`` as there.
    """
    ts, xs, us = resample_reference(t, x, u, sample_time, model)
    xs = model.check_state(xs, "x_ref")
    names = _actuated(actuation)
    cols = [INPUT_NAMES.index(n) for n in names]
    K = tvlqr_gains(model, ts, xs, us, actuation=names, Q=Q, R=R)
    final = lqr_balance(model, sample_time, design="discrete", u_max=u_max, actuation=names, R=R)
    return TVLQRTracker(model, ts, xs, us[:, cols], K, sample_time, names, final=final, u_max=u_max)


def load_reference_csv(path: str, model: Model) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Read a reference ``(t, x, u)`` from a CSV with a header naming ``t``, the model's states and ``tau1, tau2``.

    Trajectory CSVs (``Trajectory.to_csv``, ``pendulab cosim``, ``pendulab simulate``) and the
    optimal trajectory of ``pendulab swingup`` (``optimal.csv``) have these columns.
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
