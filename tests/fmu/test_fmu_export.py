"""Export: archive layout, modelDescription content, reproducibility, compilation and symbol hygiene."""

from __future__ import annotations

import shutil
import subprocess
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import numpy as np
import pytest

import pendulab as pl
from pendulab.fmu import CompilerNotFoundError, export
from pendulab.fmu.codegen import generate_sources, layout
from pendulab.fmu.export import CFLAGS, find_compiler
from pendulab.fmu.model_description import model_description


@pytest.mark.parametrize("kind", ["rigid", "elastic"])
@pytest.mark.parametrize("version", [2, 3])
def test_fmpy_validate_reports_no_problem(fmu_builds, kind, version):
    from fmpy.validation import validate_fmu

    assert validate_fmu(str(fmu_builds[(kind, version)].path)) == []


@pytest.mark.parametrize("version", [2, 3])
def test_archive_has_sources_binary_and_build_description(fmu_builds, version):
    names = zipfile.ZipFile(fmu_builds[("elastic", version)].path).namelist()
    platform = "linux64" if version == 2 else "x86_64-linux"
    assert f"binaries/{platform}/pendulab_elastic.so" in names
    for src in ("fmu_core.c", "ode_solver.c", f"fmi{version}.c", "model_functions.c", "model_casadi.c", "model.h"):
        assert f"sources/{src}" in names
    assert ("sources/buildDescription.xml" in names) == (version == 3)
    assert names == sorted(names)  # fixed order is part of reproducibility


def test_export_is_byte_reproducible_without_timestamp(fmu_builds, tmp_path):
    again = export(pl.rigid(), tmp_path / "again.fmu", 2, timestamp=False)
    assert again.read_bytes() == fmu_builds[("rigid", 2)].path.read_bytes()


def test_timestamp_is_optional_in_model_description():
    model = pl.rigid()
    lay = layout(model)
    with_stamp = model_description(model, lay, 2, "{tok}", timestamp="2026-01-01T00:00:00Z").decode()
    without = model_description(model, lay, 2, "{tok}", timestamp=None).decode()
    assert 'generationDateAndTime="2026-01-01T00:00:00Z"' in with_stamp
    assert "generationDateAndTime" not in without


def _variables(built):
    return {v.name: v for v in built.md.modelVariables}


@pytest.mark.parametrize("version", [2, 3])
def test_variables_follow_the_model_tables(fmu_builds, version):
    built = fmu_builds[("elastic", version)]
    model = pl.elastic()
    var = _variables(built)
    for info in model.state_info:
        assert var[info.name].unit == info.unit and var[info.name].description == info.description
        assert var[f"der({info.name})"].derivative is var[info.name]
    for info in model.output_info:
        assert var[info.name].causality == "output" and var[info.name].unit == info.unit
    for info in model.input_info:
        assert var[info.name].causality == "input"
    for info, value in zip(model.param_info, model.p, strict=True):
        assert var[info.name].causality == "parameter" and float(var[info.name].start) == value
    # environment, dissipation and stiffness are tunable; masses and lengths fixed (they redefine the state)
    assert var["k1"].variability == "tunable" and var["g"].variability == "tunable"
    assert var["m1"].variability == "fixed" and var["L2"].variability == "fixed"
    assert var["theta1"].displayUnit == "deg"
    units = {u.name: u for u in built.md.unitDefinitions}
    assert units["rad"].displayUnits[0].factor == pytest.approx(180 / np.pi, rel=1e-15)


@pytest.mark.parametrize("version", [2, 3])
def test_model_structure_comes_from_sparsity(fmu_builds, version):
    built = fmu_builds[("rigid", version)]
    var = _variables(built)
    outs = {u.variable.name: {d.name for d in u.dependencies} for u in built.md.outputs}
    ders = {u.variable.name: {d.name for d in u.dependencies} for u in built.md.derivatives}
    # x1 = L1 sin(theta1): depends on theta1 only; energy on all states, no input
    assert outs["x1"] == {"theta1"}
    assert outs["energy"] == {"theta1", "theta2", "omega1", "omega2"}
    # d(theta1)/dt = omega1 exactly; d(omega1)/dt depends on all states and both torques
    assert ders["der(theta1)"] == {"omega1"}
    assert ders["der(omega1)"] == {"theta1", "theta2", "omega1", "omega2", "tau1", "tau2"}
    assert list(outs) == ["x1", "y1", "x2", "y2", "energy"]
    assert var["solver"].start in ("0", 0)


def test_missing_compiler_is_a_clear_error(tmp_path):
    with pytest.raises(CompilerNotFoundError, match="no C compiler found"):
        export(pl.rigid(), tmp_path / "x.fmu", 2, cc="no-such-compiler-xyz")
    assert isinstance(CompilerNotFoundError("x"), RuntimeError)


@pytest.mark.parametrize("bad", [1, 4, "2", True])
def test_bad_fmi_version_is_rejected(tmp_path, bad):
    with pytest.raises(ValueError, match=r"fmi_version = .*expected an integer in \[2, 3\]"):
        export(pl.rigid(), tmp_path / "x.fmu", bad)


def test_bad_start_state_is_rejected(tmp_path):
    with pytest.raises(ValueError, match="x0"):
        export(pl.rigid(), tmp_path / "x.fmu", 2, x0=[1.0, 2.0])


def test_hand_written_c_compiles_with_werror(tmp_path):
    """Each translation unit, FMI 2 and 3, with -Werror -Wpedantic (the generated model code is included too)."""
    for name, data in {**generate_sources(pl.rigid(), 2), **generate_sources(pl.rigid(), 3)}.items():
        (tmp_path / name).write_bytes(data)
    cc = find_compiler()
    for unit in ("fmi2.c", "fmi3.c", "fmu_core.c", "ode_solver.c", "model_functions.c"):
        cmd = [cc, *CFLAGS, "-Werror", "-Wpedantic", "-c", str(tmp_path / unit), "-o", str(tmp_path / (unit + ".o"))]
        proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
        assert proc.returncode == 0, proc.stderr


@pytest.mark.parametrize("kind", ["rigid", "elastic"])
@pytest.mark.parametrize("version", [2, 3])
def test_binary_exports_only_fmi_symbols(fmu_builds, kind, version):
    if shutil.which("nm") is None:
        pytest.skip("nm not available")
    built = fmu_builds[(kind, version)]
    lib = next(Path(built.unzipdir, "binaries").glob("*/*.so"))
    nm = subprocess.run(["nm", "-D", "--defined-only", str(lib)], capture_output=True, text=True, check=True)
    symbols = [line.split()[-1] for line in nm.stdout.splitlines() if line.strip()]
    # hidden visibility for everything else is what lets rigid and elastic FMUs share a process
    assert len(symbols) > 40 and all(s.startswith(f"fmi{version}") for s in symbols), symbols


def test_modeldescription_is_well_formed_xml(fmu_builds):
    root = ET.fromstring(zipfile.ZipFile(fmu_builds[("rigid", 3)].path).read("modelDescription.xml"))
    assert root.get("fmiVersion") == "3.0"
    cs = root.find("CoSimulation")
    assert cs.get("canHandleVariableCommunicationStepSize") == "true"
    assert cs.get("canGetAndSetFMUState") == "true" and cs.get("providesDirectionalDerivatives") == "true"


def test_export_rejects_a_non_model(tmp_path):
    with pytest.raises(TypeError, match="model must be a pendulab Model"):
        export("rigid", tmp_path / "x.fmu", 2)


def test_fmpy_compile_rebuilds_the_binary_from_sources(fmu_builds, tmp_path):
    """FMI 3 buildDescription.xml: fmpy's CMake build of sources/ gives a working binary."""
    if shutil.which("cmake") is None:
        pytest.skip("cmake not available")
    from fmpy import simulate_fmu
    from fmpy.build import build_platform_binary

    unzipdir = shutil.copytree(fmu_builds[("rigid", 3)].unzipdir, tmp_path / "fmu")
    shutil.rmtree(unzipdir / "binaries")
    build_platform_binary(unzipdir)
    res = simulate_fmu(str(unzipdir), stop_time=1.0, start_values={"theta1": 0.5}, output=["theta1"])
    ref = pl.simulate(pl.rigid(), pl.rigid().state(theta1=0.5), 1.0, dt=0.01, rtol=1e-12, atol=1e-12)
    assert abs(res["theta1"][-1] - ref["theta1"][-1]) < 1e-6  # default tolerance 1e-8 over a 1 s swing
