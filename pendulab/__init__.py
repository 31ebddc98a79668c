"""pendulab: rigid and elastic double pendulum as an FMI co-simulation component and control testbed."""

from ._version import __version__
from .analysis.equilibria import Equilibrium, equilibria, equilibrium
from .analysis.linearize import Linearization, linearize
from .analysis.modes import Mode, modes
from .ensemble import ensemble
from .integrate import METHODS, SimulationError, simulate
from .integrate.trajectory import Trajectory
from .model.model import ACTUATIONS, Model, elastic, make_model, rigid
from .model.params import ElasticParams, RigidParams

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
