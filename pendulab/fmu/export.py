"""Export a pendulab model as an FMI 2.0 or 3.0 FMU (Co-Simulation and Model Exchange, C, with sources)."""

from __future__ import annotations

import datetime as _dt
import os
import platform
import tempfile
import zipfile
from pathlib import Path

import numpy as np

from .._inputs import checked
from .._io import atomic_open
from ..model.model import Model
from ..native.build import (
    CFLAGS,
    CompilerNotFoundError,
    compile_shared,
    compile_shared_with,
    find_compiler,
    shared_library_suffix,
)
from .binaries import MANIFEST_PATH, binary_manifest
from .codegen import compiled_sources, generate_sources, layout, token
from .documentation import LICENSE_PATH, documentation_html, license_text
from .model_description import build_description, model_description
from .platforms import (
    Platform,
    cross_compiler,
    exported_symbols,
    fmi_functions,
    host_platform,
    portable_host_compiler,
    resolve_platforms,
    runtime_requirement,
)

# CFLAGS, CompilerNotFoundError and find_compiler live in pendulab.native.build (shared with the
# native fast path) and are re-exported here, where they have always been importable.
__all__ = ["export", "find_compiler", "compile_sources", "compile_host", "CFLAGS", "CompilerNotFoundError", "binary_platform"]

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


def compile_host(src_dir: Path, units: tuple[str, ...] | list[str], out: Path, *, cc: str | None = None) -> Path:
    """Build the host binary: with Zig for an old glibc when installed and no compiler is chosen, else the host compiler.

    See :func:`~pendulab.fmu.platforms.portable_host_compiler`: on Linux with ``pendulab[cross]`` the binary
    targets glibc 2.17 (``zig cc -target x86_64-linux-gnu.2.17``; no debug information, as the host compiler's
    ``-O2`` build); otherwise ``cc``, ``$CC``, ``cc``, ``gcc``, ``clang`` as before.

    Parameters
    ----------
    src_dir : Path
        Folder with the sources and headers.
    units : sequence of str
        Translation units.
    out : Path
        Library to write (platform suffix).
    cc : str, optional
        Compiler; a given one is always used.

    Returns
    -------
    Path
        ``out``.

    Raises
    ------
    CompilerNotFoundError (RuntimeError)
        No compiler found.
    RuntimeError
        Compilation failed.
    """
    zig = portable_host_compiler(cc)
    if zig is None:
        return compile_shared(src_dir, units, out, cc=cc)
    return compile_shared_with(zig, src_dir, units, out, flags=(*CFLAGS, "-g0"))


def _cross_compile(target: Platform, src: Path, out_dir: Path, identifier: str, fmi_version: int) -> Path:
    """Build the binary of ``target`` (not the host) with a cross compiler; stripped, warning flags as usual."""
    out_dir.mkdir()
    flags = [f for f in CFLAGS if not (f == "-fPIC" and target.suffix == ".dll")] + ["-s"]
    return compile_shared_with(
        cross_compiler(target), src, compiled_sources(fmi_version), out_dir / f"{identifier}{target.suffix}", flags=flags
    )


def _checked(binary: bytes, required: tuple[str, ...], where: str) -> bytes:
    """``binary`` if it exports exactly the FMI functions ``required`` (read from the file), else RuntimeError."""
    exported = set(exported_symbols(binary))
    missing, extra = sorted(set(required) - exported), sorted(exported - set(required))
    if missing or extra:
        raise RuntimeError(f"the {where} binary exports the wrong functions: missing {missing[:5]}, unexpected {extra[:5]}")
    return binary


@checked(stop_time="t_final", step_size="comm_step")
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
    platforms: str | list[str] | tuple[str, ...] | None = None,
    flip_events: bool = False,
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
        C compiler of the host platform. Default on Linux with Zig's C compiler installed
        (``pendulab[cross]``) and ``$CC`` unset: Zig targeting glibc 2.17 (the binary loads on every
        distribution since 2014); else ``$CC``, then ``cc``, ``gcc``, ``clang`` (the binary then needs the
        build machine's glibc symbol versions, e.g. ``pow@GLIBC_2.29``). The documentation page of the
        FMU states what each binary needs, read from the built file.
    platforms : str or list of str, optional
        Binaries to build, e.g. ``["x86_64-linux", "x86_64-windows", "aarch64-linux"]`` (FMI 3
        tuples; ``linux64``, ``win64`` accepted; a comma-separated string too). Default: the host
        only. Other platforms are cross-compiled (Debian's cross gcc on PATH, else Zig's C compiler
        from ``pendulab[cross]``). FMI 2.0 defines no aarch64 folder. Every binary must export exactly
        the FMI functions of the standard header (read from the file; checked here).
    flip_events : bool
        Add the event indicators ``flip_margin1``, ``flip_margin2`` = pi - abs(theta_i) (0 when link i
        passes the upright position): Model Exchange importers then stop at every flip, and the FMI 3
        Co-Simulation interface offers event mode (``hasEventMode``): with ``eventModeUsed`` and early
        return allowed, ``DoStep`` ends at each flip (located by bisection) with ``eventHandlingNeeded``.

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
    MissingExtraError (ImportError)
        A platform other than the host, and no cross compiler (``pip install "pendulab[cross]"``).
    RuntimeError
        Compilation failed, or a binary does not export the FMI functions.

    Examples
    --------
    The FMU run by another importer (fmpy) agrees with pendulab's own integrator:

    >>> import pendulab as pl
    >>> from fmpy import simulate_fmu
    >>> from pendulab.fmu import export
    >>> model = pl.rigid()
    >>> path = export(model, "rigid.fmu", fmi_version=2, timestamp=False)  # byte-for-byte reproducible
    >>> fmu = simulate_fmu(str(path), stop_time=2.0, output_interval=0.01, start_values={"theta1": 1.0}, output=["theta1"])
    >>> native = pl.simulate(model, model.state(theta1=1.0), 2.0, method="cvodes", rtol=1e-10, atol=1e-10)
    >>> path.name, bool(abs(fmu["theta1"][-1] - native["theta1"][-1]) < 1e-6)
    ('rigid.fmu', True)
    """
    if not isinstance(model, Model):
        raise TypeError(f"model must be a pendulab Model (pendulab.rigid() or pendulab.elastic()), got {type(model).__name__}")
    if fmi_version not in (2, 3) or isinstance(fmi_version, bool):
        raise ValueError(f"fmi_version must be 2 or 3, got {fmi_version!r}")
    for name, value in (("stop_time", stop_time), ("step_size", step_size)):
        if not (isinstance(value, (int, float)) and np.isfinite(value) and value > 0):
            raise ValueError(f"{name} must be a positive finite number [s], got {value!r}")
    targets = None if platforms is None else resolve_platforms(platforms, fmi_version)
    path = Path(path)
    if not isinstance(flip_events, bool):
        raise TypeError(f"flip_events must be True or False, got {flip_events!r}")
    lay = layout(model, x0, flip_events=flip_events)
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
    files[LICENSE_PATH] = license_text()
    required = fmi_functions(sources[f"fmi{fmi_version}Functions.h"].decode(), fmi_version)
    with tempfile.TemporaryDirectory() as tmp:
        src = Path(tmp) / "sources"
        src.mkdir()
        for name, data in sources.items():
            (src / name).write_bytes(data)
        if targets is None or any(t.name == host_platform() for t in targets):
            ext = shared_library_suffix()
            lib = compile_host(src, compiled_sources(fmi_version), Path(tmp) / f"{lay.identifier}{ext}", cc=cc)
            files[f"binaries/{binary_platform(fmi_version)}/{lib.name}"] = _checked(lib.read_bytes(), required, "host")
        for target in targets or ():
            if target.name != host_platform():
                lib = _cross_compile(target, src, Path(tmp) / target.name, lay.identifier, fmi_version)
                files[f"binaries/{target.folder(fmi_version)}/{lib.name}"] = _checked(lib.read_bytes(), required, target.name)
    # what each binary needs from the C runtime, read from the built file (e.g. glibc >= 2.14; UCRT on Windows)
    binaries = {name: runtime_requirement(data) for name, data in files.items() if name.startswith("binaries/")}
    files["documentation/index.html"] = documentation_html(
        model, lay, fmi_version, stop_time=stop_time, step_size=step_size, binaries=binaries
    )
    # The binaries' SHA-256: pendulab then loads them without a probe in a child process (pendulab.fmu.binaries).
    files[MANIFEST_PATH] = binary_manifest(files)
    # Atomic: an interrupted or failing export never leaves a truncated FMU where a good one was.
    with atomic_open(path, "wb") as fh, zipfile.ZipFile(fh, "w", zipfile.ZIP_DEFLATED) as zf:
        for name in sorted(files):
            info = zipfile.ZipInfo(name, date_time=_ZIP_DATE)
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            zf.writestr(info, files[name])
    return path
