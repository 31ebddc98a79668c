"""Co-simulation: the master that drives FMUs under sampled controllers, the communication-step study, plots.

``cosim(fmu_path, controller, comm_step, t_final)`` runs one FMU;
``cosim_many`` runs several side by side with the same loop.
"""

from .master import cosim, cosim_many
from .plant import FmuInfo, StepRejectedError, inspect_fmu

__all__ = ["FmuInfo", "StepRejectedError", "cosim", "cosim_many", "inspect_fmu"]
