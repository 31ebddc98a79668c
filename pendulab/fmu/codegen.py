"""C sources of one FMU: CasADi-generated model functions plus the per-model header.

The model functions (right-hand side, outputs, their Jacobians) and their C
code come from :mod:`pendulab.native.codegen` (one generator for the FMU and
the native fast path; nothing here writes physics). The header ``model.h``
carries sizes, value references, start values and parameter defaults; the
hand-written FMI layers and model core in ``pendulab/fmu/c`` and the solver
core in ``pendulab/native/c`` are shared by all models.
"""

from __future__ import annotations

import hashlib
import zlib
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import casadi as ca
import numpy as np

from ..model.model import Model
from ..native.codegen import C_DIR as NATIVE_C_DIR
from ..native.codegen import SOLVER_HEADERS, SOLVER_SOURCES, c_functions, dependency_pattern, identifier_for_kind, model_c_source

__all__ = [
    "C_DIR",
    "NATIVE_C_DIR",
    "FIXED_SOURCES",
    "SOLVER_NAMES",
    "ModelLayout",
    "compiled_sources",
    "generate_sources",
    "identifier_for",
    "layout",
    "token",
]

C_DIR = Path(str(resources.files("pendulab.fmu") / "c"))
#: Hand-written C files compiled into every FMU (plus fmi2.c or fmi3.c); the solver core
#: (``ode_solver.c``) comes from ``pendulab/native/c``, the rest from ``pendulab/fmu/c``.
FIXED_SOURCES: tuple[str, ...] = ("fmu_core.c", *SOLVER_SOURCES)
FIXED_HEADERS: dict[int, tuple[str, ...]] = {
    2: ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h", "fmu_core.h", *SOLVER_HEADERS),
    3: ("fmi3Functions.h", "fmi3FunctionTypes.h", "fmi3PlatformTypes.h", "fmu_core.h", *SOLVER_HEADERS),
}
#: Values of the ``solver`` parameter.
SOLVER_NAMES: tuple[str, ...] = ("dopri5", "rodas4")

# Value-reference bases: one block per variable group keeps references stable
# across models and readable in logs (the elastic model has 8 states, < 100).
VR_TIME, VR_X, VR_DX, VR_U, VR_Y, VR_P = 0, 100, 200, 300, 400, 500
VR_TOL, VR_HMAX, VR_SOLVER = 900, 901, 902
DEFAULT_TOLERANCE = 1e-8


@dataclass(frozen=True)
class ModelLayout:
    """Names, value references and dependency structure of one model's FMU variables.

    Attributes
    ----------
    identifier : str
        Model identifier (C symbol prefix, binary name), e.g. ``pendulab_rigid``.
    kind : {"rigid", "elastic"}
        Model kind.
    nx, nu, ny, np : int
        Numbers of states, inputs, outputs and parameters.
    x_start : ndarray, shape (nx,)
        State start values [SI].
    p_default : ndarray, shape (np,)
        Parameter start values [SI].
    p_tunable : tuple of bool, length np
        Whether each parameter may change during a run.
    p_positive : tuple of bool, length np
        Whether each parameter must be positive.
    dependencies : ndarray of bool, shape (nx + ny, nx + nu + np)
        Structural non-zeros: rows derivatives then outputs; columns states, inputs, then parameters.
    """

    identifier: str
    kind: str
    nx: int
    nu: int
    ny: int
    np: int
    x_start: np.ndarray
    p_default: np.ndarray
    p_tunable: tuple[bool, ...]
    p_positive: tuple[bool, ...]
    #: rows: derivatives then outputs; columns: states, inputs, then parameters (structural non-zeros)
    dependencies: np.ndarray

    def vr(self, group: str, index: int = 0) -> int:
        """Value reference of a variable.

        Parameters
        ----------
        group : {"x", "dx", "u", "y", "p"}
            States, derivatives, inputs, outputs or parameters.
        index : int
            Position in the group.

        Returns
        -------
        int
            The value reference.
        """
        base = {"x": VR_X, "dx": VR_DX, "u": VR_U, "y": VR_Y, "p": VR_P}[group]
        return base + index


#: Parameters that may change during a run (FMI "tunable"): environment and
#: dissipation/compliance values, whose change leaves the meaning of the state
#: intact. Masses, lengths and inertias are "fixed": changing them mid-run would
#: make the current state describe a different body; reinstantiate instead.
TUNABLE_PARAMS = frozenset({"g", "b1", "b2", "k1", "k2", "c1", "c2"})


def _fixed_file(name: str) -> bytes:
    """A hand-written C file of the FMU: the solver core from pendulab/native/c, the rest from pendulab/fmu/c."""
    folder = NATIVE_C_DIR if name in (*SOLVER_SOURCES, *SOLVER_HEADERS) else C_DIR
    return (folder / name).read_bytes()


def identifier_for(model: Model) -> str:
    """Model identifier (C symbol prefix, binary name): ``pendulab_rigid`` or ``pendulab_elastic``.

    Parameters
    ----------
    model : Model
        The pendulum.

    Returns
    -------
    str
        ``pendulab_<kind>``.
    """
    return identifier_for_kind(model.kind)


def layout(model: Model, x0: np.ndarray | None = None) -> ModelLayout:
    """Variable layout of the FMU of ``model``.

    Parameters
    ----------
    model : Model
        The pendulum; its parameters become the parameter start values.
    x0 : ndarray, shape (nx,), optional
        State start values [SI]; default hanging at rest.

    Returns
    -------
    ModelLayout

    Raises
    ------
    ValueError
        ``x0`` has the wrong shape or is not finite.
    """
    x_start = model.rest_state() if x0 is None else model.check_state(x0, "x0")
    if x_start.ndim != 1:
        raise ValueError(f"x0 must have shape ({model.nx},), got shape {x_start.shape}")
    identifier = identifier_for(model)
    deps = dependency_pattern(model.kind)
    names = model.param_names
    return ModelLayout(
        identifier=identifier,
        kind=model.kind,
        nx=model.nx,
        nu=model.nu,
        ny=model.ny,
        np=len(names),
        x_start=np.array(x_start, dtype=float),
        p_default=np.asarray(model.p, dtype=float),
        p_tunable=tuple(n in TUNABLE_PARAMS for n in names),
        p_positive=tuple(info.positive for info in model.param_info),
        dependencies=deps,
    )


def _c_array(values: np.ndarray | tuple) -> str:
    return "{" + ", ".join(repr(float(v)) for v in values) + "}"


def _c_ints(values: tuple) -> str:
    return "{" + ", ".join(str(int(v)) for v in values) + "}"


def token(lay: ModelLayout, fmi_version: int) -> str:
    """Deterministic GUID / instantiation token: a digest of everything that defines the binary.

    Parameters
    ----------
    lay : ModelLayout
        The FMU's layout (kind, start values).
    fmi_version : {2, 3}
        FMI standard.

    Returns
    -------
    str
        ``{xxxxxxxx-xxxx-xxxx-xxxx-xxxxxxxxxxxx}``.
    """
    h = hashlib.sha256()
    h.update(f"{lay.kind}|{fmi_version}|{lay.p_default.tobytes().hex()}|{lay.x_start.tobytes().hex()}".encode())
    for name in (*FIXED_SOURCES, *FIXED_HEADERS[fmi_version], f"fmi{fmi_version}.c"):
        h.update(_fixed_file(name))
    d = h.hexdigest()
    return "{" + f"{d[:8]}-{d[8:12]}-{d[12:16]}-{d[16:20]}-{d[20:32]}" + "}"


def _header(model: Model, lay: ModelLayout, funcs: list[ca.Function], tok: str) -> str:
    sz = {k: max(getattr(f, f"sz_{k}")() for f in funcs) for k in ("arg", "res", "iw", "w")}
    pnames = "{" + ", ".join(f'"{n}"' for n in model.param_names) + "}"
    magic = zlib.crc32(tok.encode()) & 0xFFFFFFFF
    ident = lay.identifier
    protos = "\n".join(
        f"int {f.name()}(const casadi_real **arg, casadi_real **res, casadi_int *iw, casadi_real *w, int mem);" for f in funcs
    )
    return f"""/* Generated by pendulab.fmu.codegen for the {model.kind} double pendulum. Do not edit. */
#ifndef PENDULAB_MODEL_H
#define PENDULAB_MODEL_H

#ifndef casadi_real
#define casadi_real double
#endif
#ifndef casadi_int
#define casadi_int int
#endif

typedef int (*casadi_fn)(const casadi_real **arg, casadi_real **res, casadi_int *iw, casadi_real *w, int mem);
{protos}

#define MODEL_IDENTIFIER "{ident}"
#define MODEL_TOKEN "{tok}"
#define MODEL_MAGIC {magic}UL

#define MODEL_NX {lay.nx}
#define MODEL_NU {lay.nu}
#define MODEL_NY {lay.ny}
#define MODEL_NP {lay.np}

#define MODEL_VR_TIME {VR_TIME}
#define MODEL_VR_X {VR_X}
#define MODEL_VR_DX {VR_DX}
#define MODEL_VR_U {VR_U}
#define MODEL_VR_Y {VR_Y}
#define MODEL_VR_P {VR_P}
#define MODEL_VR_TOL {VR_TOL}
#define MODEL_VR_HMAX {VR_HMAX}
#define MODEL_VR_SOLVER {VR_SOLVER}

#define MODEL_X_START {_c_array(lay.x_start)}
#define MODEL_P_DEFAULT {_c_array(lay.p_default)}
#define MODEL_P_TUNABLE {_c_ints(lay.p_tunable)}
#define MODEL_P_POSITIVE {_c_ints(lay.p_positive)}
#define MODEL_P_NAMES {pnames}
#define MODEL_TOL_DEFAULT {DEFAULT_TOLERANCE!r}
#define MODEL_HMAX_DEFAULT 0.0
#define MODEL_SOLVER_DEFAULT 0

#define MODEL_RHS {funcs[0].name()}
#define MODEL_OUTPUTS {funcs[1].name()}
#define MODEL_JAC_X {funcs[2].name()}
#define MODEL_JAC_ALL {funcs[3].name()}

#define MODEL_SZ_ARG {sz["arg"]}
#define MODEL_SZ_RES {sz["res"]}
#define MODEL_SZ_IW {sz["iw"]}
#define MODEL_SZ_W {sz["w"]}

#endif
"""


_WRAPPER = """/* Generated by pendulab.fmu.codegen. Do not edit.
 * Compiles the CasADi-generated model functions; CasADi's calling convention
 * leaves some parameters unused, which is not a defect of this FMU. */
#if defined(__GNUC__)
#pragma GCC diagnostic ignored "-Wunused-parameter"
#endif
#include "model_casadi.c"
"""


def generate_sources(model: Model, fmi_version: int, lay: ModelLayout | None = None) -> dict[str, bytes]:
    """All C sources of the FMU of ``model``: {file name: contents}.

    The compiled sources are ``fmi{2,3}.c``, ``fmu_core.c``, ``ode_solver.c``
    and ``model_functions.c`` (which includes ``model_casadi.c``).

    Parameters
    ----------
    model : Model
        The pendulum.
    fmi_version : {2, 3}
        FMI standard.
    lay : ModelLayout, optional
        Layout (default :func:`layout` of ``model``).

    Returns
    -------
    dict of str to bytes
        File name -> contents, sorted by name.

    Raises
    ------
    ValueError
        Bad ``fmi_version``, or a layout of another model kind.
    """
    if fmi_version not in (2, 3):
        raise ValueError(f"fmi_version must be 2 or 3, got {fmi_version!r}")
    lay = layout(model) if lay is None else lay
    funcs = c_functions(model.kind)
    if funcs[0].name() != f"{lay.identifier}_rhs":
        raise ValueError(f"layout identifier {lay.identifier!r} does not match the generated functions of {model.kind!r}")
    tok = token(lay, fmi_version)
    out: dict[str, bytes] = {"model_casadi.c": model_c_source(model.kind)}
    out["model.h"] = _header(model, lay, funcs, tok).encode()
    out["model_functions.c"] = _WRAPPER.encode()
    for name in (*FIXED_SOURCES, *FIXED_HEADERS[fmi_version], f"fmi{fmi_version}.c"):
        out[name] = _fixed_file(name)
    return dict(sorted(out.items()))


def compiled_sources(fmi_version: int) -> tuple[str, ...]:
    """The translation units of an FMU, in build order.

    Parameters
    ----------
    fmi_version : {2, 3}
        FMI standard.

    Returns
    -------
    tuple of str
        File names among :func:`generate_sources`.
    """
    return (f"fmi{fmi_version}.c", *FIXED_SOURCES, "model_functions.c")
