"""An FMU binary pendulab did not export cannot crash the caller: it runs in a probe process first.

A truncated binary inside an FMU (the archive re-zipped, so it still reads) used to kill ``pendulab fmu
validate`` and ``pendulab cosim --fmu`` with SIGBUS. Now the exporter's manifest (SHA-256 of each binary)
lets pendulab load its own binaries directly, and any other binary, or one that no longer matches, is first
run in a child process: a crash there is a clean error naming the FMU and the signal (exit status 2 on the
CLI), and an intact foreign binary still runs. Everything that could load a damaged binary into a Python
process runs in a subprocess here, so a regression shows as a failing exit code, not a dead test session.
"""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import extract

import pendulab as pl
from pendulab.control.feedback import balance_controller, upright_state
from pendulab.cosim import cosim
from pendulab.fmu.binaries import MANIFEST_PATH, FMUBinaryError, check_fmu_binary

ROOT = Path(__file__).resolve().parents[2]


def _rewrite(src: Path, dst: Path, *, binary=None, manifest: bool = True) -> Path:
    """A copy of an FMU, re-zipped: its binaries changed by ``binary(data)``, its manifest kept or left out."""
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(dst, "w", zipfile.ZIP_DEFLATED) as zout:
        for item in zin.infolist():
            data = zin.read(item.filename)
            if item.filename == MANIFEST_PATH and not manifest:
                continue
            if binary is not None and item.filename.startswith("binaries/"):
                data = binary(data)
            zout.writestr(item, data)
    return dst


def _truncated(data: bytes) -> bytes:
    return data[: len(data) // 2]


def _run(*args: str, code: str | None = None, cwd: Path = ROOT) -> subprocess.CompletedProcess:
    cmd = [sys.executable, "-c", code] if code is not None else [sys.executable, "-m", "pendulab", *args]
    return subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, timeout=600, env={**os.environ, "NO_COLOR": "1"})


def _check(path: Path, tmp_path: Path) -> str:
    from fmpy import read_model_description

    return check_fmu_binary(extract(str(path), str(tmp_path / f"x-{path.stem}")), read_model_description(str(path)), fmu=path)


@pytest.mark.parametrize("version", [2, 3])
def test_an_exported_fmu_lists_its_binaries_and_loads_without_a_probe(fmu_builds, tmp_path, version):
    built = fmu_builds[("rigid", version)]
    with zipfile.ZipFile(built.path) as zf:
        manifest = json.loads(zf.read(MANIFEST_PATH))
        binaries = {n: hashlib.sha256(zf.read(n)).hexdigest() for n in zf.namelist() if n.startswith("binaries/")}
    assert manifest["binaries"] == binaries and manifest["generator"].startswith("pendulab")
    assert _check(built.path, tmp_path) == "exported by pendulab"


@pytest.mark.parametrize("version", [2, 3])
def test_a_truncated_binary_is_a_clean_error_from_every_api(fmu_builds, tmp_path, version):
    bad = _rewrite(fmu_builds[("rigid", version)].path, tmp_path / f"truncated{version}.fmu", binary=_truncated)
    # The check itself never loads the binary here: safe in the test process.
    with pytest.raises(FMUBinaryError, match=r"truncated\d\.fmu.*crashed a probe process with SIG[A-Z]+.*not loaded"):
        _check(bad, tmp_path)
    # The public entry points, in a subprocess: a crash would be a negative exit code, not a dead session.
    code = f"""
import json
import pendulab as pl
from pendulab.control.feedback import balance_controller
from pendulab.cosim import cosim
from pendulab.cosim.plant import FmuPlant
from pendulab.fmu import validate
out = {{}}
for name, call in (
    ("validate", lambda: validate({str(bad)!r})),
    ("FmuPlant", lambda: FmuPlant({str(bad)!r})),
    ("cosim", lambda: cosim({str(bad)!r}, balance_controller(pl.rigid(), 0.01), 0.01, 0.1)),
):
    try:
        call()
        out[name] = "no error"
    except Exception as exc:
        out[name] = f"{{type(exc).__name__}}: {{exc}}"
print(json.dumps(out))
"""
    proc = _run(code=code)
    assert proc.returncode == 0, f"exit {proc.returncode}: {proc.stderr[-2000:]}"
    for name, message in json.loads(proc.stdout).items():
        assert message.startswith("FMUBinaryError: ") and "crashed a probe process with SIG" in message, (name, message)
        assert str(bad) in message and "damaged or replaced since" in message  # it no longer matches its manifest


def test_a_truncated_binary_is_exit_status_2_on_the_cli(fmu_builds, tmp_path):
    bad = _rewrite(fmu_builds[("rigid", 2)].path, tmp_path / "truncated.fmu", binary=_truncated, manifest=False)
    for args in (
        ("fmu", "validate", str(bad)),
        ("cosim", "--fmu", str(bad), "--t-final", "0.1", "--no-gif", "--no-progress", "--out", str(tmp_path / "out")),
    ):
        proc = _run(*args)
        assert proc.returncode == 2, f"{args[0]}: exit {proc.returncode}: {proc.stderr[-2000:]}"  # SIGBUS was 135 / -7
        (line,) = [ln for ln in proc.stderr.splitlines() if "error:" in ln]
        assert f"FMU {str(bad)!r}: its binary binaries/linux64/pendulab_rigid.so crashed a probe process with SIG" in line


def test_a_binary_that_is_no_library_fails_the_probe_cleanly(fmu_builds, tmp_path):
    bad = _rewrite(fmu_builds[("rigid", 2)].path, tmp_path / "garbage.fmu", binary=lambda d: b"not a shared library\n")
    with pytest.raises(FMUBinaryError, match=r"garbage\.fmu.*failed a probe run while it was loaded.*not loaded"):
        _check(bad, tmp_path)


@pytest.mark.parametrize("version", [2, 3])
def test_an_intact_foreign_binary_is_probed_once_and_runs(fmu_builds, tmp_path, version):
    # The same FMU without pendulab's manifest: as if another tool had packed it. It runs after one probe.
    src = fmu_builds[("rigid", version)].path
    foreign = _rewrite(src, tmp_path / f"foreign{version}.fmu", manifest=False)
    assert _check(foreign, tmp_path) in ("probed", "probed before")
    assert _check(foreign, tmp_path) == "probed before"
    model = pl.rigid()
    x0 = upright_state(model) + np.array([0.05, 0.0, 0.0, 0.0])
    runs = [cosim(p, balance_controller(model, 0.01), 0.01, 0.5, x0=x0) for p in (src, foreign)]
    np.testing.assert_array_equal(runs[0].x, runs[1].x)


def test_an_intact_foreign_fmu_passes_validation_on_the_cli(fmu_builds, tmp_path):
    foreign = _rewrite(fmu_builds[("rigid", 2)].path, tmp_path / "foreign.fmu", manifest=False)
    proc = _run("fmu", "validate", str(foreign), "--scene", "rigid_forced")
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "overall: PASS" in proc.stdout
