"""The runner of ``method="taylor"`` (the registry contract of :mod:`pendulab.integrate.registry`)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..registry import STIFF_HINT, MethodSpec, RunRequest, RunResult
from .availability import check_tolerance_floor, heyoka_module, taylor_unavailable_reason
from .cache import _Borrowed, compile_count, prepared
from .outputs import grid_outputs

_OPTIONS = {"compact_mode": bool, "high_accuracy": bool, "max_steps": int}


# -- runner ---------------------------------------------------------------------
_DEFAULTS: dict[str, Any] = {"compact_mode": False, "high_accuracy": False, "max_steps": 0}


def _options(req: RunRequest) -> dict[str, Any]:
    opts = dict(_DEFAULTS)
    for name, value in req.options.items():
        if name not in _OPTIONS:
            raise ValueError(f"unknown option {name!r} for method 'taylor'; expected some of {sorted(_OPTIONS)}")
        kind = _OPTIONS[name]
        if kind is bool and not isinstance(value, (bool, np.bool_)):
            raise ValueError(f"option {name!r} of method 'taylor' must be a bool, got {value!r}")
        if kind is int and (isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 0):
            raise ValueError(f"option {name!r} of method 'taylor' must be an int >= 0, got {value!r}")
        opts[name] = kind(value)
    return opts


def _segments(schedule: np.ndarray, zero_inputs: tuple[int, ...]) -> list[tuple[int, int]]:
    """Runs ``[a, b)`` of equal consecutive rows of the held-input schedule (``zero_inputs``: its columns all zero)."""
    if len(zero_inputs) == schedule.shape[1] or np.array_equal(schedule[1:], schedule[:-1]):  # constant: one run
        return [(0, len(schedule))]
    change = np.flatnonzero(np.any(schedule[1:] != schedule[:-1], axis=1)) + 1
    bounds = [0, *change.tolist(), len(schedule)]
    return list(zip(bounds[:-1], bounds[1:], strict=True))


def _zero_inputs(schedule: np.ndarray | None, nu: int) -> tuple[int, ...]:
    """Inputs identically zero over the run (specialised away); none under feedback."""
    if schedule is None:
        return ()
    if not schedule.any():  # no torque at all (the common case): one cheap reduction
        return tuple(range(nu))
    return tuple(int(i) for i in np.flatnonzero(np.all(schedule == 0.0, axis=0)))


def run_taylor(req: RunRequest) -> RunResult:
    """Runner of the Taylor family (see the module docstring).

    Parameters
    ----------
    req : RunRequest
        A validated run.

    Returns
    -------
    RunResult
        States on the grid, held inputs; stats ``n_steps``, ``taylor_order``, ``tol``,
        ``compiled`` (True when this run compiled its integrator).

    Raises
    ------
    TaylorUnavailableError
        heyoka is not importable (an ``ImportError``).
    SimulationError
        heyoka stopped early (non-finite state, step limit).
    ValueError
        Unknown or ill-typed option.
    """
    hy = heyoka_module()
    opts = _options(req)
    model, t, sched = req.model, req.t, req.schedule
    tol = check_tolerance_floor("rtol" if req.rtol <= req.atol else "atol", min(req.rtol, req.atol))
    zero_u = tuple(range(model.nu)) if req.unforced else _zero_inputs(sched, model.nu)
    before = compile_count()
    entry, pars = prepared(model.kind, model.p, zero_u, tol, opts["compact_mode"], opts["high_accuracy"])
    # Torques specialised to zero may be absent from a system without coefficients; a run without any torque
    # keeps the zero torques of ``pars``.
    n_u = 0 if len(zero_u) == model.nu else min(model.nu, len(pars))
    kw: dict[str, Any] = {"max_steps": opts["max_steps"]}
    if req.max_step is not None:
        kw["max_delta_t"] = req.max_step
    ok = hy.taylor_outcome.time_limit
    n_steps = 0
    with _Borrowed(entry) as ta:
        ta.time = float(t[0])
        ta.state[:] = req.x0
        ta.pars[:] = pars
        if sched is not None:
            # One dense-output propagation per run of equal inputs; heyoka's last step of each
            # lands exactly on the run's last grid time, where the input may jump.
            segments = _segments(sched, zero_u)
            if len(segments) == 1:  # one run (the common case): heyoka's fresh array is the result
                if n_u:
                    ta.pars[:n_u] = sched[0, :n_u]
                X, n_steps = _propagate(ta, t, kw, req, hy)
            else:
                X = np.empty((len(t), model.nx))
                for a, b in segments:
                    ta.pars[:n_u] = sched[a, :n_u]
                    X[a : b + 1], n = _propagate(ta, t[a : b + 1], kw, req, hy)
                    n_steps += n
            U = sched
        else:
            X = np.empty((len(t), model.nx))
            U = np.empty((req.n_intervals, model.nu))
            X[0] = req.x0
            for k in range(req.n_intervals):
                U[k] = req.feedback_input(float(t[k]), X[k])
                ta.pars[:n_u] = U[k, :n_u]
                res = ta.propagate_until(float(t[k + 1]), **kw)
                n_steps += int(res[3])
                if res[0] != ok:
                    raise req.fail(ta.time, _reason(res[0], hy), _hint(res[0], hy))
                X[k + 1] = ta.state
        order = int(ta.order)
    # A non-finite state stops heyoka (err_nf_state, raised above); simulate checks every family's result again.
    stats = {"n_steps": n_steps, "taylor_order": order, "tol": tol, "compiled": compile_count() != before}
    return RunResult(X, U, stats)


def _propagate(ta: Any, grid: np.ndarray, kw: dict[str, Any], req: RunRequest, hy: Any) -> tuple[np.ndarray, int]:
    """States on ``grid`` (dense output of one propagation with constant inputs) and the steps taken."""
    res = ta.propagate_grid(grid, **kw)
    if res[0] != hy.taylor_outcome.time_limit:
        raise req.fail(ta.time, _reason(res[0], hy), _hint(res[0], hy))
    return res[-1], int(res[3])


def _reason(outcome: Any, hy: Any) -> str:
    if outcome == hy.taylor_outcome.err_nf_state:
        return "heyoka: the state became non-finite (err_nf_state)"
    if outcome == hy.taylor_outcome.step_limit:
        return "heyoka: the step limit max_steps was reached (step_limit)"
    return f"heyoka stopped with outcome {outcome}"


def _hint(outcome: Any, hy: Any) -> str:
    if outcome == hy.taylor_outcome.step_limit:
        return "raise options={'max_steps': ...} or use an implicit method for stiff springs"
    return STIFF_HINT


#: The Taylor method.
METHOD_SPECS: tuple[MethodSpec, ...] = (
    MethodSpec(
        "taylor",
        "taylor",
        "heyoka adaptive Taylor series (LLVM JIT)",
        run_taylor,
        # "outputs": simulate evaluates y(x, u) on the grid with the compiled evaluator (see .outputs).
        # heyoka calls no Python while it integrates (feedback runs between its calls): Ctrl-C arrives as
        # KeyboardInterrupt, never as a solver failure, so simulate needs no SIGINT watch around it.
        settings={"available": taylor_unavailable_reason, "outputs": grid_outputs, "passes_interrupts": True},
    ),
)
