"""The outputs ``y(x, u)`` of a Taylor run on its output grid, evaluated by a heyoka compiled function.

``simulate`` evaluates the model's outputs (positions, energy, stretches) at every output
time. For the Taylor family that evaluation was the largest part of the whole call after the
integration itself: element-wise NumPy over the columns costs ~0.1 ms for 1001 points of the
rigid model (one ufunc call per instruction of the graph), as much as a third of the
integration. Here the same CasADi graph ``outputs(x, u, p)`` is replayed instruction by
instruction as heyoka expressions (no simplification: the operations and their order are the
graph's, so results equal :meth:`~pendulab.model.model.Model.outputs` to the rounding of
the elementary functions) and compiled once per model kind and process into a
``heyoka.cfunc`` evaluated in SIMD batch mode (~10-20 us for the same 1001 points). The first
call of a kind in a process still uses NumPy (:data:`COMPILE_AFTER`): a single run would not
repay the compilation (~0.03-0.1 s; heyoka's on-disk JIT cache shortens it in later processes).

Inputs ``u`` and parameters ``p`` are runtime parameters of the compiled function, so
``model.with_params(...)`` never recompiles. A graph with an operation that has no heyoka
counterpart here gives no evaluator (:func:`output_evaluator` returns None) and the caller keeps
``model.outputs``.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

import casadi as ca
import numpy as np

from ...model.model import model_functions
from .availability import heyoka_module

__all__ = ["OutputEvaluator", "output_evaluator", "grid_outputs"]

#: Binary CasADi operations and their heyoka counterparts (same operation, same operand order).
_BINARY: dict[int, Callable[[Any, Any, Any], Any]] = {
    ca.OP_ADD: lambda hy, a, b: a + b,
    ca.OP_SUB: lambda hy, a, b: a - b,
    ca.OP_MUL: lambda hy, a, b: a * b,
    ca.OP_DIV: lambda hy, a, b: a / b,
    ca.OP_POW: lambda hy, a, b: a**b,
    ca.OP_CONSTPOW: lambda hy, a, b: a**b,
    ca.OP_ATAN2: lambda hy, a, b: hy.atan2(a, b),
}
#: Unary CasADi operations: arithmetic ones, then elementary functions by their heyoka name.
_UNARY: dict[int, Callable[[Any, Any], Any]] = {
    ca.OP_ASSIGN: lambda hy, a: a,
    ca.OP_NEG: lambda hy, a: -a,
    ca.OP_TWICE: lambda hy, a: 2.0 * a,
    ca.OP_SQ: lambda hy, a: a * a,
    ca.OP_INV: lambda hy, a: 1.0 / a,
}
_FUNCTIONS = {
    ca.OP_SQRT: "sqrt",
    ca.OP_SIN: "sin",
    ca.OP_COS: "cos",
    ca.OP_TAN: "tan",
    ca.OP_EXP: "exp",
    ca.OP_LOG: "log",
    ca.OP_ASIN: "asin",
    ca.OP_ACOS: "acos",
    ca.OP_ATAN: "atan",
    ca.OP_SINH: "sinh",
    ca.OP_COSH: "cosh",
    ca.OP_TANH: "tanh",
}


class OutputEvaluator:
    """A model kind's outputs ``y(x, u, p)`` compiled as a heyoka ``cfunc`` (batch mode over the points).

    Parameters
    ----------
    f : casadi.Function
        SX Function ``outputs(x, u, p) -> y`` with dense vector inputs.

    Raises
    ------
    NotImplementedError
        The graph uses an operation with no heyoka counterpart here.
    TaylorUnavailableError
        heyoka is not importable.
    """

    def __init__(self, f: ca.Function) -> None:
        hy = heyoka_module()
        self.nx, self.nu, self.np = (f.nnz_in(i) for i in range(3))
        sp = f.sparsity_out(0)
        self.ny = sp.size1() * sp.size2()
        self.rows = np.asarray(sp.row(), dtype=int) if sp.is_column() else np.asarray(sp.find(), dtype=int)
        xs = list(hy.make_vars(*(f"x{i}" for i in range(self.nx))))
        # Runtime parameters: only the inputs and model parameters the graph reads, numbered as first read
        # (the batch evaluation reads every parameter row at every point: the rigid energy reads 11 of 2 + 15).
        self.par_rows: list[tuple[int, int]] = []  # (1 for u or 2 for p, index) of par[0], par[1], ...
        pars_of: dict[tuple[int, int], Any] = {}

        def leaf(group: int, index: int) -> Any:
            if group == 0:
                return xs[index]
            if (group, index) not in pars_of:
                pars_of[group, index] = hy.par[len(self.par_rows)]
                self.par_rows.append((group, index))
            return pars_of[group, index]

        work: dict[int, Any] = {}
        outs: list[Any] = [hy.expression(0.0)] * f.nnz_out(0)
        for k in range(f.n_instructions()):
            op = f.instruction_id(k)
            ins = f.instruction_input(k)
            o = f.instruction_output(k)
            if op == ca.OP_INPUT:
                work[o[0]] = leaf(ins[0], ins[1])
            elif op == ca.OP_OUTPUT:
                if o[0] == 0:
                    outs[o[1]] = work[ins[0]]
            elif op == ca.OP_CONST:
                work[o[0]] = hy.expression(float(f.instruction_constant(k)))
            elif op in _BINARY:
                work[o[0]] = _BINARY[op](hy, work[ins[0]], work[ins[1]])
            elif op in _UNARY:
                work[o[0]] = _UNARY[op](hy, work[ins[0]])
            elif op in _FUNCTIONS:
                work[o[0]] = getattr(hy, _FUNCTIONS[op])(work[ins[0]])
            else:
                raise NotImplementedError(f"outputs: CasADi operation id {op} has no heyoka counterpart here")
        self.n_pars = len(self.par_rows)
        self._u_rows = [row for row, (group, _) in enumerate(self.par_rows) if group == 1]
        self._u_cols = [index for group, index in self.par_rows if group == 1]
        self._p_rows = [row for row, (group, _) in enumerate(self.par_rows) if group == 2]
        self._p_cols = [index for group, index in self.par_rows if group == 2]
        self.cfunc = hy.cfunc(outs, xs)
        self._last_unforced: tuple[tuple[bytes, int], np.ndarray] | None = None

    def __call__(self, X: np.ndarray, U: np.ndarray, p: np.ndarray) -> np.ndarray:
        """The outputs at ``N`` points.

        Parameters
        ----------
        X : ndarray, shape (N, nx)
            States.
        U : ndarray, shape (N, nu)
            Inputs [N.m].
        p : ndarray, shape (np,)
            Model parameters.

        Returns
        -------
        ndarray, shape (N, ny)
            The outputs (a transposed view of a (ny, N) array, as ``model.outputs`` returns them).
        """
        n = len(X)
        p = np.asarray(p, dtype=float)
        if self._u_cols and U[:, self._u_cols].any():
            pars = np.empty((self.n_pars, n))
            pars[self._u_rows] = U.T[self._u_cols]
            # Every point has the same model parameters: one column broadcast along the points.
            pars[self._p_rows] = p[self._p_cols, None]
        else:
            pars = self._unforced_pars(p, n)
        XT = np.ascontiguousarray(X.T)
        y = self.cfunc(XT, pars=pars) if self.n_pars else self.cfunc(XT)
        if len(self.rows) == self.ny:
            return y.T
        dense = np.zeros((self.ny, n))
        dense[self.rows] = y
        return dense.T

    def _unforced_pars(self, p: np.ndarray, n: int) -> np.ndarray:
        """The parameter array of ``n`` points without torques, kept from the last call of the same ``p`` and ``n``.

        Writing it costs as much as the evaluation itself (11 rows of 1001 points for the rigid model against
        ~14 us); free motion asks for the same one again and again. Read-only, so threads may share it.
        """
        key = (p.tobytes(), n)
        last = self._last_unforced
        if last is not None and last[0] == key:
            return last[1]
        pars = np.zeros((self.n_pars, n))
        pars[self._p_rows] = p[self._p_cols, None]
        pars.setflags(write=False)
        self._last_unforced = (key, pars)
        return pars


_EVALUATORS: dict[str, OutputEvaluator | None] = {}
_LOCK = threading.Lock()
#: Grid evaluations per model kind before the evaluator is compiled. Compiling costs ~0.03-0.1 s (less on a hit
#: in heyoka's disk cache) and saves ~0.1-0.2 ms per call: a process that simulates once (a CLI command) keeps
#: NumPy, one that simulates again (a sweep, a benchmark) compiles on its second call.
COMPILE_AFTER = 1
_CALLS: dict[str, int] = {}


def output_evaluator(kind: str) -> OutputEvaluator | None:
    """The compiled outputs of model ``kind`` (compiled once per process), or None when not translatable.

    Parameters
    ----------
    kind : {"rigid", "elastic"}
        Model kind.

    Returns
    -------
    OutputEvaluator or None

    Raises
    ------
    TaylorUnavailableError
        heyoka is not importable.
    """
    if kind in _EVALUATORS:
        return _EVALUATORS[kind]
    with _LOCK:
        if kind not in _EVALUATORS:
            try:
                _EVALUATORS[kind] = OutputEvaluator(model_functions(kind)["outputs"])
            except NotImplementedError:  # an operation heyoka lacks: the caller keeps model.outputs
                _EVALUATORS[kind] = None
    return _EVALUATORS[kind]


def grid_outputs(model: Any, X: np.ndarray, U: np.ndarray) -> np.ndarray:
    """``model.outputs(X, U)`` on a run's grid, through the compiled evaluator from the second call of a kind on.

    Parameters
    ----------
    model : Model
        The pendulum of the run.
    X : ndarray, shape (N, nx)
        States on the grid (finite: a finished run).
    U : ndarray, shape (N, nu)
        Inputs held at the grid times [N.m].

    Returns
    -------
    ndarray, shape (N, ny)
        Outputs in ``model.output_names`` order.
    """
    kind = model.kind
    if kind not in _EVALUATORS:
        calls = _CALLS.get(kind, 0)
        if calls < COMPILE_AFTER:
            _CALLS[kind] = calls + 1
            return model.outputs(X, U)
    evaluate = output_evaluator(kind)
    if evaluate is None:
        return model.outputs(X, U)
    return evaluate(X, U, model.p)
