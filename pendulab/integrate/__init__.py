"""Integration: :func:`simulate`, the one method registry, and :class:`Trajectory`.

See :mod:`pendulab.integrate.registry` for the runner contract a method family keeps.
"""

from __future__ import annotations

from .. import _lazy
from .trajectory import Trajectory

#: Imported on first use: the method registry imports every family (SciPy's integrate alone is 0.4-2.5 s),
#: which a CLI start or an import of Trajectory should not pay for.
_LAZY = {
    "MethodSpec": ".registry",
    "RunRequest": ".registry",
    "RunResult": ".registry",
    "SimulationError": ".registry",
    "METHODS": ".methods",
    "register_method": ".methods",
    "InputSpec": ".simulate",
    "input_schedule": ".simulate",
    "simulate": ".simulate",
    "time_grid": ".simulate",
}


_lazy.install(__name__, _LAZY)

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
