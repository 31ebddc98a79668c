"""Fixed-step Runge-Kutta methods as CasADi one-step maps, iterated inside CasADi.

Each method is a Butcher tableau. The one-step map ``step(x, u, p, h) -> x+``
is built from ``model.functions["rhs"]`` on SX symbols (no new physics): the
explicit methods are plain SX expressions, the implicit ones solve their stage
equations with a Newton rootfinder (``fast_newton``, initial guess f(x) in
every stage). The step is then repeated with ``Function.mapaccum`` so a whole
run is one CasADi call (two when the interval count is not a multiple of the
block size), never a Python loop per step.

Step size and output grid: a fixed-step method takes ``n_sub = ceil(dt / h)``
equal steps of ``dt / n_sub <= h`` per output interval ``dt``, i.e. the
requested step is rounded *down* so that the output times are hit exactly (the
same rule as CasADi's ``rk``/``collocation`` in :func:`pendulab.simulate`,
where ``h`` is ``max_step``). Use :func:`integrate_fixed` to run with an exact
step ``h`` and record every ``record_every``-th step.

Methods (``FIXED_METHODS``):

=====================  =====  ========  ===============================================
name                   order  implicit  stability
=====================  =====  ========  ===============================================
``forward-euler``      1      no        unstable on every undamped oscillator
``rk4``                4      no        imaginary-axis limit h w < 2 sqrt(2) = 2.83
``implicit-euler``     1      yes       L-stable (damps fast modes)
``implicit-midpoint``  2      yes       A-stable, symplectic (Gauss, 1 stage)
``gauss4``             4      yes       A-stable, symplectic (Gauss-Legendre, 2 stages)
``radau3``             3      yes       L-stable (Radau IIA, 2 stages)
=====================  =====  ========  ===============================================
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import casadi as ca
import numpy as np

from ..model.model import model_functions
from .registry import DEFAULT_FIXED_STEP, MethodSpec, RunRequest, RunResult

__all__ = ["FixedMethod", "FIXED_METHODS", "METHOD_SPECS", "step_function", "integrate_fixed", "run_fixed", "IMAG_AXIS_LIMIT"]

_S3 = math.sqrt(3.0)


@dataclass(frozen=True)
class FixedMethod:
    """A Runge-Kutta method given by its Butcher tableau (A, b, c).

    Attributes
    ----------
    name : str
        Method name, the key in ``FIXED_METHODS``.
    A : tuple of tuple of float, shape (s, s)
        Stage coefficients; strictly lower triangular for an explicit method.
    b : tuple of float, shape (s,)
        Weights of the stage derivatives in the step.
    c : tuple of float, shape (s,)
        Stage times as fractions of the step.
    order : int
        Order of accuracy.
    description : str
        One line for tables and messages.
    """

    name: str
    A: tuple[tuple[float, ...], ...]
    b: tuple[float, ...]
    c: tuple[float, ...]
    order: int
    description: str

    @property
    def explicit(self) -> bool:
        """True when ``A`` is strictly lower triangular (no stage equations to solve)."""
        return all(self.A[i][j] == 0.0 for i in range(len(self.b)) for j in range(i, len(self.b)))

    @property
    def stages(self) -> int:
        """Number of stages s."""
        return len(self.b)


FIXED_METHODS: dict[str, FixedMethod] = {
    m.name: m
    for m in (
        FixedMethod("forward-euler", ((0.0,),), (1.0,), (0.0,), 1, "forward Euler, fixed step"),
        FixedMethod(
            "rk4",
            ((0, 0, 0, 0), (0.5, 0, 0, 0), (0, 0.5, 0, 0), (0, 0, 1.0, 0)),
            (1 / 6, 1 / 3, 1 / 3, 1 / 6),
            (0, 0.5, 0.5, 1.0),
            4,
            "classical Runge-Kutta 4, fixed step (CasADi mapaccum)",
        ),
        FixedMethod("implicit-euler", ((1.0,),), (1.0,), (1.0,), 1, "implicit (backward) Euler, fixed step, L-stable"),
        FixedMethod("implicit-midpoint", ((0.5,),), (1.0,), (0.5,), 2, "implicit midpoint (Gauss, 1 stage), symplectic"),
        FixedMethod(
            "gauss4",
            ((0.25, 0.25 - _S3 / 6), (0.25 + _S3 / 6, 0.25)),
            (0.5, 0.5),
            (0.5 - _S3 / 6, 0.5 + _S3 / 6),
            4,
            "Gauss-Legendre, 2 stages (order 4), fixed step, symplectic",
        ),
        FixedMethod(
            "radau3",
            ((5 / 12, -1 / 12), (0.75, 0.25)),
            (0.75, 0.25),
            (1 / 3, 1.0),
            3,
            "Radau IIA, 2 stages (order 3), fixed step, L-stable",
        ),
    )
}

#: Largest |h w| on the imaginary axis for which an explicit method is stable
#: (|R(i y)| <= 1); RK4: |R(iy)|^2 = 1 - y^6/72 + y^8/576 <= 1 iff y <= 2 sqrt(2).
IMAG_AXIS_LIMIT: dict[str, float] = {"forward-euler": 0.0, "rk4": 2.0 * math.sqrt(2.0)}

_BLOCK = 256  # steps per mapaccum block: building a mapaccum costs superlinear time in its length


def _tag(method: str) -> str:
    """CasADi-valid function-name fragment of a method name."""
    return method.replace("-", "_")


def _get_method(name: str) -> FixedMethod:
    if name not in FIXED_METHODS:
        raise ValueError(f"unknown fixed-step method {name!r}; expected one of {list(FIXED_METHODS)}")
    return FIXED_METHODS[name]


@lru_cache(maxsize=32)
def step_function(kind: str, method: str) -> ca.Function:
    """One step ``step(x, u, p, h) -> x+`` of a fixed-step method for a model kind.

    Parameters
    ----------
    kind : {"rigid", "elastic"}
        Model kind.
    method : str
        A key of ``FIXED_METHODS``.

    Returns
    -------
    casadi.Function
        Inputs x (nx,), u (2,) [N.m], p (np,), h [s]; output x after one step.

    Raises
    ------
    ValueError
        ``method`` is not a key of ``FIXED_METHODS``.
    """
    spec = _get_method(method)
    tag = _tag(method)
    f = model_functions(kind)["rhs"]
    nx, npar = f.size1_in(0), f.size1_in(2)
    s = spec.stages
    if spec.explicit:
        x, u, p, h = ca.SX.sym("x", nx), ca.SX.sym("u", 2), ca.SX.sym("p", npar), ca.SX.sym("h")
        K: list[ca.SX] = []
        for i in range(s):
            xi = x + h * sum((spec.A[i][j] * K[j] for j in range(i) if spec.A[i][j] != 0.0), ca.SX.zeros(nx))
            K.append(f(xi, u, p))
        xn = x + h * sum((spec.b[i] * K[i] for i in range(s)), ca.SX.zeros(nx))
        return ca.Function(f"{tag}_step", [x, u, p, h], [xn], ["x", "u", "p", "h"], ["xf"])
    # Implicit: residual in the stacked stage derivatives K (s*nx), parameters (x, u, p, h).
    Ks = ca.SX.sym("K", s * nx)
    x, u, p, h = ca.SX.sym("x", nx), ca.SX.sym("u", 2), ca.SX.sym("p", npar), ca.SX.sym("h")
    Kl = ca.vertsplit(Ks, nx)
    res = [Kl[i] - f(x + h * sum((spec.A[i][j] * Kl[j] for j in range(s)), ca.SX.zeros(nx)), u, p) for i in range(s)]
    G = ca.Function("G", [Ks, ca.vertcat(x, u, p, h)], [ca.vertcat(*res)])
    # Newton from K = f(x): converges in a few iterations even for h w >> 1 because
    # the stiff part is linear in the spring coordinates.
    rf = ca.rootfinder(
        f"{tag}_newton", "fast_newton", G, {"abstol": 1e-12, "abstolStep": 1e-14, "max_iter": 30, "error_on_fail": False}
    )
    xm, um, pm, hm = ca.MX.sym("x", nx), ca.MX.sym("u", 2), ca.MX.sym("p", npar), ca.MX.sym("h")
    Ksol = ca.vertsplit(rf(ca.repmat(f(xm, um, pm), s, 1), ca.vertcat(xm, um, pm, hm)), nx)
    xn = xm + hm * sum((spec.b[i] * Ksol[i] for i in range(s)), ca.MX.zeros(nx))
    return ca.Function(f"{tag}_step", [xm, um, pm, hm], [xn], ["x", "u", "p", "h"], ["xf"])


@lru_cache(maxsize=128)
def _repeat(kind: str, method: str, n: int) -> ca.Function:
    """``n`` steps with a constant input: ``F(x, u, p, h) -> x_n`` (built in blocks)."""
    step = step_function(kind, method)
    tag = _tag(method)
    if n == 1:
        return step
    x, u, p, h = (ca.MX.sym(nm, step.size1_in(i)) for i, nm in enumerate(("x", "u", "p", "h")))
    if n <= _BLOCK:
        xs = step.mapaccum(f"{tag}_x{n}", n)(x, ca.repmat(u, 1, n), p, h)
        return ca.Function(f"{tag}_rep{n}", [x, u, p, h], [xs[:, -1]])
    q, r = divmod(n, _BLOCK)
    block = _repeat(kind, method, _BLOCK)
    xq = block.mapaccum(f"{tag}_b{q}", q)(x, ca.repmat(u, 1, q), p, h)[:, -1] if q > 1 else block(x, u, p, h)
    xn = _repeat(kind, method, r)(xq, u, p, h) if r else xq
    return ca.Function(f"{tag}_rep{n}", [x, u, p, h], [xn])


@lru_cache(maxsize=128)
def _grid(kind: str, method: str, n_sub: int, n_int: int) -> ca.Function:
    """``n_int`` output intervals of ``n_sub`` steps: ``G(x0, U (2, n_int), p, h) -> X (nx, n_int)``."""
    interval = _repeat(kind, method, n_sub)
    tag = _tag(method)
    if n_int <= _BLOCK:
        return interval.mapaccum(f"{tag}_g{n_sub}_{n_int}", n_int)
    # Blocks of _BLOCK intervals, each returning (last state, all states), accumulated on the first output.
    x, p, h = ca.MX.sym("x", interval.size1_in(0)), ca.MX.sym("p", interval.size1_in(2)), ca.MX.sym("h")
    Ub = ca.MX.sym("U", 2, _BLOCK)
    Xb = interval.mapaccum("blk", _BLOCK)(x, Ub, p, h)
    block = ca.Function("block", [x, Ub, p, h], [Xb[:, -1], Xb])
    q, r = divmod(n_int, _BLOCK)
    U = ca.MX.sym("U", 2, n_int)
    _, Xq = block.mapaccum(f"{tag}_B{q}", q, 1)(x, U[:, : q * _BLOCK], p, h)
    parts = [Xq]
    if r:
        parts.append(_grid(kind, method, n_sub, r)(Xq[:, -1], U[:, q * _BLOCK :], p, h))
    return ca.Function(f"{tag}_g{n_sub}_{n_int}", [x, U, p, h], [ca.horzcat(*parts)])


def integrate_fixed(
    model: Any,
    method: str,
    x0: Any,
    h: float,
    n_steps: int,
    u: Any = None,
    *,
    record_every: int = 1,
) -> np.ndarray:
    """Take ``n_steps`` steps of exactly ``h`` with a fixed-step method.

    Parameters
    ----------
    model : Model
        Model to integrate, at its parameters.
    method : str
        A key of ``FIXED_METHODS``.
    x0 : array_like, shape (nx,)
        Initial state.
    h : float
        Step [s], > 0.
    n_steps : int
        Number of steps, a positive multiple of ``record_every``.
    u : array_like, shape (2,), optional
        Constant torques [N.m] (default zero).
    record_every : int, default 1
        Record the state every this many steps.

    Returns
    -------
    ndarray, shape (n_steps // record_every + 1, nx)
        States at t = 0, record_every h, ...; non-finite entries mean the method blew up.

    Raises
    ------
    ValueError
        Unknown ``method``; invalid ``x0`` or ``u``; ``h`` not a positive
        finite number; ``n_steps`` or ``record_every`` not a positive integer,
        or ``n_steps`` not a multiple of ``record_every``.
    """
    _get_method(method)
    x0 = model.check_state(x0, "x0")
    if not (isinstance(h, (int, float)) and math.isfinite(h) and h > 0):
        raise ValueError(f"h must be a positive finite step in s, got {h!r}")
    for name, val in (("n_steps", n_steps), ("record_every", record_every)):
        if not isinstance(val, (int, np.integer)) or val < 1:
            raise ValueError(f"{name} must be a positive integer, got {val!r}")
    if n_steps % record_every:
        raise ValueError(f"n_steps ({n_steps}) must be a multiple of record_every ({record_every})")
    uc = model.check_input(u, "u")
    n_int = n_steps // record_every
    G = _grid(model.kind, method, int(record_every), int(n_int))
    X = np.asarray(G(x0, np.tile(uc.reshape(2, 1), (1, n_int)), model.p, float(h))).T
    return np.vstack([x0, X])


def run_fixed(req: RunRequest) -> RunResult:
    """Runner of the fixed-step family; ``rtol``/``atol`` do not apply.

    Parameters
    ----------
    req : RunRequest
        A validated run; ``max_step`` is the step (default 1e-3 s), rounded down
        so that every output time is hit.

    Returns
    -------
    RunResult
        States, held inputs and the step count.

    Raises
    ------
    ValueError
        Options were given (the fixed-step methods take none).
    """
    model, t, spec = req.model, req.t, req.spec
    if req.options:
        raise ValueError(f"options {sorted(req.options)} are not supported by the fixed-step method {spec.name!r}")
    dt = float(t[1] - t[0])
    n_sub = max(1, math.ceil(dt / (req.max_step or DEFAULT_FIXED_STEP) - 1e-9))
    h = dt / n_sub
    n_int = req.n_intervals
    if req.schedule is not None:
        G = _grid(model.kind, spec.name, n_sub, n_int)
        X = np.vstack([req.x0, np.asarray(G(req.x0, req.schedule.T, model.p, h)).T])
        U = req.schedule
    else:
        F = _repeat(model.kind, spec.name, n_sub)
        X = np.empty((n_int + 1, model.nx))
        U = np.empty((n_int, model.nu))
        X[0] = req.x0
        for k in range(n_int):
            U[k] = req.feedback_input(float(t[k]), X[k])
            X[k + 1] = np.asarray(F(X[k], U[k], model.p, h)).ravel()
    method = FIXED_METHODS[spec.name]
    n_steps = n_int * n_sub
    stats = {"n_steps": n_steps, "n_rhs": method.stages * n_steps if method.explicit else None, "step": h}
    return RunResult(X, U, stats)


#: The fixed-step methods as registry entries.
METHOD_SPECS: tuple[MethodSpec, ...] = tuple(
    MethodSpec(name, "fixed", m.description, run_fixed, True) for name, m in FIXED_METHODS.items()
)
