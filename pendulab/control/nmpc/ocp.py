"""The NMPC optimal-control problem: multiple shooting with RK4 on the model's CasADi rhs, and its solvers.

Decision variables are ordered stage-wise, ``[x0, u0, x1, u1, ..., x_{N-1}, u_{N-1}, xN]``,
and constraints per stage ``[F(x_k, u_k) - x_{k+1}; soft bounds of stage k]``: the
block structure that CasADi's structure-exploiting solvers detect (``hpipm`` inside
``sqpmethod``, and ``fatrop``), and what the warm start shifts one stage at a time.
A stage control ``u_k`` holds the driven torques and, when a velocity limit is set,
two slacks that make the rate bounds soft (the problem stays feasible whatever the
start state; a positive slack says the hard-bounded problem would not be).

The cost is linear least squares (tracking a reference, weights Q, R and the
terminal cost-to-go P), so the Gauss-Newton Hessian is constant, positive
definite and known in closed form: the SQP solvers use it (the exact Hessian of
the Lagrangian is indefinite and would need convexification every sample).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from ...model.functions import model_functions
from ...model.model import INPUT_NAMES, Model

__all__ = ["ShootingOCP", "build_ocp", "reference_window", "SOLVERS"]


def reference_window(ref: np.ndarray, idx: np.ndarray, after: Any) -> np.ndarray:
    """Rows of a sampled reference at sample indices, and ``after`` past its end (the goal, a zero torque).

    Parameters
    ----------
    ref : ndarray, shape (K, n)
        Reference on the sample grid.
    idx : ndarray of int, shape (M,)
        Sample indices (non-negative).
    after : float or ndarray, shape (n,)
        The value of every index at or past ``K``.

    Returns
    -------
    ndarray, shape (M, n)
    """
    K = len(ref)
    return np.where((idx < K)[:, None], ref[np.minimum(idx, K - 1)], after)


#: Solver names accepted by :func:`build_ocp`.
SOLVERS: tuple[str, ...] = ("sqp", "ipopt", "fatrop")


@dataclass
class ShootingOCP:
    """A built multiple-shooting NLP and the index maps into its stage-wise vectors.

    Attributes
    ----------
    solver : casadi.Function
        The ``nlpsol`` (inputs x0, p, lbx, ubx, lbg, ubg, lam_x0, lam_g0).
    solver_name : str
        ``"sqp"``, ``"ipopt"`` or ``"fatrop"``.
    N : int
        Number of shooting intervals.
    nx : int
        State dimension of the planning model.
    m : int
        Number of driven torques.
    ns : int
        Slacks per stage (2 with a velocity limit, else 0).
    x_idx : ndarray of int, shape (N+1, nx + nh)
        Positions of the stage states in the decision vector.
    u_idx : ndarray of int, shape (N, m + ns)
        Positions of the stage controls (torques, then slacks).
    g_rows : int
        Constraint rows per stage (nx + nh + 2 ns).
    lbx, ubx : ndarray, shape (n_w,)
        Variable bounds (torque limits, slacks >= 0); the start state is set per solve.
    lbg, ubg : ndarray, shape (n_g,)
        Constraint bounds.
    step : casadi.Function
        One interval of the integrator, ``(x, u_driven[, ps]) -> x_next``.
    stage_params : tuple of str
        Model parameters given per interval through the NLP parameter (``ps``).
    nh : int
        Held torques appended to each stage state (``m`` with a torque-rate penalty, else 0):
        ``x_idx`` has ``nx + nh`` columns, the first stage's held torques are the torques applied last.
    """

    solver: ca.Function
    solver_name: str
    N: int
    nx: int
    m: int
    ns: int
    x_idx: np.ndarray
    u_idx: np.ndarray
    g_rows: int
    lbx: np.ndarray
    ubx: np.ndarray
    lbg: np.ndarray
    ubg: np.ndarray
    step: ca.Function
    stage_params: tuple[str, ...] = ()
    nh: int = 0

    @property
    def n_w(self) -> int:
        """Number of decision variables."""
        return int(self.x_idx.size + self.u_idx.size)


def _rk4_step(model: Model, cols: list[int], h: float, substeps: int, stage_params: tuple[str, ...] = ()) -> ca.Function:
    """One sample interval ``h`` of RK4 with ``substeps`` steps, torques held, as an SX Function.

    Inputs ``(x, u)``, and ``ps`` (the values of the parameters ``stage_params``) if there are any; the other
    parameters are folded in.
    """
    f = model_functions(model.kind)["rhs"]
    x = ca.SX.sym("x", model.nx)
    u = ca.SX.sym("u", len(cols))
    ps = ca.SX.sym("ps", len(stage_params))
    ufull = ca.SX.zeros(len(INPUT_NAMES))
    for i, c in enumerate(cols):
        ufull[c] = u[i]
    p = ca.SX(ca.DM(model.p))
    for i, name in enumerate(stage_params):
        p[model.param_names.index(name)] = ps[i]
    dt = h / substeps
    xk = x
    for _ in range(substeps):
        k1 = f(xk, ufull, p)
        k2 = f(xk + 0.5 * dt * k1, ufull, p)
        k3 = f(xk + 0.5 * dt * k2, ufull, p)
        k4 = f(xk + dt * k3, ufull, p)
        xk = xk + dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
    if not stage_params:
        return ca.Function("rk4_step", [x, u], [xk], ["x", "u"], ["x_next"])
    return ca.Function("rk4_step", [x, u, ps], [xk], ["x", "u", "ps"], ["x_next"])


def build_ocp(
    model: Model,
    input_names: tuple[str, ...],
    *,
    N: int,
    sample_time: float,
    substeps: int,
    Q: np.ndarray,
    R: np.ndarray,
    P: np.ndarray,
    u_max: float,
    velocity_limit: float | None,
    slack_weight: float,
    solver: str,
    max_iter: int,
    max_solve_time: float | None = None,
    stage_params: tuple[str, ...] = (),
    rate_weight: float | None = None,
) -> ShootingOCP:
    """Build the tracking NLP ``min sum |x_k - xr_k|_Q^2 + |u_k - ur_k|_R^2 + |x_N - xr_N|_P^2``.

    The reference ``(xr, ur)`` and the stage parameters ``ps`` are the NLP parameter
    ``p = [xr_0..xr_N, ur_0..ur_{N-1}, ps_0..ps_{N-1}]``; the start state enters through equal
    bounds on ``x_0``.

    Parameters
    ----------
    model : Model
        Planning model (its parameters are folded in).
    input_names : tuple of str
        Driven torques (m of them).
    N : int
        Shooting intervals.
    sample_time : float
        Interval length [s].
    substeps : int
        RK4 steps per interval.
    Q : ndarray, shape (nx, nx)
        Stage state weight.
    R : ndarray, shape (m, m)
        Stage torque weight [1/(N.m)^2].
    P : ndarray, shape (nx, nx)
        Terminal weight (LQR cost-to-go).
    u_max : float
        Hard torque bound [N.m].
    velocity_limit : float or None
        Soft bound on both joint rates ``omega1``, ``omega2 - omega1`` [rad/s] (as the RTI's ``rate_limit``).
    slack_weight : float
        Weight of the slacks (linear ``w s`` plus quadratic ``10 w s^2``).
    solver : {"sqp", "ipopt", "fatrop"}
        ``sqp``: ``sqpmethod`` with ``qpsol="hpipm"`` and the Gauss-Newton Hessian,
        ``max_iter`` SQP iterations (1 = real-time iteration); ``ipopt``: IPOPT with
        exact Hessian; ``fatrop``: fatrop with automatic structure detection.
    max_iter : int
        Iteration cap of the solver.
    max_solve_time : float, optional
        Wall-time cap of one IPOPT solve [s] (IPOPT's ``max_wall_time``; an iterate cut short
        is a failed solve, handled by the controller's fallback). The real-time SQP is bounded
        by its iteration cap. None: no cap.
    stage_params : tuple of str
        Model parameters that take a value per interval (e.g. the link lengths of a rigid
        prediction with quasi-static springs); the others are folded in.
    rate_weight : float, optional
        Weight of the torque rate ``|u_k - u_{k-1}|^2`` [1/(N.m)^2] (``u_{-1}``: the torque applied
        last, a start state); the previous torques become states of each stage. None: no penalty.

    Returns
    -------
    ShootingOCP

    Raises
    ------
    ValueError
        Unknown ``solver``.
    """
    if solver not in SOLVERS:
        raise ValueError(f"solver must be one of {list(SOLVERS)}, got {solver!r}")
    nx, m = model.nx, len(input_names)
    nh = m if rate_weight is not None else 0  # the previous torques, appended to the stage state
    nxa = nx + nh
    ns = 2 if velocity_limit is not None else 0
    nu = m + ns
    cols = [INPUT_NAMES.index(n) for n in input_names]
    unknown = [n for n in stage_params if n not in model.param_names]
    if unknown:
        raise ValueError(f"stage_params must be parameters of the {model.kind} model {model.param_names}, got {unknown}")
    npar = len(stage_params)
    step = _rk4_step(model, cols, sample_time, substeps, tuple(stage_params))
    omega = [model.state_names.index(n) for n in ("omega1", "omega2")]

    xs = [ca.SX.sym(f"x{k}", nxa) for k in range(N + 1)]
    us = [ca.SX.sym(f"u{k}", nu) for k in range(N)]
    xr = ca.SX.sym("xr", nx, N + 1)
    ur = ca.SX.sym("ur", m, N)
    sp = ca.SX.sym("ps", npar, N)
    w, g, cost = [], [], 0
    lbx, ubx, lbg, ubg = [], [], [], []
    inf = np.inf
    for k in range(N):
        w += [xs[k], us[k]]
        lbx += [-inf] * nxa + [-u_max] * m + [0.0] * ns
        ubx += [inf] * nxa + [u_max] * m + [inf] * ns
        tau, s = us[k][:m], us[k][m:]
        xk = xs[k][:nx]
        ex, eu = xk - xr[:, k], tau - ur[:, k]
        cost += ca.bilin(ca.DM(Q), ex, ex) + ca.bilin(ca.DM(R), eu, eu)
        nxt = step(xk, tau, sp[:, k]) if npar else step(xk, tau)
        if nh:  # torque-rate penalty within the stage: the held torque is a state (OCP block structure kept)
            cost += rate_weight * ca.sumsqr(tau - xs[k][nx:])
            nxt = ca.vertcat(nxt, tau)
        # hpipm wants the gap as F - x_next (block A B -I), fatrop's detection as x_next - F.
        gap = nxt - xs[k + 1]
        g.append(-gap if solver == "fatrop" else gap)
        lbg += [0.0] * nxa
        ubg += [0.0] * nxa
        if ns:
            cost += slack_weight * (ca.sum1(s) + 10.0 * ca.sumsqr(s))
            w_k = ca.vertcat(xs[k][omega[0]], xs[k][omega[1]] - xs[k][omega[0]])  # joint rates: the robot's limits
            g += [w_k - s, w_k + s]
            lbg += [-inf, -inf, -velocity_limit, -velocity_limit]
            ubg += [velocity_limit, velocity_limit, inf, inf]
    w.append(xs[N])
    lbx += [-inf] * nxa
    ubx += [inf] * nxa
    eN = xs[N][:nx] - xr[:, N]
    cost += ca.bilin(ca.DM(P), eN, eN)
    W, G, Pp = ca.vertcat(*w), ca.vertcat(*g), ca.vertcat(ca.vec(xr), ca.vec(ur), ca.vec(sp))
    nlp = {"x": W, "f": cost, "g": G, "p": Pp}
    x_idx = np.array([[k * (nxa + nu) + i for i in range(nxa)] for k in range(N + 1)])
    u_idx = np.array([[k * (nxa + nu) + nxa + i for i in range(nu)] for k in range(N)])
    equality = [bool(lo == hi) for lo, hi in zip(lbg, ubg, strict=True)]
    fn = ca.nlpsol("nmpc", *_solver_plugin(solver, nlp, W, Pp, G, max_iter, equality, max_solve_time))
    return ShootingOCP(
        fn, solver, N, nx, m, ns, x_idx, u_idx, nxa + 2 * ns,
        np.array(lbx), np.array(ubx), np.array(lbg), np.array(ubg), step, tuple(stage_params), nh,
    )  # fmt: skip


def _solver_plugin(
    solver: str, nlp: dict, W: ca.SX, Pp: ca.SX, G: ca.SX, max_iter: int, equality: list[bool], max_solve_time: float | None
) -> tuple[str, dict, dict[str, Any]]:
    """Plugin name, NLP and options of one solver choice."""
    # A solve that meets NaN (a diverged warm start far from the reference) is a counted failure with a
    # fallback torque (NMPCController), so CasADi's per-evaluation NaN warnings would only flood stderr.
    common: dict[str, Any] = {"print_time": False, "error_on_fail": False, "show_eval_warnings": False}
    if solver == "ipopt":
        ipopt = {
            "print_level": 0, "max_iter": max_iter, "tol": 1e-6, "acceptable_tol": 1e-4, "sb": "yes",
            "warm_start_init_point": "yes", "warm_start_bound_push": 1e-6, "warm_start_mult_bound_push": 1e-6,
            "mu_init": 1e-3, "linear_solver": "mumps",
        }  # fmt: skip
        if max_solve_time is not None:
            ipopt["max_wall_time"] = float(max_solve_time)
        return "ipopt", nlp, {**common, "ipopt": ipopt}
    if solver == "fatrop":
        fatrop = {"print_level": 0, "max_iter": max_iter, "tol": 1e-6, "mu_init": 1e-2}
        return "fatrop", nlp, {**common, "structure_detection": "auto", "equality": equality, "fatrop": fatrop, "expand": True}
    # Gauss-Newton Hessian of the least-squares cost: constant, PD on the torques and slacks, PSD on states.
    lam_f, lam_g = ca.SX.sym("lam_f"), ca.SX.sym("lam_g", G.numel())
    H = ca.hessian(nlp["f"], W)[0]
    hess = ca.Function("nlp_hess_l", [W, Pp, lam_f, lam_g], [lam_f * H], ["x", "p", "lam_f", "lam_g"], ["hess_gamma_x_x"])
    qp_opts = {"error_on_fail": False, "hpipm": {"iter_max": 50, "warm_start": 0, "mode": "speed"}}
    opts = {
        **common, "qpsol": "hpipm", "qpsol_options": qp_opts, "hess_lag": hess, "max_iter": max_iter,
        "print_header": False, "print_iteration": False, "print_status": False, "tol_pr": 1e-6, "tol_du": 1e-6,
        "max_iter_ls": 0,
    }  # fmt: skip
    return "sqpmethod", nlp, opts
