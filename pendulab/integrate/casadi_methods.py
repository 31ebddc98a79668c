"""CasADi integrator family: CVODES (BDF, Adams), IDAS and collocation (Radau, Legendre).

The whole output grid is integrated in one CasADi call whenever the input is
known in advance (none, constant or sampled); a feedback input, or CVODES
under a varying sampled input, runs one call per output interval.
Collocation is fixed-step: ``dt / ceil(dt / max_step)`` equal steps per output
interval (default step 1e-3 s); ``rtol``/``atol`` do not apply to it.

Options are checked against the plugin's own option list before an integrator
is built (an unknown one is a ``ValueError`` naming the method and the accepted
options). Budgets (:class:`~pendulab.integrate.registry.Budget`): SUNDIALS'
``max_num_steps`` bounds each output interval (100 000, or ``max_steps`` when
the user gives it); the run's total is checked between interval calls; a
wall-time budget, or a step budget set by the user, makes the run go one output
interval per call (CVODES restarts at each output time). CVODES/IDAS
print nothing (``disable_internal_warnings``); when they fail, the failing
interval is re-run once with their messages captured to report the time they
actually reached. Ctrl-C (which CasADi turns into a solver failure) is
re-raised as ``KeyboardInterrupt``.
"""

from __future__ import annotations

import difflib
import io
import math
import os
import re
import sys
import tempfile
from collections.abc import Callable, Mapping
from functools import cache, lru_cache
from typing import Any

import casadi as ca
import numpy as np

from ..model.builders import build_elastic, build_rigid
from .registry import DEFAULT_FIXED_STEP, MethodSpec, RunRequest, RunResult, failure_hint

__all__ = ["METHOD_SPECS", "run_casadi", "freeze_options", "thaw_options", "plugin_options", "IntegratorOptionError"]

_MAPPING = "__mapping__"


def freeze_options(opts: Mapping[str, Any]) -> tuple:
    """Hashable form of integrator options (a cache key); nested mappings (e.g. ``jit_options``) included.

    Parameters
    ----------
    opts : mapping
        CasADi options.

    Returns
    -------
    tuple
        Sorted ``(key, value)`` pairs; :func:`thaw_options` inverts it.
    """

    def value(v: Any) -> Any:
        if isinstance(v, Mapping):
            return (_MAPPING, freeze_options(v))
        if isinstance(v, (list, tuple)):
            return tuple(value(x) for x in v)
        return v

    return tuple(sorted((k, value(v)) for k, v in opts.items()))


def thaw_options(key: tuple) -> dict:
    """Inverse of :func:`freeze_options` (sequences come back as lists).

    Parameters
    ----------
    key : tuple
        Output of :func:`freeze_options`.

    Returns
    -------
    dict
        CasADi options.
    """

    def value(v: Any) -> Any:
        if isinstance(v, tuple) and len(v) == 2 and v[0] == _MAPPING:
            return thaw_options(v[1])
        if isinstance(v, tuple):
            return [value(x) for x in v]
        return v

    return {k: value(v) for k, v in key}


@lru_cache(maxsize=64)
def _integrator(kind: str, plugin: str, grid: tuple[float, ...], opts_key: tuple) -> ca.Function:
    sym = build_rigid() if kind == "rigid" else build_elastic()
    dae = {"x": sym.x, "u": sym.u, "p": sym.p, "ode": sym.xdot}
    return ca.integrator("pendulab_" + plugin, plugin, dae, 0.0, list(grid), thaw_options(opts_key))


#: SUNDIALS' max_num_steps per output interval when the user sets no step budget.
_MAX_NUM_STEPS = 100_000
#: Times SUNDIALS names in its messages ("At t = 494.834, mxstep steps taken before reaching tout.").
_AT_T = re.compile(r"\bt\s*=\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)")
#: Options the runner sets from simulate's own arguments: not accepted in ``options``.
_MANAGED = {"reltol": "rtol", "abstol": "atol", "max_step_size": "max_step"}
#: SUNDIALS' switch for its own messages; the error path sets it only where the plugin accepts it (not collocation).
_QUIET = "disable_internal_warnings"


@cache
def _probe(plugin: str) -> ca.Function:
    """A tiny integrator of the plugin: asks CasADi which options the plugin accepts (``has_option``)."""
    x = ca.SX.sym("x")
    return ca.integrator(f"pendulab_probe_{plugin}", plugin, {"x": x, "ode": -x}, 0.0, [1.0], {})


@cache
def plugin_options(plugin: str) -> tuple[str, ...]:
    """The plugin's own options, as listed by ``casadi.doc_integrator(plugin)`` (for messages).

    Parameters
    ----------
    plugin : str
        CasADi integrator plugin (``"cvodes"``, ``"idas"``, ``"collocation"``).

    Returns
    -------
    tuple of str
        Sorted option names; CasADi also accepts the generic Function options
        (e.g. ``print_time``, ``verbose``), checked with ``Function.has_option``.
    """
    return tuple(sorted(set(re.findall(r"^\| (\w+)\s+\| OT_", ca.doc_integrator(plugin), re.M))))


def _check_options(req: RunRequest, plugin: str) -> None:
    """ValueError for an option CasADi does not know (before building anything), or one simulate sets itself."""
    probe = _probe(plugin)
    for name in req.options:
        if name in _MANAGED and not req.spec.fixed_step:
            raise ValueError(
                f"method {req.spec.name!r}: option {name!r} is set from simulate's argument {_MANAGED[name]!r}; "
                f"pass {_MANAGED[name]}=... instead"
            )
    unknown = sorted(n for n in req.options if not (isinstance(n, str) and probe.has_option(n)))
    if unknown:
        own = plugin_options(plugin)
        close = sorted({m for n in unknown if isinstance(n, str) for m in difflib.get_close_matches(n, own, n=3)})
        raise ValueError(
            f"method {req.spec.name!r}: unknown option(s) {unknown} for the CasADi {plugin!r} integrator"
            + (f" (did you mean {close}?)" if close else "")
            + f"; expected some of the plugin options {list(own)}, CasADi's generic Function options "
            f"(casadi.doc_integrator({plugin!r})) or the budget options ['max_steps', 'max_wall_time']"
        )


def _options(req: RunRequest) -> dict:
    spec = req.spec
    plugin = spec.settings["plugin"]
    _check_options(req, plugin)
    # Non-finite states are reported as a SimulationError; CasADi's per-step warnings are noise.
    opts: dict[str, Any] = {"show_eval_warnings": False, **spec.settings["options"]}
    if spec.fixed_step:
        # CasADi 3.8 takes one step per output-grid interval and ignores
        # number_of_finite_elements when given a grid: the runner refines the grid.
        opts["number_of_finite_elements"] = 1
        opts.setdefault("interpolation_order", 3)
    else:
        per_interval = req.budget.max_steps if req.budget.explicit_steps else min(_MAX_NUM_STEPS, req.budget.max_steps)
        # SUNDIALS prints its own warnings (e.g. "mxstep steps taken") to stderr: the SimulationError says it all.
        opts.update({"reltol": req.rtol, "abstol": req.atol, "max_num_steps": per_interval})
        if _probe(plugin).has_option(_QUIET):
            opts[_QUIET] = True
        if req.max_step is not None:
            opts["max_step_size"] = req.max_step
    opts.update(req.options)
    return opts


class IntegratorOptionError(ValueError, RuntimeError):
    """CasADi rejected an integrator option (wrong type, unknown nested option).

    A ``ValueError`` (bad input); also a ``RuntimeError``, the type CasADi itself raised before.
    """


def _build(req: RunRequest, kind: str, plugin: str, grid: tuple[float, ...], opts: dict) -> ca.Function:
    """The cached integrator; an option CasADi rejects (e.g. a wrong type) is an error naming the method."""
    try:
        return _integrator(kind, plugin, grid, freeze_options(opts))
    except RuntimeError as exc:
        lines = [_SOURCE.sub("", line).strip() for line in str(exc).splitlines()]
        found = [line for line in lines if re.search(r"Unknown option|Illegal type|option", line)]
        raise IntegratorOptionError(
            f"method {req.spec.name!r}: CasADi rejected the integrator options {dict(req.options)}: "
            f"{found[0] if found else _short(exc)}"
        ) from None


def _interrupted(req: RunRequest, exc: BaseException) -> bool:
    """Ctrl-C inside CasADi: it turns the KeyboardInterrupt into a RuntimeError (CVODES: CV_RHSFUNC_FAIL)."""
    return req.budget.interrupted or "KeyboardInterrupt" in str(exc) or "interrupted" in str(exc).lower()


def _raise_if_interrupted(req: RunRequest) -> None:
    """A call that returned although Ctrl-C arrived inside it: CasADi's collocation rootfinder swallows the
    KeyboardInterrupt and returns its last iterate (seen under load), so the flag is the only trace."""
    if req.budget.interrupted:
        raise KeyboardInterrupt


def run_casadi(req: RunRequest) -> RunResult:
    """Runner of the CasADi family (see the module docstring).

    Parameters
    ----------
    req : RunRequest
        A validated run.

    Returns
    -------
    RunResult
        States, held inputs and CasADi's statistics.

    Raises
    ------
    SimulationError
        The integrator failed or the state became non-finite.
    """
    spec, model, t = req.spec, req.model, req.t
    plugin = spec.settings["plugin"]
    opts = _options(req)
    h = t[1] - t[0]
    n_int = req.n_intervals
    n_sub = max(1, math.ceil(h / (req.max_step or DEFAULT_FIXED_STEP) - 1e-9)) if spec.fixed_step else 1
    stats: dict[str, Any] = {"n_rhs": 0, "n_steps": 0}
    sched = req.schedule
    # A whole-grid CVODES call carries its multistep history across the jumps of a sampled
    # input: it misses the requested accuracy by 10-100x and can fail with repeated error-test
    # failures. Restart it at each output interval instead (IDAS and the fixed-step methods are exact).
    restart = plugin == "cvodes" and sched is not None and not req.constant_input
    # Budgets are checked between calls: with a wall-time budget, or a step budget the user set for an
    # error-controlled method (CVODES' max_num_steps counts per output interval), one call per interval.
    budgeted = req.budget.max_wall_time is not None or (req.budget.explicit_steps and not spec.fixed_step)
    # CasADi's collocation rootfinder swallows a Ctrl-C and carries on: a whole-grid call would run to its end
    # (tens of seconds), so it goes interval by interval and the interrupt flag is checked after each call.
    per_interval = restart or budgeted or plugin == "collocation"
    if sched is not None and not per_interval:
        fine = np.linspace(0.0, t[-1], n_int * n_sub + 1)
        F = _build(req, model.kind, plugin, tuple(fine[1:].tolist()), opts)
        try:
            xf = np.asarray(F(x0=req.x0, u=np.repeat(sched, n_sub, axis=0).T, p=model.p)["xf"]).T
            _raise_if_interrupted(req)
        except RuntimeError as exc:
            if _interrupted(req, exc):
                raise KeyboardInterrupt from None
            # The whole-grid call does not say where it failed: redo the run interval by
            # interval, which either reports the failing interval or completes the run.
            stats["whole_grid_retry"] = True
        else:
            _collect_stats(F, spec, stats, n_int * n_sub)
            return RunResult(np.vstack([req.x0, xf[n_sub - 1 :: n_sub]]), sched, stats)
    return _run_intervals(req, plugin, opts, n_sub, stats)


def _run_intervals(req: RunRequest, plugin: str, opts: dict, n_sub: int, stats: dict) -> RunResult:
    """One integrator call per output interval (feedback, restarts, failure location)."""
    model, t, sched = req.model, req.t, req.schedule
    h = float(t[1] - t[0])
    n_int = req.n_intervals
    grid = tuple(np.linspace(0, h, n_sub + 1)[1:].tolist())
    F = _build(req, model.kind, plugin, grid, opts)
    X = np.empty((len(t), model.nx))
    U = np.empty((n_int, model.nu))
    X[0] = req.x0
    for k in range(n_int):
        U[k] = sched[k] if sched is not None else req.feedback_input(float(t[k]), X[k])
        u_k = np.tile(U[k], (n_sub, 1)).T
        try:
            X[k + 1] = np.asarray(F(x0=X[k], u=u_k, p=model.p)["xf"])[:, -1]
            _raise_if_interrupted(req)
        except RuntimeError as exc:
            if _interrupted(req, exc):
                raise KeyboardInterrupt from None
            t_reached = None
            if _probe(plugin).has_option(_QUIET):
                # Only SUNDIALS names the time it reached; collocation does not accept the option (and says nothing).
                loud, x_k = _loud(model.kind, plugin, grid, opts), X[k].copy()
                t_reached = _time_reached(lambda: loud(x0=x_k, u=u_k, p=model.p))  # noqa: B023 - called at once
            t_abs = float(t[k]) if t_reached is None else float(t[k]) + t_reached
            raise req.fail(t_abs, *_reason(exc, opts, req.model.kind)) from None
        if not np.all(np.isfinite(X[k + 1])):
            raise req.fail(t[k], "the state became non-finite")
        _collect_stats(F, req.spec, stats, n_sub)
        if k + 1 < n_int:
            req.check_budget(float(t[k + 1]), stats["n_steps"])
    return RunResult(X, U, stats)


def _loud(kind: str, plugin: str, grid: tuple[float, ...], opts: dict) -> ca.Function:
    """The same integrator with SUNDIALS' own messages on (they name the time reached); SUNDIALS plugins only."""
    loud = {**opts, _QUIET: False}
    return _integrator(kind, plugin, grid, freeze_options(loud))


def _time_reached(call: Callable[[], Any]) -> float | None:
    """Re-run a failing call with its messages captured; the time SUNDIALS' last message names.

    CasADi's exception does not say where the solver stopped (its stats are not
    updated on failure), SUNDIALS' own message does ("At t = 494.834, mxstep steps
    taken before reaching tout."). The run is deterministic, so the re-run stops at
    the same time. CasADi's Python module writes the message to ``sys.stderr``
    (else C code writes to file descriptor 2): both are captured. Returns None when
    nothing names a time (e.g. collocation).
    """
    buffer = io.StringIO()
    try:
        sys.stderr.flush()
        saved = os.dup(2)
    except (AttributeError, OSError, ValueError):
        saved = None
    with tempfile.TemporaryFile() as tmp:
        previous = sys.stderr
        try:
            if saved is not None:
                os.dup2(tmp.fileno(), 2)
            sys.stderr = buffer
            try:
                call()
            except RuntimeError:
                pass
        finally:
            sys.stderr = previous
            if saved is not None:
                os.dup2(saved, 2)
                os.close(saved)
        tmp.seek(0)
        text = buffer.getvalue() + tmp.read().decode("utf-8", errors="replace")
    times = _AT_T.findall(text)
    return float(times[-1]) if times else None


def _reason(exc: BaseException, opts: dict, kind: str) -> tuple[str, str]:
    """Solver message and hint of a failed interval."""
    hint = failure_hint(kind)
    reason = _short(exc)
    if "TOO_MUCH_WORK" in reason:
        reason += (
            f" ({opts.get('max_num_steps')} steps within one output interval: SUNDIALS' max_num_steps, "
            "set by options={'max_steps': ...})"
        )
        return reason, f"{hint}; or raise options={{'max_steps': ...}} or take a smaller output step dt"
    if "rootfinder" in reason:
        # Collocation: the Newton solve of one fixed step did not converge (the step is too long for the dynamics).
        return reason, "take a smaller collocation step (max_step=...) or an error-controlled implicit method such as 'cvodes'"
    return reason, hint


def _collect_stats(F: ca.Function, spec: MethodSpec, stats: dict, n_steps: int) -> None:
    if spec.fixed_step:
        # Collocation solves a Newton system per step: no plain RHS count.
        stats["n_steps"] += n_steps
        return
    s = F.stats()
    stats["n_steps"] += int(s.get("nsteps", 0))
    stats["n_rhs"] += int(s.get("nfevals", 0))
    stats["n_jac"] = stats.get("n_jac", 0) + int(s.get("n_call_jacF", 0))
    stats["n_error_test_failures"] = stats.get("n_error_test_failures", 0) + int(s.get("netfails", 0))


def _short(exc: BaseException) -> str:
    """The last line of CasADi's message without its source location (``.../cvodes_interface.cpp:403: ``)."""
    text = str(exc).strip().splitlines()
    return _SOURCE.sub("", text[-1]).strip() if text else type(exc).__name__


_SOURCE = re.compile(r"^(?:\S*[/\\])?[\w.]+\.(?:cpp|hpp|c|h):\d+:\s*")


def _spec(name: str, plugin: str, options: Mapping[str, Any], description: str, fixed: bool = False) -> MethodSpec:
    return MethodSpec(name, "casadi", description, run_casadi, fixed, {"plugin": plugin, "options": dict(options)})


_RADAU = "Radau IIA collocation, degree 3 (order 5), fixed step"
_LEGENDRE = "Gauss-Legendre collocation, degree 3 (order 6), fixed step"
_BDF = {"linear_multistep_method": "bdf"}
#: The CasADi methods (``cvodes`` is ``cvodes-bdf``; ``collocation`` is ``collocation-radau``).
METHOD_SPECS: tuple[MethodSpec, ...] = (
    _spec("cvodes", "cvodes", _BDF, "SUNDIALS CVODES, BDF"),
    _spec("cvodes-bdf", "cvodes", _BDF, "SUNDIALS CVODES, BDF"),
    _spec("cvodes-adams", "cvodes", {"linear_multistep_method": "adams"}, "CVODES, Adams-Moulton"),
    _spec("idas", "idas", {}, "SUNDIALS IDAS (BDF, DAE form)"),
    _spec("collocation", "collocation", {"collocation_scheme": "radau"}, _RADAU, True),
    _spec("collocation-radau", "collocation", {"collocation_scheme": "radau"}, _RADAU, True),
    _spec("collocation-legendre", "collocation", {"collocation_scheme": "legendre"}, _LEGENDRE, True),
)
