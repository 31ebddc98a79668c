"""Control: python-control bridge, controllability analysis, LQR balancing.

Inside this package ``import control as ct`` is python-control (absolute
imports); never add a top-level module named ``control``.
"""

from .analysis import ReportRow, controllability_report, controllable_subspace, finite_gramian, format_report
from .bridge import to_nlsys, to_statespace
from .lqr import LQRDesign, UncontrollableError, lqr_balance, wrap_state_error

__all__ = [
    "LQRDesign",
    "ReportRow",
    "UncontrollableError",
    "controllability_report",
    "controllable_subspace",
    "finite_gramian",
    "format_report",
    "lqr_balance",
    "to_nlsys",
    "to_statespace",
    "wrap_state_error",
]
