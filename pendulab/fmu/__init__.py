"""FMU export (FMI 2.0 / 3.0, Co-Simulation + Model Exchange, C) and its fmpy validation harness.

``export(model, path, fmi_version=2|3)`` writes the FMU; ``validate(path)``
checks it with fmpy against the native integrator. The hand-written C (FMI
layers, model core) lives in ``pendulab/fmu/c``. The co-simulation master
that drives FMUs under sampled controllers is :mod:`pendulab.cosim`.
"""

from __future__ import annotations

import importlib
import warnings
from typing import Any

from .export import CompilerNotFoundError, export
from .validate import ValidationReport, validate

__all__ = ["export", "validate", "CompilerNotFoundError", "ValidationReport"]

_MOVED_TO_COSIM = ("cosim", "cosim_many", "StepRejectedError")


def __getattr__(name: str) -> Any:
    # Deprecated since the co-simulation master moved to pendulab.cosim; kept for one release.
    # Loaded dynamically so that fmu (the lower layer) has no import of cosim.
    if name in _MOVED_TO_COSIM:
        warnings.warn(f"pendulab.fmu.{name} is deprecated; use pendulab.cosim.{name}", DeprecationWarning, stacklevel=2)
        return getattr(importlib.import_module("pendulab.cosim"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
