"""Tracking NMPC: one receding-horizon controller for swing-up and balance (a :class:`SampledController`).

Each sample solves the multiple-shooting problem of :mod:`.ocp` from the measured
state: track the reference (an offline-optimized swing-up, resampled to the
sample grid) over ``horizon`` intervals, with the discrete LQR cost-to-go about
the goal as terminal cost. After the reference ends the reference is the goal
itself, so the same problem becomes regulation about upright: one controller
for swing-up and balance. A from-scratch NMPC over a 0.4 s window cannot see a
swing-up of under-actuated pendulums through (the energy has to be pumped over
seconds); the plan supplies that foresight, the NMPC the feedback, torque
limits and soft state limits the linear TVLQR tracker does not have.

Design choices (measured in ``benchmarks/results/nmpc.md``):

* the warm start shifts the previous solution (states, torques, multipliers) by
  one stage; the plant angles are wrapped to the branch of the reference;
* ``solver="sqp"`` (default): CasADi ``sqpmethod`` with the structure-exploiting
  QP solver ``hpipm`` and a Gauss-Newton Hessian, one SQP iteration per sample
  (real-time iteration); ``"ipopt"`` solves to convergence; ``"fatrop"`` is the
  structure-exploiting interior-point alternative;
* a failed solve never raises: the controller applies the previous plan's next
  torque (or the LQR fallback), counts the failure and keeps going;
* an elastic plant is predicted with the cheapest adequate model (``planning="auto"``,
  the default): the planning rule's levels rigid, rigid + quasi-static springs (4 states,
  per-stage quasi-static link lengths) or elastic (8 states, RK4 substeps for the spring
  modes), chosen from the rule's predicted error against ``prediction_tolerance``
  (:mod:`.prediction`). A rigid prediction gets the plant state on the slow manifold
  (angles, and rates that keep the angular momenta), not the plain projection whose
  rates carry the spring oscillation (measured: the feedback then excites the undamped
  springs and the QP fails; docs/nmpc.md).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..._inputs import checked
from ...model.counterpart import rigid_state
from ...model.model import Model
from ..lqr import wrap_state_error
from .ocp import SOLVERS, ShootingOCP, reference_window
from .prediction import PLANNING, STATE_MAPS, PredictionChoice, SlowStateMap

__all__ = ["NMPCOptions", "NMPCController", "MAX_HORIZON"]

#: Largest prediction horizon (shooting intervals): 10 s at 50 Hz; the NLP grows linearly with it.
MAX_HORIZON = 500

# Return statuses, besides success, whose iterate is used: a real-time iteration stops after its iteration
# cap by design; an interior-point iterate cut short is not feasible and is not used.
_USABLE = {"sqp": {"Maximum_Iterations_Exceeded"}, "ipopt": {"Solved_To_Acceptable_Level"}, "fatrop": set()}


@checked(
    horizon="horizon_intervals",
    q_angle="weight",
    q_rate="weight",
    r="weight",
    slack_weight="weight",
    torque_rate="weight",
    prediction_tolerance="tolerance",
)
@dataclass(frozen=True)
class NMPCOptions:
    """Settings of the NMPC problem and its solver.

    Attributes
    ----------
    horizon : int
        Shooting intervals N (prediction ``N * sample_time`` seconds).
    sample_time : float
        Controller sample time and interval length [s].
    substeps : int or None
        RK4 steps per interval; default 2 for a rigid planning model, and for an
        elastic one enough that ``h * omega_fast / substeps <= 1`` (RK4 is stable up to 2.8).
    planning : {"auto", "model", "elastic", "rigid", "quasi-static"}
        Prediction model of an elastic plant (a rigid plant is always predicted with itself):
        ``auto`` (default) the cheapest level of the planning rule predicted within
        ``prediction_tolerance``; ``model`` or ``elastic`` the elastic model itself; ``rigid`` the
        rigid counterpart; ``quasi-static`` the rigid counterpart with per-stage quasi-static
        link lengths (:mod:`pendulab.control.nmpc.prediction`).
    prediction_tolerance : float
        Relative prediction error ``auto`` accepts (dimensionless, in (0, 1)); the feedback
        corrects it every sample (default 0.2, measured: docs/nmpc.md).
    state_map : {"average", "momentum", "project"}
        Rigid state of an elastic measurement for a rigid prediction (:mod:`.prediction`):
        ``average`` (default) the momentum map averaged over the spring periods (states in the
        window predicted with the elastic model), ``momentum`` the instantaneous map (angles, and
        rates that keep the angular momenta), ``project`` the plain projection (angles and rates as
        measured; kept to reproduce its measured failure).
    solver : {"sqp", "ipopt", "fatrop"}
        See :mod:`pendulab.control.nmpc.controller`.
    max_iter : int or None
        Iterations per sample; default 1 for ``sqp`` (real-time iteration), 50 otherwise.
    q_angle : float
        Stage weight on angle errors [1/rad^2].
    q_rate : float or None
        Stage weight on rate errors [s^2/rad^2]; default 1, and 0.1 when a rigid model predicts an
        elastic plant (its rates come from the state map: a low rate gain keeps what is left of the
        spring ringing out of the torque; measured in docs/nmpc.md).
    r : float or None
        Weight of each driven torque [1/(N.m)^2]; default ``1 / u_max^2``.
    velocity_limit : float or None
        Soft bound on both joint rates, abs(omega1) and abs(omega2 - omega1) [rad/s] (slack-penalized).
    slack_weight : float
        Weight on the slack of the soft bounds.
    slack_tol : float
        A solution whose slack exceeds this [rad/s] counts as infeasible (the hard bound would be violated).
    max_solve_time : float or None
        Wall-time cap of one ``ipopt`` solve [s] (a solve cut short is a counted failure with the
        fallback torque); ``sqp`` is bounded by its iteration cap. None: no cap.
    torque_rate : float or None
        Weight of the torque change per sample ``|u_k - u_(k-1)|^2`` [1/(N.m)^2] (the previous
        torques become prediction states). None: no penalty.

    Examples
    --------
    >>> from pendulab.control import NMPCOptions
    >>> opts = NMPCOptions(horizon=30, sample_time=0.01)
    >>> opts.horizon * opts.sample_time, opts.solver, opts.iterations_cap  # 0.3 s ahead, one SQP iteration per sample
    (0.3, 'sqp', 1)
    >>> NMPCOptions(solver="ipopt").iterations_cap
    50
    >>> NMPCOptions(horizon=0)
    Traceback (most recent call last):
        ...
    pendulab._inputs.InputError: horizon = 0: out of range; expected an integer in [1, 500]
    """

    horizon: int = 20
    sample_time: float = 0.02
    substeps: int | None = None
    planning: str = "auto"
    prediction_tolerance: float = 0.2
    state_map: str = "average"
    solver: str = "sqp"
    max_iter: int | None = None
    q_angle: float = 10.0
    q_rate: float | None = None
    r: float | None = None
    velocity_limit: float | None = None
    slack_weight: float = 1e3
    slack_tol: float = 1e-3
    max_solve_time: float | None = None
    torque_rate: float | None = None

    def __post_init__(self) -> None:
        # The numeric fields were checked against their declarations where they entered (@checked above);
        # the names are checked here, where their choices live.
        if self.horizon is None:
            raise ValueError("horizon must be an integer >= 1 (shooting intervals), got None")
        if self.planning not in PLANNING:
            raise ValueError(f"planning must be one of {list(PLANNING)}, got {self.planning!r}")
        if self.state_map not in STATE_MAPS:
            raise ValueError(f"state_map must be one of {list(STATE_MAPS)}, got {self.state_map!r}")
        if self.solver not in SOLVERS:
            raise ValueError(f"solver must be one of {list(SOLVERS)}, got {self.solver!r}")

    @property
    def iterations_cap(self) -> int:
        """Iteration cap actually used (``max_iter`` or the solver's default)."""
        return self.max_iter if self.max_iter is not None else (1 if self.solver == "sqp" else 50)


@checked()
@dataclass
class NMPCController:
    """Receding-horizon tracking of a reference, then regulation about its end (build with :func:`nmpc_controller`).

    Attributes
    ----------
    model : Model
        Plant model (its state is what ``__call__`` receives).
    plan_model : Model
        Prediction model (``model``, or the rigid counterpart of an elastic one: see ``prediction``).
    options : NMPCOptions
        Problem and solver settings.
    input_names : tuple of str
        Driven torques, in output order.
    u_max : float
        Hard torque bound [N.m].
    x_ref : ndarray, shape (K, nx_plan)
        Reference states on the sample grid (planning model).
    u_ref : ndarray, shape (K, m)
        Reference torques on the sample grid [N.m].
    goal : ndarray, shape (nx_plan,)
        Held after the reference (upright at rest by default).
    ocp : ShootingOCP
        The built NLP.
    K_lqr : ndarray, shape (m, nx_plan)
        Discrete LQR gain about ``goal`` (fallback before any plan exists).
    solve_times : list of float
        Wall time of each call [s] (state mapping, solve and warm start included).
    iterations : list of int
        Solver iterations of each call.
    failures : int
        Calls whose solve failed (a fallback torque was applied).
    infeasible : int
        Calls whose solution needed slack above ``options.slack_tol`` on the soft state bounds.
    last_status : str
        Solver return status of the latest call.
    prediction : PredictionChoice or None
        Prediction level and why (None: built without a choice, a rigid plant).
    state_map : SlowStateMap or None
        Elastic measurement -> rigid slow state (None: plain projection, or the plant's own model).
    stage_ref : ndarray, shape (K, n_ps)
        Per-sample values of ``ocp.stage_params`` along the reference (quasi-static link lengths).
    stage_goal : ndarray, shape (n_ps,)
        Their values after the reference (upright static lengths).

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.control import nmpc_controller, upright_state
    >>> model = pl.rigid()
    >>> ctrl = nmpc_controller(model, actuation="full", u_max=20.0, horizon=10)  # an NMPCController
    >>> ctrl.sample_time, ctrl.input_names, ctrl.x_ref.shape
    (0.02, ('tau1', 'tau2'), (1, 4))
    >>> u = ctrl(0.0, upright_state(model) + [0.1, 0.0, 0.0, 0.0])  # one real-time SQP iteration
    >>> u.shape, bool(np.all(np.abs(u) <= 20.0))
    ((2,), True)
    >>> stats = ctrl.stats()
    >>> stats["n_calls"], stats["failures"], stats["solver"]
    (1, 0, 'sqp')
    """

    model: Model
    plan_model: Model
    options: NMPCOptions
    input_names: tuple[str, ...]
    u_max: float
    x_ref: np.ndarray
    u_ref: np.ndarray
    goal: np.ndarray
    ocp: ShootingOCP
    K_lqr: np.ndarray
    # Counters of the controller's own life, not inputs.
    solve_times: list[float] = field(default_factory=list, init=False)
    iterations: list[int] = field(default_factory=list, init=False)
    failures: int = field(default=0, init=False)
    infeasible: int = field(default=0, init=False)
    last_status: str = ""
    prediction: PredictionChoice | None = None
    state_map: SlowStateMap | None = None
    stage_ref: np.ndarray = field(default_factory=lambda: np.zeros((1, 0)))
    stage_goal: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def __post_init__(self) -> None:
        # Warm start (previous solution, multipliers, its sample index): internal, not dataclass fields.
        self._w: np.ndarray | None = None
        self._lam_x: np.ndarray | None = None
        self._lam_g: np.ndarray | None = None
        self._k_prev = -1
        self._restart = False
        self._u_last = np.zeros(2)

    @property
    def sample_time(self) -> float:
        """Sample period [s]."""
        return self.options.sample_time

    def reset(self) -> None:
        """Forget the warm start and the statistics before a new run."""
        self._w = self._lam_x = self._lam_g = None
        self._k_prev = -1
        self._restart = False
        self._u_last = np.zeros(2)
        self.solve_times, self.iterations = [], []
        self.failures = self.infeasible = 0
        self.last_status = ""

    def plan_state(self, x: np.ndarray) -> np.ndarray:
        """The planning model's state of a plant state (slow-manifold map or projection of an elastic state).

        Parameters
        ----------
        x : array_like, shape (nx,)
            Plant state.

        Returns
        -------
        ndarray, shape (nx_plan,)
            Angles [rad] and rates [rad/s] (and lengths for an elastic planning model).
        """
        x = np.asarray(x, dtype=float)
        if self.plan_model is self.model:
            return x.copy()
        if self.state_map is not None:
            return self.state_map(x, self._u_last)
        return rigid_state(self.model, x)

    def window(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """Reference over the prediction window starting at sample ``k``; the goal after the reference.

        Parameters
        ----------
        k : int
            Sample index (time ``k * sample_time``).

        Returns
        -------
        xr : ndarray, shape (N+1, nx_plan)
        ur : ndarray, shape (N, m)
        ps : ndarray, shape (N, n_ps)
            Stage parameters (``ocp.stage_params``) of each interval.
        """
        N = self.ocp.N
        idx = np.arange(k, k + N + 1)
        xr = reference_window(self.x_ref, idx, self.goal)
        ur = reference_window(self.u_ref, idx[:N], 0.0)
        return xr, ur, reference_window(self.stage_ref, idx[:N], self.stage_goal)

    def __call__(self, t: float, x: np.ndarray) -> np.ndarray:
        """Torques [N.m] for ``input_names`` at time ``t`` [s] and plant state ``x``, shape (m,).

        Raises ValueError for a negative or non-finite ``t``, a non-finite ``x``, or ``x`` of the wrong
        shape (a bad measurement, not a solver failure: those are counted in :meth:`stats` and never raise).
        """
        start = time.perf_counter()
        x = np.asarray(x, dtype=float)
        if x.shape != (self.model.nx,) or not np.all(np.isfinite(x)):
            raise ValueError(f"x must be a finite state of shape ({self.model.nx},), got {x!r} at t={t!r}")
        try:
            t = float(t)
        except (TypeError, ValueError):
            raise ValueError(f"t must be a time >= 0 [s], got {t!r}") from None
        if not (np.isfinite(t) and t >= 0.0):
            raise ValueError(f"t must be a finite time >= 0 [s] (the controller's clock starts at 0), got {t!r}")
        ocp, m = self.ocp, self.ocp.m
        k = int(np.floor(t / self.sample_time + 1e-6))
        xr, ur, ps = self.window(k)
        xp = self.plan_state(x)
        xp = xr[0] + wrap_state_error(xp - xr[0], self.plan_model.state_names)  # same branch as the reference
        xs = np.concatenate([xp, self._u_last[self.input_cols]]) if ocp.nh else xp  # with the held torques
        w0, lam_x, lam_g = self._guess(k, xr, ur, xs)
        lbx, ubx = ocp.lbx.copy(), ocp.ubx.copy()
        lbx[ocp.x_idx[0]] = ubx[ocp.x_idx[0]] = xs
        w = None
        try:
            sol = ocp.solver(x0=w0, p=np.concatenate([xr.ravel(), ur.ravel(), ps.ravel()]), lbx=lbx, ubx=ubx,
                             lbg=ocp.lbg, ubg=ocp.ubg, lam_x0=lam_x, lam_g0=lam_g)  # fmt: skip
            st = ocp.solver.stats()
            self.last_status = str(st.get("return_status", ""))
            w = np.asarray(sol["x"], dtype=float).ravel()
            if not (st.get("success") or self.last_status in _USABLE[self.options.solver]) or not np.all(np.isfinite(w)):
                w = None
            iters = int(st.get("iter_count", 0))
        except RuntimeError as exc:  # a solver exception must not stop the control loop
            self.last_status, iters = f"error: {exc}".splitlines()[0], 0
        if w is None:
            self.failures += 1
            u = self._fallback(k, xp)
            # The failed iterate (or the shifted one that led to it) is no start for the next solve.
            self._restart = True
        else:
            self._w, self._k_prev, self._restart = w, k, False
            self._lam_x = np.asarray(sol["lam_x"], dtype=float).ravel()
            self._lam_g = np.asarray(sol["lam_g"], dtype=float).ravel()
            if ocp.ns and float(np.max(w[ocp.u_idx[:, m:]])) > self.options.slack_tol:
                self.infeasible += 1
            u = w[ocp.u_idx[0, :m]]
        self.iterations.append(iters)
        u = np.clip(u, -self.u_max, self.u_max)
        self._u_last = np.zeros(2)
        self._u_last[self.input_cols] = u
        self.solve_times.append(time.perf_counter() - start)
        return u

    @property
    def input_cols(self) -> list[int]:
        """Columns of ``input_names`` in (tau1, tau2)."""
        return [("tau1", "tau2").index(n) for n in self.input_names]

    def _guess(self, k: int, xr: np.ndarray, ur: np.ndarray, xp: np.ndarray) -> tuple[np.ndarray, Any, Any]:
        """Warm start: the previous solution shifted to sample ``k``; cold: the reference window."""
        ocp = self.ocp
        if self._w is None or k < self._k_prev or self._restart:
            w0 = np.zeros(ocp.n_w)
            w0[ocp.x_idx] = np.hstack([xr, np.vstack([ur[:1], ur])]) if ocp.nh else xr
            w0[ocp.u_idx[:, : ocp.m]] = ur
            w0[ocp.x_idx[0]] = xp
            return w0, 0.0, 0.0
        s = min(k - self._k_prev, ocp.N)
        X, U = self._w[ocp.x_idx], self._w[ocp.u_idx]
        X = np.vstack([X[s:], np.repeat(X[-1:], s, axis=0)])
        U = np.vstack([U[s:], np.repeat(U[-1:], s, axis=0)])
        w0 = np.empty(ocp.n_w)
        w0[ocp.x_idx], w0[ocp.u_idx] = X, U
        w0[ocp.x_idx[0]] = xp
        lx = self._lam_x.copy()
        lx[ocp.u_idx] = np.vstack([self._lam_x[ocp.u_idx][s:], np.repeat(self._lam_x[ocp.u_idx][-1:], s, axis=0)])
        G = self._lam_g.reshape(ocp.N, ocp.g_rows)
        lg = np.vstack([G[s:], np.repeat(G[-1:], s, axis=0)]).ravel()
        return w0, lx, lg

    def _fallback(self, k: int, xp: np.ndarray) -> np.ndarray:
        """The previous plan's torque for sample ``k`` while it lasts, else LQR about the goal."""
        s = k - self._k_prev
        if self._w is not None and 0 <= s < self.ocp.N:
            return self._w[self.ocp.u_idx[s, : self.ocp.m]]
        return -self.K_lqr @ wrap_state_error(xp - self.goal, self.plan_model.state_names)

    def stats(self) -> dict[str, float | int | str]:
        """Per-call statistics of the run so far.

        Returns
        -------
        dict
            ``solve_time_median``, ``solve_time_max`` [s], ``iterations_median``,
            ``iterations_max``, ``failures`` and ``infeasible`` (counts of calls),
            ``n_calls``, ``solver`` and ``last_status``. Times are nan before the first call.
            ``prediction_level`` (rigid, rigid+quasi-static or elastic), ``prediction_states``
            (state dimension of the prediction), ``state_map`` (of an elastic plant's state onto a rigid
            prediction; ``none`` when the plant's own model predicts), ``prediction_predicted_error`` (the planning rule's
            relative error of that level), ``prediction_tolerance`` and ``prediction_reason``.
        """
        ts, it = np.asarray(self.solve_times), np.asarray(self.iterations)
        n = len(ts)
        return {
            "solver": self.options.solver,
            "n_calls": n,
            "solve_time_median": float(np.median(ts)) if n else float("nan"),
            "solve_time_max": float(ts.max()) if n else float("nan"),
            "iterations_median": float(np.median(it)) if n else float("nan"),
            "iterations_max": int(it.max()) if n else 0,
            "failures": int(self.failures),
            "infeasible": int(self.infeasible),
            "last_status": self.last_status,
            "prediction_level": self.prediction.level if self.prediction else "rigid",
            "prediction_states": int(self.plan_model.nx),
            "state_map": "none" if self.plan_model is self.model else self.options.state_map,
            "prediction_predicted_error": self.prediction.predicted_error if self.prediction else 0.0,
            "prediction_tolerance": self.options.prediction_tolerance,
            "prediction_reason": self.prediction.reason if self.prediction else "rigid plant: predicted with its own model",
        }
