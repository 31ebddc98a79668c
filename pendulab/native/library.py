"""The native library of a model kind, called through ctypes.

:class:`NativeLibrary` wraps the shared library of ``ode_solver.c`` +
``ode_loop.c`` + ``native_api.c`` + the generated model code of a model kind:
:meth:`NativeLibrary.run_grid` integrates a whole output grid in one C call,
:class:`IntervalStepper` one interval per call. Where a library comes from
(built once per machine, loaded once per process) is :mod:`.loader`
(:func:`~pendulab.native.loader.native_library`).
"""

from __future__ import annotations

import ctypes
from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = [
    "SOLVERS",
    "ABI_VERSION",
    "ERROR_CODES",
    "LoopStats",
    "GridResult",
    "NativeLibrary",
    "IntervalStepper",
]

#: Solver codes of ode_solver.h by name.
SOLVERS: dict[str, int] = {"dopri5": 0, "rodas4": 1}
#: PENDULAB_NATIVE_ABI of native_api.h this module speaks.
ABI_VERSION = 1
#: Return codes of the C loop (ode_solver.h, ode_loop.h) by name.
ERROR_CODES: dict[str, int] = {
    "ok": 0,
    "rhs": -1,
    "step_size": -2,
    "max_steps": -3,
    "singular": -4,
    "args": -5,
    "grid": -10,
    "state": -11,
    "input": -12,
    "null": -13,
}


class LoopStats(ctypes.Structure):
    """ctypes mirror of ``OdeLoopStats`` (ode_loop.h)."""

    _fields_ = [
        ("n_steps", ctypes.c_long),
        ("n_rejected", ctypes.c_long),
        ("n_rhs", ctypes.c_long),
        ("n_jac", ctypes.c_long),
        ("t_reached", ctypes.c_double),
        ("h_next", ctypes.c_double),
        ("n_points", ctypes.c_int),
        ("reserved", ctypes.c_int),
    ]


@dataclass(frozen=True)
class GridResult:
    """What one :meth:`NativeLibrary.run_grid` call returns.

    Attributes
    ----------
    code : int
        0 on success, else a negative code of :data:`ERROR_CODES`.
    message : str
        The C library's text for ``code``.
    n_points : int
        Rows of the output buffer written (x0 included).
    t_reached : float
        Last time reached [s] (the grid's end on success).
    h_next : float
        The solver's next step-size guess [s] (pass as ``h0`` to continue).
    n_steps, n_rejected, n_rhs, n_jac : int
        Accepted and rejected steps, right-hand-side and Jacobian evaluations of this call.
    """

    code: int
    message: str
    n_points: int
    t_reached: float
    h_next: float
    n_steps: int
    n_rejected: int
    n_rhs: int
    n_jac: int

    @property
    def ok(self) -> bool:
        """True when the whole grid was integrated."""
        return self.code == 0


_dbl = ctypes.c_double
_ptr = ctypes.c_void_p


class NativeLibrary:
    """ctypes bindings of one built library (see ``native_api.h``).

    Parameters
    ----------
    kind : {"rigid", "elastic"}
        Model kind the library was generated for.
    path : Path
        The shared library.

    Raises
    ------
    RuntimeError
        The library's ABI version or struct size does not match this module.
    """

    def __init__(self, kind: str, path: Path) -> None:
        self.kind = kind
        self.path = Path(path)
        lib = ctypes.CDLL(str(self.path))
        lib.pendulab_native_abi.restype = ctypes.c_int
        lib.pendulab_native_abi.argtypes = []
        lib.pendulab_native_sizes.restype = None
        lib.pendulab_native_sizes.argtypes = [ctypes.POINTER(ctypes.c_int)] * 4
        lib.pendulab_native_run.restype = ctypes.c_int
        lib.pendulab_native_run.argtypes = [
            ctypes.c_int, _dbl, _dbl, _dbl, ctypes.c_long, _dbl,  # method, rtol, atol, h_max, max_steps, h0
            _ptr, ctypes.c_int, _ptr, ctypes.c_int, _ptr, _ptr, _ptr, ctypes.POINTER(LoopStats),
        ]  # fmt: skip
        lib.pendulab_native_error_string.restype = ctypes.c_char_p
        lib.pendulab_native_error_string.argtypes = [ctypes.c_int]
        for name in ("pendulab_native_rhs", "pendulab_native_jac"):
            getattr(lib, name).restype = ctypes.c_int
            getattr(lib, name).argtypes = [_ptr] * 4
        lib.pendulab_native_rhs_repeat.restype = ctypes.c_int
        lib.pendulab_native_rhs_repeat.argtypes = [ctypes.c_int, ctypes.c_long, _ptr, _ptr, _ptr, _ptr]
        abi = lib.pendulab_native_abi()
        sizes = [ctypes.c_int() for _ in range(4)]
        lib.pendulab_native_sizes(*[ctypes.byref(s) for s in sizes])
        self.nx, self.nu, self.np, stats_bytes = (s.value for s in sizes)
        if abi != ABI_VERSION or stats_bytes != ctypes.sizeof(LoopStats):
            raise RuntimeError(
                f"native library {self.path} has ABI {abi} (stats struct {stats_bytes} bytes); this pendulab expects "
                f"ABI {ABI_VERSION} ({ctypes.sizeof(LoopStats)} bytes): delete the file to rebuild it"
            )
        self._lib = lib
        self._run = lib.pendulab_native_run

    def __repr__(self) -> str:
        return f"NativeLibrary(kind={self.kind!r}, path={str(self.path)!r})"

    def error_string(self, code: int) -> str:
        """The C library's message for a return code.

        Parameters
        ----------
        code : int
            A return code of the loop.

        Returns
        -------
        str
        """
        return self._lib.pendulab_native_error_string(int(code)).decode()

    def _vector(self, v: np.ndarray, n: int, name: str) -> np.ndarray:
        a = np.ascontiguousarray(v, dtype=float)
        if a.shape != (n,):
            raise ValueError(f"{name} must have shape ({n},), got {a.shape}")
        return a

    def run_grid(
        self,
        solver: str,
        t: np.ndarray,
        x0: np.ndarray,
        u: np.ndarray,
        p: np.ndarray,
        *,
        rtol: float,
        atol: float,
        h_max: float = 0.0,
        max_steps: int = 1_000_000,
        h0: float = 0.0,
        out: np.ndarray | None = None,
    ) -> tuple[np.ndarray, GridResult]:
        """Integrate over the grid ``t`` in one C call, holding ``u[k]`` on ``[t[k], t[k+1]]``.

        Parameters
        ----------
        solver : {"dopri5", "rodas4"}
            The C solver.
        t : ndarray, shape (N,)
            Strictly increasing output grid [s].
        x0 : ndarray, shape (nx,)
            State at ``t[0]``.
        u : ndarray, shape (nu,), (1, nu) or (N-1, nu)
            Input held over the whole grid, or per interval.
        p : ndarray, shape (np,)
            Parameter vector.
        rtol, atol : float
            Tolerances of the mixed error test.
        h_max : float
            Largest internal step [s]; 0: unlimited.
        max_steps : int
            Budget of step attempts over the call.
        h0 : float
            First step-size guess [s]; 0: automatic.
        out : ndarray, shape (N, nx), optional
            C-contiguous float buffer for the states (allocated if not given).

        Returns
        -------
        x : ndarray, shape (N, nx)
            States on the grid; rows from ``result.n_points`` on are unset on failure.
        result : GridResult
            Code, time reached and counts.

        Raises
        ------
        ValueError
            Unknown solver, or arrays of the wrong shape (the C code checks values).
        """
        if solver not in SOLVERS:
            raise ValueError(f"solver must be one of {list(SOLVERS)}, got {solver!r}")
        t = np.ascontiguousarray(t, dtype=float)
        if t.ndim != 1 or t.size < 1:
            raise ValueError(f"t must be a non-empty 1-D grid, got shape {t.shape}")
        x0 = self._vector(x0, self.nx, "x0")
        p = self._vector(p, self.np, "p")
        u = np.ascontiguousarray(u, dtype=float)
        if u.ndim == 1:
            u = u.reshape(1, -1)
        if u.ndim != 2 or u.shape[1] != self.nu or u.shape[0] not in (1, max(t.size - 1, 1)):
            raise ValueError(f"u must have shape ({self.nu},), (1, {self.nu}) or ({t.size - 1}, {self.nu}), got {u.shape}")
        if out is None:
            out = np.empty((t.size, self.nx))
        elif out.shape != (t.size, self.nx) or out.dtype != np.float64 or not out.flags.c_contiguous:
            raise ValueError(f"out must be a C-contiguous float64 array of shape ({t.size}, {self.nx})")
        stats = LoopStats()
        code = self._run(
            SOLVERS[solver], rtol, atol, h_max, int(max_steps), h0,
            t.ctypes.data, t.size, u.ctypes.data, u.shape[0], p.ctypes.data, x0.ctypes.data, out.ctypes.data,
            ctypes.byref(stats),
        )  # fmt: skip
        return out, self._result(code, stats)

    def _result(self, code: int, stats: LoopStats) -> GridResult:
        return GridResult(
            code=int(code),
            message=self.error_string(code),
            n_points=int(stats.n_points),
            t_reached=float(stats.t_reached),
            h_next=float(stats.h_next),
            n_steps=int(stats.n_steps),
            n_rejected=int(stats.n_rejected),
            n_rhs=int(stats.n_rhs),
            n_jac=int(stats.n_jac),
        )

    def stepper(self, solver: str, p: np.ndarray, *, rtol: float, atol: float, h_max: float = 0.0) -> IntervalStepper:
        """A low-overhead caller of the C loop for one output interval at a time (sampled feedback).

        Parameters
        ----------
        solver : {"dopri5", "rodas4"}
            The C solver.
        p : ndarray, shape (np,)
            Parameter vector.
        rtol, atol, h_max : float
            As in :meth:`run_grid`.

        Returns
        -------
        IntervalStepper

        Raises
        ------
        ValueError
            Unknown solver or wrong shape of ``p``.
        """
        if solver not in SOLVERS:
            raise ValueError(f"solver must be one of {list(SOLVERS)}, got {solver!r}")
        return IntervalStepper(self, SOLVERS[solver], self._vector(p, self.np, "p"), rtol, atol, h_max)

    def rhs(self, x: np.ndarray, u: np.ndarray, p: np.ndarray) -> np.ndarray:
        """One evaluation of ``f(x, u, p)`` by the compiled model code.

        Parameters
        ----------
        x : ndarray, shape (nx,)
        u : ndarray, shape (nu,)
        p : ndarray, shape (np,)

        Returns
        -------
        ndarray, shape (nx,)

        Raises
        ------
        ValueError
            Wrong shape of an argument.
        RuntimeError
            The generated function reported an error.
        """
        x, u, p = self._vector(x, self.nx, "x"), self._vector(u, self.nu, "u"), self._vector(p, self.np, "p")
        xdot = np.empty(self.nx)
        code = self._lib.pendulab_native_rhs(x.ctypes.data, u.ctypes.data, p.ctypes.data, xdot.ctypes.data)
        if code != 0:
            raise RuntimeError(f"the compiled right-hand side failed (code {code})")
        return xdot

    def jacobian(self, x: np.ndarray, u: np.ndarray, p: np.ndarray) -> np.ndarray:
        """Dense ``df/dx`` by the compiled model code.

        Parameters
        ----------
        x : ndarray, shape (nx,)
        u : ndarray, shape (nu,)
        p : ndarray, shape (np,)

        Returns
        -------
        ndarray, shape (nx, nx)

        Raises
        ------
        ValueError
            Wrong shape of an argument.
        RuntimeError
            The generated function reported an error.
        """
        x, u, p = self._vector(x, self.nx, "x"), self._vector(u, self.nu, "u"), self._vector(p, self.np, "p")
        J = np.empty(self.nx * self.nx)
        code = self._lib.pendulab_native_jac(x.ctypes.data, u.ctypes.data, p.ctypes.data, J.ctypes.data)
        if code != 0:
            raise RuntimeError(f"the compiled Jacobian failed (code {code})")
        return J.reshape(self.nx, self.nx, order="F")

    def rhs_repeat(self, n_calls: int, x: np.ndarray, u: np.ndarray, p: np.ndarray, *, through_solver: bool) -> None:
        """Evaluate ``f(x, u, p)`` ``n_calls`` times in C (time it from outside).

        Parameters
        ----------
        n_calls : int
            Number of evaluations.
        x, u, p : ndarray
            Arguments (shapes (nx,), (nu,), (np,)).
        through_solver : bool
            False: bare calls of the generated function; True: through the callback chain the solver uses.

        Raises
        ------
        ValueError
            Wrong shape of an argument.
        RuntimeError
            The generated function reported an error.
        """
        x, u, p = self._vector(x, self.nx, "x"), self._vector(u, self.nu, "u"), self._vector(p, self.np, "p")
        xdot = np.empty(self.nx)
        code = self._lib.pendulab_native_rhs_repeat(
            int(through_solver), int(n_calls), x.ctypes.data, u.ctypes.data, p.ctypes.data, xdot.ctypes.data
        )
        if code != 0:
            raise RuntimeError(f"the compiled right-hand side failed (code {code})")


class IntervalStepper:
    """Advances one state through single output intervals, one C call each, carrying the step size.

    Made by :meth:`NativeLibrary.stepper`. The solver's next step-size guess is
    carried from call to call (as an FMU carries it across DoStep calls), and
    the counts accumulate in :attr:`totals`.

    Parameters
    ----------
    lib : NativeLibrary
        The library.
    method : int
        Solver code (:data:`SOLVERS`).
    p : ndarray, shape (np,)
        Parameter vector (C-contiguous float64, kept by reference).
    rtol, atol : float
        Tolerances.
    h_max : float
        Largest internal step [s]; 0: unlimited.
    """

    def __init__(self, lib: NativeLibrary, method: int, p: np.ndarray, rtol: float, atol: float, h_max: float) -> None:
        self.lib = lib
        self._args = (method, float(rtol), float(atol), float(h_max))
        self._p = p
        self._t = np.empty(2)
        self._u = np.empty(lib.nu)
        self._x0 = np.empty(lib.nx)
        self._x = np.empty((2, lib.nx))
        self._stats = LoopStats()
        self._stats_ref = ctypes.byref(self._stats)
        self.h = 0.0
        self.totals = {"n_steps": 0, "n_rejected": 0, "n_rhs": 0, "n_jac": 0}

    def step(self, t0: float, t1: float, x: np.ndarray, u: np.ndarray, max_steps: int) -> tuple[np.ndarray, GridResult | None]:
        """Integrate from ``(t0, x)`` to ``t1`` holding ``u``.

        Parameters
        ----------
        t0, t1 : float
            Interval [s], ``t1 > t0``.
        x : ndarray, shape (nx,)
            State at ``t0``.
        u : ndarray, shape (nu,)
            Input held on the interval.
        max_steps : int
            Step budget of this call.

        Returns
        -------
        x1 : ndarray, shape (nx,)
            State at ``t1`` (a view into an internal buffer: copy it).
        failure : GridResult or None
            None on success, else the C result.
        """
        self._t[0], self._t[1] = t0, t1
        self._u[:] = u
        self._x0[:] = x
        method, rtol, atol, h_max = self._args
        code = self.lib._run(
            method, rtol, atol, h_max, int(max_steps), self.h,
            self._t.ctypes.data, 2, self._u.ctypes.data, 1, self._p.ctypes.data, self._x0.ctypes.data,
            self._x.ctypes.data, self._stats_ref,
        )  # fmt: skip
        s = self._stats
        tot = self.totals
        tot["n_steps"] += s.n_steps
        tot["n_rejected"] += s.n_rejected
        tot["n_rhs"] += s.n_rhs
        tot["n_jac"] += s.n_jac
        if code != 0:
            return self._x0, self.lib._result(code, s)
        self.h = s.h_next
        return self._x[1], None
