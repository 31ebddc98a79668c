"""C compiler discovery and compilation of C sources into a shared library (uncached).

Used by the FMU export (an FMU carries its binary) and by the cached native build
(:mod:`pendulab.native.build`). An interrupted build (Ctrl-C) kills the compiler and
everything it started (its own process group).
"""

from __future__ import annotations

import contextlib
import os
import platform
import shutil
import signal
import subprocess
import threading
from collections.abc import Sequence
from pathlib import Path

__all__ = [
    "CFLAGS",
    "COMPILER_HINT",
    "CompilerNotFoundError",
    "find_compiler",
    "compiler_unavailable_reason",
    "shared_library_suffix",
    "compile_shared",
    "compile_shared_with",
]

#: Flags of every build (FMU and native); the sources compile warning-free with them (tested with -Werror).
CFLAGS: tuple[str, ...] = ("-Wall", "-Wextra", "-std=c99", "-O2", "-fPIC", "-fvisibility=hidden")
#: What a user without a compiler can do (appended to CompilerNotFoundError messages).
COMPILER_HINT = "install gcc or clang (e.g. apt-get install gcc), or set $CC to a C compiler"


class CompilerNotFoundError(RuntimeError):
    """No C compiler was found.

    Examples
    --------
    >>> import pendulab as pl
    >>> from pendulab.fmu import CompilerNotFoundError, export
    >>> try:
    ...     export(pl.rigid(), "rigid.fmu", cc="no-such-cc")  # a compiler that is not installed
    ... except CompilerNotFoundError as err:  # a RuntimeError
    ...     print(err)
    no C compiler found (tried ['no-such-cc']); install gcc or clang, or pass cc=/path/to/compiler
    """


def _candidates(cc: str | None) -> list[str]:
    return [cc] if cc else [c for c in (os.environ.get("CC"), "cc", "gcc", "clang") if c]


def find_compiler(cc: str | None = None) -> str:
    """Path of the C compiler.

    Parameters
    ----------
    cc : str, optional
        Compiler name or path; default ``$CC``, then ``cc``, ``gcc``, ``clang`` on PATH.

    Returns
    -------
    str
        Absolute path of the first compiler found.

    Raises
    ------
    CompilerNotFoundError (RuntimeError)
        None of the candidates exists.
    """
    candidates = _candidates(cc)
    for c in candidates:
        path = shutil.which(c)
        if path:
            return path
    raise CompilerNotFoundError(f"no C compiler found (tried {candidates}); install gcc or clang, or pass cc=/path/to/compiler")


def compiler_unavailable_reason() -> str | None:
    """Why no C code can be compiled here, or None when a compiler is found.

    Returns
    -------
    str or None
        The message of :class:`CompilerNotFoundError`, or None.
    """
    try:
        find_compiler()
    except CompilerNotFoundError as exc:
        return str(exc)
    return None


def shared_library_suffix() -> str:
    """File suffix of a shared library on this platform.

    Returns
    -------
    str
        ``".so"``, ``".dylib"`` (macOS) or ``".dll"`` (Windows).
    """
    return {"Darwin": ".dylib", "Windows": ".dll"}.get(platform.system(), ".so")


def compile_shared(
    src_dir: Path, units: Sequence[str], out: Path, *, cc: str | None = None, extra_flags: Sequence[str] = ()
) -> Path:
    """Compile ``units`` (file names in ``src_dir``) into the shared library ``out``.

    Parameters
    ----------
    src_dir : Path
        Folder holding the sources and headers (also the include path).
    units : sequence of str
        Translation units, in build order.
    out : Path
        Library to write; its suffix must be :func:`shared_library_suffix`.
    cc : str, optional
        Compiler (see :func:`find_compiler`).
    extra_flags : sequence of str
        Flags after :data:`CFLAGS`.

    Returns
    -------
    Path
        ``out``.

    Raises
    ------
    CompilerNotFoundError (RuntimeError)
        No compiler found.
    ValueError
        Wrong suffix of ``out``.
    RuntimeError
        The compiler failed (its messages included).
    """
    compiler = find_compiler(cc)
    ext = shared_library_suffix()
    if out.suffix != ext:
        raise ValueError(f"shared library name must end with {ext!r}, got {out.name!r}")
    cmd = [compiler, *CFLAGS, *extra_flags, "-shared", "-I", str(src_dir), "-o", str(out)]
    cmd += [str(src_dir / name) for name in units] + ["-lm"]
    returncode, stderr = _run_compiler(cmd)
    if returncode != 0:
        raise RuntimeError(f"C compilation failed ({' '.join(cmd)}):\n{stderr.strip()}")
    return out


def compile_shared_with(
    compiler: Sequence[str], src_dir: Path, units: Sequence[str], out: Path, *, flags: Sequence[str] = CFLAGS
) -> Path:
    """Compile ``units`` into the shared library ``out`` with a given compiler command (e.g. a cross compiler).

    Parameters
    ----------
    compiler : sequence of str
        Compiler command and its leading arguments, e.g. ``["x86_64-w64-mingw32-gcc"]`` or
        ``[sys.executable, "-m", "ziglang", "cc", "-target", "aarch64-linux-gnu"]``.
    src_dir : Path
        Folder holding the sources and headers (also the include path).
    units : sequence of str
        Translation units, in build order.
    out : Path
        Library to write (any suffix: the target decides, e.g. ``.dll``).
    flags : sequence of str
        Compiler flags (default :data:`CFLAGS`).

    Returns
    -------
    Path
        ``out``.

    Raises
    ------
    RuntimeError
        The compiler failed or does not exist (its messages included).
    """
    cmd = [*compiler, *flags, "-shared", "-I", str(src_dir), "-o", str(out)]
    cmd += [str(src_dir / name) for name in units] + ["-lm"]
    try:
        returncode, stderr = _run_compiler(cmd)
    except FileNotFoundError as exc:
        raise RuntimeError(f"C compiler {compiler[0]!r} not found: {exc}") from exc
    if returncode != 0:
        raise RuntimeError(f"C compilation failed ({' '.join(cmd)}):\n{stderr.strip()}")
    return out


def _run_compiler(cmd: Sequence[str]) -> tuple[int, str]:
    """Run the compiler; on any exception (Ctrl-C included) kill it and its children, then re-raise.

    The compiler driver starts ``cc1``, ``as`` and ``ld`` as its children: killing the driver alone
    would orphan them, so on POSIX it runs in its own process group and the whole group is killed.
    """
    posix = os.name == "posix"
    proc, interrupted = _start(cmd, posix)
    try:
        if interrupted:
            raise KeyboardInterrupt
        _, stderr = proc.communicate()
    except BaseException:
        _kill_tree(proc, posix)
        raise
    finally:
        if proc.returncode is None:  # pragma: no cover - communicate() returned without reaping
            _kill_tree(proc, posix)
    return proc.returncode, stderr or ""


def _start(cmd: Sequence[str], posix: bool) -> tuple[subprocess.Popen, bool]:
    """Start the compiler with Ctrl-C held back until the process object exists; (process, Ctrl-C arrived meanwhile).

    A KeyboardInterrupt raised inside ``Popen`` (after the fork, before it returns: seen under load) would leave a
    running compiler nobody can kill, so the main thread records a SIGINT during the start and reports it instead.
    """

    def start() -> subprocess.Popen:
        return subprocess.Popen(list(cmd), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=posix)

    previous = signal.getsignal(signal.SIGINT) if threading.current_thread() is threading.main_thread() else None
    if not callable(previous):  # another thread, a handler set outside Python, or ignored: nothing to hold back
        return start(), False
    arrived: list[int] = []
    signal.signal(signal.SIGINT, lambda signum, frame: arrived.append(signum))
    try:
        proc = start()
    finally:
        signal.signal(signal.SIGINT, previous)
    return proc, bool(arrived)


def _kill_tree(proc: subprocess.Popen, posix: bool) -> None:
    """Kill ``proc`` (and on POSIX its whole process group) and reap it."""
    if posix:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(proc.pid, signal.SIGKILL)
    with contextlib.suppress(ProcessLookupError):
        proc.kill()
    with contextlib.suppress(Exception):
        proc.communicate(timeout=5.0)
