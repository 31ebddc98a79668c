"""Output-error refinement: simulated angles against measured ones, by multiple shooting (CasADi + IPOPT).

The regression fits torques; a testbed needs the *motion* predicted. Starting from the regression,
this stage fits the same free standard parameters to the measured angles directly. Each record is
cut into windows of :data:`WINDOW` seconds (the longest validation horizon); a window's state is
free at shooting nodes every :data:`NODE_SPACING` seconds, the model runs from each node under
the measured torques (RK4 on the record's grid, :func:`pendulab.identify.simulate.rollout`), and
continuity joins the pieces of a window. Windows are independent, so a model error cannot
accumulate over a whole record, and the fit is what the validation measures: prediction from a
state over up to a second. The physical-consistency constraints and the prior term are the
regression's (:mod:`pendulab.identify.fit`).

Intervals come from the Gauss-Newton covariance of the base parameters, ``s^2 (J^T J)^-1`` with
``J`` the angles' sensitivity to the base parameters and the window starts, inflated by the
residuals' correlation time (``N / N_eff``, ``N_eff = N / (1 + 2 sum rho_k)``).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from functools import cache

import casadi as ca
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .preprocess import Prepared
from .regressor import FIXED_NAMES, STANDARD_NAMES, BaseParameters
from .simulate import rollout

__all__ = ["WINDOW", "NODE_SPACING", "Windows", "windows", "OutputErrorFit", "fit_output_error"]

#: Window length [s] and shooting-node spacing [s].
WINDOW = 1.0
NODE_SPACING = 0.1


@dataclass(frozen=True)
class Windows:
    """Shooting intervals cut from prepared records.

    Attributes
    ----------
    x0 : numpy.ndarray, shape (4, n_intervals)
        Filtered measured state at each interval's start (the initial guess).
    U : numpy.ndarray, shape (2, n_intervals * steps)
        Torque readings per step.
    Q : numpy.ndarray, shape (2, n_intervals * steps)
        Measured angles after each step.
    nodes : int
        Intervals per window.
    steps : int
        RK4 steps per interval.
    h : float
        Step [s].
    """

    x0: np.ndarray
    U: np.ndarray
    Q: np.ndarray
    nodes: int
    steps: int
    h: float

    @property
    def intervals(self) -> int:
        """Number of shooting intervals."""
        return self.x0.shape[1]


def windows(preps: Sequence[Prepared], window: float = WINDOW, node_spacing: float = NODE_SPACING) -> Windows:
    """Cut records into windows of shooting intervals.

    Parameters
    ----------
    preps : sequence of Prepared
        Records on grids of equal interval (to 1 %).
    window, node_spacing : float
        Window length and node spacing [s].

    Returns
    -------
    Windows
        All intervals, window after window.

    Raises
    ------
    ValueError
        Records with different grids, or none long enough for one window.
    """
    h = preps[0].dt
    if any(abs(p.dt - h) > 0.01 * h for p in preps):
        raise ValueError(f"records must share a grid interval for the output-error fit, got {[p.dt for p in preps]}")
    steps = max(1, int(round(node_spacing / h)))
    nodes = max(1, int(round(window / (steps * h))))
    x0, U, Q = [], [], []
    for p in preps:
        usable = np.flatnonzero(p.use)
        for start in range(usable[0], usable[-1] - nodes * steps, nodes * steps):
            for k in range(nodes):
                s = start + k * steps
                x0.append(p.state(s))
                U.append(p.tau[s : s + steps].T)
                Q.append(p.q_measured[s + 1 : s + steps + 1].T)
    if not x0:
        raise ValueError(f"no record is long enough for one {window} s window")
    return Windows(x0=np.array(x0).T, U=np.hstack(U), Q=np.hstack(Q), nodes=nodes, steps=steps, h=h)


@dataclass(frozen=True)
class OutputErrorFit:
    """The refined base parameters and their covariance.

    Attributes
    ----------
    base : BaseParameters
        The identifiable combinations fitted.
    beta : numpy.ndarray, shape (n_base,)
        Their values.
    covariance : numpy.ndarray, shape (n_base, n_base)
        Their covariance.
    pi : dict of str to float
        Standard parameters reproducing ``beta`` with the dependent ones (the masses) as started.
    angle_rms : numpy.ndarray, shape (2,)
        RMS angle error over the fitted windows [rad].
    iterations : int
        Gauss-Newton iterations.
    """

    base: BaseParameters
    beta: np.ndarray
    covariance: np.ndarray
    pi: dict[str, float]
    angle_rms: np.ndarray
    iterations: int

    def stderr(self) -> np.ndarray:
        """Standard error of each base parameter.

        Returns
        -------
        numpy.ndarray, shape (n_base,)
            In the base parameters' units.
        """
        return np.sqrt(np.maximum(np.diag(self.covariance), 0.0))


def _autocorrelation_factor(r: np.ndarray, max_lag: int = 500) -> float:
    """``N / N_eff = 1 + 2 sum_k rho_k`` over the positive lags of a residual series."""
    r = r - r.mean()
    var = float(r @ r)
    if var == 0.0:
        return 1.0
    factor = 1.0
    for k in range(1, min(max_lag, r.size - 1)):
        rho = float(r[:-k] @ r[k:]) / var
        if rho <= 0.0:
            break
        factor += 2.0 * rho
    return factor


@cache
def _interval_sensitivities(steps: int, h: float, n_beta: int) -> ca.Function:
    """One shooting interval and its Jacobian in the start state and the base parameters."""
    x0, U = ca.MX.sym("x0", 4), ca.MX.sym("U", 2, steps)
    beta, pi_of_beta = ca.MX.sym("beta", n_beta), ca.MX.sym("P", len(STANDARD_NAMES), n_beta)
    pi0, fixed = ca.MX.sym("pi0", len(STANDARD_NAMES)), ca.MX.sym("fixed", len(FIXED_NAMES))
    X = ca.vec(rollout(steps, h)(x0, U, pi0 + pi_of_beta @ beta, fixed))
    return ca.Function(
        "oe_interval", [x0, U, beta, pi_of_beta, pi0, fixed], [X, ca.jacobian(X, ca.vertcat(x0, beta))],
        ["x0", "U", "beta", "P", "pi0", "fixed"], ["X", "J"],
    )  # fmt: skip


def fit_output_error(
    preps: Sequence[Prepared],
    base: BaseParameters,
    start: Mapping[str, float],
    fixed: Mapping[str, float],
    *,
    window: float = WINDOW,
    node_spacing: float = NODE_SPACING,
    max_iter: int = 12,
    progress: Callable[[int, float], None] | None = None,
) -> OutputErrorFit:
    """Refine the base parameters on measured angles by multiple shooting (see the module docstring).

    The solver is the generalized Gauss-Newton method of multiple-shooting parameter estimation
    (Bock): each iteration linearizes the angle residuals and the continuity conditions of every
    interval (CasADi's forward sensitivities of the RK4 rollout) and solves the equality-constrained
    linear least-squares problem as one sparse KKT system; a step is halved until the residual
    and the continuity gaps together decrease. Friction and rotor inertia stay non-negative
    (clipped). Measured: IPOPT with exact Hessians needed minutes per fit on the eight C.1
    records, with L-BFGS it had not converged after 60 iterations; Gauss-Newton converges in a few.

    Parameters
    ----------
    preps : sequence of Prepared
        Records to fit.
    base : BaseParameters
        The structure's identifiable combinations (:func:`pendulab.identify.regressor.base_parameters`).
    start : mapping of str to float
        Starting standard parameters (the regression's fit); the dependent ones stay as given.
    fixed : mapping of str to float
        Values of :data:`FIXED_NAMES`.
    window, node_spacing : float
        Window length and node spacing [s].
    max_iter : int, default 12
        Iteration limit.
    progress : callable, optional
        Called with the iteration number and the RMS angle error [rad] after each iteration.

    Returns
    -------
    OutputErrorFit
        Refined base parameters and their covariance.

    Raises
    ------
    RuntimeError
        The iteration produced non-finite values.
    """
    w = windows(preps, window, node_spacing)
    nb, n_int = len(base.independent), w.intervals
    # pi(beta) = pi0 + P beta: the independent columns carry beta, the dependent ones keep their start values.
    pi_start = np.array([float(start[n]) for n in STANDARD_NAMES])
    P = np.zeros((len(STANDARD_NAMES), nb))
    pi0 = pi_start.copy()
    for k, name in enumerate(base.independent):
        i = STANDARD_NAMES.index(name)
        P[i, k] = 1.0
        pi0[i] = 0.0
    dep = np.array([float(start[n]) for n in base.dependent])
    # beta = pi_ind + K pi_dep, so pi_ind = beta - K pi_dep: the offset goes into pi0.
    for k, name in enumerate(base.independent):
        pi0[STANDARD_NAMES.index(name)] = -(base.K[k] @ dep) if dep.size else 0.0
    beta = base.beta(start)
    lower = np.array([0.0 if n in ("Ir", "b1", "b2", "cf1", "cf2") else -np.inf for n in base.independent])
    fx = np.array([float(fixed[k]) for k in FIXED_NAMES])
    F = _interval_sensitivities(w.steps, w.h, nb).map(n_int, "thread", 2)
    Q = w.Q.reshape(2, n_int, w.steps).transpose(0, 2, 1)  # (2, steps, intervals)
    joins = np.array([k for k in range(n_int) if (k + 1) % w.nodes != 0])
    S = w.x0.copy()

    def evaluate(S: np.ndarray, beta: np.ndarray, jac: bool):
        X, J = F(S, w.U, beta, P, pi0, fx)
        Xs = np.asarray(X).reshape(w.steps, 4, n_int).transpose(1, 0, 2)  # (4, steps, intervals)
        r = (Xs[:2] - Q).transpose(2, 1, 0).reshape(n_int, -1)  # per interval: steps x 2, row-major
        gaps = Xs[:, -1, joins] - S[:, joins + 1]
        return r, gaps, (np.asarray(J).reshape(4 * w.steps, n_int, 4 + nb) if jac else None), Xs

    def merit(r: np.ndarray, gaps: np.ndarray) -> float:
        return float((r**2).mean() + 1e2 * (gaps**2).mean())

    r, gaps, J, _ = evaluate(S, beta, True)
    it = 0
    for it in range(1, max_iter + 1):
        H, b = _kkt(J, r, gaps, joins, w.steps, n_int, nb)
        delta = spla.spsolve(H, b)
        dS = delta[: 4 * n_int].reshape(n_int, 4).T
        dbeta = delta[4 * n_int : 4 * n_int + nb]
        m0, alpha = merit(r, gaps), 1.0
        while alpha > 1e-3:
            beta_new = np.maximum(beta + alpha * dbeta, lower)
            r_new, gaps_new, _, _ = evaluate(S + alpha * dS, beta_new, False)
            if np.isfinite(r_new).all() and merit(r_new, gaps_new) < m0:
                break
            alpha /= 2
        else:
            break
        S, beta = S + alpha * dS, beta_new
        r, gaps, J, _ = evaluate(S, beta, True)
        if not np.isfinite(J).all():
            raise RuntimeError("output-error fit: the simulation produced non-finite sensitivities")
        if progress is not None:
            progress(it, float(np.sqrt((r**2).mean())))
        if m0 - merit(r, gaps) < 1e-3 * m0:  # converged: the last step bought less than 0.1 % of the merit
            break
    # Covariance of beta (constrained least squares): s^2 times the beta block of the inverse KKT matrix.
    H, _ = _kkt(J, r, gaps, joins, w.steps, n_int, nb)
    lu = spla.splu(H.tocsc())
    n_var = 4 * n_int + nb
    block = np.column_stack([lu.solve(np.eye(H.shape[0])[:, 4 * n_int + k])[4 * n_int : n_var] for k in range(nb)])
    res = r.reshape(n_int, w.steps, 2)
    s2 = float((r**2).sum()) / max(1, r.size - n_var + len(joins) * 4)
    inflation = max(_autocorrelation_factor(res[:, :, j].ravel()) for j in range(2))
    cov = s2 * inflation * block
    pi = dict(zip(STANDARD_NAMES, (pi0 + P @ beta).tolist(), strict=True))
    rms = np.sqrt((res**2).mean(axis=(0, 1)))
    return OutputErrorFit(base=base, beta=beta, covariance=0.5 * (cov + cov.T), pi=pi, angle_rms=rms, iterations=it)


def _kkt(J: np.ndarray, r: np.ndarray, gaps: np.ndarray, joins: np.ndarray, steps: int, n_int: int, nb: int):
    """The Gauss-Newton KKT system ``[[J^T J, C^T], [C, 0]] [d; mu] = [-J^T r; -c]`` of multiple shooting."""
    n_var = 4 * n_int + nb
    rows_H, cols_H, vals_H = [], [], []
    g = np.zeros(n_var)
    ang = np.array([4 * s + j for s in range(steps) for j in range(2)])  # angle rows of vec(X), in r's order
    beta_cols = np.arange(4 * n_int, n_var)
    for i in range(n_int):
        Ji = J[ang, i, :]  # (2 steps, 4 + nb)
        cols = np.concatenate([np.arange(4 * i, 4 * i + 4), beta_cols])
        Hi = Ji.T @ Ji
        rr, cc = np.meshgrid(cols, cols, indexing="ij")
        rows_H.append(rr.ravel())
        cols_H.append(cc.ravel())
        vals_H.append(Hi.ravel())
        np.add.at(g, cols, Ji.T @ r[i])
    rows_C, cols_C, vals_C = [], [], []
    for c, i in enumerate(joins):
        end = J[4 * (steps - 1) : 4 * steps, i, :]  # d x_end / d (s_i, beta)
        cols = np.concatenate([np.arange(4 * i, 4 * i + 4), beta_cols])
        rr, cc = np.meshgrid(np.arange(4 * c, 4 * c + 4), cols, indexing="ij")
        rows_C += [rr.ravel(), np.arange(4 * c, 4 * c + 4)]
        cols_C += [cc.ravel(), np.arange(4 * (i + 1), 4 * (i + 1) + 4)]
        vals_C += [end.ravel(), -np.ones(4)]
    n_c = 4 * len(joins)
    Hm = sp.coo_matrix((np.concatenate(vals_H), (np.concatenate(rows_H), np.concatenate(cols_H))), shape=(n_var, n_var))
    Cm = sp.coo_matrix((np.concatenate(vals_C), (np.concatenate(rows_C), np.concatenate(cols_C))), shape=(n_c, n_var))
    reg = sp.identity(n_var) * 1e-12 * max(1.0, abs(Hm).max())
    K = sp.bmat([[Hm + reg, Cm.T], [Cm, None]]).tocsc()
    rhs = np.concatenate([-g, -gaps.T.ravel()])
    return K, rhs
