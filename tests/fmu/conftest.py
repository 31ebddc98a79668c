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


def _shared_dir(tmp_path_factory) -> Path:
    """A directory shared by all pytest-xdist workers of this session (the worker's basetemp parent)."""
    base = tmp_path_factory.getbasetemp()
    return base.parent if base.name.startswith("popen-gw") else base


@pytest.fixture(scope="session")
def fmu_builds(tmp_path_factory) -> dict[tuple[str, int], BuiltFMU]:
    import fcntl
    from concurrent.futures import ThreadPoolExecutor

    from fmpy import extract, read_model_description

    root = _shared_dir(tmp_path_factory) / "pendulab_fmus"
    root.mkdir(exist_ok=True)
    combos = [(kind, version) for kind in ("rigid", "elastic") for version in (2, 3)]
    # one worker builds (the compiler runs in parallel threads), the others wait and reuse the archives
    with open(root / "build.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        missing = [c for c in combos if not (root / f"{c[0]}{c[1]}.fmu").exists()]
        with ThreadPoolExecutor(max_workers=4) as pool:
            list(pool.map(lambda c: export(pl.make_model(c[0]), root / f"{c[0]}{c[1]}.fmu", c[1], timestamp=False), missing))
        fcntl.flock(lock, fcntl.LOCK_UN)
    out = {}
    unzip_root = tmp_path_factory.mktemp("unzipped")
    for kind, version in combos:
        path = root / f"{kind}{version}.fmu"
        unzipdir = extract(str(path), str(unzip_root / f"{kind}{version}"))
        out[(kind, version)] = BuiltFMU(path, kind, version, unzipdir, read_model_description(str(path)))
    return out


@pytest.fixture(scope="session")
def cosim_fmu(fmu_builds):
    """``cosim_fmu(kind, fmi_version) -> Path`` of the session's FMU with default parameters."""

    def path(kind: str, fmi_version: int = 2) -> Path:
        return fmu_builds[(kind, fmi_version)].path

    return path
