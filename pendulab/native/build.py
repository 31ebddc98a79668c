"""Compile C sources into a shared library, cached on disk by a digest of the sources and flags.

Used by the FMU export (:mod:`pendulab.fmu.export`, uncached: an FMU carries
its binary) and by the native fast path (:func:`build_cached`): the library
of a model kind is compiled once per machine and reused by every later
process. The cache directory is ``$PENDULAB_CACHE_DIR`` if set, else
``$XDG_CACHE_HOME/pendulab`` or ``~/.cache/pendulab``; libraries live in its
``native/`` folder under a name that carries the digest, so a change of any
source or flag builds a new file and stale files are never loaded.

A cached file cannot poison later runs (:func:`cached_artifact`, the one mechanism of every
cache: also the Gymnasium backend's cached FMU and the plan library): each file is built to a
temporary name, its seal (SHA-256 and the key of the entry: here the full digest of the sources
and flags) is written beside it (``<file>.sha256``) and both are renamed into place; every
later use checks the seal *before* the file is loaded (loading a damaged shared
library can crash the process), and a missing, wrong or another entry's seal rebuilds the file
once, with a :class:`CacheRebuildWarning` naming the path. Builds of one file are
serialized by a lock file (``<file>.lock``, POSIX ``flock``), so concurrent
processes neither build twice nor see a half-written file. An interrupted build
(Ctrl-C) kills the compiler and everything it started (its own process group).

Compiler discovery and compilation live in :mod:`pendulab.native.compiler`, the verified
on-disk cache in :mod:`pendulab.native.cache`; their names are importable from here too.
"""

from __future__ import annotations

import hashlib
import platform
import shutil  # noqa: F401  (kept as an attribute: tests patch pendulab.native.build.shutil.which)
import sys
import tempfile
from collections.abc import Mapping, Sequence
from pathlib import Path

from .cache import (
    CacheRebuildWarning,
    cache_dir,
    cached_artifact,
    digest_path,
    file_digest,
    publish,
    read_sealed,
    seal,
    sealed_key,
    verify_cached,
)
from .compiler import (
    CFLAGS,
    COMPILER_HINT,
    CompilerNotFoundError,
    _candidates,
    compile_shared,
    compile_shared_with,
    compiler_unavailable_reason,
    find_compiler,
    shared_library_suffix,
)

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
    "library_path",
    "source_digest",
    "CacheRebuildWarning",
    "file_digest",
    "digest_path",
    "verify_cached",
    "cached_artifact",
    "publish",
    "read_sealed",
    "seal",
    "sealed_key",
]

#: Part of the cache key: bump when the way a library is built changes in a way the flags do not show.
_BUILD_VERSION = "3"  # 2: every cached file has its SHA-256 beside it; 3: its seal names the entry's key too


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


def library_path(name: str, sources: Mapping[str, bytes], units: Sequence[str], directory: Path | None = None) -> Path:
    """Where :func:`build_cached` keeps the library of ``sources`` (whether or not it is built yet).

    Parameters
    ----------
    name : str
        Stem of the library file.
    sources : mapping of str to bytes
        Every file of the build by name.
    units : sequence of str
        Translation units among ``sources``.
    directory : Path, optional
        Cache folder; default :func:`cache_dir`.

    Returns
    -------
    Path
        ``<folder>/<name>-<digest prefix><suffix>``.
    """
    folder = cache_dir() if directory is None else Path(directory)
    return folder / f"{name}-{source_digest(sources, units)[:20]}{shared_library_suffix()}"


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
    path = library_path(name, sources, units, directory)
    key = f"{name}-{source_digest(sources, units)}"  # sealed with the file: another entry's library moved here is refused
    reason = rebuild if rebuild is not None else verify_cached(path, key)
    if reason is None:
        return path
    who = f"{purpose} needs" if purpose else "pendulab needs"
    try:
        cc_path = find_compiler(cc)
    except CompilerNotFoundError as exc:
        damaged = "" if reason == "is missing" else f" (the cached file {path} {reason} and must be rebuilt)"
        raise CompilerNotFoundError(
            f"{who} a C compiler to build its native library (once per machine, cached in {path.parent}){damaged}, and no C "
            f"compiler was found (tried {_candidates(cc)}); hint: {COMPILER_HINT}{', ' + hint if hint else ''}"
        ) from exc

    def compile_into(out: Path) -> None:
        with tempfile.TemporaryDirectory(prefix="pendulab-build-") as tmp:
            src = Path(tmp)
            for fname, data in sources.items():
                (src / fname).write_bytes(data)
            compile_shared(src, units, out, cc=cc_path)

    return cached_artifact(path, compile_into, what=f"{who} its native library; it", rebuild=rebuild, key=key)
