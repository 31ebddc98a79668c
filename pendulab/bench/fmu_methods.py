"""The FMU's embedded co-simulation solvers as work-precision methods.

``fmu-dopri5`` (``solver = 0``, explicit Dormand-Prince 5(4)) and
``fmu-rodas4`` (``solver = 1``, L-stable Rosenbrock 4(3) with the exact
Jacobian) are run through fmpy's ``simulate_fmu`` as a Co-Simulation FMU
(FMI 2) over a tolerance sweep (the FMU uses rtol = atol = tolerance, like the
native adaptive methods).

* One FMU per model kind is exported on first use and cached, unpacked, in a
  temporary directory that lives as long as the process (the export is a C
  compilation of a few seconds: it falls into the benchmark's untimed warm-up
  run). The case's parameters and initial state are start values, so the same
  FMU serves every stiffness.
* **Communication step = output interval = the case's output step dt**, i.e.
  one ``doStep`` per output point. The embedded solver integrates exactly to
  each communication point and keeps its step-size guess across steps, so this
  costs one forced step end per output point (at most 200 here, against the
  hundreds to tens of thousands of internal steps), and it is how a master
  samples the FMU's outputs on a grid. A single ``doStep`` over the horizon
  would be cheaper but would only give the final state, not the grid error.
* The timed run is the whole ``simulate_fmu`` call on the unpacked FMU
  (instantiate, set start values, initialize, the stepping loop, terminate,
  free), just as the native methods are timed over the whole ``simulate``
  call with their compiled functions cached.
"""

from __future__ import annotations

import atexit
import math
import shutil
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ..integrate import SimulationError, time_grid
from ..integrate.trajectory import Trajectory
from ..model.model import Model
from .methods import BenchMethod

__all__ = ["FMU_SOLVERS", "fmu_bench_runner", "fmu_bench_methods"]

#: Method name -> value of the FMU's ``solver`` parameter.
FMU_SOLVERS: dict[str, int] = {"fmu-dopri5": 0, "fmu-rodas4": 1}

_cache: dict[str, tuple[str, Any]] = {}  # model kind -> (unzipped FMU directory, fmpy model description)
_tmpdir: list[Path] = []


def _unpacked_fmu(model: Model) -> tuple[str, Any]:
    """Export (once per process and model kind) and unpack the FMU of ``model.kind``."""
    if model.kind not in _cache:
        from fmpy import extract, read_model_description

        from ..fmu.export import export

        if not _tmpdir:
            _tmpdir.append(Path(tempfile.mkdtemp(prefix="pendulab_bench_fmu_")))
            atexit.register(shutil.rmtree, _tmpdir[0], ignore_errors=True)
        path = export(model, _tmpdir[0] / f"{model.kind}.fmu", 2, timestamp=False)
        unzipdir = extract(str(path), str(_tmpdir[0] / model.kind))
        _cache[model.kind] = (unzipdir, read_model_description(str(path)))
    return _cache[model.kind]


def fmu_bench_runner(solver: int) -> Callable[[Model, np.ndarray, float, float, float], Trajectory]:
    """Runner ``run(model, x0, t_final, dt, tol) -> Trajectory`` for the FMU's embedded ``solver``.

    Parameters
    ----------
    solver : int
        Value of the FMU's ``solver`` parameter: 0 (dopri5) or 1 (rodas4).

    Returns
    -------
    callable
        ``run(model, x0, t_final, dt, tol) -> Trajectory``: one unforced
        Co-Simulation run of the (cached) FMI 2 FMU of ``model.kind`` with the
        model's parameters and ``x0`` as start values, communication step =
        output step ``dt`` [s] and rtol = atol = ``tol``. It raises
        ``SimulationError`` when the FMU reports an error (e.g. a solver
        failure), returns the wrong number of samples or a non-finite state.

    Raises
    ------
    ValueError
        ``solver`` is not 0 or 1.
    """
    if solver not in FMU_SOLVERS.values():
        raise ValueError(f"solver must be one of {sorted(FMU_SOLVERS.values())}, got {solver!r}")
    method = "fmu:" + ("dopri5", "rodas4")[solver]

    def run(model: Model, x0: np.ndarray, t_final: float, dt: float, tol: float) -> Trajectory:
        from fmpy import simulate_fmu

        unzipdir, md = _unpacked_fmu(model)
        start: dict[str, float | int] = dict(zip(model.param_names, map(float, model.p), strict=True))
        start.update(zip(model.state_names, map(float, x0), strict=True))
        start["solver"] = solver
        t = time_grid(t_final, dt)
        try:
            res = simulate_fmu(
                unzipdir,
                model_description=md,
                fmi_type="CoSimulation",
                start_time=0.0,
                stop_time=float(t[-1]),
                step_size=dt,
                output_interval=dt,
                relative_tolerance=tol,
                start_values=start,
                output=list(model.state_names) + list(model.output_names),
                validate=False,
                record_events=False,
            )
        except Exception as exc:  # fmpy raises FMICallException (an Exception) on an Error status
            reason = f"the FMU returned an error ({str(exc).splitlines()[0]}; time of failure not reported by fmpy)"
            raise SimulationError(method, math.nan, t_final, reason, "see the FMU's log message above") from exc
        x = np.column_stack([res[n] for n in model.state_names])
        if len(x) != len(t):
            raise SimulationError(method, float(res["time"][-1]), t_final, f"{len(x)} samples, expected {len(t)}")
        bad = ~np.all(np.isfinite(x), axis=1)
        if bad.any():
            raise SimulationError(method, float(t[np.argmax(bad)]), t_final, "non-finite state")
        return Trajectory(
            t=t,
            x=x,
            u=np.zeros((len(t), len(model.input_names))),
            y=np.column_stack([res[n] for n in model.output_names]),
            state_names=tuple(model.state_names),
            input_names=tuple(model.input_names),
            output_names=tuple(model.output_names),
            method=method,
        )

    return run


def fmu_bench_methods(settings: tuple[float, ...], quick: tuple[float, ...]) -> list[BenchMethod]:
    """One ``BenchMethod`` per embedded solver.

    Parameters
    ----------
    settings, quick : tuple of float
        Full and quick tolerance sweeps (rtol = atol), loosest first.

    Returns
    -------
    list of BenchMethod
        ``fmu-dopri5`` and ``fmu-rodas4``.
    """
    return [BenchMethod(name, "tol", settings, quick, fmu_bench_runner(solver), "fmu") for name, solver in FMU_SOLVERS.items()]
