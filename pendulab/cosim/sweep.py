"""Communication-step study: where does a fixed LQR balance loop lose stability when sampled ever more slowly?

The classical sampled-data question: one continuous-time LQR gain ``K``
(designed once, for the upright equilibrium) is applied through a zero-order
hold whose period is the communication step ``h``. The linear prediction is
the spectral radius of ``Ad(h) - Bd(h) K`` with the exact ZOH discretization of
the upright linearization: the loop is predicted stable while it is < 1.

The co-simulation measures the same thing: from a small perturbation of the
upright state, the per-step contraction factor of the angular error (a log-linear
fit over the run) estimates the dominant closed-loop eigenvalue modulus; from a
large perturbation, whether the loop recovers at all (nonlinear stability).

Runs go through an FMU (:func:`pendulab.cosim.cosim`) or natively
(:func:`pendulab.simulate` with the same controller); the study code is the same.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from scipy.optimize import brentq

from .._checks import is_interrupt
from ..control.feedback import (
    LinearStateFeedback,
    as_feedback,
    balance_controller,
    closed_loop_spectral_radius,
    upright_state,
)
from ..control.lqr import wrap_state_error
from ..integrate.trajectory import Trajectory
from ..model.model import Model

__all__ = [
    "SweepPoint",
    "SweepResult",
    "comm_step_sweep",
    "predicted_critical_step",
    "contraction_factor",
    "native_runner",
    "fmu_runner",
    "plot_sweep",
]

#: Runs a closed loop: (controller, comm_step, x0, t_final) -> Trajectory.
LoopRunner = Callable[[LinearStateFeedback, float, np.ndarray, float], Trajectory]

_DIVERGED = 1.5  # angle error [rad] beyond which a run counts as lost (far outside the balance region)


@dataclass(frozen=True)
class SweepPoint:
    """One communication step of the sweep.

    Attributes
    ----------
    h : float
        Communication (= sample) step [s].
    rho_pred : float
        Spectral radius of the ZOH-discretized linear closed loop.
    rho_meas : float
        Measured per-step contraction of the angular error from the small perturbation (nan if not measurable).
    stable_small, stable_large : bool
        The run from the small / large perturbation ended with a smaller angular error than it started with.
    err_small, err_large : float
        Final norm of the angular-state error (inf once an angle strays 1.5 rad).
    """

    h: float
    rho_pred: float
    rho_meas: float
    stable_small: bool
    stable_large: bool
    err_small: float
    err_large: float


@dataclass(frozen=True)
class SweepResult:
    """Sweep for one plant kind.

    Attributes
    ----------
    kind : str
        "rigid" or "elastic".
    points : tuple of SweepPoint
        One per communication step, increasing.
    h_crit_pred : float
        Predicted critical step [s] (:func:`predicted_critical_step`); nan if none.
    h_crit_meas : float
        Step [s] where the measured contraction crosses 1 (linear
        interpolation); nan if it never does.
    h_crit_large : float
        Step [s] from which the large perturbation is lost (refined by
        bisection); nan if it always recovers.
    small, large : float
        Perturbation amplitudes [rad].
    runner : str
        Label of the loop runner (e.g. native or FMU).
    K : ndarray, shape (m, nx)
        The fixed continuous LQR gain [N.m per state unit].
    curve : (ndarray, ndarray)
        Predicted spectral radius on a fine grid: steps [s] and radii, shape (300,) each.
    """

    kind: str
    points: tuple[SweepPoint, ...]
    h_crit_pred: float
    h_crit_meas: float
    h_crit_large: float
    small: float
    large: float
    runner: str
    K: np.ndarray = field(repr=False)
    curve: tuple[np.ndarray, np.ndarray] = field(repr=False, default=(np.empty(0), np.empty(0)))

    def table(self) -> str:
        """Markdown table of the sweep.

        Returns
        -------
        str
            One row per point: h [s], predicted and measured rho, final
            angular errors [rad] of both runs (``diverged`` / ``(unstable)``
            where lost).
        """
        rows = [
            "| h [s] | rho predicted | rho measured | small: final err [rad] | large: final err [rad] |",
            "|---:|---:|---:|---:|---:|",
        ]
        for p in self.points:
            rows.append(
                f"| {p.h:.4g} | {p.rho_pred:.4f} | {p.rho_meas:.4f} | {_fmt_err(p.err_small, p.stable_small)} "
                f"| {_fmt_err(p.err_large, p.stable_large)} |"
            )
        return "\n".join(rows)


def _fmt_err(err: float, stable: bool) -> str:
    text = "diverged" if not math.isfinite(err) else f"{err:.2e}"
    return text + ("" if stable else " (unstable)")


def predicted_critical_step(model: Model, K: np.ndarray, input_names: Sequence[str], h_max: float = 1.0) -> float:
    """Smallest ``h`` at which the linear sampled closed loop's spectral radius reaches 1.

    Scans 200 steps up to ``h_max`` and refines the first crossing with Brent's method.

    Parameters
    ----------
    model : Model
        Rigid or elastic pendulum (upright linearization).
    K : ndarray, shape (m, nx)
        Continuous gain applied with a zero-order hold [N.m per state unit].
    input_names : sequence of str
        The m torques the rows of ``K`` drive.
    h_max : float
        Largest step searched [s].

    Returns
    -------
    float
        Critical step [s]; ``h_max / 200`` if already unstable there; nan if
        the loop stays stable up to ``h_max``.
    """
    hs = np.linspace(h_max / 200, h_max, 200)
    rho = np.array([closed_loop_spectral_radius(model, K, h, input_names) for h in hs])
    above = np.nonzero(rho >= 1.0)[0]
    if len(above) == 0:
        return math.nan
    i = int(above[0])
    if i == 0:
        return float(hs[0])
    return float(brentq(lambda h: closed_loop_spectral_radius(model, K, h, input_names) - 1.0, hs[i - 1], hs[i], xtol=1e-10))


def _angular_error(model: Model, traj: Trajectory, x_eq: np.ndarray) -> np.ndarray:
    sel = np.array([n.startswith(("theta", "omega")) for n in model.state_names])
    e = wrap_state_error(traj.x - x_eq, model.state_names)[:, sel]
    return np.linalg.norm(e, axis=1)


def contraction_factor(err: np.ndarray, floor: float = 1e-7, ceiling: float = 0.1) -> float:
    """Per-step contraction of an error sequence: ``exp(slope)`` of a least-squares fit of ``log err``.

    Only samples between ``floor`` (above solver noise) and ``ceiling`` (linear
    regime) count, and of those the last two thirds (the dominant mode has
    taken over).

    Parameters
    ----------
    err : array_like, shape (n,)
        Error norms, one per step.
    floor : float
        Smallest error used.
    ceiling : float
        Largest error used.

    Returns
    -------
    float
        Estimated per-step factor (< 1: contracting); nan if fewer than 8
        samples remain.
    """
    err = np.asarray(err, dtype=float)
    idx = np.nonzero(np.isfinite(err) & (err > floor) & (err < ceiling))[0]
    idx = idx[len(idx) // 3 :]
    if len(idx) < 8:
        return math.nan
    slope = np.polyfit(idx, np.log(err[idx]), 1)[0]
    return float(np.exp(slope))


def _run_point(model, ctrl, run, h, amplitude, n_min, t_min):
    x_eq = upright_state(model)
    x0 = x_eq.copy()
    x0[0] += amplitude
    x0[1] -= amplitude
    n = max(n_min, math.ceil(t_min / h))
    try:
        traj = run(ctrl, h, x0, n * h)
    except (RuntimeError, ValueError) as exc:
        if is_interrupt(exc):  # a Ctrl-C that CasADi or the FMU layer turned into an error: no failed point
            raise KeyboardInterrupt from exc
        return np.array([np.linalg.norm([amplitude, amplitude]), math.inf])
    err = _angular_error(model, traj, x_eq)
    angles = np.abs(wrap_state_error(traj.x - x_eq, model.state_names)[:, :2]).max(axis=1)
    bad = ~np.isfinite(err) | (angles > _DIVERGED)
    if bad.any():
        err = err.copy()
        err[int(np.argmax(bad)) :] = math.inf
    return err


def comm_step_sweep(
    model: Model,
    steps: Sequence[float],
    run: LoopRunner,
    *,
    small: float = 1e-3,
    large: float = 0.15,
    n_min: int = 150,
    t_min: float = 6.0,
    runner_name: str = "",
    refine: int = 4,
    progress: Callable[[str], None] | None = None,
) -> SweepResult:
    """Sweep the communication step for the fixed continuous LQR balance gain.

    Parameters
    ----------
    model : Model
        Design model (its upright linearization gives ``K`` and the prediction);
        must match the plant behind ``run``.
    steps : sequence of float
        Communication steps [s] to try, increasing.
    run : callable
        ``run(controller, h, x0, t_final) -> Trajectory``: one closed-loop run
        with comm step = sample time ``h`` (an FMU or the native loop).
    small, large : float
        Perturbation [rad] of the upright state: theta1 + a, theta2 - a.
    n_min, t_min : int, float
        Each run lasts at least ``n_min`` steps and ``t_min`` seconds.
    runner_name : str
        Label for reports.
    refine : int
        Bisection steps on the large-perturbation stability boundary.
    progress : callable, optional
        Called with a one-line message per step (the CLI prints it).

    Returns
    -------
    SweepResult
        Per-step predictions and measurements and the three critical steps.

    Raises
    ------
    ValueError
        ``steps`` is empty or not all positive.
    """
    steps = sorted(float(h) for h in steps)
    if not steps or steps[0] <= 0:
        raise ValueError(f"steps must be positive communication steps [s], got {steps!r}")
    design = balance_controller(model, steps[0], design="continuous")
    points = []
    for i, h in enumerate(steps):
        ctrl = LinearStateFeedback(model, design.K, design.x_eq, design.u_eq, h, design.input_names, P=design.P)
        rho_pred = closed_loop_spectral_radius(model, design.K, h, design.input_names)
        e_small = _run_point(model, ctrl, run, h, small, n_min, t_min)
        e_large = _run_point(model, ctrl, run, h, large, n_min, t_min)
        point = SweepPoint(
            h=h,
            rho_pred=rho_pred,
            rho_meas=contraction_factor(e_small),
            stable_small=bool(e_small[-1] < e_small[0]),
            stable_large=bool(e_large[-1] < e_large[0]),
            err_small=float(e_small[-1]),
            err_large=float(e_large[-1]),
        )
        points.append(point)
        if progress is not None:
            progress(
                f"[{i + 1}/{len(steps)}] {model.kind} h = {h:.4g} s: rho predicted {rho_pred:.4f}, measured "
                f"{point.rho_meas:.4f}; large perturbation {'recovers' if point.stable_large else 'lost'}"
            )
    h_large = _first_unstable([p.h for p in points], [p.stable_large for p in points])
    lo = max((p.h for p in points if p.h < h_large), default=math.nan)
    for _ in range(refine if math.isfinite(h_large) and math.isfinite(lo) else 0):
        # Bisect the nonlinear boundary from the large perturbation between the last recovering and first lost step.
        mid = 0.5 * (lo + h_large)
        ctrl = LinearStateFeedback(model, design.K, design.x_eq, design.u_eq, mid, design.input_names, P=design.P)
        e = _run_point(model, ctrl, run, mid, large, n_min, t_min)
        lo, h_large = (mid, h_large) if e[-1] < e[0] else (lo, mid)
        if progress is not None:
            progress(f"  {model.kind} bisecting the large-perturbation boundary: ({lo:.4g}, {h_large:.4g}) s")
    fine = np.linspace(steps[0], steps[-1], 300)
    return SweepResult(
        kind=model.kind,
        points=tuple(points),
        h_crit_pred=predicted_critical_step(model, design.K, design.input_names, h_max=2 * steps[-1]),
        h_crit_meas=_crossing([p.h for p in points], [p.rho_meas for p in points]),
        h_crit_large=0.5 * (lo + h_large) if math.isfinite(lo) else h_large,
        small=small,
        large=large,
        runner=runner_name,
        K=design.K,
        curve=(fine, np.array([closed_loop_spectral_radius(model, design.K, hf, design.input_names) for hf in fine])),
    )


def _crossing(h: Sequence[float], rho: Sequence[float]) -> float:
    """First h where rho crosses 1, linearly interpolated (nan if it never does)."""
    for i in range(1, len(h)):
        if np.isfinite(rho[i]) and rho[i] >= 1.0 and np.isfinite(rho[i - 1]) and rho[i - 1] < 1.0:
            return float(h[i - 1] + (1.0 - rho[i - 1]) * (h[i] - h[i - 1]) / (rho[i] - rho[i - 1]))
    return math.nan


def _first_unstable(h: Sequence[float], stable: Sequence[bool]) -> float:
    for hi, s in zip(h, stable, strict=True):
        if not s:
            return float(hi)
    return math.nan


def native_runner(model: Model, method: str = "cvodes", rtol: float = 1e-10, atol: float = 1e-10) -> LoopRunner:
    """The native sampled loop: ``simulate(model, x0, t_final, dt=h, u=controller)``.

    Parameters
    ----------
    model : Model
        The plant.
    method : str
        Integration method (see :func:`pendulab.simulate`).
    rtol, atol : float
        Integrator tolerances.

    Returns
    -------
    callable
        ``run(controller, h, x0, t_final) -> Trajectory``, a ``LoopRunner``.
    """
    from ..integrate import simulate

    def run(ctrl: LinearStateFeedback, h: float, x0: np.ndarray, t_final: float) -> Trajectory:
        return simulate(model, x0, t_final, dt=h, method=method, rtol=rtol, atol=atol, u=as_feedback(ctrl, model))

    return run


def fmu_runner(fmu_path: str | Path, *, tolerance: float | None = 1e-10, solver: Any = None, params: Any = None) -> LoopRunner:
    """The co-simulation loop through an FMU: :func:`pendulab.cosim.cosim`.

    Parameters
    ----------
    fmu_path : str or Path
        A pendulab Co-Simulation FMU.
    tolerance : float or None
        Relative tolerance of the embedded solver.
    solver : str or int, optional
        Embedded solver (the FMU's ``solver`` parameter).
    params : mapping, optional
        FMU parameters by name.

    Returns
    -------
    callable
        ``run(controller, h, x0, t_final) -> Trajectory``, a ``LoopRunner``
        (one ``cosim`` call with communication step ``h``).
    """
    from .master import cosim

    def run(ctrl: LinearStateFeedback, h: float, x0: np.ndarray, t_final: float) -> Trajectory:
        return cosim(fmu_path, ctrl, h, t_final, x0=x0, tolerance=tolerance, solver=solver, params=params)

    return run


def plot_sweep(results: Sequence[SweepResult], path: str | Path) -> Path:
    """Spectral radius (predicted line, measured markers) vs communication step, one panel per plant kind.

    Parameters
    ----------
    results : sequence of SweepResult
        One panel each.
    path : str or Path
        Image file to write (parent directories are created).

    Returns
    -------
    Path
        The written file.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(results), figsize=(6.2 * len(results), 4.6), squeeze=False)
    for ax, res in zip(axes[0], results, strict=True):
        h = np.array([p.h for p in res.points])
        ax.plot(*res.curve, "-", color="C0", lw=2, label="predicted: linear ZOH closed loop")
        meas = np.array([p.rho_meas for p in res.points])
        ax.plot(h, meas, "o", color="C1", ms=5, label=f"measured ({res.runner}), {res.small:g} rad start")
        if math.isfinite(res.h_crit_large):
            ax.axvspan(res.h_crit_large, h[-1], color="C3", alpha=0.12, label=f"lost from {res.large:g} rad start")
        ax.axhline(1.0, color="k", lw=0.8, ls="--")
        if math.isfinite(res.h_crit_pred):
            ax.axvline(res.h_crit_pred, color="C0", lw=0.8, ls=":")
            ax.annotate(
                f"predicted h* = {res.h_crit_pred * 1e3:.1f} ms",
                (res.h_crit_pred, 1.2),
                rotation=90,
                xytext=(-12, 0),
                textcoords="offset points",
                fontsize=8,
                color="C0",
            )
        ax.set_ylim(0.5, max(1.5, float(np.nanmax(res.curve[1])) * 1.05))
        ax.set_xlabel("communication step h = sample time [s]")
        ax.set_ylabel("spectral radius / per-step contraction [-]")
        ax.set_title(f"{res.kind}: fixed continuous LQR gain under ZOH")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    from ..viz.save import save_figure

    return save_figure(fig, path, dpi=120)
