"""pendulab: rigid and elastic double pendulum as an FMI co-simulation component and control testbed."""

from . import _aliases

_aliases.install()  # deprecated names (one table, above every layer); before any subpackage is imported
from ._version import __version__  # noqa: E402
from .analysis.equilibria import Equilibrium, equilibria, equilibrium  # noqa: E402
from .analysis.linearize import Linearization, linearize  # noqa: E402
from .analysis.modes import Mode, modes  # noqa: E402
from .ensemble import ensemble  # noqa: E402
from .integrate import METHODS, SimulationError, simulate  # noqa: E402
from .integrate.trajectory import Trajectory  # noqa: E402
from .model.model import ACTUATIONS, Model, elastic, make_model, rigid  # noqa: E402
from .model.params import ElasticParams, RigidParams  # noqa: E402

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
