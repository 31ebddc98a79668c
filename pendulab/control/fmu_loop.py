"""Close a sampled-data feedback loop around a pendulab Co-Simulation FMU (FMI 2, fmpy).

A minimal master: at each communication point read the state, evaluate the
controller, set the torques, ``doStep`` one controller sample. The same
zero-order-hold semantics as ``pendulab.simulate(..., u=callable)``, so the two
closed loops can be compared sample by sample.
"""

from __future__ import annotations

import math
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ..model.model import Model
from ..model.trajectory import Trajectory

__all__ = ["closed_loop_fmu"]


def closed_loop_fmu(
    fmu_path: str | Path,
    model: Model,
    x0: np.ndarray,
    controller: Callable[[float, np.ndarray], Any],
    t_final: float,
    dt: float,
    tolerance: float = 1e-8,
) -> Trajectory:
    """Run ``controller`` in closed loop with a pendulab FMU exported for ``model`` (FMI 2 Co-Simulation).

    Parameters
    ----------
    fmu_path : path-like
        FMU from :func:`pendulab.fmu.export.export` (``fmi_version=2``).
    model : Model
        Model of the FMU; its parameters are set as start values.
    x0 : array_like, shape (nx,)
        Start state.
    controller : callable ``u(t, x) -> (tau1, tau2)``
    t_final, dt : float
        Episode length and communication step = controller sample time [s].
    tolerance : float
        Tolerance of the FMU's embedded solver.

    Returns
    -------
    Trajectory
        States, held torques and outputs on the communication grid (``method = "fmu:cs"``).

    Raises
    ------
    RuntimeError
        The FMU refused a step (message names the time).
    """
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    x0 = model.check_state(x0, "x0")
    n = max(1, math.ceil(t_final / dt - 1e-9))
    md = read_model_description(str(fmu_path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    vr_x = [vr[s] for s in model.state_names]
    vr_u = [vr[s] for s in model.input_names]
    unzipdir = extract(str(fmu_path))
    fmu = FMU2Slave(
        guid=md.guid, unzipDirectory=unzipdir, modelIdentifier=md.coSimulation.modelIdentifier, instanceName="swingup"
    )
    t = np.linspace(0.0, n * dt, n + 1)
    X = np.empty((n + 1, model.nx))
    U = np.zeros((n + 1, model.nu))
    try:
        fmu.instantiate()
        fmu.setupExperiment(tolerance=tolerance, startTime=0.0, stopTime=float(t[-1]))
        fmu.setReal([vr[p] for p in model.param_names], [float(v) for v in model.p])
        fmu.setReal(vr_x, [float(v) for v in x0])
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        for k in range(n + 1):
            X[k] = fmu.getReal(vr_x)
            U[k] = np.asarray(controller(float(t[k]), X[k].copy()), dtype=float).reshape(model.nu)
            if k == n:
                break
            fmu.setReal(vr_u, [float(v) for v in U[k]])
            try:
                fmu.doStep(currentCommunicationPoint=float(t[k]), communicationStepSize=float(dt))
            except Exception as exc:  # fmpy raises a bare Exception on fmi2Error
                raise RuntimeError(f"FMU step at t = {t[k]:.6g} s of {t[-1]:.6g} s failed: {exc}") from exc
        fmu.terminate()
    finally:
        fmu.freeInstance()
        shutil.rmtree(unzipdir, ignore_errors=True)
    Y = model.outputs(X, U)
    return Trajectory(t, X, U, Y, model.state_names, model.input_names, model.output_names, "fmu:cs")
