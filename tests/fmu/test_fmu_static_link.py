"""Source FMUs with the standard FMI headers: FMI2_FUNCTION_PREFIX / FMI3_FUNCTION_PREFIX are honoured.

A rigid and an elastic source FMU, compiled with different prefixes, link statically into one C program
(no duplicate symbols) and each runs its own model.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import zipfile
from pathlib import Path

import numpy as np
import pytest

import pendulab as pl
from pendulab.fmu.codegen import compiled_sources
from pendulab.fmu.export import find_compiler

HARNESS = Path(__file__).parent / "c"
WARN = ["-std=c99", "-Wall", "-Wextra", "-pedantic", "-Werror"]


def _objects(cc: str, fmu: Path, version: int, prefix: str, out: Path) -> list[str]:
    """Compile the FMU's sources/ with the function prefix; returns the object files."""
    src = out / prefix
    with zipfile.ZipFile(fmu) as zf:
        for name in zf.namelist():
            if name.startswith("sources/"):
                (src / Path(name).name).parent.mkdir(parents=True, exist_ok=True)
                (src / Path(name).name).write_bytes(zf.read(name))
    objs = []
    for unit in compiled_sources(version):
        obj = src / (unit + ".o")
        # the generated CasADi code has unused parameters by its calling convention (silenced in its wrapper)
        cmd = [cc, *WARN, "-O2", f"-DFMI{version}_FUNCTION_PREFIX={prefix}", "-c", str(src / unit), "-o", str(obj)]
        proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
        assert proc.returncode == 0 and not proc.stderr.strip(), proc.stderr  # warning-free with the prefix
        objs.append(str(obj))
    return objs


@pytest.mark.parametrize("version", [2, 3])
def test_two_source_fmus_link_statically_into_one_program(fmu_builds, version, tmp_path):
    cc = find_compiler()
    rigid, elastic = fmu_builds[("rigid", version)], fmu_builds[("elastic", version)]
    objs = _objects(cc, rigid.path, version, "rigid_", tmp_path) + _objects(cc, elastic.path, version, "elastic_", tmp_path)
    if shutil.which("nm"):
        # every defined global symbol carries its FMU's prefix: nothing can clash with a third FMU either
        for obj in objs:
            out = subprocess.run(["nm", "-g", "--defined-only", obj], capture_output=True, text=True, check=True).stdout
            names = [line.split()[-1] for line in out.splitlines() if line.strip()]
            prefix = "rigid_" if "/rigid_/" in obj else "elastic_"
            assert all(n.startswith(prefix) for n in names), [n for n in names if not n.startswith(prefix)]
    exe = tmp_path / "two"
    cmd = [cc, *WARN, f"-DFMI_VERSION={version}", "-I", str(tmp_path / "rigid_"), str(HARNESS / "static_link_two.c"), *objs]
    proc = subprocess.run([*cmd, "-o", str(exe), "-lm"], capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stderr
    run = subprocess.run([str(exe), rigid.md.guid, elastic.md.guid, "100"], capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stderr
    got = {k: float(v) for k, v in re.findall(r"(\w+)=(\S+)", run.stdout)}
    for kind in ("rigid", "elastic"):
        model = pl.make_model(kind)
        ref = pl.simulate(model, model.state(theta1=1.0), 1.0, dt=0.01, rtol=1e-12, atol=1e-12)
        # embedded solver at tolerance 1e-10 over a 1 s swing; the two models differ by ~1e-3 rad
        np.testing.assert_allclose(got[kind], ref["theta1"][-1], atol=1e-7)
    assert abs(got["rigid"] - got["elastic"]) > 1e-5  # each prefix reached its own model


def test_the_headers_are_the_standard_ones_with_the_prefix_macro(fmu_builds):
    src = Path(fmu_builds[("rigid", 2)].unzipdir, "sources")
    text = (src / "fmi2Functions.h").read_text()
    assert "fmi2PasteB(FMI2_FUNCTION_PREFIX, name)" in text  # the standard's prefix macro (fmpy's copy drops it)
    assert "2-Clause BSD License" in text  # the license header is kept
