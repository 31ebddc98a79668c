"""Stability where methods fail: the elastic pendulum's spring mode against the step.

Four studies (``pendulab bench stability``):

1. **Map** over spring stiffness k and fixed step h for the fixed-step methods
   of :mod:`pendulab.integrate.fixed_step`, from theta = 0.3 rad with the springs
   at rest length (the spring mode is excited), over 1 s: *unstable* (state
   non-finite or the energy above the static equilibrium grew tenfold),
   *stable but inaccurate* (bob positions off by more than ``POSITION_TOL``
   against a CVODES Adams 1e-10 solution at t = 0.1, 0.2, ..., 1 s) or *stable and
   accurate*. Overlaid: the explicit methods' theoretical limit
   h = c / w_max(k), with w_max the largest |Im| eigenvalue of
   ``jac_rhs`` at the static equilibrium and c the imaginary-axis stability
   bound (2 sqrt(2) for RK4).
2. **RK4 blow-up step**, measured by bisection on h (blown up = the
   deviation from rest grew 1000-fold in 2000 steps from a tiny
   perturbation) against the prediction 2 sqrt(2) / w_max.
3. **Step counts** of adaptive explicit methods (RK45, DOP853) against k,
   proportional to sqrt(k) once stability bounds the step, and of L-stable
   implicit ones (SciPy Radau, CVODES BDF) that step over the spring mode
   after a quasi-static start (and must resolve it after a rest-length start).
4. **Energy** on undamped springs (k = 1e4, rest-length start, 10 s) with a
   step that does not resolve the spring mode: Gauss-Legendre collocation
   and implicit midpoint (symplectic) keep it, Radau collocation and
   CVODES BDF dissipate the spring oscillation.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp

from .._checks import is_interrupt
from ..integrate import simulate
from ..integrate.fixed_step import FIXED_METHODS, IMAG_AXIS_LIMIT, integrate_fixed
from ..model.model import Model, elastic
from ..model.quasistatic import quasi_static_state
from .journal import Journal
from .stability_report import write_stability
from .stability_result import _HORIZON, ACCURATE, FAILED, INACCURATE, POSITION_TOL, UNSTABLE, StabilityResult
from .workprecision import watch_interrupt

__all__ = [
    "omega_max",
    "rk4_blowup_step",
    "classify",
    "run_stability",
    "write_stability",
    "StabilityResult",
    "POSITION_TOL",
    "UNSTABLE",
    "INACCURATE",
    "ACCURATE",
    "FAILED",
]

_THETA = (0.3, 0.3)
Progress = Callable[[int, int, str], None]


def omega_max(model: Model) -> float:
    """Fastest linearized mode: max |Im(eig(A))| of ``jac_rhs`` at the static equilibrium.

    Parameters
    ----------
    model : Model
        Linearized at ``model.rest_state()`` with zero torque.

    Returns
    -------
    float
        Largest oscillation frequency [rad/s].
    """
    x = model.rest_state()
    A = np.asarray(model.functions["jac_rhs"](x, np.zeros(model.nu), model.p)[0])
    return float(np.max(np.abs(np.linalg.eigvals(A).imag)))


def _blows_up(model: Model, method: str, h: float, n_steps: int) -> bool:
    x_rest = model.rest_state()
    # Tiny perturbation of every mode: stays linear, so the linear stability bound applies.
    dx0 = np.array([1e-3, -1e-3, 1e-7, -1e-7, 0, 0, 0, 0])
    X = integrate_fixed(model, method, x_rest + dx0, h, n_steps, record_every=n_steps // 10)
    dev = np.max(np.abs(X - x_rest), axis=1)
    return bool(not np.all(np.isfinite(X)) or dev[-1] > 1e3 * dev[0])


def rk4_blowup_step(k: float, *, n_steps: int = 2000, rel_tol: float = 2e-3) -> tuple[float, float]:
    """Measured and predicted RK4 blow-up step for springs of stiffness k.

    Bisects h in [0.7, 1.5] times the prediction; a step blows up when the
    deviation from rest of a tiny perturbation grows 1000-fold (or goes
    non-finite) in ``n_steps`` steps.

    Parameters
    ----------
    k : float
        Stiffness of both springs, k1 = k2 [N/m] (other parameters default).
    n_steps : int
        RK4 steps per trial.
    rel_tol : float
        Bisection stops when the bracket is narrower than ``rel_tol`` times
        the predicted step.

    Returns
    -------
    h_measured, h_predicted : float
        Bisection bracket midpoint of the smallest step that blows up, and
        ``2 sqrt(2) / omega_max``, both [s].

    Raises
    ------
    RuntimeError
        The blow-up step is not inside the initial bracket.
    """
    model = elastic(k1=k, k2=k)
    h_pred = IMAG_AXIS_LIMIT["rk4"] / omega_max(model)
    lo, hi = 0.7 * h_pred, 1.5 * h_pred
    if _blows_up(model, "rk4", lo, n_steps) or not _blows_up(model, "rk4", hi, n_steps):
        raise RuntimeError(f"RK4 blow-up step for k = {k:g} N/m is outside [{lo:.3g}, {hi:.3g}] s")
    while hi - lo > rel_tol * h_pred:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if _blows_up(model, "rk4", mid, n_steps) else (mid, hi)
    return 0.5 * (lo + hi), h_pred


def _start(model: Model, start: str) -> np.ndarray:
    if start == "quasi-static":
        return quasi_static_state(model, _THETA)
    return model.state(theta1=_THETA[0], theta2=_THETA[1], r1=model.params.L1, r2=model.params.L2)


def classify(model: Model, method: str, n_steps: int, ref_positions: np.ndarray) -> tuple[int, float]:
    """Class and position error of one map cell.

    The run starts at theta1 = theta2 = 0.3 rad with the springs at rest
    length and lasts 1 s. Unstable: a non-finite state, |x| > 1e6, or the
    energy above the static equilibrium grew tenfold.

    Parameters
    ----------
    model : Model
        Elastic pendulum (the stiffness of the cell).
    method : str
        Fixed-step method (a key of ``FIXED_METHODS``).
    n_steps : int
        Steps over the 1 s horizon (h = 1 / n_steps [s]); a multiple of 10.
    ref_positions : ndarray, shape (11, 4)
        Reference bob positions (x1, y1, x2, y2) [m] at t = 0, 0.1, ..., 1 s.

    Returns
    -------
    cls : int
        ``UNSTABLE``, ``INACCURATE`` or ``ACCURATE``.
    error : float
        Max abs bob-position error [m] (inf when unstable).
    """
    x0 = _start(model, "rest-length")
    X = integrate_fixed(model, method, x0, _HORIZON / n_steps, n_steps, record_every=n_steps // 10)
    if not np.all(np.isfinite(X)) or np.max(np.abs(X)) > 1e6:
        return UNSTABLE, math.inf
    e_rest = model.energy(model.rest_state())
    excess = model.energy(X) - e_rest
    if np.max(excess) > 10.0 * excess[0]:
        return UNSTABLE, math.inf
    err = float(np.max(np.abs(model.positions(X) - ref_positions)))
    return (ACCURATE if err <= POSITION_TOL else INACCURATE), err


def _step_count(model: Model, method: str, x0: np.ndarray, tol: float) -> int:
    """Accepted steps over the 1 s horizon."""
    if method.startswith("cvodes"):
        return int(simulate(model, x0, _HORIZON, _HORIZON, method, tol, tol).stats["n_steps"])
    from ..integrate.scipy_methods import python_rhs

    rhs, p = python_rhs("elastic"), model.p.tolist()
    jac_fun = model.functions["jac_rhs"]
    kw: dict[str, Any] = {}
    if method in ("Radau", "BDF"):
        kw["jac"] = lambda _t, x: np.asarray(jac_fun(x, np.zeros(2), model.p)[0])
    sol = solve_ivp(lambda _t, x: rhs(x, [0.0, 0.0], p), (0.0, _HORIZON), x0, method=method, rtol=tol, atol=tol, **kw)
    if sol.status != 0:
        raise RuntimeError(f"{method} failed for k = {model.params.k1:g}: {sol.message}")
    return len(sol.t) - 1


def run_stability(
    *, quick: bool = False, progress: Progress | None = None, journal: str | Path | None = None, resume: bool = False
) -> StabilityResult:
    """Run the four stability studies (3-9 min on 2 cores; ``quick``: a few seconds).

    Each finished unit (a map cell, a blow-up bisection, a step count, an
    energy run) is recorded in ``journal`` (rewritten atomically), so an
    interrupted or crashed run keeps it and ``resume=True`` continues. A unit
    that raises (any ``Exception``) is recorded as failed with its reason
    (``StabilityResult.failures``; a failed map cell has class ``FAILED``)
    and the study goes on.

    Parameters
    ----------
    quick : bool
        Fewer stiffnesses, steps and methods, and a 2 s energy run.
    progress : callable(int, int, str), optional
        Called as ``progress(done, total, label)`` after each unit of work (resumed units count as done).
    journal : str or Path, optional
        JSON file recording every finished unit (see :class:`~pendulab.bench.journal.Journal`).
    resume : bool
        Skip the units already recorded in ``journal`` (written with the same ``quick``).

    Returns
    -------
    StabilityResult
        The map, the RK4 blow-up steps, the step counts and the energy study.

    Raises
    ------
    ValueError
        A journal to resume that was written with another ``quick``.
    """
    ks = np.array([1e2, 1e6]) if quick else np.logspace(2, 6, 9)
    n_steps = np.array([20, 200, 2000]) if quick else np.array([10, 20, 50, 100, 200, 500, 1000, 2000, 5000, 10000])
    methods = ["forward-euler", "rk4", "implicit-midpoint"] if quick else list(FIXED_METHODS)
    blow_ks = [1e6] if quick else [1e4, 1e5, 1e6]
    sc_ks = [1e2, 1e4] if quick else [1e2, 1e3, 1e4, 1e5, 1e6]
    sc_methods = ["RK45", "Radau"] if quick else ["RK45", "DOP853", "Radau", "cvodes-bdf"]
    total = len(ks) * len(methods) * len(n_steps) + len(blow_ks) + len(sc_ks) * len(sc_methods) * 2 + len(_ENERGY_RUNS)
    log = Journal(journal, "stability", {"quick": quick}, resume=resume)
    done = 0

    with watch_interrupt() as interrupted:

        def unit(key: str, compute: Callable[[], Any]) -> Any:
            """The recorded value of ``key``, else ``compute()`` recorded (or ``{"failed": reason}``)."""
            nonlocal done
            if key in log:
                value = log.get(key)
            else:
                try:
                    value = compute()
                except Exception as exc:
                    if is_interrupt(exc):
                        raise KeyboardInterrupt from exc
                    value = {"failed": f"{type(exc).__name__}: {(str(exc).strip().splitlines() or [''])[0][:300]}"}
                # A native solver (CVODES) may have swallowed a Ctrl-C and carried on: stop anyway (unrecorded).
                if interrupted():
                    raise KeyboardInterrupt
                log.record(key, value)
            done += 1
            if progress is not None:
                progress(done, total, key)
            return value

        return _run_studies(ks, n_steps, methods, blow_ks, sc_ks, sc_methods, quick, unit)


def _failed(value: Any) -> str | None:
    return value.get("failed") if isinstance(value, dict) else None


def _run_studies(
    ks: np.ndarray,
    n_steps: np.ndarray,
    methods: list[str],
    blow_ks: list[float],
    sc_ks: list[float],
    sc_methods: list[str],
    quick: bool,
    unit: Callable[[str, Callable[[], Any]], Any],
) -> StabilityResult:
    res = StabilityResult(ks=ks, n_steps=n_steps, omega_max=np.array([omega_max(elastic(k1=k, k2=k)) for k in ks]))
    for m in methods:
        res.maps[m] = np.zeros((len(ks), len(n_steps)), dtype=int)
        res.errors[m] = np.zeros((len(ks), len(n_steps)))
    for i, k in enumerate(ks):
        model = elastic(k1=k, k2=k)
        ref_pos: list[np.ndarray] = []  # computed on the first cell of this k that is not recorded

        def cell(m: str, n: int, model: Model = model, ref_pos: list = ref_pos) -> list[float]:
            if not ref_pos:
                ref = simulate(model, _start(model, "rest-length"), _HORIZON, 0.1, "cvodes-adams", 1e-10, 1e-10)
                ref_pos.append(model.positions(ref.x))
            cls, err = classify(model, m, n, ref_pos[0])
            return [cls, err]

        for m in methods:
            for j, n in enumerate(n_steps):
                key = f"map|{m}|k={float(k)!r}|n={int(n)}"
                value = unit(key, lambda m=m, n=int(n): cell(m, n))
                if _failed(value):
                    res.failures.append({"unit": key, "reason": _failed(value)})
                    value = [FAILED, math.nan]
                res.maps[m][i, j], res.errors[m][i, j] = int(value[0]), float(value[1])
    for k in blow_ks:
        key = f"rk4-blowup|k={k!r}"
        value = unit(key, lambda k=k: list(rk4_blowup_step(k)))
        if _failed(value):
            res.failures.append({"unit": key, "reason": _failed(value)})
        else:
            res.blowup.append((k, float(value[0]), float(value[1])))
    for k in sc_ks:
        model = elastic(k1=k, k2=k)
        for start in ("quasi-static", "rest-length"):
            for m in sc_methods:
                key = f"steps|{m}|k={k!r}|{start}"
                value = unit(key, lambda model=model, start=start, m=m: _step_count(model, m, _start(model, start), 1e-6))
                if _failed(value):
                    res.failures.append({"unit": key, "reason": _failed(value)})
                else:
                    res.step_counts.append({"k": k, "start": start, "method": m, "steps": int(value)})
    for label in _ENERGY_RUNS:
        key = f"energy|{label}"
        value = unit(key, lambda label=label: _energy_run(label, quick))
        if _failed(value):
            res.failures.append({"unit": key, "reason": _failed(value)})
        else:
            res.energy[label] = (np.asarray(value[0], dtype=float), np.asarray(value[1], dtype=float))
    return res


_ENERGY_H = 0.02  # h * omega_max = 3.2 at k = 1e4: the spring mode is not resolved
#: The energy study's runs: label -> simulate keywords.
_ENERGY_RUNS: dict[str, dict[str, Any]] = {
    "Gauss-Legendre collocation (h = 0.02 s)": dict(method="collocation-legendre", max_step=_ENERGY_H),
    "implicit midpoint (h = 0.02 s)": dict(method="implicit-midpoint", max_step=_ENERGY_H),
    "Radau IIA collocation (h = 0.02 s)": dict(method="collocation-radau", max_step=_ENERGY_H),
    "CVODES BDF (rtol = 1e-4)": dict(method="cvodes-bdf", rtol=1e-4, atol=1e-6),
}


def _energy_run(label: str, quick: bool) -> list[list[float]]:
    """One run of the energy study: [t [s], E(t) - E(0) [J]] (undamped springs, k = 1e4, rest-length start)."""
    model = elastic(k1=1e4, k2=1e4)
    x0 = _start(model, "rest-length")
    tr = simulate(model, x0, 2.0 if quick else 10.0, _ENERGY_H, **_ENERGY_RUNS[label])
    E = model.energy(tr.x)
    return [tr.t.tolist(), (E - E[0]).tolist()]
