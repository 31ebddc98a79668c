"""Transcriptions of a :class:`SwingUpProblem` into an IPOPT nonlinear program.

Two interchangeable families, one interface (:class:`Transcription`):

* direct collocation (``"radau"``, ``"legendre"``; polynomial degree ``d``),
  one polynomial per interval, defects at the ``d`` collocation points;
* multiple shooting with a CasADi integrator (``"shooting"``; ``rk`` by
  default, or ``cvodes``) from each grid state over one interval.

Controls are piecewise constant on the ``N`` intervals (the same zero-order
hold the controller and the co-simulation master use), so both families
discretise the same continuous problem and agree as their accuracy improves.

The mesh may be non-uniform: interval ``k`` has length ``T * mesh[k]`` with
positive fractions summing to one (a uniform mesh is ``mesh[k] = 1 / N``).

The NLP is built once per structure (model kind, method, N, degree, free or
fixed horizon, integrator, objective, IPOPT options) and cached: model
parameters, the fixed horizon, the time weight and the mesh fractions are NLP
parameters; start, goal, torque and state limits are variable bounds.
Homotopies, randomized starts and mesh refinements that keep N therefore
re-solve the same compiled NLP with different parameters, bounds and warm
starts. Only h-refinement is offered (one collocation degree for all
intervals): a per-interval degree would make the structure depend on the
degree pattern, i.e. a new NLP build (~1 s) at every refinement.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import casadi as ca
import numpy as np

from ..._checks import bounded_int
from ...model.model import model_functions
from .iterations import IterationCallback, notify_build
from .problem import DEFAULT_INTERVALS, INTERVALS_WHY, MAX_INTERVALS, SwingUpProblem

__all__ = ["Transcription", "TRANSCRIPTIONS", "get_transcription", "COLLOCATION", "SHOOTING", "MAX_INTERVALS"]

COLLOCATION: tuple[str, ...] = ("radau", "legendre")
SHOOTING: tuple[str, ...] = ("shooting",)
TRANSCRIPTIONS: tuple[str, ...] = COLLOCATION + SHOOTING
_INTEGRATORS = ("cvodes", "rk")
#: Weight of the effort regulariser in the "time" objective [1/(N^2.m^2)].
_TIME_REGULARISER = 1e-3
#: Largest expanded collocation graph (model instructions x intervals x degree) built as one SX NLP; above it
#: the NLP stays MX around the mapped interval (build time linear in nothing but the interval).
_EXPAND_INSTRUCTIONS = 200_000


@dataclass(frozen=True)
class Transcription:
    """A compiled NLP of one problem structure.

    Attributes
    ----------
    method, N, degree, integrator, free_horizon, objective, kind
        The structure this NLP was built for.
    solver : casadi.Function
        IPOPT ``nlpsol``.
    nx, nw : int
        State size and number of decision variables.
    n_states : int
        Number of state columns in the decision vector: N + 1 grid states,
        plus ``N * degree`` collocation states for collocation.
    build_time : float
        Wall time spent building the NLP [s].
    callback : IterationCallback or None
        The NLP's IPOPT ``iteration_callback`` (:mod:`.iterations`), kept alive with the solver.
    joint_rows : int
        Constraint rows after the equalities bounding the elbow joint rate ``omega2 - omega1`` of every state column
        (0 without a ``velocity_limit``; :meth:`SwingUpProblem.state_bounds` boxes ``omega1``).
    """

    method: str
    N: int
    degree: int
    integrator: str
    free_horizon: bool
    objective: str
    kind: str
    solver: ca.Function
    nx: int
    nw: int
    build_time: float
    callback: Any = None
    joint_rows: int = 0

    @property
    def n_coll(self) -> int:
        return self.N * self.degree if self.method in COLLOCATION else 0

    # -- decision vector layout: [X (nx, N+1) | Xc (nx, N*d) | U (2, N) | T] ----------
    def split(self, w: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, float | None]:
        """Split a decision vector into its blocks.

        Parameters
        ----------
        w : array_like, shape (nw,)
            Decision vector laid out as ``[X | Xc | U | T]`` (T only with a
            free horizon).

        Returns
        -------
        X : ndarray, shape (N + 1, nx)
            Grid states.
        Xc : ndarray, shape (N * degree, nx)
            Collocation states (zero rows for shooting).
        U : ndarray, shape (N, 2)
            Held torques (tau1, tau2) [N.m].
        T : float or None
            Horizon [s] when free, else None.
        """
        nx, N = self.nx, self.N
        w = np.asarray(w, dtype=float).ravel()
        i = nx * (N + 1)
        X = w[:i].reshape(N + 1, nx)
        j = i + nx * self.n_coll
        Xc = w[i:j].reshape(self.n_coll, nx)
        k = j + 2 * N
        U = w[j:k].reshape(N, 2)
        T = float(w[k]) if self.free_horizon else None
        return X, Xc, U, T

    def join(self, X: np.ndarray, Xc: np.ndarray, U: np.ndarray, T: float | None) -> np.ndarray:
        """Assemble a decision vector from its blocks (the inverse of :meth:`split`).

        Parameters
        ----------
        X : array_like, shape (N + 1, nx)
            Grid states.
        Xc : array_like, shape (N * degree, nx)
            Collocation states (empty for shooting).
        U : array_like, shape (N, 2)
            Held torques (tau1, tau2) [N.m].
        T : float or None
            Horizon [s]; appended only with a free horizon.

        Returns
        -------
        ndarray, shape (nw,)
            ``[X | Xc | U | T]``, each block flattened row by row.
        """
        parts = [np.ravel(X), np.ravel(Xc), np.ravel(U)]
        if self.free_horizon:
            parts.append([float(T)])
        return np.concatenate(parts)

    def collocation_times(self) -> np.ndarray:
        """Collocation points within the unit interval.

        Returns
        -------
        ndarray, shape (degree,)
            CasADi's Radau or Legendre points in (0, 1] for ``method``.
        """
        return np.array(ca.collocation_points(self.degree, self.method))

    def bounds(
        self, problem: SwingUpProblem, torque_lb: np.ndarray, torque_ub: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Variable and constraint bounds for one problem.

        Start and goal fix the first and last grid states; state bounds apply
        to the other grid and collocation states.

        Parameters
        ----------
        problem : SwingUpProblem
            Start, goal, state bounds and horizon bounds.
        torque_lb, torque_ub : ndarray, shape (2,)
            Bounds on (tau1, tau2) [N.m] on every interval.

        Returns
        -------
        lbx, ubx : ndarray, shape (nw,)
            Decision-variable bounds.
        lbg, ubg : ndarray
            Zeros for the equalities (defects, continuity), then +-``velocity_limit`` on the elbow joint rate of
            each state column (:attr:`joint_rows`).
        """
        nx, N = self.nx, self.N
        slb, sub = problem.state_bounds()
        XL = np.tile(slb, (N + 1, 1))
        XU = np.tile(sub, (N + 1, 1))
        XL[0] = XU[0] = problem.start
        XL[-1] = XU[-1] = problem.target
        lbx = self.join(XL, np.tile(slb, (self.n_coll, 1)), np.tile(torque_lb, (N, 1)), problem.horizon_bounds[0])
        ubx = self.join(XU, np.tile(sub, (self.n_coll, 1)), np.tile(torque_ub, (N, 1)), problem.horizon_bounds[1])
        ng = nx * N * (self.degree + 1) if self.method in COLLOCATION else nx * N
        vmax = np.inf if problem.velocity_limit is None else problem.velocity_limit
        lbg = np.concatenate([np.zeros(ng), np.full(self.joint_rows, -vmax)])
        return lbx, ubx, lbg, -lbg

    def fractions(self, mesh: Any = None) -> np.ndarray:
        """Checked interval fractions of a mesh.

        Parameters
        ----------
        mesh : array_like, shape (N,), or None
            Positive relative interval lengths (normalised to sum 1 here);
            None = uniform.

        Returns
        -------
        ndarray, shape (N,)
            Interval lengths as fractions of the horizon, summing to 1.

        Raises
        ------
        ValueError
            A mesh of the wrong length or with non-positive or non-finite entries.
        """
        if mesh is None:
            return np.full(self.N, 1.0 / self.N)
        frac = np.asarray(mesh, dtype=float)
        if frac.shape != (self.N,):
            raise ValueError(f"mesh must hold N = {self.N} interval fractions, got shape {frac.shape}")
        if not np.all(np.isfinite(frac)) or np.any(frac <= 0.0):
            raise ValueError("mesh interval fractions must be positive and finite")
        return frac / frac.sum()

    def grid(self, T: float, mesh: Any = None) -> np.ndarray:
        """Grid times of a mesh.

        Parameters
        ----------
        T : float
            Horizon [s].
        mesh : array_like, shape (N,), or None
            Interval fractions (see :meth:`fractions`); None = uniform.

        Returns
        -------
        ndarray, shape (N + 1,)
            ``0 = t_0 < ... < t_N = T`` [s] (the last point exactly T).
        """
        t = T * np.concatenate([[0.0], np.cumsum(self.fractions(mesh))])
        t[-1] = T
        return t

    def parameters(self, problem: SwingUpProblem, mesh: Any = None) -> np.ndarray:
        """NLP parameter vector of one problem.

        Parameters
        ----------
        problem : SwingUpProblem
            Gives the model parameters, the horizon and the time weight.
        mesh : array_like, shape (N,), or None
            Interval fractions (see :meth:`fractions`); None = uniform.

        Returns
        -------
        ndarray, shape (n_p + 2 + N,)
            ``[model.p, horizon [s], time_weight, interval fractions]``.
        """
        return np.concatenate([problem.model.p, [problem.horizon, problem.time_weight], self.fractions(mesh)])

    def solve(
        self, problem: SwingUpProblem, w0: np.ndarray, torque_lb: np.ndarray, torque_ub: np.ndarray, mesh: Any = None
    ) -> dict[str, Any]:
        """Run IPOPT from ``w0`` with the bounds of :meth:`bounds`.

        Parameters
        ----------
        problem : SwingUpProblem
            Bounds and NLP parameters.
        w0 : ndarray, shape (nw,)
            Initial guess; clipped into the variable bounds first.
        torque_lb, torque_ub : ndarray, shape (2,)
            Bounds on (tau1, tau2) [N.m].
        mesh : array_like, shape (N,), or None
            Interval fractions (see :meth:`fractions`); None = uniform.

        Returns
        -------
        dict
            ``w`` (solution, shape (nw,)), ``f`` (objective), ``g`` (each constraint's
            violation: its distance outside its bounds, 0 when kept) and ``stats`` (the solver's ``stats()``).
        """
        lbx, ubx, lbg, ubg = self.bounds(problem, torque_lb, torque_ub)
        # IPOPT needs a start within the bounds it treats as hard (fixed start and goal).
        w0 = np.clip(w0, lbx, ubx)
        out = self.solver(x0=w0, p=self.parameters(problem, mesh), lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg)
        g = np.asarray(out["g"]).ravel()
        return {
            "w": np.asarray(out["x"]).ravel(),
            "f": float(out["f"]),
            "g": np.maximum(np.maximum(lbg - g, g - ubg), 0.0),
            "stats": self.solver.stats(),
        }


def _check_structure(method: str, N: int, degree: int, integrator: str) -> None:
    if method not in TRANSCRIPTIONS:
        raise ValueError(f"method must be one of {list(TRANSCRIPTIONS)}, got {method!r}")
    if isinstance(N, float) or not isinstance(N, (int, np.integer)):
        raise ValueError(f"N (number of intervals) must be an integer >= 2, got {N!r}")
    bounded_int("N", N, low=2, high=MAX_INTERVALS, why=INTERVALS_WHY)
    if method in COLLOCATION and not (isinstance(degree, (int, np.integer)) and 1 <= degree <= 9):
        raise ValueError(f"degree must be an integer in 1..9 for collocation, got {degree!r}")
    if method in SHOOTING and integrator not in _INTEGRATORS:
        raise ValueError(f"integrator must be one of {list(_INTEGRATORS)} for multiple shooting, got {integrator!r}")


def get_transcription(
    problem: SwingUpProblem,
    method: str = "radau",
    N: int = DEFAULT_INTERVALS,
    degree: int = 3,
    integrator: str = "rk",
    ipopt_options: dict[str, Any] | None = None,
) -> Transcription:
    """The (cached) compiled NLP for a problem's structure.

    Parameters
    ----------
    problem : SwingUpProblem
    method : {"radau", "legendre", "shooting"}
    N : int
        Number of control intervals.
    degree : int
        Collocation polynomial degree (ignored for shooting).
    integrator : {"rk", "cvodes"}
        Integrator of multiple shooting (ignored for collocation): ``rk`` =
        CasADi's fixed-step RK4, 4 steps per interval, exact Hessian (fast);
        ``cvodes`` = adaptive BDF at 1e-10 with a quasi-Newton Hessian (slow,
        minutes for N = 40).
    ipopt_options : dict or None
        Extra IPOPT options (e.g. ``{"max_iter": 500}``).

    Returns
    -------
    Transcription
        Built on the first call for this structure, then reused (up to 64
        structures cached).

    Raises
    ------
    ValueError
        Unknown method or integrator, N < 2, or a collocation degree outside 1..9.
    """
    _check_structure(method, N, degree, integrator)
    extra = tuple(sorted((ipopt_options or {}).items()))
    return _build(
        problem.model.kind,
        method,
        int(N),
        int(degree) if method in COLLOCATION else 0,
        integrator,
        problem.free_horizon,
        problem.objective,
        extra,
        problem.velocity_limit is not None,
    )


@lru_cache(maxsize=64)
def _build(
    kind: str, method: str, N: int, degree: int, integrator: str, free: bool, objective: str, extra: tuple, joint_bound: bool
) -> Transcription:
    notify_build(f"{method} N={N}" + (f" degree {degree}" if method in COLLOCATION else "") + f", {kind} model")
    t_start = time.perf_counter()
    f = model_functions(kind)["rhs"]
    nx = f.size1_in(0)
    npar = f.size1_in(2)
    # Collocation of a small graph: everything SX, expanded (the fastest iterations). A large one (the elastic
    # model at a high degree) stays MX around the mapped interval Function: expanding it took 21-26 s for the
    # elastic radau N=156 degree 7 NLP against 0.5-0.9 s unexpanded, at the same time per IPOPT iteration
    # (MUMPS dominates there). Shooting: MX variables around a mapped interval Function.
    expand = method in COLLOCATION and f.n_instructions() * N * degree <= _EXPAND_INSTRUCTIONS
    SX = ca.SX if expand else ca.MX
    X = SX.sym("X", nx, N + 1)
    U = SX.sym("U", 2, N)
    # Parameters: model, fixed horizon, time weight, then the N interval fractions of the mesh
    # (so a re-meshed problem with the same N reuses this NLP).
    P = SX.sym("P", npar + 2 + N)
    pm, T_fixed, w_time = P[:npar], P[npar], P[npar + 1]
    T = SX.sym("T") if free else T_fixed
    h = T * P[npar + 2 :].T  # (1, N) interval lengths [s]
    if method in COLLOCATION:
        Xc = SX.sym("Xc", nx, N * degree)
        defects, x_end = _collocation_maps(kind, method, degree, N)(X[:, :N], ca.reshape(Xc, nx * degree, N), U, h, pm)
        g = ca.vertcat(ca.vec(defects), ca.vec(X[:, 1:] - x_end))
        w_parts = [ca.vec(X), ca.vec(Xc), ca.vec(U)]
    else:
        Fmap = _shooting_map(kind, integrator, N)
        x_end = Fmap(X[:, :N], U, h, pm)
        g = ca.vec(X[:, 1:] - x_end)
        w_parts = [ca.vec(X), ca.vec(U)]
    joint_rows = 0
    if joint_bound:  # the elbow joint's rate of every state column (the shoulder's is omega1 itself: a box)
        cols = ca.horzcat(X, Xc) if method in COLLOCATION else X
        nq = nx // 2
        g = ca.vertcat(g, (cols[nq + 1, :] - cols[nq, :]).T)
        joint_rows = cols.size2()
    if free:
        w_parts.append(T)
    effort = ca.dot(h.T, ca.sum1(U**2).T)
    J = {"effort": effort, "time": T + _TIME_REGULARISER * effort, "mix": w_time * T + effort}[objective]
    nlp = {"x": ca.vertcat(*w_parts), "f": J, "g": g, "p": P}
    ipopt = {"print_level": 0, "sb": "yes", "max_iter": 1000, "tol": 1e-8, "acceptable_tol": 1e-6, "mu_strategy": "adaptive"}
    ipopt.update(dict(extra))
    opts: dict[str, Any] = {"ipopt": ipopt, "print_time": False, "error_on_fail": False}
    if expand:
        opts["expand"] = True
    elif method in SHOOTING and integrator == "cvodes":
        # CVODES cannot give exact second derivatives cheaply: quasi-Newton Hessian.
        ipopt.setdefault("hessian_approximation", "limited-memory")
    nw = nlp["x"].numel()
    # Progress, budgets and prompt interrupts (.iterations); kept alive by the Transcription.
    callback = IterationCallback(f"swingup_iter_{method}_{kind}_{N}", nw, g.numel(), P.numel())
    opts["iteration_callback"] = callback
    solver = ca.nlpsol(f"swingup_{method}_{kind}_{N}", "ipopt", nlp, opts)
    return Transcription(
        method,
        N,
        degree,
        integrator,
        free,
        objective,
        kind,
        solver,
        nx,
        nw,
        time.perf_counter() - t_start,
        callback,
        joint_rows,
    )


def _collocation_maps(kind: str, scheme: str, d: int, N: int) -> ca.Function:
    """One collocation interval as a Function, mapped over the N intervals.

    Inputs: x_k (nx,), Xc (nx*d,) collocation states, u_k (2,), h [s], p.
    Outputs: defects (nx*d,) = h f(Xc_j) - dp/dtau(tau_j), end state (nx,).
    """
    f = model_functions(kind)["rhs"]
    nx = f.size1_in(0)
    tau = np.append(0.0, ca.collocation_points(d, scheme))
    C = np.zeros((d + 1, d + 1))  # C[r, j]: derivative of Lagrange basis r at tau_j
    D = np.zeros(d + 1)  # D[r]: Lagrange basis r at tau = 1
    for r in range(d + 1):
        coeffs = np.array([1.0])
        for s in range(d + 1):
            if s != r:
                coeffs = np.convolve(coeffs, [1.0, -tau[s]]) / (tau[r] - tau[s])
        D[r] = np.polyval(coeffs, 1.0)
        dcoeffs = np.polyder(coeffs)
        C[r] = np.polyval(dcoeffs, tau)
    xk = ca.SX.sym("xk", nx)
    xc = ca.SX.sym("xc", nx, d)
    u = ca.SX.sym("u", 2)
    h = ca.SX.sym("h")
    p = ca.SX.sym("p", f.size1_in(2))
    pts = ca.horzcat(xk, xc)
    dx = ca.mtimes(pts, C[:, 1:])  # (nx, d): dp/dtau at the collocation points
    fx = f.map(d)(xc, ca.repmat(u, 1, d), p)
    defects = h * fx - dx
    x_end = ca.mtimes(pts, D)
    one = ca.Function("coll_interval", [xk, ca.vec(xc), u, h, p], [ca.vec(defects), x_end])
    return one.map(N)


def _shooting_map(kind: str, plugin: str, N: int) -> ca.Function:
    """Integrator over one interval (time scaled to [0, 1]), mapped over N intervals."""
    f = model_functions(kind)["rhs"]
    nx, npar = f.size1_in(0), f.size1_in(2)
    x, u, h, p = ca.SX.sym("x", nx), ca.SX.sym("u", 2), ca.SX.sym("h"), ca.SX.sym("p", npar)
    dae = {"x": x, "p": ca.vertcat(u, h, p), "ode": h * f(x, u, p)}
    if plugin == "cvodes":
        opts = {"abstol": 1e-10, "reltol": 1e-10, "max_num_steps": 100000}
    else:
        opts = {"number_of_finite_elements": 4, "simplify": True}
    F = ca.integrator("ms_step", plugin, dae, 0.0, 1.0, opts)
    # rk: one interval expands to SX (exact Hessian, one small Function mapped N times);
    # cvodes stays MX (its sensitivities come from CVODES itself).
    Sym = ca.MX if plugin == "cvodes" else ca.SX
    xk, uk, hk, pk = Sym.sym("xk", nx), Sym.sym("uk", 2), Sym.sym("hk"), Sym.sym("pk", npar)
    xf = F(x0=xk, p=ca.vertcat(uk, hk, pk))["xf"]
    one = ca.Function("ms_interval", [xk, uk, hk, pk], [xf])
    return one.map(N)
