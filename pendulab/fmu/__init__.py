"""FMU export (FMI 2.0 / 3.0, Co-Simulation + Model Exchange, C) and its fmpy validation harness.

``export(model, path, fmi_version=2|3)`` writes the FMU; ``validate(path)``
checks it with fmpy against the native integrator. The hand-written C (FMI
layers, model core) lives in ``pendulab/fmu/c``. The co-simulation master
that drives FMUs under sampled controllers is :mod:`pendulab.cosim`.
"""

from __future__ import annotations

from .export import CompilerNotFoundError, export
from .validate import ValidationReport, validate

__all__ = ["export", "validate", "CompilerNotFoundError", "ValidationReport"]
# The deprecated names pendulab.fmu.cosim, cosim_many, StepRejectedError (moved to pendulab.cosim) are served by
# pendulab._aliases, above every layer: fmu holds no reference to cosim.
