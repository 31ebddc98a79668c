"""Compile C sources into a shared library, cached on disk by a digest of the sources and flags.

Used by the FMU export (:mod:`pendulab.fmu.export`, uncached: an FMU carries
its binary) and by the native fast path (:func:`build_cached`): the library
of a model kind is compiled once per machine and reused by every later
process. The cache directory is ``$PENDULAB_CACHE_DIR`` if set, else
``$XDG_CACHE_HOME/pendulab`` or ``~/.cache/pendulab``; libraries live in its
``native/`` folder under a name that carries the digest, so a change of any
source or flag builds a new file and stale files are never loaded.

A cached file cannot poison later runs (:func:`cached_artifact`, also used for the
Gymnasium backend's cached FMU): each file is built to a temporary name, its SHA-256
is written beside it (``<file>.sha256``) and both are renamed into place; every
later use checks the digest *before* the file is loaded (loading a damaged shared
library can crash the process), and a missing or wrong digest rebuilds the file
once, with a :class:`CacheRebuildWarning` naming the path. Builds of one file are
serialized by a lock file (``<file>.lock``, POSIX ``flock``), so concurrent
processes neither build twice nor see a half-written file. An interrupted build
(Ctrl-C) kills the compiler and everything it started (its own process group).
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import platform
import shutil
import signal
import subprocess
import sys
import tempfile
import warnings
from collections.abc import Callable, Iterator, Mapping, Sequence
from pathlib import Path

__all__ = [
    "CFLAGS",
    "CompilerNotFoundError",
    "find_compiler",
    "compiler_unavailable_reason",
    "shared_library_suffix",
    "cache_dir",
    "compile_shared",
    "compile_shared_with",
    "build_cached",
    "source_digest",
    "CacheRebuildWarning",
    "file_digest",
    "digest_path",
    "verify_cached",
    "cached_artifact",
]

#: Flags of every build (FMU and native); the sources compile warning-free with them (tested with -Werror).
CFLAGS: tuple[str, ...] = ("-Wall", "-Wextra", "-std=c99", "-O2", "-fPIC", "-fvisibility=hidden")
#: Part of the cache key: bump when the way a library is built changes in a way the flags do not show.
_BUILD_VERSION = "2"  # 2: every cached file has its SHA-256 beside it
#: What a user without a compiler can do (appended to CompilerNotFoundError messages).
COMPILER_HINT = "install gcc or clang (e.g. apt-get install gcc), or set $CC to a C compiler"


class CompilerNotFoundError(RuntimeError):
    """No C compiler was found."""


class CacheRebuildWarning(RuntimeWarning):
    """A cached file (native library, gym FMU) was damaged or failed to load, and is being rebuilt."""


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
    proc = subprocess.Popen(
        list(cmd), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=posix
    )  # fmt: skip
    try:
        _, stderr = proc.communicate()
    except BaseException:
        _kill_tree(proc, posix)
        raise
    finally:
        if proc.returncode is None:  # pragma: no cover - communicate() returned without reaping
            _kill_tree(proc, posix)
    return proc.returncode, stderr or ""


def _kill_tree(proc: subprocess.Popen, posix: bool) -> None:
    """Kill ``proc`` (and on POSIX its whole process group) and reap it."""
    if posix:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(proc.pid, signal.SIGKILL)
    with contextlib.suppress(ProcessLookupError):
        proc.kill()
    with contextlib.suppress(Exception):
        proc.communicate(timeout=5.0)


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
    rebuild: str | None = None,
) -> Path:
    """The cached shared library of ``sources``, compiled on the first request, verified on every later one.

    The library's SHA-256 is checked against the digest written beside it before the path is
    returned (see :func:`cached_artifact`); a damaged file is rebuilt once with a
    :class:`CacheRebuildWarning`.

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
    rebuild : str, optional
        Rebuild even when the digest matches, for this reason (e.g. the library failed to load).

    Returns
    -------
    Path
        The library (existing and intact, or just compiled and renamed into place).

    Raises
    ------
    CompilerNotFoundError (RuntimeError)
        The library is not cached and no compiler is found; the message names
        ``purpose`` and a hint.
    RuntimeError
        The cache folder cannot be written, or the compiler failed; the message names the cache path.
    """
    folder = cache_dir() if directory is None else Path(directory)
    path = folder / f"{name}-{source_digest(sources, units)[:20]}{shared_library_suffix()}"
    reason = rebuild if rebuild is not None else verify_cached(path)
    if reason is None:
        return path
    who = f"{purpose} needs" if purpose else "pendulab needs"
    try:
        cc_path = find_compiler(cc)
    except CompilerNotFoundError as exc:
        damaged = "" if reason == "is missing" else f" (the cached file {path} {reason} and must be rebuilt)"
        raise CompilerNotFoundError(
            f"{who} a C compiler to build its native library (once per machine, cached in {folder}){damaged}, and no C "
            f"compiler was found (tried {_candidates(cc)}); hint: {COMPILER_HINT}{', ' + hint if hint else ''}"
        ) from exc

    def compile_into(out: Path) -> None:
        with tempfile.TemporaryDirectory(prefix="pendulab-build-") as tmp:
            src = Path(tmp)
            for fname, data in sources.items():
                (src / fname).write_bytes(data)
            compile_shared(src, units, out, cc=cc_path)

    return cached_artifact(path, compile_into, what=f"{who} its native library; it", rebuild=rebuild)


def file_digest(path: Path) -> str:
    """SHA-256 of a file's bytes.

    Parameters
    ----------
    path : Path
        The file.

    Returns
    -------
    str
        Hex digest.

    Raises
    ------
    OSError
        The file cannot be read.
    """
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def digest_path(path: Path) -> Path:
    """Where the SHA-256 of a cached file is kept: ``<file>.sha256`` beside it.

    Parameters
    ----------
    path : Path
        The cached file.

    Returns
    -------
    Path
    """
    path = Path(path)
    return path.with_name(path.name + ".sha256")


def verify_cached(path: Path) -> str | None:
    """Why the cached file ``path`` must not be used, or None when it matches the digest written beside it.

    Reads the file and hashes it; nothing is loaded or executed, so a damaged file is harmless here.

    Parameters
    ----------
    path : Path
        The cached file.

    Returns
    -------
    str or None
        ``"is missing"`` (not built yet), a reason the file is damaged (no digest file, digest
        mismatch, unreadable), or None when it is intact.
    """
    path = Path(path)
    if not path.exists():
        return "is missing"
    try:
        expected = digest_path(path).read_text(encoding="ascii").strip()
    except FileNotFoundError:
        return f"has no digest file {digest_path(path).name}"
    except (OSError, UnicodeDecodeError) as exc:
        return f"has an unreadable digest file ({exc})"
    try:
        actual = file_digest(path)
    except OSError as exc:
        return f"cannot be read ({exc})"
    if actual != expected:
        return f"does not match its SHA-256 digest (damaged or replaced; {path.stat().st_size} bytes)"
    return None


@contextlib.contextmanager
def _build_lock(path: Path) -> Iterator[None]:
    """Hold an exclusive lock on ``<path>.lock`` (POSIX ``flock``; no lock elsewhere). Ctrl-C interrupts the wait."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - Windows: the atomic renames still keep readers safe
        yield
        return
    with open(path.with_name(path.name + ".lock"), "a+b") as fh:
        fcntl.flock(fh.fileno(), fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(fh.fileno(), fcntl.LOCK_UN)


def cached_artifact(path: Path, make: Callable[[Path], object], *, what: str, rebuild: str | None = None) -> Path:
    """The cached file ``path``, verified by its digest; built by ``make`` when missing, rebuilt when damaged.

    ``make(tmp)`` writes the file to a temporary path in the same folder (same suffix); its SHA-256
    goes to :func:`digest_path`, and both are renamed into place. A file that exists but fails
    :func:`verify_cached` (or any file when ``rebuild`` gives a reason, e.g. a load failure) is
    rebuilt with a :class:`CacheRebuildWarning` naming the path.

    Parameters
    ----------
    path : Path
        The cached file.
    make : callable
        ``make(tmp_path)`` builds the file at ``tmp_path``.
    what : str
        Who needs the file, for messages (e.g. ``"method 'compiled-dopri5' needs its native library; it"``).
    rebuild : str, optional
        Rebuild even if the digest matches, for this reason (e.g. ``"failed to load (...)"``).

    Returns
    -------
    Path
        ``path``, intact.

    Raises
    ------
    RuntimeError
        The folder cannot be written, or ``make`` failed; the message names ``path``.
    """
    path = Path(path)
    folder = path.parent
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise RuntimeError(
            f"{what} needs a writable cache folder, but {folder} cannot be created ({exc}); "
            "set $PENDULAB_CACHE_DIR to a writable folder"
        ) from exc
    with contextlib.ExitStack() as stack:
        try:
            stack.enter_context(_build_lock(path))
        except OSError as exc:
            raise RuntimeError(
                f"{what} cannot lock its cache file {path} ({exc}); set $PENDULAB_CACHE_DIR to a writable folder"
            ) from exc
        reason = rebuild if rebuild is not None else verify_cached(path)  # again: another process may have built it
        if reason is None:
            return path
        if reason != "is missing":
            warnings.warn(
                f"pendulab: the cached file {path} {reason}; rebuilding it (the cache folder is {folder})",
                CacheRebuildWarning,
                stacklevel=_stacklevel_outside_package(),
            )
        _build_into(path, make, what)
    reason = verify_cached(path)
    if reason is not None:  # pragma: no cover - someone damaged it again between the rename and here
        raise RuntimeError(f"{what}: the cached file {path} {reason} right after it was built; delete {folder} and retry")
    return path


#: The pendulab package folder: a warning points at the first frame outside it (the user's call).
_PACKAGE_DIR = str(Path(__file__).resolve().parents[1]) + os.sep


def _stacklevel_outside_package() -> int:
    """``stacklevel`` (for a ``warnings.warn`` in the caller) of the first frame outside the pendulab package."""
    frame = sys._getframe(1)
    level = 1
    while frame is not None and frame.f_code.co_filename.startswith(_PACKAGE_DIR):
        frame = frame.f_back
        level += 1
    return level


def _build_into(path: Path, make: Callable[[Path], object], what: str) -> None:
    """Build with ``make`` to temporary files in ``path``'s folder, write the digest, rename both into place."""
    folder = path.parent
    tmp_file = tmp_digest = None
    try:
        fd, name = tempfile.mkstemp(prefix=f".{path.stem}-", suffix=path.suffix, dir=folder)
        os.close(fd)
        tmp_file = Path(name)
        try:
            make(tmp_file)
        except (CompilerNotFoundError, KeyboardInterrupt):
            raise
        except Exception as exc:
            raise RuntimeError(f"{what} could not be built into the cache file {path}: {exc}") from exc
        digest = file_digest(tmp_file)
        fd, name = tempfile.mkstemp(prefix=f".{path.stem}-", suffix=".sha256", dir=folder)
        tmp_digest = Path(name)
        with os.fdopen(fd, "w", encoding="ascii") as fh:
            fh.write(digest + "\n")
        # The file first, then its digest: a reader between the two renames sees a mismatch and waits on the lock.
        os.replace(tmp_file, path)
        os.replace(tmp_digest, digest_path(path))
    except OSError as exc:
        raise RuntimeError(
            f"{what} could not write the cache file {path} ({exc}); set $PENDULAB_CACHE_DIR to a writable folder"
        ) from exc
    finally:
        for tmp in (tmp_file, tmp_digest):
            if tmp is not None:
                with contextlib.suppress(OSError):
                    tmp.unlink()
