"""A second importer independent of fmpy: small C programs that dlopen the binary and drive the FMI calls.

Under valgrind memcheck (when installed) they also prove no invalid access and no leak.
"""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

from pendulab.fmu.export import find_compiler

HARNESS = Path(__file__).parent / "c"


def _build(built, tmp_path: Path) -> tuple[Path, list[str]]:
    exe = tmp_path / f"harness{built.version}"
    src = HARNESS / f"fmi{built.version}_harness.c"
    cmd = [
        find_compiler(),
        "-Wall",
        "-Wextra",
        "-Werror",
        "-std=c99",
        "-I",
        str(Path(built.unzipdir, "sources")),
        str(src),
        "-o",
        str(exe),
        "-ldl",
        "-lm",
    ]
    subprocess.run(cmd, check=True, capture_output=True, text=True)
    lib = next(Path(built.unzipdir, "binaries").glob("*/*.so"))
    token = built.md.guid  # fmpy stores the FMI 3 instantiationToken as guid too
    return exe, [str(lib), token]


@pytest.mark.parametrize("kind", ["rigid", "elastic"])
@pytest.mark.parametrize("version", [2, 3])
def test_c_importer_runs_the_fmu(fmu_builds, kind, version, tmp_path):
    exe, args = _build(fmu_builds[(kind, version)], tmp_path)
    proc = subprocess.run([str(exe), *args, "200"], capture_output=True, text=True, timeout=60, check=False)
    assert proc.returncode == 0, proc.stderr
    drift = float(proc.stdout.split("energy_drift=")[1])
    assert drift < 1e-7  # 2 s undamped swing at tolerance 1e-10: energy is conserved to the tolerance scale


@pytest.mark.skipif(shutil.which("valgrind") is None, reason="valgrind not installed")
@pytest.mark.parametrize("version", [2, 3])
def test_c_importer_is_clean_under_valgrind(fmu_builds, version, tmp_path):
    exe, args = _build(fmu_builds[("elastic", version)], tmp_path)
    cmd = [
        "valgrind",
        "--leak-check=full",
        "--errors-for-leak-kinds=definite,indirect",
        "--error-exitcode=9",
        "-q",
        str(exe),
        *args,
        "30",
    ]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=300, check=False)
    assert proc.returncode == 0, proc.stderr
    assert "Invalid" not in proc.stderr and "definitely lost" not in proc.stderr, proc.stderr


def test_ode_solvers_converge_and_rodas4_steps_over_a_stiff_spring(tmp_path):
    """The FMI-independent solvers on their own (tests/fmu/c/ode_solver_test.c states each check)."""
    c_dir = Path(__file__).parents[2] / "pendulab" / "native" / "c"
    exe = tmp_path / "ode_solver_test"
    cmd = [
        find_compiler(),
        "-Wall",
        "-Wextra",
        "-Werror",
        "-std=c99",
        "-O2",
        "-I",
        str(c_dir),
        str(HARNESS / "ode_solver_test.c"),
        str(c_dir / "ode_solver.c"),
        "-o",
        str(exe),
        "-lm",
    ]
    subprocess.run(cmd, check=True, capture_output=True, text=True)
    proc = subprocess.run([str(exe)], capture_output=True, text=True, timeout=60, check=False)
    assert proc.returncode == 0, proc.stdout
    assert proc.stdout.count(" ok") == 8, proc.stdout
