"""FMU export (FMI 2.0 / 3.0, Co-Simulation + Model Exchange, C) and its fmpy validation harness.

``export(model, path, fmi_version=2|3)`` writes the FMU; ``validate(path)``
checks it with fmpy against the native integrator. The hand-written C (FMI
layers, model core, ODE solvers) lives in ``pendulab/fmu/c``; the solvers in
``ode_solver.{h,c}`` do not depend on FMI and can be reused by a native
compiled fast path. ``cosim(fmu_path, controller, comm_step, t_final)`` is the
co-simulation master (``cosim.py``; ``cosim_many`` for several FMUs).
"""

from ..cosim.master import StepRejectedError, cosim, cosim_many
from .export import CompilerNotFoundError, export
from .validate import SCENES, ValidationReport, validate

__all__ = ["export", "validate", "CompilerNotFoundError", "ValidationReport", "SCENES"]
__all__ += ["cosim", "cosim_many", "StepRejectedError"]
