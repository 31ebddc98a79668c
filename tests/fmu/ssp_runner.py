"""A small SSP 1.0 importer for the tests (a second importer besides pendulab): fmpy runs the FMUs.

It knows nothing of pendulab: it reads ``SystemStructure.ssd``, loads every FMU component with fmpy,
applies the parameter sets bound to the components, connects per the SSD's ``Connection`` elements and
steps all components with one fixed communication step (Jacobi for the step, the connections resolved
in as many passes as there are components before each step, which settles any acyclic direct
feedthrough: here the plant's states do not depend on its inputs, the controller's torques do).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
from fmpy.fmi3 import FMU3Slave

SSD = "{http://ssp-standard.org/SSP1/SystemStructureDescription}"
SSV = "{http://ssp-standard.org/SSP1/SystemStructureParameterValues}"


class _Component:
    def __init__(self, name: str, fmu_path: Path, unzip: Path, params: dict[str, float]) -> None:
        self.name = name
        self.md = read_model_description(str(fmu_path))
        self.v3 = self.md.fmiVersion.startswith("3")
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        cls = FMU3Slave if self.v3 else FMU2Slave
        self.fmu = cls(
            guid=self.md.guid,
            unzipDirectory=extract(str(fmu_path), str(unzip)),
            modelIdentifier=self.md.coSimulation.modelIdentifier,
            instanceName=name,
        )
        self.fmu.instantiate()
        self.set(params)

    def set(self, values: dict[str, float]) -> None:
        if values:
            (self.fmu.setFloat64 if self.v3 else self.fmu.setReal)([self.vr[n] for n in values], list(values.values()))

    def get(self, names: list[str]) -> list[float]:
        return list((self.fmu.getFloat64 if self.v3 else self.fmu.getReal)([self.vr[n] for n in names]))

    def initialize(self, start: float) -> None:
        if self.v3:
            self.fmu.enterInitializationMode(startTime=start)
        else:
            self.fmu.setupExperiment(startTime=start)
            self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()

    def close(self) -> None:
        self.fmu.terminate()
        self.fmu.freeInstance()


def _parameter_set(data: bytes) -> dict[str, float]:
    root = ET.fromstring(data)
    return {p.get("name"): float(p.find(f"{SSV}Real").get("value")) for p in root.iter(f"{SSV}Parameter")}


def run_ssp(ssp: Path, workdir: Path, step: float, stop_time: float, record: tuple[str, list[str]]) -> dict[str, np.ndarray]:
    """Run an SSP: ``{"t": (N+1,), "x": (N+1, len(names)), "connections": ...}`` of the recorded component's outputs.

    ``record = (component, variable names)`` is sampled at every communication point before the step.
    """
    with zipfile.ZipFile(ssp) as z:
        z.extractall(workdir)
    root = ET.parse(workdir / "SystemStructure.ssd").getroot()
    system = root.find(f"{SSD}System")
    comps: dict[str, _Component] = {}
    for el in system.find(f"{SSD}Elements"):
        assert (
            el.tag == f"{SSD}Component" and el.get("type", "application/x-fmu-sharedlibrary") == "application/x-fmu-sharedlibrary"
        )
        params: dict[str, float] = {}
        for binding in el.iter(f"{SSD}ParameterBinding"):
            params.update(_parameter_set((workdir / binding.get("source")).read_bytes()))
        comps[el.get("name")] = _Component(
            el.get("name"), workdir / el.get("source"), workdir / f"unzip_{el.get('name')}", params
        )
    connections = [
        (c.get("startElement"), c.get("startConnector"), c.get("endElement"), c.get("endConnector"))
        for c in system.find(f"{SSD}Connections")
    ]
    for comp in comps.values():
        comp.initialize(0.0)
    n = round(stop_time / step)
    name, names = record
    X = np.empty((n + 1, len(names)))
    try:
        for k in range(n + 1):
            t = k * step
            for _ in comps:  # settle the connections (acyclic direct feedthrough)
                for se, sc, ee, ec in connections:
                    comps[ee].set({ec: comps[se].get([sc])[0]})
            X[k] = comps[name].get(names)
            if k == n:
                break
            for comp in comps.values():
                comp.fmu.doStep(t, step)
    finally:
        for comp in comps.values():
            comp.close()
    return {"t": np.arange(n + 1) * step, "x": X}
