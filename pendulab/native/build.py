"""Compile C sources into a shared library, cached on disk by a digest of the sources and flags.

Used by the FMU export (:mod:`pendulab.fmu.export`, uncached: an FMU carries
its binary) and by the native fast path (:func:`build_cached`): the library
of a model kind is compiled once per machine and reused by every later
process. The cache directory is ``$PENDULAB_CACHE_DIR`` if set, else
``$XDG_CACHE_HOME/pendulab`` or ``~/.cache/pendulab``; libraries live in its
``native/`` folder under a name that carries the digest, so a change of any
source or flag builds a new file and stale files are never loaded. Writes are
atomic (compile to a temporary file in the same folder, then rename), so
concurrent processes never see a half-written library.
"""

from __future__ import annotations

import hashlib
import os
import platform
import shutil
import subprocess
import sys
import tempfile
from collections.abc import Mapping, Sequence
from pathlib import Path

__all__ = [
    "CFLAGS",
    "CompilerNotFoundError",
    "find_compiler",
    "compiler_unavailable_reason",
    "shared_library_suffix",
    "cache_dir",
    "compile_shared",
    "build_cached",
    "source_digest",
]

#: Flags of every build (FMU and native); the sources compile warning-free with them (tested with -Werror).
CFLAGS: tuple[str, ...] = ("-Wall", "-Wextra", "-std=c99", "-O2", "-fPIC", "-fvisibility=hidden")
#: Part of the cache key: bump when the way a library is built changes in a way the flags do not show.
_BUILD_VERSION = "1"
#: What a user without a compiler can do (appended to CompilerNotFoundError messages).
COMPILER_HINT = "install gcc or clang (e.g. apt-get install gcc), or set $CC to a C compiler"


class CompilerNotFoundError(RuntimeError):
    """No C compiler was found."""


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


def cache_dir() -> Path:
    """Folder of the cached native libraries (not created here).

    Returns
    -------
    Path
        ``$PENDULAB_CACHE_DIR/native``, else ``$XDG_CACHE_HOME/pendulab/native``,
        else ``~/.cache/pendulab/native``.
    """
    root = os.environ.get("PENDULAB_CACHE_DIR")
    if root:
        return Path(root).expanduser() / "native"
    xdg = os.environ.get("XDG_CACHE_HOME")
    base = Path(xdg).expanduser() if xdg else Path.home() / ".cache"
    return base / "pendulab" / "native"


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
    proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if proc.returncode != 0:
        raise RuntimeError(f"C compilation failed ({' '.join(cmd)}):\n{proc.stderr.strip()}")
    return out


def source_digest(sources: Mapping[str, bytes], units: Sequence[str], extra_flags: Sequence[str] = ()) -> str:
    """Cache key of a build: SHA-256 of the sources, the units, the flags and the platform.

    Parameters
    ----------
    sources : mapping of str to bytes
        Every file of the build (sources and headers) by name.
    units : sequence of str
        Translation units.
    extra_flags : sequence of str
        Flags after :data:`CFLAGS`.

    Returns
    -------
    str
        Hex digest.
    """
    h = hashlib.sha256()
    meta = [_BUILD_VERSION, platform.system(), platform.machine(), sys.byteorder, *CFLAGS, "|", *extra_flags, "|", *units]
    h.update("\0".join(meta).encode())
    for name in sorted(sources):
        h.update(b"\0" + name.encode() + b"\0" + hashlib.sha256(sources[name]).digest())
    return h.hexdigest()


def build_cached(
    name: str,
    sources: Mapping[str, bytes],
    units: Sequence[str],
    *,
    purpose: str = "",
    hint: str = "",
    cc: str | None = None,
    directory: Path | None = None,
) -> Path:
    """The cached shared library of ``sources``, compiled on the first request.

    Parameters
    ----------
    name : str
        Stem of the library file (the digest is appended).
    sources : mapping of str to bytes
        Every file of the build by name.
    units : sequence of str
        Translation units among ``sources``.
    purpose : str
        What needs the library (e.g. ``"method 'compiled-rodas4'"``), for error messages.
    hint : str
        What else the user can do without a compiler (appended to the hint).
    cc : str, optional
        Compiler (see :func:`find_compiler`); not part of the cache key.
    directory : Path, optional
        Cache folder; default :func:`cache_dir`.

    Returns
    -------
    Path
        The library (existing, or just compiled and renamed into place).

    Raises
    ------
    CompilerNotFoundError (RuntimeError)
        The library is not cached and no compiler is found; the message names
        ``purpose`` and a hint.
    RuntimeError
        The cache folder cannot be written, or the compiler failed.
    """
    folder = cache_dir() if directory is None else Path(directory)
    path = folder / f"{name}-{source_digest(sources, units)[:20]}{shared_library_suffix()}"
    if path.is_file():
        return path
    who = f"{purpose} needs" if purpose else "pendulab needs"
    try:
        cc_path = find_compiler(cc)
    except CompilerNotFoundError as exc:
        raise CompilerNotFoundError(
            f"{who} a C compiler to build its native library (once per machine, cached in {folder}), and no C compiler "
            f"was found (tried {_candidates(cc)}); hint: {COMPILER_HINT}{', ' + hint if hint else ''}"
        ) from exc
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise RuntimeError(
            f"{who} a writable cache folder for its native library, but {folder} cannot be created ({exc}); "
            "set $PENDULAB_CACHE_DIR to a writable folder"
        ) from exc
    with tempfile.TemporaryDirectory(prefix="pendulab-build-") as tmp:
        src = Path(tmp)
        for fname, data in sources.items():
            (src / fname).write_bytes(data)
        fd, tmp_name = tempfile.mkstemp(prefix=f".{name}-", suffix=shared_library_suffix(), dir=folder)
        os.close(fd)
        tmp_lib = Path(tmp_name)
        try:
            compile_shared(src, units, tmp_lib, cc=cc_path)
            os.replace(tmp_lib, path)  # atomic: a concurrent build of the same digest writes the same bytes
        finally:
            if tmp_lib.exists():
                tmp_lib.unlink()
    return path
