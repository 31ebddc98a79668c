"""Integration: :func:`simulate`, the one method registry, and :class:`Trajectory`.

See :mod:`pendulab.integrate.registry` for the runner contract a method family keeps.
"""

from .methods import METHODS, register_method
from .registry import MethodSpec, RunRequest, RunResult, SimulationError
from .simulate import InputSpec, input_schedule, simulate, time_grid
from .trajectory import Trajectory

__all__ = [
    "METHODS",
    "InputSpec",
    "MethodSpec",
    "RunRequest",
    "RunResult",
    "SimulationError",
    "Trajectory",
    "input_schedule",
    "register_method",
    "simulate",
    "time_grid",
]
