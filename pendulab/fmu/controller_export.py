"""Export a pendulab sampled-data controller as a Co-Simulation FMU (FMI 2.0 or 3.0, C, no Python inside).

The controller FMU has the measured plant state as inputs (``theta1``, ... in the model's state order),
the driven torques as outputs (``tau1`` and/or ``tau2``) and the sample time as a parameter
(``sample_time``). Between samples the torques are held (zero-order hold), exactly as
:class:`~pendulab.control.feedback.SampledController` is driven by :func:`pendulab.cosim.cosim` and
``pendulab.simulate``: at a sample instant the outputs are the law at the current inputs.

The control laws are CasADi SX expressions built here from the designed controller's data and the
model's own CasADi functions (the energy of the swing-up), emitted as C by CasADi's CodeGenerator:

* :class:`~pendulab.control.feedback.LinearStateFeedback` (``lqr``): ``u = clip(u_eq - K wrap(x - x_eq))``;
* :class:`~pendulab.control.feedback.EnergySwingUp` (``swingup``): energy pumping, then the LQR catch
  (the mode switch on the LQR cost-to-go is the one piece of logic in the fixed C core);
* :class:`~pendulab.control.tracking.TVLQRTracker` (``tvlqr``): the time grid, reference states,
  torques and gains of the plan as constant arrays in generated C, then the final LQR.

The FMI layer is a small one of its own (``pendulab/fmu/c/ctrl_*.c``): the plant's fixed layer is built
around continuous states, an embedded ODE solver and Model Exchange, none of which a sampled-data
controller has (see ``docs/fmu.md``).
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import math
import os
import tempfile
import xml.etree.ElementTree as ET
import zipfile
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

from .._io import atomic_open
from .._version import __version__
from ..control.feedback import EnergySwingUp, LinearStateFeedback
from ..control.tracking import TVLQRTracker
from ..model.model import Model
from ..native.build import compile_shared, shared_library_suffix
from .codegen import C_DIR
from .export import binary_platform
from .model_description import UNITS

__all__ = [
    "EXPORTABLE",
    "ControllerLaw",
    "controller_law",
    "design_controller",
    "generate_controller_sources",
    "controller_model_description",
    "export_controller",
]

#: Controllers that can be exported as FMUs (the NMPC cannot: see :data:`NMPC_NOT_EXPORTABLE`).
EXPORTABLE: tuple[str, ...] = ("lqr", "tvlqr", "swingup")
#: Why ``nmpc`` is not exported (docs/fmu.md has the measurements).
NMPC_NOT_EXPORTABLE = (
    "the NMPC is not exported as an FMU: the C that CasADi generates for its solver (sqpmethod with the hpipm QP "
    "solver) calls HPIPM and BLASFEO (libraries of CasADi's wheel, BLASFEO built per CPU target), and ipopt and fatrop "
    "call their external libraries; only sqpmethod with CasADi's own dense QP solver qrqp generates self-contained C "
    "(see docs/fmu.md)"
)

#: Value references of the controller FMU's variables.
VR_TIME, VR_X, VR_U, VR_SAMPLE_TIME = 0, 100, 200, 300
#: Kinds of control law (``CTRL_KIND`` in the generated header).
KINDS: dict[str, int] = {"lqr": 0, "swingup": 1, "tvlqr": 2}
_FIXED = {2: ("ctrl_core.h", "ctrl_core.c", "ctrl_fmi2.c"), 3: ("ctrl_core.h", "ctrl_core.c", "ctrl_fmi3.c")}
_HEADERS = {
    2: ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h"),
    3: ("fmi3Functions.h", "fmi3FunctionTypes.h", "fmi3PlatformTypes.h"),
}
_ZIP_DATE = (1980, 1, 1, 0, 0, 0)


@dataclass(frozen=True)
class ControllerLaw:
    """A controller as data for C: CasADi functions of the law and constants of the fixed core.

    Attributes
    ----------
    kind : {"lqr", "swingup", "tvlqr"}
        Control law.
    model : Model
        Design model (state names and units).
    state_names : tuple of str
        FMU inputs, in the model's state order.
    output_names : tuple of str
        FMU outputs: the driven torques.
    sample_time : float
        Default of the ``sample_time`` parameter [s].
    functions : tuple of casadi.Function
        ``balance(x) -> (u, cost)`` (when there is an LQR), ``pump(x) -> u`` (swing-up),
        ``track(x, x_ref, u_ref, K) -> u`` (TVLQR).
    constants : dict
        ``#define`` values of the generated header (limits, thresholds, sizes).
    arrays : dict of str to ndarray
        Constant arrays of the generated C (TVLQR plan: ``t_ref``, ``x_ref``, ``u_ref``, ``k_ref``).
    x_start : ndarray, shape (nx,)
        Start values of the inputs.
    """

    kind: str
    model: Model
    state_names: tuple[str, ...]
    output_names: tuple[str, ...]
    sample_time: float
    functions: tuple[ca.Function, ...]
    constants: dict[str, Any] = field(default_factory=dict)
    arrays: dict[str, np.ndarray] = field(default_factory=dict)
    x_start: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def identifier(self) -> str:
        """Model identifier: ``pendulab_<kind>_controller``."""
        return f"pendulab_{self.kind}_controller"


def _pymod(a: ca.SX, b: float) -> ca.SX:
    """Python's / NumPy's float ``a % b`` for ``b > 0``: C's fmod, moved into [0, b) (bit-identical to NumPy)."""
    m = ca.fmod(a, b)
    return ca.if_else(m < 0, m + b, m)


def _wrapped_error(x: ca.SX, ref: Any, names: tuple[str, ...]) -> ca.SX:
    """``pendulab.control.lqr.wrap_state_error(x - ref)``: angle differences into (-pi, pi]."""
    d = x - ref
    return ca.vertcat(
        *[-(_pymod(-d[i] + math.pi, 2 * math.pi) - math.pi) if n.startswith("theta") else d[i] for i, n in enumerate(names)]
    )


def _clip(u: ca.SX, limit: float | None) -> ca.SX:
    return u if limit is None else ca.fmin(ca.fmax(u, -float(limit)), float(limit))


def _affine(u0: Any, K: Any, e: ca.SX, m: int, nx: int) -> ca.SX:
    """``u0 - K e`` row by row (K given as a callable (i, j) -> entry)."""
    return ca.vertcat(*[u0[i] - sum((K(i, j) * e[j] for j in range(nx)), ca.SX(0)) for i in range(m)])


def _finite(name: str, value: Any) -> np.ndarray:
    """``value`` as a float array; ValueError when any entry is NaN or infinite (never exported as a broken law)."""
    arr = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"controller {name} must be finite to be exported, got non-finite entries in {np.ravel(arr)[:6]!r}")
    return arr


def _balance(ident: str, lsf: LinearStateFeedback, x: ca.SX) -> ca.Function:
    for name in ("K", "x_eq", "u_eq") + (("P",) if lsf.P is not None else ()) + (("u_max",) if lsf.u_max is not None else ()):
        _finite(name, getattr(lsf, name))
    names = lsf.model.state_names
    e = _wrapped_error(x, ca.DM(lsf.x_eq), names)
    K = np.asarray(lsf.K, dtype=float)
    u = _clip(_affine([float(v) for v in lsf.u_eq], lambda i, j: float(K[i, j]), e, K.shape[0], len(names)), lsf.u_max)
    cost = ca.mtimes([e.T, ca.DM(np.asarray(lsf.P, dtype=float)), e]) if lsf.P is not None else ca.dot(e, e)
    return ca.Function(f"{ident}_balance", [x], [u, cost], ["x"], ["u", "cost"])


def controller_law(controller: Any) -> ControllerLaw:
    """The control law of a designed pendulab controller, as CasADi functions and constants.

    Parameters
    ----------
    controller : LinearStateFeedback, EnergySwingUp or TVLQRTracker
        A designed sampled-data controller, e.g. from
        :func:`pendulab.control.controllers.controller_for_task` or ``make_controller``.

    Returns
    -------
    ControllerLaw

    Raises
    ------
    TypeError
        Another kind of controller (e.g. the NMPC, whose solver is not generated as C).
    ValueError
        A TVLQR tracker whose final controller is not a linear state feedback.
    """
    if isinstance(controller, LinearStateFeedback):
        kind = "lqr"
    elif isinstance(controller, EnergySwingUp):
        kind = "swingup"
    elif isinstance(controller, TVLQRTracker):
        kind = "tvlqr"
    else:
        raise TypeError(
            "controller must be a LinearStateFeedback (lqr), EnergySwingUp (swingup) or TVLQRTracker (tvlqr), got "
            f"{type(controller).__name__}"
        )
    model: Model = controller.model
    names = model.state_names
    ident = f"pendulab_{kind}_controller"
    x = ca.SX.sym("x", model.nx)
    outs = tuple(controller.input_names)
    consts: dict[str, Any] = {"CTRL_U_MAX": 0.0 if controller.u_max is None else float(controller.u_max)}
    arrays: dict[str, np.ndarray] = {}
    if kind == "lqr":
        funcs: tuple[ca.Function, ...] = (_balance(ident, controller, x),)
        x_start = np.asarray(controller.x_eq, dtype=float)
    elif kind == "swingup":
        sw: EnergySwingUp = controller
        for name in ("k_energy", "kp", "kd", "u_max", "catch_cost", "e_up"):
            _finite(name, getattr(sw, name))
        energy = model.functions["energy"](x, ca.DM(np.asarray(model.p, dtype=float)))
        deficit = sw.e_up - energy
        w1, w2 = x[model.nq], x[model.nq + 1]
        rate = w2 - w1 if sw.actuation == "acrobot" else w1
        pump = ca.if_else(ca.fabs(rate) > 1e-3, sw.k_energy * deficit * rate, sw.u_max * ca.sign(deficit))
        if sw.actuation == "full":
            rel = _pymod(x[1] - x[0] + math.pi, 2 * math.pi) - math.pi
            u = ca.vertcat(pump, -sw.kp * rel - sw.kd * (w2 - w1))
        else:
            u = pump
        pump_f = ca.Function(f"{ident}_pump", [x], [_clip(u, sw.u_max)], ["x"], ["u"])
        funcs = (_balance(ident, sw.balance, x), pump_f)
        consts.update(
            CTRL_CATCH_COST=float(sw.catch_cost),
            CTRL_RELEASE_FACTOR=0.0 if sw.release_factor is None else float(sw.release_factor),
            CTRL_U_MAX=float(sw.u_max),
        )
        x_start = model.rest_state()
    else:
        tr: TVLQRTracker = controller
        for name in ("t_ref", "x_ref", "u_ref", "K") + (("u_max",) if tr.u_max is not None else ()):
            _finite(name, getattr(tr, name))
        m, nx = len(outs), model.nx
        xr, ur, kk = ca.SX.sym("x_ref", nx), ca.SX.sym("u_ref", m), ca.SX.sym("K", m * nx)
        u = _clip(_affine(ur, lambda i, j: kk[i * nx + j], _wrapped_error(x, xr, names), m, nx), tr.u_max)
        funcs = (ca.Function(f"{ident}_track", [x, xr, ur, kk], [u], ["x", "x_ref", "u_ref", "K"], ["u"]),)
        if tr.final is not None:
            if not isinstance(tr.final, LinearStateFeedback):
                raise ValueError(
                    f"a TVLQR tracker's final controller must be a LinearStateFeedback, got {type(tr.final).__name__}"
                )
            funcs = (_balance(ident, tr.final, x), *funcs)
        nk = min(len(tr.K), len(tr.u_ref), len(tr.t_ref) - 1)
        consts.update(
            CTRL_NT=len(tr.t_ref),
            CTRL_NK=nk,
            CTRL_NU_ROWS=len(tr.u_ref),
            CTRL_DESIGN_SAMPLE_TIME=float(tr.sample_time),
            CTRL_HAS_BALANCE=int(tr.final is not None),
        )
        arrays = {
            "t_ref": np.asarray(tr.t_ref, dtype=float),
            "x_ref": np.asarray(tr.x_ref, dtype=float).ravel(),
            "u_ref": np.asarray(tr.u_ref, dtype=float).ravel(),
            "k_ref": np.asarray(tr.K, dtype=float).ravel(),
        }
        x_start = np.asarray(tr.x_ref[0], dtype=float)
    return ControllerLaw(kind, model, names, outs, float(controller.sample_time), funcs, consts, arrays, x_start)


def design_controller(
    name: str,
    task: Any = None,
    *,
    kind: str = "rigid",
    sample_time: float | None = None,
    u_max: float = 20.0,
) -> tuple[Any, np.ndarray, Model]:
    """Design a named controller to export, with its start state and plant model.

    With a task: :func:`pendulab.control.controllers.controller_for_task` (the task's model, actuation,
    torque limit; ``tvlqr`` tracks the task's optimized swing-up). Without: ``make_controller`` on the
    default ``kind`` model (``tvlqr`` tracks the native energy swing-up).

    Parameters
    ----------
    name : {"lqr", "tvlqr", "swingup"}
        Controller.
    task : Task or str, optional
        Swing-up task or its name.
    kind : {"rigid", "elastic"}
        Model without a task.
    sample_time : float, optional
        [s]; default the task's ``dt``, else 0.01.
    u_max : float
        Torque limit [N.m] without a task.

    Returns
    -------
    controller : SampledController
        The designed controller.
    x0 : ndarray, shape (nx,)
        Its natural start state.
    model : Model
        The plant model it was designed for.

    Raises
    ------
    ValueError
        ``nmpc`` (not exportable), an unknown name, a bad sample time, or a failed design.
    """
    from ..control.controllers import controller_for_task, make_controller
    from ..model.model import make_model

    if name == "nmpc":
        raise ValueError(NMPC_NOT_EXPORTABLE)
    if name not in EXPORTABLE:
        raise ValueError(f"controller must be one of {list(EXPORTABLE)}, got {name!r}")
    if task is not None:
        ctrl, x0 = controller_for_task(name, task, sample_time=sample_time)
    else:
        ctrl, x0 = make_controller(name, make_model(kind), 0.01 if sample_time is None else sample_time, u_max=u_max)
    return ctrl, np.asarray(x0, dtype=float), ctrl.model


def _c_double(v: float) -> str:
    if not math.isfinite(v):  # a design with NaN/inf gains or references must not become a silently wrong FMU
        raise ValueError(f"controller data must be finite to be exported, got {v!r}")
    return repr(float(v))


def _c_array(values: np.ndarray) -> str:
    return "{" + ", ".join(_c_double(v) for v in np.ravel(values)) + "}"


def _casadi_source(law: ControllerLaw) -> bytes:
    with tempfile.TemporaryDirectory() as tmp:
        cg = ca.CodeGenerator("controller_casadi.c", {"casadi_int": "int", "with_export": False, "with_header": False})
        for f in law.functions:
            cg.add(f)
        cg.generate(tmp + "/")
        return (Path(tmp) / "controller_casadi.c").read_bytes()


def _token(law: ControllerLaw, fmi_version: int, generated: bytes) -> str:
    h = hashlib.sha256()
    h.update(f"{law.identifier}|{fmi_version}|{law.sample_time!r}|{law.x_start.tobytes().hex()}".encode())
    h.update(generated)
    for name in (*_FIXED[fmi_version], *_HEADERS[fmi_version]):
        h.update((C_DIR / name).read_bytes())
    d = h.hexdigest()
    return "{" + f"{d[:8]}-{d[8:12]}-{d[12:16]}-{d[16:20]}-{d[20:32]}" + "}"


def _header(law: ControllerLaw, token: str) -> str:
    fn = {f.name().rsplit("_", 1)[-1]: f.name() for f in law.functions}
    sz = {k: max(getattr(f, f"sz_{k}")() for f in law.functions) for k in ("arg", "res", "iw", "w")}
    protos = "\n".join(
        f"int {f.name()}(const casadi_real **arg, casadi_real **res, casadi_int *iw, casadi_real *w, int mem);"
        for f in law.functions
    )
    consts = dict(law.constants)
    consts.setdefault("CTRL_HAS_BALANCE", int("balance" in fn))
    lines = [f"#define {k} {_c_double(v) if isinstance(v, float) else v}" for k, v in sorted(consts.items())]
    lines += [f"#define CTRL_FN_{role.upper()} {name}" for role, name in sorted(fn.items())]
    arrays = "\n".join(f"extern const double ctrl_{name}[{max(len(a), 1)}];" for name, a in law.arrays.items())
    return f"""/* Generated by pendulab.fmu.controller_export for the {law.kind} controller. Do not edit. */
#ifndef PENDULAB_CONTROLLER_H
#define PENDULAB_CONTROLLER_H

#ifndef casadi_real
#define casadi_real double
#endif
#ifndef casadi_int
#define casadi_int int
#endif

typedef int (*casadi_fn)(const casadi_real **arg, casadi_real **res, casadi_int *iw, casadi_real *w, int mem);
{protos}

#define CTRL_IDENTIFIER "{law.identifier}"
#define CTRL_TOKEN "{token}"
#define CTRL_MAGIC {zlib.crc32(token.encode()) & 0xFFFFFFFF}UL

#define CTRL_KIND_LQR {KINDS["lqr"]}
#define CTRL_KIND_SWINGUP {KINDS["swingup"]}
#define CTRL_KIND_TVLQR {KINDS["tvlqr"]}
#define CTRL_KIND {KINDS[law.kind]}

#define CTRL_NX {law.model.nx}
#define CTRL_NU {len(law.output_names)}
#define CTRL_VR_TIME {VR_TIME}
#define CTRL_VR_X {VR_X}
#define CTRL_VR_U {VR_U}
#define CTRL_VR_SAMPLE_TIME {VR_SAMPLE_TIME}
#define CTRL_X_START {_c_array(law.x_start)}
#define CTRL_SAMPLE_TIME {_c_double(law.sample_time)}
{chr(10).join(lines)}

#define CTRL_SZ_ARG {sz["arg"]}
#define CTRL_SZ_RES {sz["res"]}
#define CTRL_SZ_IW {sz["iw"]}
#define CTRL_SZ_W {sz["w"]}

extern const char *const ctrl_x_names[CTRL_NX];
{arrays}

#endif
"""


def _data_source(law: ControllerLaw) -> str:
    names = ", ".join(f'"{n}"' for n in law.state_names)
    arrays = "\n".join(f"const double ctrl_{name}[{max(len(a), 1)}] = {_c_array(a)};" for name, a in law.arrays.items())
    return f"""/* Generated by pendulab.fmu.controller_export. Do not edit: the controller's constant data. */
#include "controller.h"

const char *const ctrl_x_names[CTRL_NX] = {{{names}}};
{arrays}
"""


_WRAPPER = """/* Generated by pendulab.fmu.controller_export. Do not edit.
 * Compiles the CasADi-generated control law; CasADi's calling convention leaves some parameters unused. */
#if defined(__GNUC__)
#pragma GCC diagnostic ignored "-Wunused-parameter"
#endif
#include "controller_casadi.c"
"""


def compiled_units(fmi_version: int) -> tuple[str, ...]:
    """Translation units of a controller FMU, in build order.

    Parameters
    ----------
    fmi_version : {2, 3}
        FMI standard.

    Returns
    -------
    tuple of str
        File names among :func:`generate_controller_sources`.
    """
    return (f"ctrl_fmi{fmi_version}.c", "ctrl_core.c", "controller_functions.c", "controller_data.c")


def generate_controller_sources(law: ControllerLaw, fmi_version: int) -> tuple[dict[str, bytes], str]:
    """All C sources of a controller FMU and its token.

    Parameters
    ----------
    law : ControllerLaw
        From :func:`controller_law`.
    fmi_version : {2, 3}
        FMI standard.

    Returns
    -------
    sources : dict of str to bytes
        File name -> contents.
    token : str
        GUID / instantiation token.

    Raises
    ------
    ValueError
        Bad ``fmi_version``.
    """
    if fmi_version not in (2, 3) or isinstance(fmi_version, bool):
        raise ValueError(f"fmi_version must be 2 or 3, got {fmi_version!r}")
    out: dict[str, bytes] = {"controller_casadi.c": _casadi_source(law), "controller_data.c": _data_source(law).encode()}
    token = _token(law, fmi_version, out["controller_casadi.c"] + out["controller_data.c"])
    out["controller.h"] = _header(law, token).encode()
    out["controller_functions.c"] = _WRAPPER.encode()
    for name in (*_FIXED[fmi_version], *_HEADERS[fmi_version]):
        out[name] = (C_DIR / name).read_bytes()
    return dict(sorted(out.items())), token


def controller_model_description(
    law: ControllerLaw, fmi_version: int, token: str, *, timestamp: str | None = None, stop_time: float = 10.0
) -> bytes:
    """The ``modelDescription.xml`` of a controller FMU (Co-Simulation only).

    Parameters
    ----------
    law : ControllerLaw
        The controller.
    fmi_version : {2, 3}
        FMI standard.
    token : str
        GUID (FMI 2) or instantiation token (FMI 3).
    timestamp : str, optional
        ``generationDateAndTime``; omitted when None.
    stop_time : float
        ``DefaultExperiment`` stop time [s]; the step size is the sample time.

    Returns
    -------
    bytes
        UTF-8 XML.
    """
    v3 = fmi_version == 3
    ident = law.identifier
    root = ET.Element(
        "fmiModelDescription",
        {
            "fmiVersion": "3.0" if v3 else "2.0",
            "modelName": ident,
            ("instantiationToken" if v3 else "guid"): token,
            "description": f"pendulab {law.kind} controller for the {law.model.kind} double pendulum: measured state in, "
            "torques out, sample-and-hold at sample_time (CasADi-generated C)",
            "generationTool": f"pendulab {__version__}",
            **({"generationDateAndTime": timestamp} if timestamp else {}),
            "variableNamingConvention": "structured",
            **({} if v3 else {"numberOfEventIndicators": "0"}),
        },
    )
    caps = {
        "modelIdentifier": ident,
        "canHandleVariableCommunicationStepSize": "true",
        ("canGetAndSetFMUState" if v3 else "canGetAndSetFMUstate"): "true",
        ("canSerializeFMUState" if v3 else "canSerializeFMUstate"): "true",
        **({"hasEventMode": "false"} if v3 else {}),
    }
    cs = ET.SubElement(root, "CoSimulation", caps)
    if not v3:
        files = ET.SubElement(cs, "SourceFiles")
        for name in compiled_units(2):
            ET.SubElement(files, "File", name=name)
    units = {info.unit for info in law.model.state_info} | {"N.m", "s"}
    ud = ET.SubElement(root, "UnitDefinitions")
    for name in sorted(units):
        base, disp = UNITS[name]
        u = ET.SubElement(ud, "Unit", name=name)
        ET.SubElement(u, "BaseUnit", {k: str(v) for k, v in base.items()})
        if disp:
            ET.SubElement(u, "DisplayUnit", name=disp[0], factor=repr(float(disp[1])))
    cats = ET.SubElement(root, "LogCategories")
    for name, desc in (("logStatusError", "errors"), ("logStatusWarning", "warnings"), ("logCalls", "every FMI call (debug)")):
        ET.SubElement(cats, "Category", name=name, description=desc)
    ET.SubElement(root, "DefaultExperiment", startTime="0.0", stopTime=repr(float(stop_time)), stepSize=repr(law.sample_time))
    mv = ET.SubElement(root, "ModelVariables")
    info = {i.name: i for i in law.model.state_info}
    variables: list[tuple[str, int, dict[str, str], dict[str, str]]] = []
    if v3:
        variables.append(
            ("time", VR_TIME, {"causality": "independent", "variability": "continuous", "description": "time"}, {"unit": "s"})
        )
    for i, n in enumerate(law.state_names):
        common = {"causality": "input", "variability": "continuous", "description": f"measured {info[n].description}"}
        variables.append((n, VR_X + i, common, {"unit": info[n].unit, "start": repr(float(law.x_start[i]))}))
    for i, n in enumerate(law.output_names):
        common = {
            "causality": "output",
            "variability": "discrete",
            "initial": "calculated",
            "description": f"torque {n} [N.m], held between samples",
        }
        variables.append((n, VR_U + i, common, {"unit": "N.m"}))
    variables.append(
        (
            "sample_time",
            VR_SAMPLE_TIME,
            {
                "causality": "parameter",
                "variability": "fixed",
                "initial": "exact",
                "description": "sample period [s] (> 0): samples at startTime + k sample_time",
            },
            {"unit": "s", "start": repr(law.sample_time)},
        )
    )
    index: dict[int, int] = {}
    for pos, (name, vr, common, attrs) in enumerate(variables, start=1):
        index[vr] = pos
        if v3:
            ET.SubElement(mv, "Float64", {"name": name, "valueReference": str(vr), **common, **attrs})
        else:
            sv = ET.SubElement(mv, "ScalarVariable", {"name": name, "valueReference": str(vr), **common})
            ET.SubElement(sv, "Real", attrs)
    ms = ET.SubElement(root, "ModelStructure")
    inputs = [VR_X + i for i in range(len(law.state_names))]
    outputs = [VR_U + i for i in range(len(law.output_names))]
    if v3:
        for tag in ("Output", "InitialUnknown"):
            for vr in outputs:
                ET.SubElement(ms, tag, valueReference=str(vr), dependencies=" ".join(map(str, inputs)))
    else:
        for tag in ("Outputs", "InitialUnknowns"):
            group = ET.SubElement(ms, tag)
            for vr in outputs:
                ET.SubElement(group, "Unknown", index=str(index[vr]), dependencies=" ".join(str(index[d]) for d in inputs))
    ET.indent(root, space="  ")
    return b'<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="utf-8") + b"\n"


def _build_description(law: ControllerLaw) -> bytes:
    root = ET.Element("fmiBuildDescription", fmiVersion="3.0")
    bc = ET.SubElement(root, "BuildConfiguration", modelIdentifier=law.identifier)
    sfs = ET.SubElement(bc, "SourceFileSet", language="C99")
    for name in compiled_units(3):
        ET.SubElement(sfs, "SourceFile", name=name)
    ET.indent(root, space="  ")
    return b'<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="utf-8") + b"\n"


def export_controller(
    controller: Any,
    path: str | os.PathLike,
    fmi_version: int = 2,
    *,
    timestamp: bool = True,
    stop_time: float = 10.0,
    cc: str | None = None,
) -> Path:
    """Write a Co-Simulation FMU of a designed controller (LQR, energy swing-up or TVLQR).

    Parameters
    ----------
    controller : LinearStateFeedback, EnergySwingUp or TVLQRTracker
        The designed controller (see :func:`controller_law`).
    path : path-like
        Output file, conventionally ``*.fmu``.
    fmi_version : {2, 3}
        FMI standard of the archive.
    timestamp : bool
        Write ``generationDateAndTime`` (False: byte-for-byte reproducible archive).
    stop_time : float
        ``DefaultExperiment`` stop time [s].
    cc : str, optional
        C compiler.

    Returns
    -------
    Path
        The written FMU.

    Raises
    ------
    TypeError
        Not an exportable controller.
    ValueError
        Bad ``fmi_version`` or ``stop_time``.
    CompilerNotFoundError (RuntimeError)
        No C compiler found.
    RuntimeError
        Compilation failed.
    """
    law = controller_law(controller)
    if not (isinstance(stop_time, (int, float)) and math.isfinite(stop_time) and stop_time > 0):
        raise ValueError(f"stop_time must be a positive finite number [s], got {stop_time!r}")
    sources, token = generate_controller_sources(law, fmi_version)
    stamp = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ") if timestamp else None
    files = {"modelDescription.xml": controller_model_description(law, fmi_version, token, timestamp=stamp, stop_time=stop_time)}
    files.update({f"sources/{n}": d for n, d in sources.items()})
    if fmi_version == 3:
        files["sources/buildDescription.xml"] = _build_description(law)
    with tempfile.TemporaryDirectory() as tmp:
        src = Path(tmp) / "sources"
        src.mkdir()
        for name, data in sources.items():
            (src / name).write_bytes(data)
        lib = compile_shared(src, compiled_units(fmi_version), Path(tmp) / f"{law.identifier}{shared_library_suffix()}", cc=cc)
        files[f"binaries/{binary_platform(fmi_version)}/{lib.name}"] = lib.read_bytes()
    path = Path(path)
    with atomic_open(path, "wb") as fh, zipfile.ZipFile(fh, "w", zipfile.ZIP_DEFLATED) as zf:
        for name in sorted(files):
            info = zipfile.ZipInfo(name, date_time=_ZIP_DATE)
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            zf.writestr(info, files[name])
    return path
