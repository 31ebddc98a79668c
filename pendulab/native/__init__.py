"""The C solver core shared by the FMU and the native fast path, and its build as a shared library.

One C implementation, two front ends:

* ``c/ode_solver.{c,h}``: adaptive DOPRI5 and RODAS4 for ``x' = f(x)``,
  independent of FMI; every exported FMU compiles and ships these files.
* ``c/ode_loop.{c,h}``: the output-grid loop (interval by interval, input
  held per interval, every grid state written to the caller's buffer).
* ``c/native_api.{c,h}``: the entry points of the native library of one model kind.
* :mod:`~pendulab.native.codegen`: the CasADi-generated model functions of a
  model kind (parameters are a runtime input), the same ``model_casadi.c`` the FMU ships.
* :mod:`~pendulab.native.build`: compiler lookup and compilation, with an on-disk
  cache keyed by a digest of the sources and flags; every cached file is verified
  by its SHA-256 before it is loaded and rebuilt once when damaged.
* :mod:`~pendulab.native.library`: the library of a kind loaded through ctypes
  (:func:`native_library`), used by ``simulate(method="compiled-dopri5" | "compiled-rodas4")``.

Nothing is compiled at import: the first use of a kind builds its library.
"""

from __future__ import annotations

from .build import (
    CFLAGS,
    CacheRebuildWarning,
    CompilerNotFoundError,
    build_cached,
    cache_dir,
    compiler_unavailable_reason,
    find_compiler,
)
from .codegen import C_DIR, model_c_source, native_sources
from .library import SOLVERS, GridResult, IntervalStepper, NativeLibrary
from .loader import native_library

__all__ = [
    "CFLAGS",
    "C_DIR",
    "CacheRebuildWarning",
    "CompilerNotFoundError",
    "GridResult",
    "IntervalStepper",
    "NativeLibrary",
    "SOLVERS",
    "build_cached",
    "cache_dir",
    "compiler_unavailable_reason",
    "find_compiler",
    "model_c_source",
    "native_library",
    "native_sources",
]
