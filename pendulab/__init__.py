"""pendulab: rigid and elastic double pendulum as an FMI co-simulation component and control testbed.

The public names are imported on first use (PEP 562 ``__getattr__``): ``import pendulab`` and every CLI
start, ``--help`` and a bad-option error included, no longer pay for SciPy, CasADi and the ensemble engine
(0.6-3.4 s) before they are needed, and a Ctrl-C during start-up lands in pendulab's own entry point.
"""

from __future__ import annotations

from . import _aliases, _lazy

_aliases.install()  # deprecated names (one table, above every layer); before any subpackage is imported
from ._version import __version__  # noqa: E402

#: Public name -> the module that defines it (imported on first access).
_LAZY: dict[str, str] = {
    "ACTUATIONS": ".model.model",
    "Model": ".model.model",
    "elastic": ".model.model",
    "make_model": ".model.model",
    "rigid": ".model.model",
    "ElasticParams": ".model.params",
    "RigidParams": ".model.params",
    "Equilibrium": ".analysis.equilibria",
    "equilibria": ".analysis.equilibria",
    "equilibrium": ".analysis.equilibria",
    "Linearization": ".analysis.linearize",
    "linearize": ".analysis.linearize",
    "Mode": ".analysis.modes",
    "modes": ".analysis.modes",
    "ensemble": ".ensemble.engine",
    "METHODS": ".integrate",
    "SimulationError": ".integrate",
    "simulate": ".integrate",
    "Trajectory": ".integrate.trajectory",
}


_lazy.install(__name__, _LAZY)

__all__ = [
    "__version__",
    "ACTUATIONS",
    "METHODS",
    "Mode",
    "ElasticParams",
    "Equilibrium",
    "Linearization",
    "Model",
    "RigidParams",
    "SimulationError",
    "Trajectory",
    "elastic",
    "ensemble",
    "equilibria",
    "equilibrium",
    "linearize",
    "make_model",
    "modes",
    "rigid",
    "simulate",
]
