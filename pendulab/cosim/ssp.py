"""The closed loop as an SSP (System Structure and Parameterization 1.0): plant FMU + controller FMU.

:func:`export_ssp` writes an ``.ssp`` archive (a zip) with

* ``SystemStructure.ssd``: one system ``loop`` with the components ``plant`` and ``controller``, their
  connectors, the connections plant state -> controller input and controller torque -> plant input,
  the units and the default experiment (stop time, the controller's sample time as step);
* ``resources/plant.fmu``: the pendulum FMU (:func:`pendulab.fmu.export`) with the controller's start
  state as start values, its states also declared outputs (SSP connects outputs to inputs, and for
  FMI the connector kind must match the variable's causality; a state may be an output with
  ``initial="exact"``, as the Reference FMUs' BouncingBall ``h``; the binary is unchanged);
* ``resources/controller.fmu``: the controller FMU (:func:`pendulab.fmu.controller_export.export_controller`);
* ``resources/plant.ssv`` and ``resources/controller.ssv``: parameter sets (the plant's parameters, the
  controller's sample time), bound to the components by ``ParameterBinding``.

Run it under any SSP importer; with the controller's sample time as communication step it is the loop
of :func:`pendulab.cosim.cosim` (plant FMU under the Python controller, sample-and-hold).
"""

from __future__ import annotations

import io
import math
import os
import tempfile
import xml.etree.ElementTree as ET
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .._inputs import checked
from .._io import atomic_open
from .._version import __version__
from ..fmu.controller_export import design_controller, export_controller
from ..fmu.export import export
from ..fmu.model_description import UNITS

__all__ = ["SSD_NS", "SSC_NS", "SSV_NS", "SspExport", "export_ssp", "states_as_outputs"]

SSD_NS = "http://ssp-standard.org/SSP1/SystemStructureDescription"
SSC_NS = "http://ssp-standard.org/SSP1/SystemStructureCommon"
SSV_NS = "http://ssp-standard.org/SSP1/SystemStructureParameterValues"
_FMU_TYPE = "application/x-fmu-sharedlibrary"
_ZIP_DATE = (1980, 1, 1, 0, 0, 0)


@dataclass(frozen=True)
class SspExport:
    """What :func:`export_ssp` wrote.

    Attributes
    ----------
    path : Path
        The ``.ssp`` archive.
    controller : str
        Controller name.
    task : str or None
        Task name.
    fmi_version : int
        FMI version of both FMUs.
    sample_time : float
        Controller sample time = the SSD's default step [s].
    stop_time : float
        Default stop time [s].
    x0 : ndarray, shape (nx,)
        Start state (the plant FMU's start values).
    state_names : tuple of str
        Connected signals plant -> controller.
    torque_names : tuple of str
        Connected signals controller -> plant.
    """

    path: Path
    controller: str
    task: str | None
    fmi_version: int
    sample_time: float
    stop_time: float
    x0: np.ndarray
    state_names: tuple[str, ...]
    torque_names: tuple[str, ...]


def states_as_outputs(fmu: bytes, state_names: tuple[str, ...]) -> bytes:
    """A pendulab plant FMU whose states are also outputs (causality ``output``, ``initial="exact"``).

    Only ``modelDescription.xml`` changes: the variables keep their value references (the binary
    reads them as before) and ``ModelStructure`` lists them as outputs (first: they come first in
    ``ModelVariables``). Outputs with ``initial="exact"`` are no initial unknowns.

    Parameters
    ----------
    fmu : bytes
        The FMU archive.
    state_names : tuple of str
        Names of the state variables.

    Returns
    -------
    bytes
        The new archive (same entries, same order).

    Raises
    ------
    ValueError
        A state name is not a local variable of the FMU.
    """
    with zipfile.ZipFile(io.BytesIO(fmu)) as zin:
        root = ET.fromstring(zin.read("modelDescription.xml"))
        v3 = root.get("fmiVersion", "").startswith("3")
        mv = root.find("ModelVariables")
        found: dict[str, tuple[int, str]] = {}
        for pos, var in enumerate(list(mv), start=1):
            name = var.get("name")
            if name in state_names:
                if var.get("causality", "local") != "local":
                    raise ValueError(f"state {name!r} of the FMU has causality {var.get('causality')!r}, expected local")
                var.set("causality", "output")
                found[name] = (pos, var.get("valueReference"))
        missing = [n for n in state_names if n not in found]
        if missing:
            raise ValueError(f"state_names {missing} are not variables of the FMU")
        ms = root.find("ModelStructure")
        if v3:
            for k, name in enumerate(state_names):
                el = ET.Element("Output", valueReference=found[name][1], dependencies=found[name][1])
                ms.insert(k, el)
        else:
            outputs = ms.find("Outputs")
            for k, name in enumerate(state_names):
                outputs.insert(k, ET.Element("Unknown", index=str(found[name][0]), dependencies=str(found[name][0])))
        ET.indent(root, space="  ")
        md = b'<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="utf-8") + b"\n"
        out = io.BytesIO()
        with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as zout:
            for info in zin.infolist():
                zout.writestr(info, md if info.filename == "modelDescription.xml" else zin.read(info.filename))
    return out.getvalue()


def _units_element(parent: ET.Element, tag: str, units: set[str]) -> None:
    el = ET.SubElement(parent, tag)
    for name in sorted(units):
        base, _ = UNITS[name]
        u = ET.SubElement(el, f"{{{SSC_NS}}}Unit", name=name)
        ET.SubElement(u, f"{{{SSC_NS}}}BaseUnit", {k: str(v) for k, v in base.items()})


def _connector(parent: ET.Element, name: str, kind: str, unit: str | None) -> None:
    c = ET.SubElement(parent, f"{{{SSD_NS}}}Connector", name=name, kind=kind)
    ET.SubElement(c, f"{{{SSC_NS}}}Real", {"unit": unit} if unit else {})


def _xml(root: ET.Element) -> bytes:
    ET.indent(root, space="  ")
    return b'<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="utf-8") + b"\n"


def _parameter_set(name: str, values: list[tuple[str, float, str | None]]) -> bytes:
    root = ET.Element(f"{{{SSV_NS}}}ParameterSet", version="1.0", name=name)
    params = ET.SubElement(root, f"{{{SSV_NS}}}Parameters")
    for pname, value, unit in values:
        p = ET.SubElement(params, f"{{{SSV_NS}}}Parameter", name=pname)
        ET.SubElement(p, f"{{{SSV_NS}}}Real", {"value": repr(float(value)), **({"unit": unit} if unit else {})})
    used = {u for _, _, u in values if u}
    if used:
        _units_element(root, f"{{{SSV_NS}}}Units", used)
    return _xml(root)


def _ssd(model: Any, ctrl: Any, sample_time: float, stop_time: float, name: str, description: str) -> bytes:
    ET.register_namespace("ssd", SSD_NS)
    ET.register_namespace("ssc", SSC_NS)
    ET.register_namespace("ssv", SSV_NS)
    root = ET.Element(
        f"{{{SSD_NS}}}SystemStructureDescription",
        {"version": "1.0", "name": name, "description": description, "generationTool": f"pendulab {__version__}"},
    )
    system = ET.SubElement(root, f"{{{SSD_NS}}}System", name="loop", description="plant FMU under the controller FMU")
    elements = ET.SubElement(system, f"{{{SSD_NS}}}Elements")
    units = {"N.m", "s"}
    state_units = {i.name: i.unit for i in model.state_info}
    units |= set(state_units.values())
    param_units = {i.name: i.unit for i in model.param_info}
    units |= {u for u in param_units.values() if u in UNITS}
    # plant
    plant = ET.SubElement(elements, f"{{{SSD_NS}}}Component", name="plant", type=_FMU_TYPE, source="resources/plant.fmu")
    pc = ET.SubElement(plant, f"{{{SSD_NS}}}Connectors")
    for n in model.state_names:
        _connector(pc, n, "output", state_units[n])
    for n in model.input_names:
        _connector(pc, n, "input", "N.m")
    for n in model.param_names:
        _connector(pc, n, "parameter", param_units[n] if param_units[n] in UNITS else None)
    pb = ET.SubElement(ET.SubElement(plant, f"{{{SSD_NS}}}ParameterBindings"), f"{{{SSD_NS}}}ParameterBinding")
    pb.set("source", "resources/plant.ssv")
    # controller
    comp = ET.SubElement(elements, f"{{{SSD_NS}}}Component", name="controller", type=_FMU_TYPE, source="resources/controller.fmu")
    cc = ET.SubElement(comp, f"{{{SSD_NS}}}Connectors")
    for n in model.state_names:
        _connector(cc, n, "input", state_units[n])
    for n in ctrl.input_names:
        _connector(cc, n, "output", "N.m")
    _connector(cc, "sample_time", "parameter", "s")
    cb = ET.SubElement(ET.SubElement(comp, f"{{{SSD_NS}}}ParameterBindings"), f"{{{SSD_NS}}}ParameterBinding")
    cb.set("source", "resources/controller.ssv")
    connections = ET.SubElement(system, f"{{{SSD_NS}}}Connections")
    for n in model.state_names:
        ET.SubElement(
            connections,
            f"{{{SSD_NS}}}Connection",
            startElement="plant",
            startConnector=n,
            endElement="controller",
            endConnector=n,
        )
    for n in ctrl.input_names:
        ET.SubElement(
            connections,
            f"{{{SSD_NS}}}Connection",
            startElement="controller",
            startConnector=n,
            endElement="plant",
            endConnector=n,
        )
    _units_element(root, f"{{{SSD_NS}}}Units", units)
    ET.SubElement(root, f"{{{SSD_NS}}}DefaultExperiment", startTime="0.0", stopTime=repr(float(stop_time)))
    return _xml(root)


@checked(stop_time="t_final")
def export_ssp(
    path: str | os.PathLike,
    *,
    controller: str = "lqr",
    task: Any = None,
    kind: str = "rigid",
    fmi_version: int = 2,
    sample_time: float | None = None,
    stop_time: float | None = None,
    timestamp: bool = True,
    cc: str | None = None,
) -> SspExport:
    """Write the closed loop (plant FMU + controller FMU + connections + parameter sets) as an SSP 1.0 archive.

    Parameters
    ----------
    path : path-like
        Output file, conventionally ``*.ssp``.
    controller : {"lqr", "tvlqr", "swingup"}
        Controller (designed by :func:`pendulab.fmu.controller_export.design_controller`).
    task : Task or str, optional
        Swing-up task: model, actuation, torque limit, start state, horizon and sample time.
    kind : {"rigid", "elastic"}
        Plant model without a task.
    fmi_version : {2, 3}
        FMI version of both FMUs.
    sample_time : float, optional
        Controller sample time [s]; default the task's ``dt``, else 0.01.
    stop_time : float, optional
        Default experiment stop time [s]; default the task's horizon, else 10.
    timestamp : bool
        Write generation time stamps into the FMUs.
    cc : str, optional
        C compiler.

    Returns
    -------
    SspExport

    Raises
    ------
    ValueError
        Unknown or non-exportable controller (``nmpc``), bad times or FMI version.
    CompilerNotFoundError (RuntimeError)
        No C compiler.
    """
    if task is not None:
        from ..control.swingup.tasks import resolve_task

        task = resolve_task(task)
    if fmi_version not in (2, 3) or isinstance(fmi_version, bool):
        raise ValueError(f"fmi_version must be 2 or 3, got {fmi_version!r}")
    ctrl, x0, model = design_controller(controller, task, kind=kind, sample_time=sample_time)
    h = float(ctrl.sample_time)
    t_end = (task.t_final if task is not None else 10.0) if stop_time is None else stop_time
    if not (isinstance(t_end, (int, float)) and math.isfinite(t_end) and t_end > 0):
        raise ValueError(f"stop_time must be a positive finite time [s], got {t_end!r}")
    name = f"{task.name if task is not None else model.kind}_{controller}"
    with tempfile.TemporaryDirectory() as tmp:
        plant_path = export(
            model, Path(tmp) / "plant.fmu", fmi_version, timestamp=timestamp, x0=x0, stop_time=t_end, step_size=h, cc=cc
        )
        plant = states_as_outputs(plant_path.read_bytes(), model.state_names)
        ctrl_path = export_controller(
            ctrl, Path(tmp) / "controller.fmu", fmi_version, timestamp=timestamp, stop_time=t_end, cc=cc
        )
        files = {
            "SystemStructure.ssd": _ssd(
                model,
                ctrl,
                h,
                t_end,
                name,
                f"pendulab closed loop: {model.kind} pendulum under {controller} (sample time {h:g} s)",
            ),
            "resources/plant.fmu": plant,
            "resources/controller.fmu": ctrl_path.read_bytes(),
            "resources/plant.ssv": _parameter_set(
                "plant",
                [
                    (n, v, i.unit if i.unit in UNITS else None)
                    for n, v, i in zip(model.param_names, model.p, model.param_info, strict=True)
                ],
            ),
            "resources/controller.ssv": _parameter_set("controller", [("sample_time", h, "s")]),
        }
    path = Path(path)
    with atomic_open(path, "wb") as fh, zipfile.ZipFile(fh, "w", zipfile.ZIP_DEFLATED) as zf:
        for fname in files:  # SystemStructure.ssd first
            info = zipfile.ZipInfo(fname, date_time=_ZIP_DATE)
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            zf.writestr(info, files[fname])
    return SspExport(
        path,
        controller,
        task.name if task is not None else None,
        fmi_version,
        h,
        float(t_end),
        x0,
        model.state_names,
        tuple(ctrl.input_names),
    )
