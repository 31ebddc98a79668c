"""The CasADi Functions of one model kind, built once per process, and their element-wise NumPy twins."""

from __future__ import annotations

from collections.abc import Callable
from functools import cache

import casadi as ca
import numpy as np

from .builders import SymbolicModel, build_elastic, build_rigid
from .pycode import to_python

__all__ = ["model_functions"]


@cache
def model_functions(kind: str) -> dict[str, ca.Function]:
    """CasADi Functions of one model kind, built once per process.

    Parameters
    ----------
    kind : {"rigid", "elastic"}
        Model kind (anything other than ``"rigid"`` builds the elastic model).

    Returns
    -------
    dict of str to casadi.Function
        The functions listed under :class:`Model` ``functions``, each taking the
        parameter vector ``p`` as an explicit input.
    """
    sym: SymbolicModel = build_rigid() if kind == "rigid" else build_elastic()
    x, u, p = sym.x, sym.u, sym.p
    energy = sym.kinetic + sym.potential
    outputs = [sym.positions, energy]
    if kind == "elastic":
        outputs.append(sym.stretch)
    y = ca.vertcat(*outputs)
    xdot = sym.xdot
    return {
        "rhs": ca.Function("rhs", [x, u, p], [xdot], ["x", "u", "p"], ["xdot"]),
        "outputs": ca.Function("outputs", [x, u, p], [y], ["x", "u", "p"], ["y"]),
        "jac_rhs": ca.Function(
            "jac_rhs",
            [x, u, p],
            [ca.jacobian(xdot, x), ca.jacobian(xdot, u)],
            ["x", "u", "p"],
            ["A", "B"],
        ),
        "mass_matrix": ca.Function("mass_matrix", [x, p], [sym.eom.M], ["x", "p"], ["M"]),
        "bias": ca.Function("bias", [x, p], [sym.eom.bias], ["x", "p"], ["bias"]),
        "kinetic": ca.Function("kinetic", [x, p], [sym.kinetic], ["x", "p"], ["T"]),
        "potential": ca.Function("potential", [x, p], [sym.potential], ["x", "p"], ["V"]),
        "spring_energy": ca.Function("spring_energy", [x, p], [sym.spring], ["x", "p"], ["V_spring"]),
        "energy": ca.Function("energy", [x, p], [energy], ["x", "p"], ["E"]),
        "positions": ca.Function("positions", [x, p], [sym.positions], ["x", "p"], ["pos"]),
        "stretch": ca.Function("stretch", [x, p], [sym.stretch], ["x", "p"], ["stretch"]),
        "dissipation": ca.Function("dissipation", [x, p], [sym.dissipation], ["x", "p"], ["P_diss"]),
        "power_in": ca.Function("power_in", [x, u, p], [sym.power_in], ["x", "u", "p"], ["P_in"]),
    }


@cache
def _scalar(kind: str, fname: str) -> Callable[..., np.ndarray]:
    """Plain-Python (``math``) translation of one model function, for single points (lists of floats)."""
    return to_python(model_functions(kind)[fname])


@cache
def _vectorized(kind: str, fname: str) -> Callable[..., np.ndarray]:
    """Element-wise NumPy translation of one model function (inputs (n_in, N), output (n_out, N))."""
    generated = to_python(model_functions(kind)[fname], vectorized=True)

    def evaluate(X: np.ndarray, *rest: np.ndarray) -> np.ndarray:
        out = generated(X, *rest)
        if out.ndim == 2 and out.shape[1] == X.shape[1]:
            return out
        # Outputs that do not depend on the state (e.g. the rigid model's zero stretch) come back unbroadcast.
        return np.tile(out.reshape(len(out), 1), (1, X.shape[1]))

    return evaluate
