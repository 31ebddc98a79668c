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

The law is built in :mod:`pendulab.fmu.controller_laws`, its C in :mod:`pendulab.fmu.controller_sources`;
this module writes the model description and the archive (their public names are importable from here too).
"""

from __future__ import annotations

import datetime as _dt
import html
import math
import os
import tempfile
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path
from typing import Any

from .._inputs import checked
from .._io import atomic_open
from .._version import __version__
from ..native.build import shared_library_suffix
from .binaries import MANIFEST_PATH, binary_manifest
from .controller_laws import EXPORTABLE, ControllerLaw, controller_law, design_controller
from .controller_laws import NMPC_NOT_EXPORTABLE as NMPC_NOT_EXPORTABLE
from .controller_sources import KINDS as KINDS
from .controller_sources import (
    VR_SAMPLE_TIME,
    VR_TIME,
    VR_U,
    VR_X,
    compiled_units,
    generate_controller_sources,
)
from .documentation import binaries_html
from .export import binary_platform, compile_host
from .model_description import UNITS
from .platforms import runtime_requirement

__all__ = [
    "EXPORTABLE",
    "ControllerLaw",
    "controller_law",
    "design_controller",
    "generate_controller_sources",
    "controller_model_description",
    "export_controller",
]

_ZIP_DATE = (1980, 1, 1, 0, 0, 0)


@checked(stop_time="t_final")
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


def _documentation(law: ControllerLaw, fmi_version: int, binaries: dict[str, str]) -> bytes:
    """``documentation/index.html`` of a controller FMU: the interface, sample-and-hold, and what the binary needs."""
    e = html.escape
    rows = [f"<tr><td>{e(n)}</td><td>input</td><td>measured state</td></tr>" for n in law.state_names]
    rows += [f"<tr><td>{e(n)}</td><td>output</td><td>torque [N.m], held between samples</td></tr>" for n in law.output_names]
    rows.append(f"<tr><td>sample_time</td><td>parameter</td><td>sample period [s], default {law.sample_time!r}</td></tr>")
    page = f"""<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>{e(law.identifier)}</title>
</head>
<body>
<h1>{e(law.identifier)}</h1>
<p>Generated by pendulab {e(__version__)}: the {e(law.kind)} controller of the {e(law.model.kind)} double pendulum as an
FMI {fmi_version}.0 Co-Simulation FMU (CasADi-generated C, sources included; no Python or CasADi runtime is needed).
Samples at startTime + k&middot;sample_time; at a sample instant the outputs are the law at the current inputs, between
samples they are held. <code>DoStep</code> with a step size &le; 0 or a non-finite one returns <code>Error</code>.</p>
<h2 id="variables">Variables</h2>
<table>
<tr><th>name</th><th>causality</th><th>description</th></tr>
{chr(10).join(rows)}
</table>
{binaries_html(binaries)}
</body>
</html>
"""
    return page.encode()


def _build_description(law: ControllerLaw) -> bytes:
    root = ET.Element("fmiBuildDescription", fmiVersion="3.0")
    bc = ET.SubElement(root, "BuildConfiguration", modelIdentifier=law.identifier)
    sfs = ET.SubElement(bc, "SourceFileSet", language="C99")
    for name in compiled_units(3):
        ET.SubElement(sfs, "SourceFile", name=name)
    ET.indent(root, space="  ")
    return b'<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="utf-8") + b"\n"


@checked(stop_time="t_final")
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
        C compiler; default as :func:`pendulab.fmu.export.export` (on Linux with ``pendulab[cross]``: Zig
        targeting glibc 2.17). ``documentation/index.html`` states what the binary needs, read from the file.

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
        lib = compile_host(src, compiled_units(fmi_version), Path(tmp) / f"{law.identifier}{shared_library_suffix()}", cc=cc)
        files[f"binaries/{binary_platform(fmi_version)}/{lib.name}"] = lib.read_bytes()
    binaries = {name: runtime_requirement(data) for name, data in files.items() if name.startswith("binaries/")}
    files["documentation/index.html"] = _documentation(law, fmi_version, binaries)
    files[MANIFEST_PATH] = binary_manifest(files)  # the binaries' SHA-256 (pendulab.fmu.binaries)
    path = Path(path)
    with atomic_open(path, "wb") as fh, zipfile.ZipFile(fh, "w", zipfile.ZIP_DEFLATED) as zf:
        for name in sorted(files):
            info = zipfile.ZipInfo(name, date_time=_ZIP_DATE)
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            zf.writestr(info, files[name])
    return path
