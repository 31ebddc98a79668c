"""Compiled family: ``compiled-dopri5`` and ``compiled-rodas4``, the FMU's C solvers run natively.

The same C solver core an exported FMU embeds (``pendulab/native/c/ode_solver.c``:
Dormand-Prince 5(4), and RODAS4, an L-stable Rosenbrock method with the exact
Jacobian) and the same CasADi-generated model code, built once per model kind
as a shared library (cached on disk, see :mod:`pendulab.native.build`) and
called through ctypes. The whole loop runs in C: the library integrates from
grid point to grid point, holding each interval's input, and writes every grid
state into the result buffer.

* Input known in advance (none, constant or sampled): **one** C call per
  :func:`~pendulab.simulate`.
* Feedback ``u(t, x)``: one C call per output interval (state in, state out),
  carrying the solver's step-size guess from call to call, as an FMU does
  across DoStep calls.

One solver runs the whole grid with the error test
``|err_i| <= atol + rtol * max(|x_i|, |x_new_i|)`` (RMS over the states);
``max_step`` caps the internal step. Options: ``max_steps`` (budget of step
attempts, accepted + rejected, over the whole run; default 1 000 000).

Nothing is compiled at import: the first run of a model kind builds (or loads
from the disk cache) its library; a missing C compiler is a
:class:`~pendulab.native.CompilerNotFoundError` naming the method and a hint.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from ..native.build import compiler_unavailable_reason
from ..native.library import ERROR_CODES, GridResult
from ..native.loader import native_library
from .registry import MethodSpec, RunRequest, RunResult

__all__ = ["METHOD_SPECS", "run_compiled", "compiled_unavailable_reason", "DEFAULT_MAX_STEPS", "MIN_RTOL"]

#: Default budget of step attempts over one run (``options={"max_steps": ...}``).
DEFAULT_MAX_STEPS = 1_000_000
#: Smallest accepted rtol: 100 machine epsilons (as SciPy's solve_ivp); below it the error test asks for
#: more digits than a double carries and the step size collapses.
MIN_RTOL = 100 * float(np.finfo(float).eps)
_OPTIONS: Mapping[str, type] = {"max_steps": int}


def compiled_unavailable_reason() -> str | None:
    """Why the compiled methods cannot build their library here (None when a C compiler is found).

    Returns
    -------
    str or None
        One line, or None.
    """
    reason = compiler_unavailable_reason()
    return None if reason is None else f"needs a C compiler to build its native library once: {reason}"


def _options(req: RunRequest) -> dict[str, Any]:
    unknown = sorted(set(req.options) - set(_OPTIONS))
    if unknown:
        raise ValueError(f"method {req.spec.name!r}: unknown option(s) {unknown}; expected some of {sorted(_OPTIONS)}")
    max_steps = req.options.get("max_steps", DEFAULT_MAX_STEPS)
    if isinstance(max_steps, bool) or not isinstance(max_steps, (int, np.integer)) or not 1 <= max_steps <= 2**31 - 1:
        raise ValueError(f"method {req.spec.name!r}: option max_steps must be an integer in [1, 2**31 - 1], got {max_steps!r}")
    if req.rtol < MIN_RTOL:
        raise ValueError(
            f"method {req.spec.name!r}: rtol must be >= {MIN_RTOL:.3g} (100 machine epsilons), got {req.rtol!r}; "
            "a tighter relative tolerance cannot be met in double precision"
        )
    return {"max_steps": int(max_steps)}


def _failure(req: RunRequest, res: GridResult, max_steps: int) -> Exception:
    """The SimulationError of a failed C call, with the time the C loop reached."""
    explicit = req.spec.settings["solver"] == "dopri5"
    stiff = "stiff springs need an implicit method: try 'compiled-rodas4'" if explicit else ""
    code, reason = res.code, res.message
    if code == ERROR_CODES["rhs"]:
        hint = "the state blows up: check the initial state and parameters" + (f"; {stiff}" if stiff else "")
    elif code == ERROR_CODES["step_size"]:
        hint = "check the state, or loosen rtol/atol" + (f"; {stiff}" if stiff else "")
    elif code == ERROR_CODES["max_steps"]:
        reason = f"step budget exhausted ({max_steps} step attempts, accepted + rejected)"
        hint = "raise options={'max_steps': ...}" + (f", or {stiff}" if stiff else "")
    elif code == ERROR_CODES["singular"]:
        hint = "check the parameters (zero mass or length?)"
    else:
        reason = f"the C loop rejected its arguments (code {code}): {reason}"
        hint = ""
    return req.fail(res.t_reached, reason, hint)


def run_compiled(req: RunRequest) -> RunResult:
    """Runner of the compiled family (see the module docstring).

    Parameters
    ----------
    req : RunRequest
        A validated run.

    Returns
    -------
    RunResult
        States on the grid, held inputs and the C solver's counts (``n_steps``,
        ``n_rejected``, ``n_rhs``, ``n_jac``, ``c_calls``).

    Raises
    ------
    ValueError
        Unknown option, bad ``max_steps``, or ``rtol`` below :data:`MIN_RTOL`.
    CompilerNotFoundError (RuntimeError)
        The library of the model kind is not cached and no C compiler is found.
    SimulationError
        The C solver stopped (non-finite state, step-size underflow, step budget);
        the message names the method, the time reached and a hint.
    """
    spec, model, t = req.spec, req.model, req.t
    solver = spec.settings["solver"]
    opts = _options(req)
    max_steps = opts["max_steps"]
    lib = native_library(
        model.kind, purpose=f"method {spec.name!r}", hint=f"or use method={spec.settings['fallback']!r} (no compiler needed)"
    )
    h_max = 0.0 if req.max_step is None else float(req.max_step)
    p = np.ascontiguousarray(model.p, dtype=float)

    if req.feedback is None:
        sched = req.schedule
        X, res = lib.run_grid(
            solver, t, req.x0, sched[:1] if req.constant_input else sched, p,
            rtol=req.rtol, atol=req.atol, h_max=h_max, max_steps=max_steps,
        )  # fmt: skip
        if not res.ok:
            raise _failure(req, res, max_steps)
        stats = {"n_steps": res.n_steps, "n_rejected": res.n_rejected, "n_rhs": res.n_rhs, "n_jac": res.n_jac, "c_calls": 1}
        return RunResult(X, sched, stats)

    stepper = lib.stepper(solver, p, rtol=req.rtol, atol=req.atol, h_max=h_max)
    n_int = req.n_intervals
    X = np.empty((len(t), model.nx))
    U = np.empty((n_int, model.nu))
    X[0] = req.x0
    tot = stepper.totals
    for k in range(n_int):
        U[k] = req.feedback_input(float(t[k]), X[k])
        left = max_steps - tot["n_steps"] - tot["n_rejected"]
        if left < 1:
            res = GridResult(ERROR_CODES["max_steps"], "too many internal steps", 1, float(t[k]), stepper.h, 0, 0, 0, 0)
            raise _failure(req, res, max_steps)
        x1, failure = stepper.step(float(t[k]), float(t[k + 1]), X[k], U[k], left)
        if failure is not None:
            raise _failure(req, failure, max_steps)
        X[k + 1] = x1
    return RunResult(X, U, {**tot, "c_calls": n_int})


def _spec(name: str, solver: str, fallback: str, description: str) -> MethodSpec:
    settings = {"solver": solver, "fallback": fallback, "available": compiled_unavailable_reason}
    return MethodSpec(name, "compiled", description, run_compiled, False, settings)


#: The compiled methods.
METHOD_SPECS: tuple[MethodSpec, ...] = (
    _spec("compiled-dopri5", "dopri5", "cvodes-adams", "Dormand-Prince 5(4) in C (the FMU's solver), whole grid in one call"),
    _spec(
        "compiled-rodas4",
        "rodas4",
        "cvodes",
        "RODAS4 Rosenbrock (L-stable, exact Jacobian) in C (the FMU's solver), whole grid in one call",
    ),
)
