"""Session fixtures: each FMU (rigid/elastic x FMI 2/3) is built once per test session."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import pytest

import pendulab as pl
from pendulab.fmu import export


@dataclass(frozen=True)
class BuiltFMU:
    path: Path
    kind: str
    version: int
    unzipdir: str
    md: object  # fmpy ModelDescription

    @property
    def vr(self) -> dict[str, int]:
        return {v.name: v.valueReference for v in self.md.modelVariables}

    def instance(self, interface: str = "CS", name: str = "inst", logger=None):
        """Instantiated fmpy low-level object (not initialized). ``logger(status, message)`` collects messages."""
        from fmpy import fmi2, fmi3

        ident = f"pendulab_{self.kind}"
        if self.version == 2:
            cls = fmi2.FMU2Slave if interface == "CS" else fmi2.FMU2Model
            fmu = cls(guid=self.md.guid, unzipDirectory=self.unzipdir, modelIdentifier=ident, instanceName=name)
            fmu.instantiate()
        else:
            cls = fmi3.FMU3Slave if interface == "CS" else fmi3.FMU3Model
            fmu = cls(guid=self.md.guid, unzipDirectory=self.unzipdir, modelIdentifier=ident, instanceName=name)
            if logger is None:
                fmu.instantiate()
            else:
                fmu.instantiate(logMessage=lambda env, status, cat, msg: logger(status, msg.decode()))
        return fmu


@pytest.fixture(scope="session")
def fmu_builds(tmp_path_factory) -> dict[tuple[str, int], BuiltFMU]:
    from fmpy import extract, read_model_description

    root = tmp_path_factory.mktemp("fmus")
    out = {}
    for kind in ("rigid", "elastic"):
        for version in (2, 3):
            path = export(pl.make_model(kind), root / f"{kind}{version}.fmu", version, timestamp=False)
            unzipdir = extract(str(path), str(root / f"{kind}{version}"))
            out[(kind, version)] = BuiltFMU(path, kind, version, unzipdir, read_model_description(str(path)))
    return out


@pytest.fixture(scope="session")
def cosim_fmu(fmu_builds):
    """``cosim_fmu(kind, fmi_version) -> Path`` of the session's FMU with default parameters."""

    def path(kind: str, fmi_version: int = 2) -> Path:
        return fmu_builds[(kind, fmi_version)].path

    return path
