"""The outcome of a swing-up solve: the plan, how it was found, and how good it is."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .errors import ErrorEstimate
from .guess import Guess
from .problem import SwingUpProblem

__all__ = ["SwingUpResult"]


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
        Solve time incl. guesses, homotopy stages, refinements and error estimates [s] (NLP building excluded).
    build_time : float
        Time spent building the NLP(s) this call, summed over meshes and the
        rigid guess (exactly 0 when all were cached) [s].
    t : ndarray, shape (N + 1,)
        Grid times [s]: the actual (possibly non-uniform, refined) grid.
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
    error : ErrorEstimate or None
        A posteriori error estimate of the final plan (None when
        :func:`swing_up` ran with ``tolerance=None``).
    mesh_history : tuple of dict
        One entry per mesh solved (the first, then each refinement): ``N``,
        ``worst`` (relative defect, nan without an estimate), ``passed``,
        ``status`` (IPOPT), ``iterations``, ``solve_time`` [s] (IPOPT incl.
        guesses), ``estimate_time`` [s] and ``build_time`` [s].
    solve_time : float
        Solve time of the final mesh alone [s] (the last entry of
        ``mesh_history``; build and error estimate excluded).

    Notes
    -----
    ``wall_time`` covers the whole call without NLP building: every mesh's
    solve and every error estimate.

    Examples
    --------
    >>> import numpy as np
    >>> from pendulab.control import swing_up
    >>> from pendulab.control.swingup.tasks import load_task
    >>> res = swing_up(load_task("acrobot").problem, N=40)  # a SwingUpResult
    >>> res.t.shape, res.x.shape, res.u.shape  # grid, states on it, torques held on each interval
    ((51,), (51, 4), (50, 2))
    >>> np.round(res.x_at(1.5), 2), round(float(res.u_at(1.5)[1]), 2)  # interpolated state, held elbow torque
    (array([2.86, 1.14, 4.67, 7.66]), 0.35)
    >>> bool(np.allclose(res.x_at(res.horizon), res.problem.target))  # upright at rest at T = 3 s
    True
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
    error: ErrorEstimate | None = None
    mesh_history: tuple[dict[str, Any], ...] = ()
    solve_time: float = float("nan")

    @property
    def horizon(self) -> float:
        """Final time T [s]."""
        return float(self.t[-1])

    @property
    def mesh(self) -> np.ndarray:
        """Interval lengths as fractions of the horizon, shape (N,) (uniform: all 1 / N)."""
        return np.diff(self.t) / self.horizon

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
