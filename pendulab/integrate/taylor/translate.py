"""Translate the model's CasADi ``rhs`` into a lean heyoka ODE system (:func:`translate`)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import casadi as ca
import numpy as np

from ...model.pycode import to_python
from .algebra import _ARITH_BINARY, _ARITH_UNARY, _N_SAMPLES, _ONE, _STRATEGIES, _UNARY, _Builder, _Coef, _Lin, _op_name
from .availability import heyoka_module


@dataclass(frozen=True)
class TaylorSystem:
    """A model's right-hand side as a heyoka ODE system with hoisted runtime parameters.

    Attributes
    ----------
    sys : list of (heyoka.expression, heyoka.expression)
        ``(state variable, derivative)`` pairs, in ``state_names`` order.
    state_names : tuple of str
        heyoka variable names.
    n_inputs : int
        Runtime parameters ``par[0:n_inputs]`` are the inputs ``u`` (zero-specialised ones are unused).
    n_derived : int
        Number of hoisted parameter coefficients, ``par[n_inputs:]``.
    coefficients : tuple of casadi.SX
        The hoisted coefficients as expressions of ``p`` (for inspection).
    cost : float
        Estimated cost of one Taylor step (convolutions + 0.1 x linear operations).
    strategy : str
        The rebuilding strategy that gave the lowest cost.
    derived : callable
        ``derived(p) -> ndarray`` of shape (n_derived,), the hoisted coefficients' values.
    """

    sys: list
    state_names: tuple[str, ...]
    n_inputs: int
    n_derived: int
    coefficients: tuple
    cost: float
    strategy: str
    derived: Callable[[Sequence[float]], np.ndarray] = field(repr=False)

    @cached_property
    def n_pars(self) -> int:
        """Runtime parameters the heyoka system has (the highest ``par`` index used + 1).

        Structural zeros can remove every use of the last parameters (e.g. both torques specialised to
        zero and no parameter coefficient left); heyoka sizes the system by the indices it sees.

        Returns
        -------
        int
            At most ``n_inputs + n_derived``.
        """
        return used_parameter_count([rhs for _, rhs in self.sys])

    def pars(self, u: Sequence[float], p: Sequence[float]) -> np.ndarray:
        """Runtime parameter vector of the heyoka system.

        Parameters
        ----------
        u : sequence of float, shape (n_inputs,)
            Torques [N.m].
        p : sequence of float
            Model parameter vector (``model.p``).

        Returns
        -------
        ndarray, shape (n_pars,)
            ``[u, derived(p)]``, cut to the parameters the system uses.
        """
        out = np.empty(self.n_inputs + self.n_derived)
        out[: self.n_inputs] = u
        out[self.n_inputs :] = self.derived(p)
        return out[: self.n_pars]


def used_parameter_count(expressions: Sequence[Any]) -> int:
    """Number of runtime parameters heyoka sees in ``expressions``: the highest ``par`` index + 1 (0 if none).

    Parameters
    ----------
    expressions : sequence of heyoka.expression
        Right-hand sides (and event functions).

    Returns
    -------
    int
    """
    hy = heyoka_module()
    return 1 + max((int(str(q)[1:]) for q in hy.get_params(list(expressions))), default=-1)


def translate(
    f: ca.Function,
    *,
    zero_params: Sequence[int] = (),
    zero_inputs: Sequence[int] = (),
    state_names: Sequence[str] | None = None,
) -> TaylorSystem:
    """Rebuild ``f(x, u, p) -> xdot`` (a CasADi SX Function) as a simplified heyoka ODE system.

    The graph is walked instruction by instruction once per rebuilding strategy; the
    result with the lowest estimated cost is returned (see the module docstring).

    Parameters
    ----------
    f : casadi.Function
        SX Function with dense vector inputs ``x`` (nx,), ``u`` (nu,), ``p`` (np,) and
        first output ``xdot`` (nx,).
    zero_params : sequence of int
        Indices of ``p`` specialised to the constant 0.
    zero_inputs : sequence of int
        Indices of ``u`` specialised to the constant 0.
    state_names : sequence of str, optional
        heyoka variable names (default ``x0, x1, ...``).

    Returns
    -------
    TaylorSystem

    Raises
    ------
    NotImplementedError
        The graph uses an operation with no heyoka counterpart here (the message names it).
    ValueError
        ``f`` is not an SX Function of three dense vector inputs with an output the size of ``x``.
    TaylorUnavailableError
        heyoka is not importable.
    """
    hy = heyoka_module()
    if not isinstance(f, ca.Function) or not f.is_a("SXFunction"):
        raise ValueError(f"translate needs a CasADi SX Function, got {type(f).__name__}")
    if f.n_in() != 3 or f.nnz_out(0) > f.nnz_in(0) or any(not f.sparsity_in(i).is_dense() for i in range(3)):
        raise ValueError("translate needs f(x, u, p) -> xdot with dense vector inputs and xdot the size of x")
    nx, nu, npar = (f.nnz_in(i) for i in range(3))
    names = tuple(state_names) if state_names is not None else tuple(f"x{i}" for i in range(nx))
    if len(names) != nx:
        raise ValueError(f"state_names must have {nx} entries, got {len(names)}")
    xs = list(hy.make_vars(*names)) if nx > 1 else [hy.make_vars(*names)]
    p_sym = ca.SX.sym("p", npar)
    # Log-uniform sample points in [0.5, 2]: the parameters are positive physical quantities.
    samples = np.exp(np.random.default_rng(20240611).uniform(np.log(0.5), np.log(2.0), (npar, _N_SAMPLES)))
    zero_p, zero_u = {int(i) for i in zero_params}, {int(i) for i in zero_inputs}
    params = [_Coef(p_sym[i], samples[i], samples[i]) for i in range(npar) if i not in zero_p]
    best: tuple[float, _Builder, list[Any]] | None = None
    for strategy in _STRATEGIES:
        b = _Builder(hy, nu, strategy, params)
        rhs = _walk(f, b, xs, p_sym, samples, zero_p, zero_u)
        cost = b.cost(rhs)
        if best is None or cost < best[0]:
            best = (cost, b, rhs)
    cost, b, rhs = best
    coefs = tuple(c.sx for c in b.coefs)
    fn = to_python(ca.Function("taylor_coefficients", [p_sym], [ca.vertcat(*coefs) if coefs else ca.SX(0, 1)]))
    n_der = len(coefs)

    def derived(p: Sequence[float]) -> np.ndarray:
        return np.asarray(fn(p), dtype=float).reshape(n_der)

    label = f"expand={b.strategy.expand}, reciprocal={b.strategy.reciprocal}"
    return TaylorSystem(list(zip(xs, rhs, strict=True)), names, nu, n_der, coefs, cost, label, derived)


def _walk(
    f: ca.Function, b: _Builder, xs: list[Any], p_sym: Any, samples: np.ndarray, zero_p: set[int], zero_u: set[int]
) -> list[Any]:
    """Replay the instructions of ``f`` with ``b``; the heyoka expressions of the dense output."""
    hy = b.hy
    nu, npar = f.nnz_in(1), f.nnz_in(2)
    leaves: list[list[_Lin]] = [
        [{(b.atom(v),): _ONE} for v in xs],
        [{} if i in zero_u else {(b.input_atom(i),): _ONE} for i in range(nu)],
        [{} if i in zero_p else {(): _Coef(p_sym[i], samples[i], samples[i])} for i in range(npar)],
    ]
    work: dict[int, _Lin] = {}
    outs: list[_Lin] = [{} for _ in range(f.nnz_out(0))]
    for k in range(f.n_instructions()):
        op = f.instruction_id(k)
        ins = f.instruction_input(k)
        o = f.instruction_output(k)
        if op == ca.OP_INPUT:
            work[o[0]] = leaves[ins[0]][ins[1]]
        elif op == ca.OP_OUTPUT:
            if o[0] == 0:
                outs[o[1]] = work[ins[0]]
        elif op == ca.OP_CONST:
            v = float(f.instruction_constant(k))
            work[o[0]] = {} if v == 0.0 else {(): _Coef.const(v)}
        elif op in _ARITH_UNARY or op in _UNARY:
            work[o[0]] = b.apply(op, [work[ins[0]]])
        elif op in _ARITH_BINARY:
            work[o[0]] = b.apply(op, [work[ins[0]], work[ins[1]]])
        else:
            raise NotImplementedError(f"translate: CasADi operation {_op_name(op)!r} has no heyoka counterpart here")
    rhs = [hy.expression(0.0)] * len(xs)
    for nz, r in enumerate(f.sparsity_out(0).row()):
        rhs[r] = b.materialize(outs[nz])
    return rhs
