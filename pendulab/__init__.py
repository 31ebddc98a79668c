"""pendulab: rigid and elastic double pendulum as an FMI co-simulation component and control testbed."""

from .model.equilibria import Equilibrium, equilibria, equilibrium
from .model.linearize import Linearization, linearize
from .model.model import ACTUATIONS, Model, elastic, make_model, rigid
from .model.modes import Mode, modes
from .model.params import ElasticParams, RigidParams
from .model.simulate import METHODS, SimulationError, simulate
from .model.trajectory import Trajectory

__all__ = [
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
    "equilibria",
    "equilibrium",
    "linearize",
    "make_model",
    "modes",
    "rigid",
    "simulate",
]
__version__ = "0.1.0"
