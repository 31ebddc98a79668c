"""The methods of the work-precision study: the integrate registry's methods plus the FMU's solvers.

A :class:`BenchMethod` is a name, the kind of sweep (tolerance or fixed
step), its settings and a runner ``run(model, x0, t_final, dt, setting) ->
Trajectory`` on the output grid ``time_grid(t_final, dt)``. The native ones
are looked up in :data:`pendulab.integrate.METHODS` (one registry: a new
integration method joins the study by its name in :data:`NATIVE`); the FMU's
embedded solvers come from :mod:`.fmu_methods`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ..integrate import METHODS, simulate
from ..integrate.trajectory import Trajectory
from ..model.model import Model

__all__ = ["BenchMethod", "Runner", "NATIVE", "TOLS", "TOLS_QUICK", "native_bench_methods"]

Runner = Callable[[Model, np.ndarray, float, float, float], Trajectory]

#: Tolerance sweeps (rtol = atol), loosest first.
TOLS = (1e-3, 1e-5, 1e-7, 1e-9, 1e-11)
TOLS_QUICK = (1e-4, 1e-7)
_STEPS = (5e-2, 2e-2, 1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4)
_STEPS_QUICK = (1e-2, 2e-3)
#: Native methods in the study (legend order); the step sweep of collocation stops at 2 ms because
#: CasADi builds one integrator over the whole refined grid (keep it below ~5000 points).
NATIVE: tuple[str, ...] = (
    "taylor",
    "compiled-dopri5",
    "compiled-rodas4",
    "cvodes-bdf",
    "cvodes-adams",
    "idas",
    "RK45",
    "DOP853",
    "Radau",
    "BDF",
    "LSODA",
    "collocation-radau",
    "collocation-legendre",
    "rk4",
    "gauss4",
    "radau3",
)
_SHORT_STEP_SWEEP = ("collocation-radau", "collocation-legendre")


def _adaptive(method: str) -> Runner:
    def run(model: Model, x0: np.ndarray, t_final: float, dt: float, tol: float) -> Trajectory:
        return simulate(model, x0, t_final, dt, method, rtol=tol, atol=tol)

    return run


def _fixed(method: str) -> Runner:
    def run(model: Model, x0: np.ndarray, t_final: float, dt: float, h: float) -> Trajectory:
        return simulate(model, x0, t_final, dt, method, max_step=h)

    return run


@dataclass(frozen=True)
class BenchMethod:
    """One method of the benchmark.

    Attributes
    ----------
    name : str
        Label in tables and charts.
    sweep : {"tol", "step"}
        What the settings are: rtol = atol, or the fixed step h [s].
    settings, quick : tuple of float
        Full and quick sweeps, loosest first.
    run : callable
        ``run(model, x0, t_final, dt, setting) -> Trajectory`` on the output
        grid ``time_grid(t_final, dt)``; raise ``SimulationError`` on failure.
    family : str
        Grouping for colours: "casadi", "scipy", "fixed", "fmu", ...
    """

    name: str
    sweep: str
    settings: tuple[float, ...]
    quick: tuple[float, ...]
    run: Runner = field(repr=False)
    family: str = ""

    def __post_init__(self) -> None:
        if self.sweep not in ("tol", "step"):
            raise ValueError(f"sweep must be 'tol' or 'step', got {self.sweep!r}")
        if not self.settings or not self.quick:
            raise ValueError(f"method {self.name!r}: settings and quick settings must be non-empty")


def native_bench_methods(names: tuple[str, ...] = NATIVE) -> dict[str, BenchMethod]:
    """Benchmark entries of registered integration methods.

    Parameters
    ----------
    names : tuple of str
        Keys of :data:`pendulab.integrate.METHODS`.

    Returns
    -------
    dict of str to BenchMethod
        In the order given; fixed-step methods sweep the step, the others the tolerance.
    """
    out: dict[str, BenchMethod] = {}
    for name in names:
        spec = METHODS[name]
        if spec.fixed_step:
            steps = _STEPS[:5] if name in _SHORT_STEP_SWEEP else _STEPS
            out[name] = BenchMethod(name, "step", steps, _STEPS_QUICK, _fixed(name), spec.family)
        else:
            out[name] = BenchMethod(name, "tol", TOLS, TOLS_QUICK, _adaptive(name), spec.family)
    return out
