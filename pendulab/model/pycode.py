"""Translate a CasADi SX Function into a plain-Python (``math``) function.

SciPy's explicit integrators call the right-hand side once per stage from
Python; a CasADi Function call costs ~20 us of overhead there, while the
straight-line Python generated here from the *same* SX graph costs a few us.
The equations are still derived symbolically, never typed by hand.
"""

from __future__ import annotations

from collections.abc import Callable

import casadi as ca
import numpy as np

__all__ = ["to_python"]

# Element-wise (NumPy) versions of the templates that are scalar-only in plain Python.
_VECTOR = {
    ca.OP_FMIN: "_np.minimum({0}, {1})",
    ca.OP_FMAX: "_np.maximum({0}, {1})",
    ca.OP_LT: "(({0} < {1}) * 1.0)",
    ca.OP_LE: "(({0} <= {1}) * 1.0)",
    ca.OP_EQ: "(({0} == {1}) * 1.0)",
    ca.OP_NE: "(({0} != {1}) * 1.0)",
    ca.OP_IF_ELSE_ZERO: "_np.where({0}, {1}, 0.0)",
    ca.OP_SIGN: "_np.sign({0})",
}

_BINARY = {
    ca.OP_ADD: "{0} + {1}",
    ca.OP_SUB: "{0} - {1}",
    ca.OP_MUL: "{0} * {1}",
    ca.OP_DIV: "{0} / {1}",
    ca.OP_POW: "{0} ** {1}",
    ca.OP_CONSTPOW: "{0} ** {1}",
    ca.OP_ATAN2: "_m.atan2({0}, {1})",
    ca.OP_FMIN: "min({0}, {1})",
    ca.OP_FMAX: "max({0}, {1})",
    ca.OP_LT: "float({0} < {1})",
    ca.OP_LE: "float({0} <= {1})",
    ca.OP_EQ: "float({0} == {1})",
    ca.OP_NE: "float({0} != {1})",
    ca.OP_IF_ELSE_ZERO: "({1} if {0} else 0.0)",
    ca.OP_COPYSIGN: "_m.copysign({0}, {1})",
    ca.OP_HYPOT: "_m.hypot({0}, {1})",
}
_UNARY = {
    ca.OP_NEG: "-{0}",
    ca.OP_SQ: "{0} * {0}",
    ca.OP_TWICE: "2.0 * {0}",
    ca.OP_INV: "1.0 / {0}",
    ca.OP_SQRT: "_m.sqrt({0})",
    ca.OP_SIN: "_m.sin({0})",
    ca.OP_COS: "_m.cos({0})",
    ca.OP_TAN: "_m.tan({0})",
    ca.OP_EXP: "_m.exp({0})",
    ca.OP_LOG: "_m.log({0})",
    ca.OP_FABS: "abs({0})",
    ca.OP_ASIN: "_m.asin({0})",
    ca.OP_ACOS: "_m.acos({0})",
    ca.OP_ATAN: "_m.atan({0})",
    ca.OP_SINH: "_m.sinh({0})",
    ca.OP_COSH: "_m.cosh({0})",
    ca.OP_TANH: "_m.tanh({0})",
    ca.OP_SIGN: "_m.copysign(1.0, {0}) if {0} != 0.0 else 0.0",
    ca.OP_ASSIGN: "{0}",
}


class _NumpyMath:
    """The ``math`` functions the templates use, element-wise."""

    sqrt, sin, cos, tan, exp, log = np.sqrt, np.sin, np.cos, np.tan, np.exp, np.log
    asin, acos, atan, sinh, cosh, tanh = np.arcsin, np.arccos, np.arctan, np.sinh, np.cosh, np.tanh
    atan2, copysign, hypot = np.arctan2, np.copysign, np.hypot


def to_python(f: ca.Function, vectorized: bool = False) -> Callable[..., np.ndarray]:
    """Return a Python function equivalent to the SX Function ``f``.

    The generated function takes one flat float sequence per input of ``f`` and
    returns the first output as a 1-D NumPy array (dense, column-major). With
    ``vectorized=True`` an input may instead be an array of shape (n_in, N)
    (N points at once, element-wise NumPy); the result then has shape (n_out, N).

    Parameters
    ----------
    f : casadi.Function
        An SX Function, e.g. ``model.functions["rhs"]``.
    vectorized : bool, optional
        Generate element-wise NumPy code for many points per call (default: scalar ``math`` code).

    Returns
    -------
    callable
        ``g(*inputs) -> ndarray`` with one flat float sequence per input of
        ``f``; the result has shape (size1 * size2,) of the first output,
        structural zeros included.

    Raises
    ------
    TypeError
        If ``f`` is not an SX Function or uses an operation not supported here.
    """
    if not f.is_a("SXFunction"):
        raise TypeError(f"to_python needs an SXFunction, got {f.class_name()}")
    n_out = f.nnz_out(0)
    sp_out = f.sparsity_out(0)
    lines = [f"def _generated({', '.join(f'i{k}' for k in range(f.n_in()))}):"]
    out_slots: dict[int, str] = {}
    for k in range(f.n_instructions()):
        op = f.instruction_id(k)
        ins = f.instruction_input(k)
        outs = f.instruction_output(k)
        if op == ca.OP_INPUT:
            lines.append(f"    w{outs[0]} = i{ins[0]}[{ins[1]}]")
        elif op == ca.OP_OUTPUT:
            # Work variables are reused after an output is written: copy now.
            if outs[0] == 0:
                lines.append(f"    o{outs[1]} = w{ins[0]}")
                out_slots[outs[1]] = f"o{outs[1]}"
        elif op == ca.OP_CONST:
            lines.append(f"    w{outs[0]} = {float(f.instruction_constant(k))!r}")
        elif vectorized and op in _VECTOR:
            lines.append(f"    w{outs[0]} = " + _VECTOR[op].format(*(f"w{i}" for i in ins)))
        elif op in _BINARY:
            lines.append(f"    w{outs[0]} = " + _BINARY[op].format(f"w{ins[0]}", f"w{ins[1]}"))
        elif op in _UNARY:
            lines.append(f"    w{outs[0]} = " + _UNARY[op].format(f"w{ins[0]}"))
        else:
            raise TypeError(f"to_python: CasADi operation id {op} is not supported")
    # Dense output in column-major order; structural zeros stay 0.0.
    dense = ["0.0"] * (sp_out.size1() * sp_out.size2())
    rows, cols = sp_out.get_triplet()
    for nz, (r, c) in enumerate(zip(rows, cols, strict=True)):
        dense[r + c * sp_out.size1()] = out_slots.get(nz, "0.0")
    if vectorized:
        lines.append(f"    return _np.stack(_np.broadcast_arrays({', '.join(dense)}))")
    else:
        lines.append(f"    return _np.array([{', '.join(dense)}])")
    namespace: dict[str, object] = {"_m": _NumpyMath if vectorized else __import__("math"), "_np": np}
    exec(compile("\n".join(lines), f"<pendulab:{f.name()}>", "exec"), namespace)  # noqa: S102
    generated = namespace["_generated"]
    generated.__doc__ = f"Plain-Python translation of CasADi function {f.name()!r} ({n_out} nonzero outputs)."
    return generated  # type: ignore[return-value]
