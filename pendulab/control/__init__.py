"""Control: python-control bridge, controllability analysis, LQR balancing.

Inside this package ``import control as ct`` is python-control (absolute
imports); never add a top-level module named ``control``.
"""

from .analysis import ReportRow, controllability_report, controllable_subspace, finite_gramian, format_report
from .balance import ROAResult, balanced, format_roa, region_of_attraction, simulate_balance
from .bridge import to_nlsys, to_statespace
from .lqr import LQRDesign, UncontrollableError, lqr_balance, wrap_state_error

__all__ = [
    "LQRDesign",
    "ROAResult",
    "ReportRow",
    "UncontrollableError",
    "balanced",
    "controllability_report",
    "controllable_subspace",
    "finite_gramian",
    "format_report",
    "format_roa",
    "lqr_balance",
    "region_of_attraction",
    "simulate_balance",
    "to_nlsys",
    "to_statespace",
    "wrap_state_error",
]
