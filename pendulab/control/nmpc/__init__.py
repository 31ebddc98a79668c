"""Nonlinear model predictive control: tracking NMPC for swing-up and balance in one controller.

* :mod:`.ocp` builds the multiple-shooting problem (RK4 on the model's CasADi rhs) and its solver
  (``sqpmethod`` + ``hpipm`` real-time iteration, IPOPT or fatrop);
* :mod:`.controller` is the sampled controller (:class:`NMPCController`, :class:`NMPCOptions`);
* :mod:`.factories` plans a task's swing-up and builds the controller (:func:`nmpc_for_task`).
"""

from .build import nmpc_controller
from .controller import NMPCController, NMPCOptions
from .factories import nmpc_for_task, nmpc_swingup, plan_swingup
from .ocp import SOLVERS

__all__ = ["NMPCController", "NMPCOptions", "nmpc_controller", "nmpc_for_task", "nmpc_swingup", "plan_swingup", "SOLVERS"]
