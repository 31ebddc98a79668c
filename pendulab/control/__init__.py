"""Control: python-control bridge, controllability analysis, LQR balancing, swing-up and tracking.

Inside this package ``import control as ct`` is python-control (absolute
imports); never add a top-level module named ``control``.
"""

from .analysis import ReportRow, controllability_report, controllable_subspace, finite_gramian, format_report
from .balance import ROAResult, balanced, format_roa, region_of_attraction, simulate_balance
from .bridge import to_nlsys, to_statespace
from .guess import Guess, energy_guess, linear_guess
from .lqr import LQRDesign, UncontrollableError, lqr_balance, wrap_state_error
from .problem import OBJECTIVES, SwingUpProblem, upright_state
from .swingup import GUESSES, SwingUpResult, swing_up
from .transcription import TRANSCRIPTIONS

__all__ = [
    "GUESSES",
    "Guess",
    "LQRDesign",
    "OBJECTIVES",
    "ROAResult",
    "ReportRow",
    "SwingUpProblem",
    "SwingUpResult",
    "TRANSCRIPTIONS",
    "UncontrollableError",
    "balanced",
    "controllability_report",
    "controllable_subspace",
    "energy_guess",
    "finite_gramian",
    "format_report",
    "format_roa",
    "linear_guess",
    "lqr_balance",
    "region_of_attraction",
    "simulate_balance",
    "swing_up",
    "to_nlsys",
    "to_statespace",
    "upright_state",
    "wrap_state_error",
]
