"""``modelDescription.xml`` (FMI 2.0 and 3.0) and ``buildDescription.xml`` of a pendulab FMU.

Names, units and descriptions come from the model's own tables
(``state_info``, ``input_info``, ``output_info``, ``param_info``); the
ModelStructure dependencies come from the CasADi sparsity of the Jacobian of
(derivatives, outputs) with respect to (states, inputs).
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET

from .._version import __version__
from ..model.model import Model
from .codegen import (
    DEFAULT_TOLERANCE,
    SOLVER_NAMES,
    SPRING_LIMIT,
    VR_HMAX,
    VR_SOLVER,
    VR_TIME,
    VR_TOL,
    VR_Z,
    ModelLayout,
    compiled_sources,
    event_indicator_names,
)

__all__ = ["model_description", "build_description", "UNITS", "POSITIVE_MIN", "BELOW_ONE_MAX", "POSITIVE_STATES", "variables"]

# unit -> SI base-unit exponents (FMI BaseUnit attributes) and optional display unit (name, factor)
_DEG = 180.0 / math.pi
UNITS: dict[str, tuple[dict[str, int], tuple[str, float] | None]] = {
    "s": ({"s": 1}, None),
    "rad": ({"rad": 1}, ("deg", _DEG)),
    "rad/s": ({"s": -1, "rad": 1}, ("deg/s", _DEG)),
    "rad/s2": ({"s": -2, "rad": 1}, ("deg/s2", _DEG)),
    "m": ({"m": 1}, None),
    "m/s": ({"m": 1, "s": -1}, None),
    "m/s2": ({"m": 1, "s": -2}, None),
    "kg": ({"kg": 1}, None),
    "kg.m2": ({"kg": 1, "m": 2}, None),
    "N.m": ({"kg": 1, "m": 2, "s": -2}, None),
    "J": ({"kg": 1, "m": 2, "s": -2}, None),
    "N/m": ({"kg": 1, "s": -2}, None),
    "N.s/m": ({"kg": 1, "s": -1}, None),
    "N.m.s/rad": ({"kg": 1, "m": 2, "s": -1, "rad": -1}, None),
    "1": ({}, None),  # dimensionless (the gear ratio)
}
#: ``min`` of a variable that must be > 0: FMI has no exclusive bound; the smallest positive double
#: (subnormal 2**-1074) makes ``value >= min`` the same as ``value > 0`` for every double.
POSITIVE_MIN = "5e-324"
#: ``max`` of a variable that must be < 1 (the solver tolerance): the largest double below 1.
BELOW_ONE_MAX = repr(1.0 - 2.0**-53)
#: States that must stay positive (spring lengths of the elastic model; the model is singular at r = 0).
POSITIVE_STATES = frozenset({"r1", "r2"})
_DERIVATIVE_UNIT = {"rad": "rad/s", "rad/s": "rad/s2", "m": "m/s", "m/s": "m/s2"}
_CATEGORIES = (
    ("logStatusError", "errors: bad calls, bad values, solver failures"),
    ("logStatusWarning", "warnings"),
    ("logCalls", "every FMI call and initialization details (debug)"),
)


def _fmt(v: float) -> str:
    return repr(float(v))


def _clean(description: str) -> str:
    # Python-side "None means derived" has no FMU meaning: the start value is explicit.
    return re.sub(r"\s*\(None: [^)]*\)", "", description)


class _Var:
    """One FMU variable, independent of the FMI version."""

    def __init__(self, name: str, vr: int, causality: str, variability: str, description: str, **attrs: str) -> None:
        self.name, self.vr, self.causality, self.variability, self.description = (
            name,
            vr,
            causality,
            variability,
            description,
        )
        self.type = attrs.pop("type", "Real")
        self.initial = attrs.pop("initial", None)
        self.attrs = attrs  # unit, displayUnit, start, min, max, derivative (as VR)


def _variables(model: Model, lay: ModelLayout, fmi_version: int) -> list[_Var]:
    out: list[_Var] = []
    if fmi_version == 3:
        out.append(_Var("time", VR_TIME, "independent", "continuous", "simulation time", unit="s"))
    for i, info in enumerate(model.state_info):
        disp = UNITS[info.unit][1]
        extra = {"displayUnit": disp[0]} if disp else {}
        if info.name in POSITIVE_STATES:
            extra["min"] = POSITIVE_MIN
        out.append(
            _Var(
                info.name,
                lay.vr("x", i),
                "local",
                "continuous",
                info.description,
                initial="exact",
                unit=info.unit,
                start=_fmt(lay.x_start[i]),
                **extra,
            )
        )
    for i, info in enumerate(model.state_info):
        unit = _DERIVATIVE_UNIT[info.unit]
        disp = UNITS[unit][1]
        extra = {"displayUnit": disp[0]} if disp else {}
        out.append(
            _Var(
                f"der({info.name})",
                lay.vr("dx", i),
                "local",
                "continuous",
                f"time derivative of {info.name}",
                initial="calculated",
                unit=unit,
                derivative=str(lay.vr("x", i)),
                **extra,
            )
        )
    for i, info in enumerate(model.input_info):
        out.append(_Var(info.name, lay.vr("u", i), "input", "continuous", info.description, unit=info.unit, start="0.0"))
    for i, info in enumerate(model.output_info):
        out.append(
            _Var(info.name, lay.vr("y", i), "output", "continuous", info.description, initial="calculated", unit=info.unit)
        )
    for i, name in enumerate(event_indicator_names(lay.kind, lay.flip_events)):
        j = int(name[-1])  # spring or link number
        spring = name.startswith("spring")
        desc = (
            f"event indicator: r{j} - {SPRING_LIMIT!r} L{j} (the model is singular at r = 0; the FMU stops when it reaches 0)"
            if spring
            else f"event indicator: pi - |theta{j}| (0 when link {j} passes the upright position; Model Exchange)"
        )
        out.append(_Var(name, VR_Z + i, "local", "continuous", desc, initial="calculated", unit="m" if spring else "rad"))
    for i, info in enumerate(model.param_info):
        tun = lay.p_tunable[i]
        extra = {"min": POSITIVE_MIN if info.positive else "0.0"}
        out.append(
            _Var(
                info.name,
                lay.vr("p", i),
                "parameter",
                "tunable" if tun else "fixed",
                _clean(info.description),
                initial="exact",
                unit=info.unit,
                start=_fmt(lay.p_default[i]),
                **extra,
            )
        )
    out.append(
        _Var(
            "solver_tolerance",
            VR_TOL,
            "parameter",
            "fixed",
            "relative and absolute error tolerance of the embedded solver (overridden by the master's "
            "tolerance when it defines one)",
            initial="exact",
            start=_fmt(DEFAULT_TOLERANCE),
            min=POSITIVE_MIN,
            max=BELOW_ONE_MAX,
        )
    )
    out.append(
        _Var(
            "max_step",
            VR_HMAX,
            "parameter",
            "fixed",
            "largest internal step of the embedded solver (0: unlimited)",
            initial="exact",
            unit="s",
            start="0.0",
            min="0.0",
        )
    )
    out.append(
        _Var(
            "solver",
            VR_SOLVER,
            "parameter",
            "fixed",
            "embedded co-simulation solver: "
            + ", ".join(f"{i} = {n}" for i, n in enumerate(SOLVER_NAMES))
            + " (Rosenbrock, L-stable: use for stiff springs)",
            type="Integer",
            initial="exact",
            start="0",
            min="0",
            max=str(len(SOLVER_NAMES) - 1),
        )
    )
    return out


def variables(model: Model, lay: ModelLayout, fmi_version: int) -> list:
    """The FMU's variables in ``ModelVariables`` order (what ``modelDescription.xml`` and the documentation list).

    Parameters
    ----------
    model : Model
        The pendulum.
    lay : ModelLayout
        Value references and start values.
    fmi_version : {2, 3}
        FMI standard (FMI 3 lists ``time``).

    Returns
    -------
    list
        Objects with ``name``, ``vr``, ``causality``, ``variability``, ``description``, ``type``,
        ``initial`` and ``attrs`` (unit, displayUnit, start, min, max, derivative as strings).
    """
    return _variables(model, lay, fmi_version)


def _unit_definitions(parent: ET.Element, used: set[str]) -> None:
    ud = ET.SubElement(parent, "UnitDefinitions")
    for name in sorted(used):
        base, disp = UNITS[name]
        u = ET.SubElement(ud, "Unit", name=name)
        ET.SubElement(u, "BaseUnit", {k: str(v) for k, v in base.items()})
        if disp:
            ET.SubElement(u, "DisplayUnit", name=disp[0], factor=_fmt(disp[1]))


def _dependencies(lay: ModelLayout, row: int, with_params: bool = False) -> list[int]:
    """Value references that row ``row`` of (derivatives; outputs) depends on.

    States and inputs; with ``with_params`` also the parameters (initial unknowns).
    """
    groups = [("x", lay.nx), ("u", lay.nu)] + ([("p", lay.np)] if with_params else [])
    out, col = [], 0
    for group, n in groups:
        out += [lay.vr(group, j) for j in range(n) if lay.dependencies[row, col + j]]
        col += n
    return out


def model_description(
    model: Model,
    lay: ModelLayout,
    fmi_version: int,
    token: str,
    *,
    timestamp: str | None = None,
    stop_time: float = 10.0,
    step_size: float = 0.01,
) -> bytes:
    """The ``modelDescription.xml`` of a pendulab FMU (Model Exchange and Co-Simulation).

    Parameters
    ----------
    model : Model
        Rigid or elastic pendulum; gives variable names, units, descriptions
        and start values.
    lay : ModelLayout
        Value references and the dependency sparsity of the generated code.
    fmi_version : int
        2 or 3 (FMI 2.0 or 3.0 schema).
    token : str
        GUID (FMI 2) or instantiation token (FMI 3).
    timestamp : str, optional
        ``generationDateAndTime`` (ISO 8601 UTC); omitted when None.
    stop_time : float
        ``DefaultExperiment`` stop time [s].
    step_size : float
        ``DefaultExperiment`` communication step [s].

    Returns
    -------
    bytes
        UTF-8 XML with declaration, indented, ending in a newline.
    """
    v3 = fmi_version == 3
    ident = lay.identifier
    root = ET.Element(
        "fmiModelDescription",
        {
            "fmiVersion": "3.0" if v3 else "2.0",
            "modelName": ident,
            ("instantiationToken" if v3 else "guid"): token,
            "description": f"{model.kind} double pendulum (pendulab): CasADi-generated model functions, "
            "embedded dopri5 / rodas4 co-simulation solvers",
            "generationTool": f"pendulab {__version__}",
            **({"generationDateAndTime": timestamp} if timestamp else {}),
            "variableNamingConvention": "structured",
            **({} if v3 else {"numberOfEventIndicators": str(len(event_indicator_names(lay.kind, lay.flip_events)))}),
        },
    )
    caps = {
        ("canGetAndSetFMUState" if v3 else "canGetAndSetFMUstate"): "true",
        ("canSerializeFMUState" if v3 else "canSerializeFMUstate"): "true",
        ("providesDirectionalDerivatives" if v3 else "providesDirectionalDerivative"): "true",
        **({"providesAdjointDerivatives": "true"} if v3 else {}),
    }
    me = ET.SubElement(root, "ModelExchange", {"modelIdentifier": ident, **caps})
    cs = ET.SubElement(
        root,
        "CoSimulation",
        {
            "modelIdentifier": ident,
            "canHandleVariableCommunicationStepSize": "true",
            # a spring reaching its limit (or, in event mode, a flip) ends the step early when the importer allows it
            **({"mightReturnEarlyFromDoStep": "true"} if v3 and (lay.kind == "elastic" or lay.flip_events) else {}),
            **({"hasEventMode": "true"} if v3 and lay.flip_events else {}),
            **caps,
        },
    )
    if not v3:
        for el in (me, cs):
            files = ET.SubElement(el, "SourceFiles")
            for name in compiled_sources(2):
                ET.SubElement(files, "File", name=name)
    variables = _variables(model, lay, fmi_version)
    _unit_definitions(root, {v.attrs["unit"] for v in variables if "unit" in v.attrs})
    cats = ET.SubElement(root, "LogCategories")
    for name, desc in _CATEGORIES:
        ET.SubElement(cats, "Category", name=name, description=desc)
    ET.SubElement(
        root,
        "DefaultExperiment",
        startTime="0.0",
        stopTime=_fmt(stop_time),
        tolerance=_fmt(DEFAULT_TOLERANCE),
        stepSize=_fmt(step_size),
    )
    mv = ET.SubElement(root, "ModelVariables")
    index = {}  # FMI 2 ModelStructure refers to 1-based positions in ModelVariables
    for pos, var in enumerate(variables, start=1):
        index[var.vr] = pos
        common = {
            "name": var.name,
            "valueReference": str(var.vr),
            "description": var.description,
            "causality": var.causality,
            "variability": var.variability,
        }
        if var.initial:
            common["initial"] = var.initial
        attrs = dict(var.attrs)
        if v3:
            tag = "Int32" if var.type == "Integer" else "Float64"
            ET.SubElement(mv, tag, {**common, **attrs})
        else:
            if "derivative" in attrs:
                attrs["derivative"] = str(index[int(attrs["derivative"])])
            sv = ET.SubElement(mv, "ScalarVariable", common)
            ET.SubElement(sv, var.type, attrs)
    ms = ET.SubElement(root, "ModelStructure")
    outputs = [(lay.vr("y", i), lay.nx + i) for i in range(lay.ny)]
    derivs = [(lay.vr("dx", i), i) for i in range(lay.nx)]
    if v3:
        for tag, rows in (("Output", outputs), ("ContinuousStateDerivative", derivs), ("InitialUnknown", outputs + derivs)):
            for vr, row in rows:
                deps = _dependencies(lay, row, with_params=tag == "InitialUnknown")
                ET.SubElement(ms, tag, valueReference=str(vr), dependencies=" ".join(map(str, deps)))
        for i, name in enumerate(event_indicator_names(lay.kind, lay.flip_events)):
            # a spring margin depends on the state r_j (index 2, 3 of the elastic state), a flip margin on theta_j
            j = int(name[-1]) - 1
            state = lay.vr("x", 2 + j if name.startswith("spring") else j)
            ET.SubElement(ms, "EventIndicator", valueReference=str(VR_Z + i), dependencies=str(state))
    else:
        for tag, rows in (("Outputs", outputs), ("Derivatives", derivs), ("InitialUnknowns", outputs + derivs)):
            group = ET.SubElement(ms, tag)
            for vr, row in sorted(rows, key=lambda r: index[r[0]]):
                deps = sorted(index[d] for d in _dependencies(lay, row, with_params=tag == "InitialUnknowns"))
                ET.SubElement(group, "Unknown", index=str(index[vr]), dependencies=" ".join(map(str, deps)))
    ET.indent(root, space="  ")
    return b'<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="utf-8") + b"\n"


def build_description(lay: ModelLayout) -> bytes:
    """FMI 3 ``sources/buildDescription.xml``: what ``fmpy compile`` (or any build tool) compiles.

    Parameters
    ----------
    lay : ModelLayout
        Gives the model identifier.

    Returns
    -------
    bytes
        UTF-8 XML listing the C99 sources of the FMI 3 build.
    """
    root = ET.Element("fmiBuildDescription", fmiVersion="3.0")
    bc = ET.SubElement(root, "BuildConfiguration", modelIdentifier=lay.identifier)
    sfs = ET.SubElement(bc, "SourceFileSet", language="C99")
    for name in compiled_sources(3):
        ET.SubElement(sfs, "SourceFile", name=name)
    ET.indent(root, space="  ")
    return b'<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="utf-8") + b"\n"
