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
import re
import tempfile
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
    "adjoint_function",
    "adjoint_c_source",
    "compiled_sources",
    "event_indicator_names",
    "external_symbols",
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
#: Event indicators (value references VR_Z + i): spring margins of the elastic model, r_i - SPRING_LIMIT * L_i.
#: The model is singular at r = 0; when a margin reaches 0 the FMU stops (ME: terminateSimulation at the
#: event, CS: the step ends at the last sub-step before the limit with Discard / terminateSimulation).
VR_Z = 1000
#: 10 % of the rest length: far outside a Hooke spring's range already, and a margin for importers whose
#: integrator tries states past the event before locating it (fmusim's CVode at tolerance 1e-6 overshot the
#: crossing by 0.018 m at 10 m/s; a state with r <= 0 is refused, the model being singular there).
SPRING_LIMIT = 0.1


def event_indicator_names(kind: str, flip_events: bool = False) -> tuple[str, ...]:
    """Names of the FMU's event-indicator variables.

    ``spring_margin1``, ``spring_margin2`` (elastic model: r_i - SPRING_LIMIT L_i), then, with
    ``flip_events``, ``flip_margin1``, ``flip_margin2`` (pi - |theta_i|: 0 when link i passes upright).

    Parameters
    ----------
    kind : {"rigid", "elastic"}
        Model kind.
    flip_events : bool
        Whether the FMU has flip events (an export option).

    Returns
    -------
    tuple of str
        Spring margins first, then flip margins; empty for the rigid model without flip events.
    """
    springs = ("spring_margin1", "spring_margin2") if kind == "elastic" else ()
    return springs + (("flip_margin1", "flip_margin2") if flip_events else ())


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
    flip_events : bool
        Declare the event indicators pi - abs(theta_i) (Model Exchange: the importer locates every flip).
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
    #: event indicators pi - |theta_i| (Model Exchange: the importer locates every flip of a link)
    flip_events: bool = False

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


def layout(model: Model, x0: np.ndarray | None = None, flip_events: bool = False) -> ModelLayout:
    """Variable layout of the FMU of ``model``.

    Parameters
    ----------
    model : Model
        The pendulum; its parameters become the parameter start values.
    x0 : ndarray, shape (nx,), optional
        State start values [SI]; default hanging at rest.
    flip_events : bool
        Add the flip event indicators pi - |theta_i|.

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
        flip_events=bool(flip_events),
    )


def adjoint_function(kind: str) -> ca.Function:
    """Vector-Jacobian product of the FMU's model functions: ``<id>_adj(x, u, p, v) -> J' v``.

    ``J = d(xdot, y) / d(x, u)`` is the Jacobian behind the directional derivatives
    (``<id>_jac_all``); the product is CasADi's reverse mode (``jtimes`` with ``tr=True``)
    on the same graph (the ``rhs`` and ``outputs`` functions of :func:`c_functions`).

    Parameters
    ----------
    kind : {"rigid", "elastic"}
        Model kind.

    Returns
    -------
    casadi.Function
        Inputs ``x`` (nx), ``u`` (nu), ``p`` (np), ``v`` (nx + ny); output ``w`` (nx + nu), dense.
    """
    rhs, outputs = c_functions(kind)[:2]
    x = ca.SX.sym("x", rhs.size1_in(0))
    u = ca.SX.sym("u", rhs.size1_in(1))
    p = ca.SX.sym("p", rhs.size1_in(2))
    f = ca.vertcat(rhs(x, u, p), outputs(x, u, p))
    v = ca.SX.sym("v", f.size1())
    w = ca.densify(ca.jtimes(f, ca.vertcat(x, u), v, True))
    return ca.Function(f"{identifier_for_kind(kind)}_adj", [x, u, p, v], [w], ["x", "u", "p", "v"], ["w"])


def adjoint_c_source(kind: str) -> bytes:
    """CasADi-generated C of :func:`adjoint_function` (``sources/model_adjoint_casadi.c``).

    Parameters
    ----------
    kind : {"rigid", "elastic"}
        Model kind.

    Returns
    -------
    bytes
        Self-contained C; deterministic for a given CasADi version.
    """
    with tempfile.TemporaryDirectory() as tmp:
        cg = ca.CodeGenerator("model_adjoint_casadi.c", {"casadi_int": "int", "with_export": False, "with_header": False})
        cg.add(adjoint_function(kind))
        cg.generate(tmp + "/")
        return (Path(tmp) / "model_adjoint_casadi.c").read_bytes()


_ADJOINT_WRAPPER = """/* Generated by pendulab.fmu.codegen. Do not edit.
 * Compiles the CasADi-generated vector-Jacobian product (fmi3GetAdjointDerivative); CasADi prefixes
 * its internal symbols with the file name (model_adjoint_casadi_), so they do not clash with model_casadi.c. */
#if defined(__GNUC__)
#pragma GCC diagnostic ignored "-Wunused-parameter"
#endif
#include "model.h"
#if defined(PENDULAB_PREFIX)
#define CASADI_CODEGEN_PREFIX
#define CODEGEN_PREFIX PENDULAB_PREFIXED(model_adjoint_casadi_)
#endif
#include "model_adjoint_casadi.c"
"""


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
    if lay.flip_events:  # (absent otherwise: the tokens of FMUs without flip events are unchanged)
        h.update(b"|flip_events")
    for name in (*FIXED_SOURCES, *FIXED_HEADERS[fmi_version], f"fmi{fmi_version}.c"):
        h.update(_fixed_file(name))
    d = h.hexdigest()
    return "{" + f"{d[:8]}-{d[8:12]}-{d[12:16]}-{d[16:20]}-{d[20:32]}" + "}"


def _header(model: Model, lay: ModelLayout, funcs: list[ca.Function], tok: str, symbols: tuple[str, ...] = ()) -> str:
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
{_namespace_block(symbols)}

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
#define MODEL_NZ {len(event_indicator_names(lay.kind, lay.flip_events))}
#define MODEL_NF {2 if lay.flip_events else 0}
#define MODEL_SPRING_LIMIT {SPRING_LIMIT!r}

#define MODEL_VR_TIME {VR_TIME}
#define MODEL_VR_X {VR_X}
#define MODEL_VR_DX {VR_DX}
#define MODEL_VR_U {VR_U}
#define MODEL_VR_Y {VR_Y}
#define MODEL_VR_P {VR_P}
#define MODEL_VR_TOL {VR_TOL}
#define MODEL_VR_HMAX {VR_HMAX}
#define MODEL_VR_SOLVER {VR_SOLVER}
#define MODEL_VR_Z {VR_Z}

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
#define MODEL_ADJOINT {funcs[4].name()}

#define MODEL_SZ_ARG {sz["arg"]}
#define MODEL_SZ_RES {sz["res"]}
#define MODEL_SZ_IW {sz["iw"]}
#define MODEL_SZ_W {sz["w"]}

#endif
"""


_WRAPPER = """/* Generated by pendulab.fmu.codegen. Do not edit.
 * Compiles the CasADi-generated model functions; CasADi's calling convention
 * leaves some parameters unused, which is not a defect of this FMU. model.h comes
 * first: with a function prefix it renames the model functions (static linking). */
#if defined(__GNUC__)
#pragma GCC diagnostic ignored "-Wunused-parameter"
#endif
#include "model.h"
#if defined(PENDULAB_PREFIX)
#define CASADI_CODEGEN_PREFIX
#define CODEGEN_PREFIX PENDULAB_PREFIXED(model_casadi_)
#endif
#include "model_casadi.c"
"""

_SOLVER_WRAPPER = """/* Generated by pendulab.fmu.codegen. Do not edit.
 * Compiles the FMI-independent solver core (ode_solver.c, shared with pendulab's native fast path).
 * model.h comes first: with FMI2_FUNCTION_PREFIX / FMI3_FUNCTION_PREFIX it renames the solver's
 * functions too, so that several source FMUs link statically into one program. */
#include "model.h"
#include "ode_solver.c"
"""

#: A C function definition at the start of a line (external linkage: not ``static``): its name.
_C_DEFINITION = re.compile(r"^(?!static\b|typedef\b|extern\b)[A-Za-z_][\w \t*]*?\b([A-Za-z_]\w*)\s*\([^;{]*\)\s*\{", re.M)


def external_symbols(*c_texts: str) -> tuple[str, ...]:
    """Names of the functions with external linkage defined in C sources, besides ``fmi2*`` / ``fmi3*``.

    CasADi's internal helpers (``casadi_*``) are left out: CasADi renames them itself
    (``CASADI_CODEGEN_PREFIX`` / ``CODEGEN_PREFIX``, set by the wrappers).

    Parameters
    ----------
    *c_texts : str
        C source texts (definitions start in the first column, as in pendulab's C files and CasADi's output).

    Returns
    -------
    tuple of str
        Sorted, unique names.
    """
    names = set()
    for text in c_texts:
        for m in _C_DEFINITION.finditer(text):
            name = m.group(1)
            if not name.startswith(("fmi2", "fmi3", "casadi_")) and name not in ("if", "for", "while", "switch", "return"):
                names.add(name)
    return tuple(sorted(names))


def _namespace_block(symbols: tuple[str, ...]) -> str:
    renames = "\n".join(f"#define {name} PENDULAB_PREFIXED({name})" for name in symbols)
    return f"""
/* Static linking of several source FMUs into one program: when FMI2_FUNCTION_PREFIX or FMI3_FUNCTION_PREFIX
 * is defined, the standard FMI headers prefix the fmi2* / fmi3* functions and this block prefixes every
 * other function with external linkage (model core, solver, CasADi model functions), so that nothing clashes. */
#if defined(FMI2_FUNCTION_PREFIX) || defined(FMI3_FUNCTION_PREFIX)
#if defined(FMI2_FUNCTION_PREFIX)
#define PENDULAB_PREFIX FMI2_FUNCTION_PREFIX
#else
#define PENDULAB_PREFIX FMI3_FUNCTION_PREFIX
#endif
#define PENDULAB_PASTE_(a, b) a##b
#define PENDULAB_PASTE(a, b) PENDULAB_PASTE_(a, b)
#define PENDULAB_PREFIXED(name) PENDULAB_PASTE(PENDULAB_PREFIX, name)
{renames}
#endif
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
    funcs = [*c_functions(model.kind), adjoint_function(model.kind)]
    if funcs[0].name() != f"{lay.identifier}_rhs":
        raise ValueError(f"layout identifier {lay.identifier!r} does not match the generated functions of {model.kind!r}")
    tok = token(lay, fmi_version)
    out: dict[str, bytes] = {"model_casadi.c": model_c_source(model.kind)}
    out["model_functions.c"] = _WRAPPER.encode()
    out["solver_functions.c"] = _SOLVER_WRAPPER.encode()
    if fmi_version == 3:  # fmi3GetAdjointDerivative (FMI 2 has no adjoint derivatives)
        out["model_adjoint_casadi.c"] = adjoint_c_source(model.kind)
        out["model_adjoint.c"] = _ADJOINT_WRAPPER.encode()
    for name in (*FIXED_SOURCES, *FIXED_HEADERS[fmi_version], f"fmi{fmi_version}.c"):
        out[name] = _fixed_file(name)
    # every function with external linkage besides fmi2*/fmi3*, for the prefix renames of model.h
    symbols = external_symbols(*(out[n].decode() for n in out if n.endswith(".c") and not n.startswith("fmi")))
    out["model.h"] = _header(model, lay, funcs, tok, symbols).encode()
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
    adjoint = ("model_adjoint.c",) if fmi_version == 3 else ()  # fmi3GetAdjointDerivative
    fixed = (n for n in FIXED_SOURCES if n not in SOLVER_SOURCES)
    return (f"fmi{fmi_version}.c", *fixed, "solver_functions.c", "model_functions.c", *adjoint)
