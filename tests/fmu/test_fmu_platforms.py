"""Binaries for more than the host: cross-compiled, checked for their exported FMI functions and, where an
emulator is installed (qemu-user, wine), run against the host binary."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import zipfile
from pathlib import Path

import pytest

import pendulab as pl
from pendulab._checks import MissingExtraError
from pendulab.fmu import export
from pendulab.fmu.export import find_compiler
from pendulab.fmu.platforms import (
    PLATFORMS,
    cross_compiler,
    exported_symbols,
    fmi_functions,
    resolve_platforms,
    runtime_requirement,
)

HARNESS = Path(__file__).parent / "c"
TARGETS = ("x86_64-linux", "x86_64-windows", "aarch64-linux")


def _cross_missing() -> str | None:
    try:
        for name in TARGETS[1:]:
            cross_compiler(PLATFORMS[name])
    except MissingExtraError as exc:
        return f"no cross toolchain: {exc}"
    return None


needs_cross = pytest.mark.skipif(_cross_missing() is not None, reason=str(_cross_missing()))


@pytest.fixture(scope="module")
def cross_fmus(tmp_path_factory):
    """{version: path} of elastic FMUs with binaries for x86_64-linux, x86_64-windows (and aarch64-linux, FMI 3)."""
    root = tmp_path_factory.mktemp("cross")
    out = {}
    for version, targets in ((3, TARGETS), (2, ("linux64", "win64"))):
        out[version] = export(pl.elastic(), root / f"elastic{version}.fmu", version, timestamp=False, platforms=list(targets))
    return out


@needs_cross
@pytest.mark.parametrize("version", [2, 3])
def test_every_binary_exports_exactly_the_fmi_functions(cross_fmus, version):
    with zipfile.ZipFile(cross_fmus[version]) as zf:
        required = fmi_functions(zf.read(f"sources/fmi{version}Functions.h").decode(), version)
        binaries = {n: zf.read(n) for n in zf.namelist() if n.startswith("binaries/")}
    folders = {n.split("/")[1] for n in binaries}
    assert folders == ({"x86_64-linux", "x86_64-windows", "aarch64-linux"} if version == 3 else {"linux64", "win64"})
    assert len(required) > 40
    for name, data in binaries.items():
        assert exported_symbols(data) == required, name
        if name.endswith(".dll"):
            pe = int.from_bytes(data[0x3C:0x40], "little")
            assert data[pe + 4 : pe + 6] == b"\x64\x86"  # IMAGE_FILE_MACHINE_AMD64
        else:
            machine = int.from_bytes(data[18:20], "little")
            assert machine == (0xB7 if "aarch64" in name else 0x3E)  # EM_AARCH64 / EM_X86_64


def _emulated_run(fmu: Path, folder: str, tmp_path: Path, version: int) -> float | None:
    """theta1 after 2 s from the binary in ``folder``, run natively or under its emulator; None if none is installed."""
    from fmpy import read_model_description

    token = read_model_description(str(fmu)).guid
    with zipfile.ZipFile(fmu) as zf:
        zf.extractall(tmp_path)
    lib = next((tmp_path / "binaries" / folder).iterdir())
    src = tmp_path / "sources"
    flags = ["-std=c99", "-Wall", "-Wextra", "-pedantic", "-Werror", f"-DFMI_VERSION={version}", "-I", str(src)]
    if folder in ("x86_64-linux", "linux64"):
        exe, run = tmp_path / "run_host", []
        cmd = [find_compiler(), *flags, str(HARNESS / "run_binary.c"), "-o", str(exe), "-ldl"]
    elif "aarch64" in folder:
        sysroot = Path("/usr/aarch64-linux-gnu")
        if shutil.which("qemu-aarch64") is None or not sysroot.is_dir():
            return None
        exe, run = tmp_path / "run_a64", ["qemu-aarch64", "-L", str(sysroot)]
        cmd = [*cross_compiler(PLATFORMS["aarch64-linux"]), *flags, str(HARNESS / "run_binary.c"), "-o", str(exe), "-ldl"]
    else:
        if shutil.which("wine") is None:
            return None
        exe, run = tmp_path / "run_win.exe", ["wine"]
        cmd = [*cross_compiler(PLATFORMS["x86_64-windows"]), *flags, str(HARNESS / "run_binary.c"), "-o", str(exe)]
        shutil.copy(lib, tmp_path / lib.name)
        lib = Path(lib.name)
    subprocess.run(cmd, check=True, capture_output=True, text=True)
    env = {**os.environ, "WINEDEBUG": "-all"}
    proc = subprocess.run(
        [*run, str(exe), str(lib), token, "200"], capture_output=True, text=True, timeout=300, cwd=tmp_path, env=env
    )
    assert proc.returncode == 0, proc.stderr
    return float(re.search(r"theta1=(\S+)", proc.stdout).group(1))


@needs_cross
@pytest.mark.parametrize("folder", ["aarch64-linux", "x86_64-windows"])
def test_cross_binaries_run_under_an_emulator_like_the_host_binary(cross_fmus, folder, tmp_path):
    host = _emulated_run(cross_fmus[3], "x86_64-linux", tmp_path / "host", 3)
    other = _emulated_run(cross_fmus[3], folder, tmp_path / folder, 3)
    if other is None:
        pytest.skip(f"no emulator for {folder} installed (qemu-user with an aarch64 sysroot / wine)")
    # same C code from another compiler (FMA contraction, libm): rounding-level differences over 200 adaptive steps
    assert abs(other - host) < 1e-11
    assert abs(host) > 1e-3  # the pendulum moved


@needs_cross
def test_windows_dll_imports_the_c_runtime_its_documentation_names(cross_fmus, tmp_path):
    """The DLL's C runtime (Zig: the Universal C Runtime, api-ms-win-crt-*.dll), read from its imports and stated on the
    FMU's documentation page; checked against ``objdump -p`` where binutils is installed."""
    import html

    with zipfile.ZipFile(cross_fmus[3]) as zf:
        name = next(n for n in zf.namelist() if n.endswith(".dll"))
        data, page = zf.read(name), zf.read("documentation/index.html").decode()
    need = runtime_requirement(data)
    assert f"<code>{name}</code>: needs {html.escape(need)}" in page
    if shutil.which("objdump") is None:
        pytest.skip("objdump (binutils) is not installed: the imports were read by pendulab only")
    (tmp_path / "x.dll").write_bytes(data)
    out = subprocess.run(["objdump", "-p", str(tmp_path / "x.dll")], capture_output=True, text=True, check=True).stdout
    crt = {d.lower() for d in re.findall(r"DLL Name: (\S+)", out)} - {"kernel32.dll"}
    assert crt, out[:2000]
    if all(d.startswith("api-ms-win-crt-") for d in crt):
        assert need == "the Universal C Runtime (UCRT: api-ms-win-crt-*.dll)"
    else:
        assert need == ", ".join(sorted(crt))


def test_platform_names_are_validated():
    assert [p.name for p in resolve_platforms("linux64, win64", 2)] == ["x86_64-linux", "x86_64-windows"]
    assert [p.name for p in resolve_platforms(["aarch64-linux", "x86_64-linux", "linux64"], 3)] == [
        "aarch64-linux",
        "x86_64-linux",
    ]
    with pytest.raises(ValueError, match="unknown platform 'riscv64-linux'"):
        resolve_platforms("riscv64-linux", 3)
    with pytest.raises(ValueError, match="FMI 2.0 defines no binaries folder for 'aarch64-linux'"):
        resolve_platforms("aarch64-linux", 2)
    with pytest.raises(ValueError, match="at least one platform"):
        resolve_platforms(" , ", 3)
    with pytest.raises(TypeError, match="platforms must be a string or a list of strings"):
        resolve_platforms(64, 3)


def test_missing_cross_toolchain_names_the_extra(monkeypatch, tmp_path):
    import builtins

    real_import = builtins.__import__

    def no_zig(name, *args, **kwargs):
        if name == "ziglang":
            raise ImportError("no ziglang")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(shutil, "which", lambda name: None)
    monkeypatch.setattr(builtins, "__import__", no_zig)
    with pytest.raises(MissingExtraError, match=r'pip install "pendulab\[cross\]".*x86_64-w64-mingw32-gcc'):
        export(pl.rigid(), tmp_path / "r.fmu", 2, platforms="win64")
    assert not (tmp_path / "r.fmu").exists()  # nothing half-written


def test_cli_platforms_option(tmp_path, capsys):
    from pendulab.cli import main

    out = tmp_path / "r.fmu"
    assert main(["fmu", "export", "--model", "rigid", "--platforms", "riscv64-linux", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "unknown platform 'riscv64-linux'" in err and "Traceback" not in err
    assert main(["fmu", "export", "--model", "rigid", "--platforms", "aarch64-linux", "--out", str(out)]) == 2
    assert "--fmi-version 3" in capsys.readouterr().err
    assert not out.exists()
    # the host platform alone needs no cross toolchain
    from pendulab.fmu.platforms import host_platform

    args = [
        "fmu",
        "export",
        "--model",
        "rigid",
        "--fmi-version",
        "3",
        "--platforms",
        host_platform(),
        "--json",
        "--out",
        str(out),
    ]
    assert main(args) == 0
    assert f'"{host_platform()}"' in capsys.readouterr().out
