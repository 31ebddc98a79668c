"""One real-time iteration (RTI) of the tracking NMPC as a single CasADi Function, ready for C code generation.

The step is the Gauss-Newton SQP iteration of the multiple-shooting problem

``min sum_k c_k (|x_k - xr_k|_Q^2 + |u_k - ur_k|_R^2) + |x_N - xr_N|_P^2 [+ w sum_k sum_i (|v_ki| - v_max)_+^2]``
``s.t. x_{k+1} = F_k(x_k, u_k), x_0 = x_meas, |u_k| <= u_max``

(the bracket: an optional soft bound on the joint rates ``v`` (``omega1``, ``omega2 - omega1``) of every node, a
least-squares penalty, so it stays inside the Gauss-Newton scheme and the QP keeps box constraints only)

(``c_k``: 1, or the interval length for a cost per second; the intervals may differ, a non-uniform grid)

(``F``: RK4 over one interval; the same cost as :mod:`.ocp`), linearized at the current guess
``(X, U)`` and solved in three parts, all in one graph:

1. **linearization**: ``F``, ``A_k = dF/dx``, ``B_k = dF/du`` of every interval (one SX Function mapped
   over the horizon), gaps ``d_k = F(x_k, u_k) - x_{k+1}``;
2. **condensing**: the state corrections are eliminated, ``dX = Gbar dU + xi``, which leaves a dense,
   strictly convex QP in the ``N m`` torque corrections with box bounds (``H = Gbar' W Gbar + Rbar``);
3. **box-QP solve**: a fixed number of primal-dual active-set iterations (Hintermueller, Ito and Kunisch
   2002, a semismooth Newton method), started from the bounds the warm start sits on: each fixes the
   torques whose bound is predicted active, solves the others from one LDL' factorization (CasADi's
   ``ldl`` linear solver, code-generable) and updates the multipliers. With the right active set (none,
   or the previous sample's, the usual case) the first solve is the exact QP solution; a fixed count
   keeps the per-call time bounded (the output says whether the last iterate is a KKT point).

The outputs are the updated trajectory (``X + dX``, ``U + dU``), the first torque and the same trajectory
shifted by one controller sample (linear interpolation inside the intervals), the warm start of the next call.
Everything is an MX graph over small SX kernels with dense linear algebra in loops, so the generated C is
compact (it compiles in seconds) and its run time does not depend on the state.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import casadi as ca
import numpy as np

from ...model.functions import model_functions
from ...model.model import INPUT_NAMES, Model

__all__ = ["rk4_interval", "rollout_function", "rti_step_function", "STEP_INPUTS", "STEP_OUTPUTS"]

#: Inputs of the step Function, in order.
STEP_INPUTS: tuple[str, ...] = ("x0", "X", "U", "XR", "UR")
#: Outputs of the step Function, in order.
STEP_OUTPUTS: tuple[str, ...] = ("u0", "X_new", "U_new", "X_next", "U_next", "info")


def rk4_interval(model: Model, cols: list[int], dt: float, substeps: int) -> ca.Function:
    """RK4 over one interval ``dt`` [s] with ``substeps`` steps, the driven torques held: ``(x, u) -> x_next``.

    Parameters
    ----------
    model : Model
        Prediction model (its parameters are folded in as constants).
    cols : list of int
        Columns of the driven torques in ``INPUT_NAMES``.
    dt : float
        Interval [s].
    substeps : int
        RK4 steps per interval.

    Returns
    -------
    casadi.Function
        SX Function ``(x (nx,), u (m,)) -> x_next (nx,)``.
    """
    f = model_functions(model.kind)["rhs"]
    x = ca.SX.sym("x", model.nx)
    u = ca.SX.sym("u", len(cols))
    ufull = ca.SX.zeros(len(INPUT_NAMES))
    for i, c in enumerate(cols):
        ufull[c] = u[i]
    p = ca.DM(model.p)
    h = dt / substeps
    xk = x
    for _ in range(substeps):
        k1 = f(xk, ufull, p)
        k2 = f(xk + 0.5 * h * k1, ufull, p)
        k3 = f(xk + 0.5 * h * k2, ufull, p)
        k4 = f(xk + h * k3, ufull, p)
        xk = xk + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
    return ca.Function("rti_rk4", [x, u], [xk], ["x", "u"], ["x_next"])


def rollout_function(
    model: Model, input_names: tuple[str, ...], intervals: Sequence[float], substeps: Sequence[int]
) -> ca.Function:
    """The prediction simulated from a state with the torques held per interval: ``(x0, U) -> X``.

    The consistent start guess of a real-time iteration (no gaps between the shooting nodes): a cold start
    from the reference alone puts every node near the goal while the measured state is elsewhere, and one
    Gauss-Newton step from such a guess can throw the trajectory far outside the region the RK4 interval
    is stable in.

    Parameters
    ----------
    model : Model
        Prediction model.
    input_names : tuple of str
        Driven torques (m of them).
    intervals : sequence of float
        The N interval lengths [s].
    substeps : sequence of int
        RK4 steps of each interval.

    Returns
    -------
    casadi.Function
        SX Function ``(x0 (nx,), U (m, N)) -> X (nx, N+1)``.
    """
    cols = [INPUT_NAMES.index(n) for n in input_names]
    N = len(intervals)
    x0, U = ca.SX.sym("x0", model.nx), ca.SX.sym("U", len(cols), N)
    steps = {key: rk4_interval(model, cols, *key) for key in set(zip(intervals, substeps, strict=True))}
    X = [x0]
    for k, key in enumerate(zip(intervals, substeps, strict=True)):
        X.append(steps[key](X[k], U[:, k]))
    return ca.Function("rti_rollout", [x0, U], [ca.horzcat(*X)], ["x0", "U"], ["X"])


def _stage_linearization(step: ca.Function, nx: int, m: int) -> ca.Function:
    """SX kernel ``(x, u) -> (F, A, B)`` of one interval."""
    x, u = ca.SX.sym("x", nx), ca.SX.sym("u", m)
    F = step(x, u)
    return ca.Function("rti_lin", [x, u], [F, ca.jacobian(F, x), ca.jacobian(F, u)], ["x", "u"], ["F", "A", "B"])


def _box_qp_pdas(
    H: ca.MX,
    g: ca.MX,
    lb: ca.MX,
    ub: ca.MX,
    upper: ca.MX,
    lower: ca.MX,
    iterations: int,
    penalty: tuple[ca.MX, ca.MX, float, float] | None = None,
) -> tuple[ca.MX, ca.MX, ca.MX]:
    """``min 0.5 z'Hz + g'z [+ p(z)], lb <= z <= ub`` by at most ``iterations`` primal-dual active-set steps.

    ``upper``, ``lower`` (0/1) are the first guess of the bounds that are active (the warm start's
    saturated torques). Each step solves with the guessed bounds held, then re-guesses them from the
    multipliers and the bound violations. ``penalty = (SZ, SG, w, v_max)``: the term
    ``0.5 w sum (|SZ + SG z| - v_max)_+^2``, taken on the piece (``sign(v)`` where ``|v| > v_max``, else 0)
    each entry sits on, re-chosen at every step with the bounds (a semismooth Newton step on both).

    When a step re-guesses the same bounds and pieces, the next solve would return the same iterate: the
    remaining steps are skipped at run time (a ``Function.if_else`` switch, short-circuited in the generated
    C too), so a call costs the steps it needs, at most ``iterations``; the numbers are those of running them all.
    Returns the last iterate, whether it is a KKT point of the box QP (free entries inside their bounds,
    multipliers of the held ones of the right sign: 1.0 / 0.0), and the number of bounds held.
    """
    n = H.size1()
    ones = ca.DM.ones(n)
    # The scale c of the complementarity function: any c > 0 works; the mean diagonal of H balances z and lam.
    c = ca.sum1(ca.diag(H)) / n
    tol = 1e-9

    def pieces(z: ca.MX) -> ca.MX:
        if penalty is None:
            return ca.MX.zeros(0, 1)
        SZ, SG, _, vmax = penalty
        v = SZ + ca.mtimes(SG, z)
        return ca.sign(v) * (ca.fabs(v) > vmax)

    # One solve as a Function of its data, so that a switch can skip it: (H, g, lb, ub, [SZ, SG], upper, lower,
    # piece, z, lam) -> (z, lam); "keep" returns the z, lam it is given.
    data = [H, g, lb, ub] + ([] if penalty is None else [penalty[0], penalty[1]])
    sym = [ca.MX.sym(f"d{i}", d.sparsity()) for i, d in enumerate(data)]
    up_s, lo_s = ca.MX.sym("upper", n), ca.MX.sym("lower", n)
    pc_s = ca.MX.sym("piece", 0 if penalty is None else penalty[0].size1())
    z_s, lam_s = ca.MX.sym("z", n), ca.MX.sym("lam", n)
    Hs, gs, lbs, ubs = sym[:4]
    if penalty is not None:
        SZs, SGs = sym[4:]
        w, vmax = penalty[2], penalty[3]
        DG = ca.times(ca.repmat(w * ca.fabs(pc_s), 1, n), SGs)
        Hs, gs = Hs + ca.mtimes(SGs.T, DG), gs + ca.mtimes(DG.T, SZs - pc_s * vmax)
    act = ca.fmax(up_s, lo_s)
    zb = up_s * ubs + lo_s * lbs
    free = ones - act
    M = Hs * ca.mtimes(free, free.T) + ca.diag(act)
    z_new = ca.solve(M, free * (-gs - ca.mtimes(Hs, act * zb)) + act * zb, "ldl")
    lam_new = act * (-(ca.mtimes(Hs, z_new) + gs))
    args = [*sym, up_s, lo_s, pc_s, z_s, lam_s]
    solve = ca.Function("rti_pdas_solve", args, [z_new, lam_new])
    keep = ca.Function("rti_pdas_keep", args, [z_s, lam_s])
    step = ca.Function.if_else("rti_pdas_step", solve, keep)

    z = lam = ca.MX.zeros(n)
    piece = pieces(z)
    z, lam = solve(*data, upper, lower, piece, z, lam)
    for _ in range(iterations - 1):
        new_upper = lam + c * (z - ub) > 0
        new_lower = lam + c * (z - lb) < 0
        new_piece = pieces(z)
        changed = ca.mmax(ca.vertcat(ca.fabs(new_upper - upper), ca.fabs(new_lower - lower), ca.fabs(new_piece - piece), 0))
        z, lam = step(changed > 0, *data, new_upper, new_lower, new_piece, z, lam)
        upper, lower, piece = new_upper, new_lower, new_piece
    act = ca.fmax(upper, lower)
    free = ones - act
    feasible = ca.mmax(ca.vertcat(free * (z - ub), free * (lb - z), -upper * lam, lower * lam)) <= tol
    return z, feasible, ca.sum1(act)


def _per_interval(value: Any, N: int, kind: type, name: str) -> list:
    """``value`` as a list of N entries: one number repeated, or a sequence of N."""
    if np.ndim(value) == 0:
        return [kind(value)] * N
    out = [kind(v) for v in value]
    if len(out) != N:
        raise ValueError(f"{name} must be one number or {N} of them (one per interval), got {len(out)}")
    return out


def rti_step_function(
    model: Model,
    input_names: tuple[str, ...],
    *,
    N: int,
    interval: float | Sequence[float],
    substeps: int | Sequence[int],
    shift: float | Sequence[float],
    Q: np.ndarray,
    R: np.ndarray,
    P: np.ndarray,
    u_max: float,
    qp_iterations: int,
    stage_scale: Sequence[float] | None = None,
    rate_limit: float | None = None,
    rate_weight: float = 1e3,
    name: str = "rti_step",
) -> ca.Function:
    """The whole real-time iteration as one MX Function (see the module docstring).

    Parameters
    ----------
    model : Model
        Prediction model (parameters folded in).
    input_names : tuple of str
        Driven torques (m of them).
    N : int
        Shooting intervals.
    interval : float or sequence of float
        Interval length [s], or the N interval lengths of a non-uniform grid.
    substeps : int or sequence of int
        RK4 steps per interval (one number, or one per interval).
    shift : float or sequence of float
        Controller sample time as a fraction of the interval (in (0, 1]; one per interval on a
        non-uniform grid): how far the warm start ``X_next, U_next`` is shifted.
    Q, R, P : ndarray
        Stage state weight (nx, nx), torque weight (m, m), terminal weight (nx, nx).
    u_max : float
        Torque bound [N.m].
    qp_iterations : int
        Primal-dual active-set solves of the box QP.
    stage_scale : sequence of float, optional
        Factor of each stage cost (N of them, e.g. the interval lengths for a cost per second);
        default 1 (the terminal cost is never scaled).
    rate_limit : float, optional
        Soft bound on the joint rates (``omega1``, ``omega2 - omega1``) of every node [rad/s]: adds
        ``rate_weight (|v| - rate_limit)_+^2`` per rate of the linearized prediction. None: no bound.
    rate_weight : float
        Weight of the rate bound's penalty [s^2/rad^2].
    name : str
        Function name (the C symbol).

    Returns
    -------
    casadi.Function
        ``(x0 (nx,), X (nx, N+1), U (m, N), XR (nx, N+1), UR (m, N)) ->
        (u0 (m,), X_new, U_new, X_next, U_next, info (3,))``, ``info = [QP solved: the iterate is a KKT point
        (1/0), active bounds, max |gap| of the linearization point]``.
    """
    nx, m = model.nx, len(input_names)
    cols = [INPUT_NAMES.index(n) for n in input_names]
    dts = _per_interval(interval, N, float, "interval")
    steps = _per_interval(substeps, N, int, "substeps")
    shifts = _per_interval(shift, N, float, "shift")
    scale = _per_interval(1.0 if stage_scale is None else stage_scale, N, float, "stage_scale")
    x0 = ca.MX.sym("x0", nx)
    X, U = ca.MX.sym("X", nx, N + 1), ca.MX.sym("U", m, N)
    XR, UR = ca.MX.sym("XR", nx, N + 1), ca.MX.sym("UR", m, N)
    # One mapped SX kernel per run of equal intervals (a single map on a uniform grid).
    parts, k0 = [], 0
    for k in range(1, N + 1):
        if k == N or (dts[k], steps[k]) != (dts[k0], steps[k0]):
            lin = _stage_linearization(rk4_interval(model, cols, dts[k0], steps[k0]), nx, m).map(k - k0)
            parts.append(lin(X[:, k0:k], U[:, k0:k]))
            k0 = k
    F, A, B = (ca.horzcat(*col) for col in zip(*parts, strict=True))
    d = F - X[:, 1:]
    # Condensing: xi_k (free response) and G_k (sensitivity of x_k to all torque corrections), forward.
    xi = [x0 - X[:, 0]]
    G = [ca.MX(nx, N * m)]
    for k in range(N):
        Ak, Bk = A[:, k * nx : (k + 1) * nx], B[:, k * m : (k + 1) * m]
        xi.append(ca.mtimes(Ak, xi[k]) + d[:, k])
        head = ca.mtimes(Ak, G[k][:, : k * m]) if k else ca.MX(nx, 0)
        G.append(ca.horzcat(head, Bk, ca.MX(nx, (N - k - 1) * m)))
    Gbar, Xi = ca.vertcat(*G), ca.vertcat(*xi)
    W = ca.DM(ca.diagcat(*([ca.DM(Q) * c for c in scale] + [ca.DM(P)])))
    Rbar = ca.DM(ca.diagcat(*[ca.DM(R) * c for c in scale]))
    E = ca.vec(X - XR) + Xi
    WG = ca.mtimes(W, Gbar)
    H = ca.mtimes(Gbar.T, WG) + Rbar
    g = ca.mtimes(WG.T, E) + ca.mtimes(Rbar, ca.vec(U - UR))
    penalty = None
    if rate_limit is not None:
        # w (|v| - v_max)_+^2 on every *joint* rate (omega1, omega2 - omega1: the robot's limits are on its joints)
        # of the linearized prediction v = S (Z + Gbar dU) (Z: at dU = 0), taken on the piece each rate sits on at
        # the QP's current iterate: (v - sign(v) v_max)^2 where it is past the bound.
        w1, w2 = model.state_names.index("omega1"), model.state_names.index("omega2")
        S = ca.DM.zeros(2 * (N + 1), nx * (N + 1))
        for k in range(N + 1):
            S[2 * k, k * nx + w1] = 1.0
            S[2 * k + 1, k * nx + w2], S[2 * k + 1, k * nx + w1] = 1.0, -1.0
        penalty = (ca.mtimes(S, ca.vec(X) + Xi), ca.mtimes(S, Gbar), float(rate_weight), float(rate_limit))

    Uv = ca.vec(U)
    # Warm active set: the torques of the guess on a bound (the shifted previous solution).
    edge = u_max * (1 - 1e-9)
    dU, settled, n_active = _box_qp_pdas(H, g, -u_max - Uv, u_max - Uv, Uv >= edge, Uv <= -edge, qp_iterations, penalty)
    X_new = X + ca.reshape(ca.mtimes(Gbar, dU) + Xi, nx, N + 1)
    U_new = ca.reshape(ca.fmin(ca.fmax(Uv + dU, -u_max), u_max), m, N)
    # Warm start of the next call: the trajectory a fraction `shift` of an interval later (last interval held).
    # (node k moves the fraction shifts[k] of its interval towards node k+1; the last node is held).
    sx = ca.repmat(ca.DM(shifts + [shifts[-1]]).T, nx, 1)
    su = ca.repmat(ca.DM(shifts).T, m, 1)
    X_next = X_new * (1 - sx) + ca.horzcat(X_new[:, 1:], X_new[:, N:]) * sx
    U_next = U_new * (1 - su) + ca.horzcat(U_new[:, 1:], U_new[:, N - 1 :]) * su
    info = ca.vertcat(settled, n_active, ca.mmax(ca.fabs(d)))
    return ca.Function(
        name, [x0, X, U, XR, UR], [U_new[:, 0], X_new, U_new, X_next, U_next, info], list(STEP_INPUTS), list(STEP_OUTPUTS)
    )
