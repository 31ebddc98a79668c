"""Export a pendulab model as an FMI 2.0 or 3.0 FMU (Co-Simulation and Model Exchange, C, with sources)."""

from __future__ import annotations

import datetime as _dt
import os
import platform
import shutil
import subprocess
import tempfile
import zipfile
from pathlib import Path

import numpy as np

from ..model.model import Model
from .codegen import compiled_sources, generate_sources, layout, token
from .model_description import build_description, model_description

__all__ = ["export", "find_compiler", "compile_sources", "CFLAGS", "binary_platform"]

#: Flags of every build; the sources compile warning-free with them (checked in the tests with -Werror).
CFLAGS: tuple[str, ...] = ("-Wall", "-Wextra", "-std=c99", "-O2", "-fPIC", "-fvisibility=hidden")
_ZIP_DATE = (1980, 1, 1, 0, 0, 0)  # fixed zip timestamps: same input -> same archive bytes


class CompilerNotFoundError(RuntimeError):
    """No C compiler was found."""


def find_compiler(cc: str | None = None) -> str:
    """Path of the C compiler: ``cc`` if given, else ``$CC``, ``cc``, ``gcc`` or ``clang`` on PATH."""
    candidates = [cc] if cc else [c for c in (os.environ.get("CC"), "cc", "gcc", "clang") if c]
    for c in candidates:
        path = shutil.which(c)
        if path:
            return path
    raise CompilerNotFoundError(f"no C compiler found (tried {candidates}); install gcc or clang, or pass cc=/path/to/compiler")


def binary_platform(fmi_version: int) -> str:
    """Platform folder under ``binaries/``: e.g. ``linux64`` (FMI 2) or ``x86_64-linux`` (FMI 3)."""
    system = {"Linux": "linux", "Darwin": "darwin", "Windows": "win"}.get(platform.system())
    machine = platform.machine().lower()
    if system is None:
        raise RuntimeError(f"unsupported platform {platform.system()!r}")
    arch = {"amd64": "x86_64", "arm64": "aarch64"}.get(machine, machine)
    if fmi_version == 2:
        return f"{system}64" if arch in ("x86_64", "aarch64") else f"{system}32"
    return f"{arch}-{'windows' if system == 'win' else system}"


def compile_sources(
    src_dir: Path, out: Path, fmi_version: int, *, cc: str | None = None, extra_flags: tuple[str, ...] = ()
) -> Path:
    """Compile the FMU sources in ``src_dir`` into the shared library ``out``; raise RuntimeError on failure."""
    compiler = find_compiler(cc)
    ext = {"Darwin": ".dylib", "Windows": ".dll"}.get(platform.system(), ".so")
    if out.suffix != ext:
        raise ValueError(f"shared library name must end with {ext!r}, got {out.name!r}")
    cmd = [compiler, *CFLAGS, *extra_flags, "-shared", "-I", str(src_dir), "-o", str(out)]
    cmd += [str(src_dir / name) for name in compiled_sources(fmi_version)] + ["-lm"]
    proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if proc.returncode != 0:
        raise RuntimeError(f"C compilation failed ({' '.join(cmd)}):\n{proc.stderr.strip()}")
    return out


def export(
    model: Model,
    path: str | os.PathLike,
    fmi_version: int = 2,
    *,
    timestamp: bool = True,
    x0: np.ndarray | None = None,
    stop_time: float = 10.0,
    step_size: float = 0.01,
    cc: str | None = None,
) -> Path:
    """Write an FMU of ``model`` with Co-Simulation and Model Exchange interfaces.

    Parameters
    ----------
    model : Model
        Rigid or elastic pendulum; its parameters become the parameter start values.
    path : path-like
        Output file, conventionally ``*.fmu``.
    fmi_version : {2, 3}
        FMI standard of the archive (one archive carries one version).
    timestamp : bool
        Write ``generationDateAndTime``. With ``False`` the archive is byte-for-byte
        reproducible (fixed file order and zip timestamps).
    x0 : ndarray, shape (nx,), optional
        State start values [SI]; default: hanging at rest (static spring lengths).
    stop_time, step_size : float
        ``DefaultExperiment`` stop time and communication step [s].
    cc : str, optional
        C compiler; default ``$CC``, then ``cc``, ``gcc``, ``clang``.

    Returns
    -------
    Path
        The written FMU.

    Raises
    ------
    TypeError
        ``model`` is not a :class:`~pendulab.Model`.
    ValueError
        Bad ``fmi_version``, ``x0`` or experiment settings.
    CompilerNotFoundError (RuntimeError)
        No C compiler found.
    RuntimeError
        Compilation failed.
    """
    if not isinstance(model, Model):
        raise TypeError(f"model must be a pendulab Model (pendulab.rigid() or pendulab.elastic()), got {type(model).__name__}")
    if fmi_version not in (2, 3) or isinstance(fmi_version, bool):
        raise ValueError(f"fmi_version must be 2 or 3, got {fmi_version!r}")
    for name, value in (("stop_time", stop_time), ("step_size", step_size)):
        if not (isinstance(value, (int, float)) and np.isfinite(value) and value > 0):
            raise ValueError(f"{name} must be a positive finite number [s], got {value!r}")
    path = Path(path)
    lay = layout(model, x0)
    sources = generate_sources(model, fmi_version, lay)
    stamp = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ") if timestamp else None
    files: dict[str, bytes] = {
        "modelDescription.xml": model_description(
            model, lay, fmi_version, token(lay, fmi_version), timestamp=stamp, stop_time=stop_time, step_size=step_size
        )
    }
    for name, data in sources.items():
        files[f"sources/{name}"] = data
    if fmi_version == 3:
        files["sources/buildDescription.xml"] = build_description(lay)
    with tempfile.TemporaryDirectory() as tmp:
        src = Path(tmp) / "sources"
        src.mkdir()
        for name, data in sources.items():
            (src / name).write_bytes(data)
        ext = {"Darwin": ".dylib", "Windows": ".dll"}.get(platform.system(), ".so")
        lib = compile_sources(src, Path(tmp) / f"{lay.identifier}{ext}", fmi_version, cc=cc)
        files[f"binaries/{binary_platform(fmi_version)}/{lib.name}"] = lib.read_bytes()
    path.parent.mkdir(parents=True, exist_ok=True)
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as zf:
        for name in sorted(files):
            info = zipfile.ZipInfo(name, date_time=_ZIP_DATE)
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            zf.writestr(info, files[name])
    return path
