"""Where a native library comes from: built on first use (cached on disk, :mod:`.build`), loaded once per process."""

from __future__ import annotations

import os
import threading
from pathlib import Path

from .build import build_cached
from .codegen import KINDS, native_sources, native_units
from .library import NativeLibrary

__all__ = ["native_library", "loaded_libraries", "library_state"]


_LOADED: dict[Path, NativeLibrary] = {}
#: (kind, the environment that decides the cache folder) -> library: later calls skip hashing the sources
#: and looking at the disk.
_BY_KEY: dict[tuple[str | None, ...], NativeLibrary] = {}
_CACHE_ENV = ("PENDULAB_CACHE_DIR", "XDG_CACHE_HOME", "HOME")
_LOCK = threading.Lock()


def native_library(kind: str, *, purpose: str = "", hint: str = "") -> NativeLibrary:
    """The native library of a model kind: built on first use (cached on disk), loaded once per process.

    The cached file is checked against its SHA-256 before ``dlopen`` (a damaged shared library
    can crash the process when loaded); a damaged file, or one that fails to load, is rebuilt once.

    Parameters
    ----------
    kind : {"rigid", "elastic"}
        Model kind.
    purpose : str
        What needs it (e.g. ``"method 'compiled-dopri5'"``), for error messages.
    hint : str
        Alternative without a compiler, appended to the hint of a missing-compiler error.

    Returns
    -------
    NativeLibrary

    Raises
    ------
    ValueError
        Unknown kind.
    CompilerNotFoundError (RuntimeError)
        Not cached and no C compiler found; names ``purpose`` and a hint.
    RuntimeError
        Compilation failed, the cache folder is not writable, or the library fails to load after one
        rebuild; the message names the cache path.

    Warns
    -----
    CacheRebuildWarning
        The cached library was damaged (digest mismatch) or failed to load, and was rebuilt.
    """
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {list(KINDS)}, got {kind!r}")
    key = (kind, *(os.environ.get(v) for v in _CACHE_ENV))  # cheaper than cache_dir() on every run
    lib = _BY_KEY.get(key)
    if lib is not None:
        return lib
    with _LOCK:
        args = (f"pendulab_native_{kind}", native_sources(kind), native_units())
        path = build_cached(*args, purpose=purpose, hint=hint)  # verified by its digest before it is loaded
        lib = _LOADED.get(path)
        if lib is None:
            try:
                lib = NativeLibrary(kind, path)
            except (OSError, RuntimeError, AttributeError) as exc:  # dlopen failed, a symbol is missing, wrong ABI
                path = build_cached(*args, purpose=purpose, hint=hint, rebuild=f"failed to load ({exc})")
                try:
                    lib = NativeLibrary(kind, path)
                except (OSError, RuntimeError, AttributeError) as exc2:
                    raise RuntimeError(
                        f"the native library {path} fails to load even after a rebuild ({exc2}); "
                        f"delete the cache folder {path.parent} and retry"
                    ) from exc2
            _LOADED[path] = lib
        _BY_KEY[key] = lib
        return lib


def loaded_libraries() -> tuple[NativeLibrary, ...]:
    """The libraries loaded in this process.

    Returns
    -------
    tuple of NativeLibrary
    """
    with _LOCK:
        return tuple(_LOADED.values())


def library_state(kind: str) -> str:
    """How much of the native library of ``kind`` is ready, without building or loading anything.

    Parameters
    ----------
    kind : {"rigid", "elastic"}
        Model kind.

    Returns
    -------
    {"loaded", "on disk", "not built"}
        Loaded in this process, compiled and cached on disk (a load away), or still to be compiled.

    Raises
    ------
    ValueError
        Unknown kind.
    """
    from .build import library_path

    if kind not in KINDS:
        raise ValueError(f"kind must be one of {list(KINDS)}, got {kind!r}")
    if _BY_KEY.get((kind, *(os.environ.get(v) for v in _CACHE_ENV))) is not None:
        return "loaded"
    return "on disk" if library_path(f"pendulab_native_{kind}", native_sources(kind), native_units()).is_file() else "not built"
