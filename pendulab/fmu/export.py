"""Export a pendulab model as an FMI 2.0 or 3.0 FMU (Co-Simulation and Model Exchange, C, with sources)."""

from __future__ import annotations

import datetime as _dt
import os
import platform
import tempfile
import zipfile
from pathlib import Path

import numpy as np

from .._io import atomic_open
from ..model.model import Model
from ..native.build import CFLAGS, CompilerNotFoundError, compile_shared, find_compiler, shared_library_suffix
from .codegen import compiled_sources, generate_sources, layout, token
from .model_description import build_description, model_description

# CFLAGS, CompilerNotFoundError and find_compiler live in pendulab.native.build (shared with the
# native fast path) and are re-exported here, where they have always been importable.
__all__ = ["export", "find_compiler", "compile_sources", "CFLAGS", "CompilerNotFoundError", "binary_platform"]

_ZIP_DATE = (1980, 1, 1, 0, 0, 0)  # fixed zip timestamps: same input -> same archive bytes


def binary_platform(fmi_version: int) -> str:
    """Platform folder under ``binaries/``: e.g. ``linux64`` (FMI 2) or ``x86_64-linux`` (FMI 3).

    Parameters
    ----------
    fmi_version : {2, 3}
        FMI standard.

    Returns
    -------
    str
        The folder name for this machine.

    Raises
    ------
    RuntimeError
        Not Linux, macOS or Windows.
    """
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
    """Compile the FMU sources in ``src_dir`` into the shared library ``out``.

    Parameters
    ----------
    src_dir : Path
        Folder with the files of :func:`~pendulab.fmu.codegen.generate_sources`.
    out : Path
        Library to write (platform suffix, e.g. ``.so``).
    fmi_version : {2, 3}
        FMI standard (which FMI layer to compile).
    cc : str, optional
        C compiler; default ``$CC``, then ``cc``, ``gcc``, ``clang``.
    extra_flags : tuple of str
        Flags after :data:`CFLAGS`.

    Returns
    -------
    Path
        ``out``.

    Raises
    ------
    CompilerNotFoundError (RuntimeError)
        No C compiler found.
    RuntimeError
        Compilation failed.
    """
    return compile_shared(src_dir, compiled_sources(fmi_version), out, cc=cc, extra_flags=extra_flags)


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
        ext = shared_library_suffix()
        lib = compile_sources(src, Path(tmp) / f"{lay.identifier}{ext}", fmi_version, cc=cc)
        files[f"binaries/{binary_platform(fmi_version)}/{lib.name}"] = lib.read_bytes()
    # Atomic: an interrupted or failing export never leaves a truncated FMU where a good one was.
    with atomic_open(path, "wb") as fh, zipfile.ZipFile(fh, "w", zipfile.ZIP_DEFLATED) as zf:
        for name in sorted(files):
            info = zipfile.ZipInfo(name, date_time=_ZIP_DATE)
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            zf.writestr(info, files[name])
    return path
