"""C code of the model functions, generated once per model kind, shared by the FMU and the native library.

The model functions (right-hand side, outputs and their Jacobians) are the
CasADi Functions of :func:`pendulab.model.model.model_functions` evaluated on
fresh SX arguments and emitted with :class:`casadi.CodeGenerator`; nothing
here writes physics. The parameter vector ``p`` is a runtime input of every
generated function, so the C code depends on the model *kind* only: changing a
parameter value never recompiles. :func:`model_c_source` is what the FMU ships
as ``sources/model_casadi.c`` and what the native library compiles, byte for byte.
"""

from __future__ import annotations

import tempfile
from functools import cache
from importlib import resources
from pathlib import Path

import casadi as ca
import numpy as np

from ..model.model import model_functions

__all__ = [
    "C_DIR",
    "SOLVER_SOURCES",
    "SOLVER_HEADERS",
    "NATIVE_SOURCES",
    "NATIVE_HEADERS",
    "KINDS",
    "identifier_for_kind",
    "c_functions",
    "dependency_pattern",
    "model_c_source",
    "native_sources",
    "native_units",
]

#: Hand-written C of this package (the solver core, the grid loop, the native entry points).
C_DIR = Path(str(resources.files("pendulab.native") / "c"))
#: The solver core compiled into every FMU and every native library.
SOLVER_SOURCES: tuple[str, ...] = ("ode_solver.c",)
SOLVER_HEADERS: tuple[str, ...] = ("ode_solver.h",)
#: Fixed (hand-written) sources of the native library besides the solver core.
NATIVE_SOURCES: tuple[str, ...] = ("ode_loop.c", "native_api.c")
NATIVE_HEADERS: tuple[str, ...] = ("ode_loop.h", "native_api.h")
#: Model kinds with generated code.
KINDS: tuple[str, ...] = ("rigid", "elastic")


def identifier_for_kind(kind: str) -> str:
    """C symbol prefix of a model kind's generated functions: ``pendulab_rigid`` or ``pendulab_elastic``.

    Parameters
    ----------
    kind : {"rigid", "elastic"}
        Model kind.

    Returns
    -------
    str
        The prefix (also the FMU's model identifier).

    Raises
    ------
    ValueError
        Unknown kind.
    """
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {list(KINDS)}, got {kind!r}")
    return f"pendulab_{kind}"


def c_functions(kind: str) -> list[ca.Function]:
    """The four generated functions of a model kind, all ``(x, u, p) -> one dense output``.

    Parameters
    ----------
    kind : {"rigid", "elastic"}
        Model kind.

    Returns
    -------
    list of casadi.Function
        ``<id>_rhs -> xdot`` (nx), ``<id>_outputs -> y`` (ny), ``<id>_jac_x -> df/dx``
        (nx x nx, dense, column-major) and ``<id>_jac_all -> d(xdot, y)/d(x, u)`` (dense).
    """
    return list(_functions(kind)[0])


def dependency_pattern(kind: str) -> np.ndarray:
    """Structural non-zeros of ``d(xdot, y) / d(x, u, p)``.

    Parameters
    ----------
    kind : {"rigid", "elastic"}
        Model kind.

    Returns
    -------
    ndarray of bool, shape (nx + ny, nx + nu + np)
        Rows: derivatives then outputs; columns: states, inputs, then parameters.
    """
    return _functions(kind)[1].copy()


@cache
def _functions(kind: str) -> tuple[tuple[ca.Function, ...], np.ndarray]:
    identifier = identifier_for_kind(kind)
    mf = model_functions(kind)
    rhs, outputs = mf["rhs"], mf["outputs"]
    # Arguments only: the physics comes from model_functions.
    x = ca.SX.sym("x", rhs.size1_in(0))
    u = ca.SX.sym("u", rhs.size1_in(1))
    p = ca.SX.sym("p", rhs.size1_in(2))
    xdot = rhs(x, u, p)
    y = outputs(x, u, p)
    jac_all = ca.jacobian(ca.vertcat(xdot, y), ca.vertcat(x, u))
    deps = np.array(ca.DM(ca.jacobian(ca.vertcat(xdot, y), ca.vertcat(x, u, p)).sparsity(), 1)) != 0
    names = ["x", "u", "p"]
    funcs = (
        ca.Function(f"{identifier}_rhs", [x, u, p], [xdot], names, ["xdot"]),
        ca.Function(f"{identifier}_outputs", [x, u, p], [y], names, ["y"]),
        ca.Function(f"{identifier}_jac_x", [x, u, p], [ca.densify(ca.jacobian(xdot, x))], names, ["A"]),
        ca.Function(f"{identifier}_jac_all", [x, u, p], [ca.densify(jac_all)], names, ["J"]),
    )
    return funcs, deps


@cache
def model_c_source(kind: str) -> bytes:
    """CasADi-generated C of the four functions of :func:`c_functions` (self-contained, no header).

    Parameters
    ----------
    kind : {"rigid", "elastic"}
        Model kind.

    Returns
    -------
    bytes
        Contents of ``model_casadi.c``; deterministic for a given CasADi version.
    """
    with tempfile.TemporaryDirectory() as tmp:
        cg = ca.CodeGenerator("model_casadi.c", {"casadi_int": "int", "with_export": False, "with_header": False})
        for f in c_functions(kind):
            cg.add(f)
        cg.generate(tmp + "/")
        return (Path(tmp) / "model_casadi.c").read_bytes()


def work_sizes(kind: str) -> dict[str, int]:
    """CasADi work-array sizes (``arg``, ``res``, ``iw``, ``w``) large enough for every generated function.

    Parameters
    ----------
    kind : {"rigid", "elastic"}
        Model kind.

    Returns
    -------
    dict of str to int
        Maximum over the four functions of ``sz_arg``, ``sz_res``, ``sz_iw``, ``sz_w``.
    """
    funcs = c_functions(kind)
    return {k: max(getattr(f, f"sz_{k}")() for f in funcs) for k in ("arg", "res", "iw", "w")}


_WRAPPER = """/* Generated by pendulab.native.codegen. Do not edit.
 * Compiles the CasADi-generated model functions; CasADi's calling convention
 * leaves some parameters unused, which is not a defect of this library. */
#if defined(__GNUC__)
#pragma GCC diagnostic ignored "-Wunused-parameter"
#endif
#include "model_casadi.c"
"""


def _native_header(kind: str) -> str:
    funcs = c_functions(kind)
    rhs = funcs[0]
    sz = work_sizes(kind)
    protos = "\n".join(
        f"int {f.name()}(const casadi_real **arg, casadi_real **res, casadi_int *iw, casadi_real *w, int mem);" for f in funcs
    )
    return f"""/* Generated by pendulab.native.codegen for the {kind} double pendulum. Do not edit. */
#ifndef PENDULAB_NATIVE_MODEL_H
#define PENDULAB_NATIVE_MODEL_H

#ifndef casadi_real
#define casadi_real double
#endif
#ifndef casadi_int
#define casadi_int int
#endif

{protos}

#define NATIVE_KIND "{kind}"
#define NATIVE_NX {rhs.size1_in(0)}
#define NATIVE_NU {rhs.size1_in(1)}
#define NATIVE_NP {rhs.size1_in(2)}
#define NATIVE_RHS {funcs[0].name()}
#define NATIVE_JAC_X {funcs[2].name()}
#define NATIVE_SZ_ARG {sz["arg"]}
#define NATIVE_SZ_RES {sz["res"]}
#define NATIVE_SZ_IW {sz["iw"]}
#define NATIVE_SZ_W {sz["w"]}

#endif
"""


@cache
def _native_sources(kind: str) -> tuple[tuple[str, bytes], ...]:
    out: dict[str, bytes] = {
        "model_casadi.c": model_c_source(kind),
        "model_functions.c": _WRAPPER.encode(),
        "native_model.h": _native_header(kind).encode(),
    }
    for name in (*SOLVER_SOURCES, *SOLVER_HEADERS, *NATIVE_SOURCES, *NATIVE_HEADERS):
        out[name] = (C_DIR / name).read_bytes()
    return tuple(sorted(out.items()))


def native_sources(kind: str) -> dict[str, bytes]:
    """All C sources of the native library of a model kind: {file name: contents}.

    Parameters
    ----------
    kind : {"rigid", "elastic"}
        Model kind.

    Returns
    -------
    dict of str to bytes
        The fixed files of ``pendulab/native/c`` (solver core, grid loop, entry
        points), the generated ``model_casadi.c`` (identical to the FMU's), its
        wrapper ``model_functions.c`` and the generated header ``native_model.h``.
    """
    return dict(_native_sources(kind))


def native_units() -> tuple[str, ...]:
    """The translation units of the native library, in build order.

    Returns
    -------
    tuple of str
        File names among :func:`native_sources`.
    """
    return (*SOLVER_SOURCES, *NATIVE_SOURCES, "model_functions.c")
