"""Control: python-control bridge, controllability analysis, LQR balancing, swing-up and tracking.

One design per concept: :mod:`.lqr` holds the LQR design (continuous or
discrete), the TVLQR Riccati recursion, the ZOH discretization and the angle
wrapping; :mod:`.sampled` and :mod:`.tracking_sampled` wrap those gains as
sampled-data controllers for co-simulation; :mod:`.tracking` stabilizes an
optimized swing-up with them.

Inside this package ``import control as ct`` is python-control (absolute
imports); never add a top-level module named ``control``.
"""

from .balance import ROAResult, balanced, format_roa, region_of_attraction, simulate_balance
from .bridge import to_nlsys, to_statespace
from .controllability import ReportRow, controllability_report, controllable_subspace, finite_gramian, format_report
from .lqr import LQRDesign, UncontrollableError, actuation_name, discrete_tvlqr, lqr_balance, wrap_state_error, zoh
from .sampled import (
    CONTROLLERS,
    EnergySwingUp,
    LinearStateFeedback,
    SampledController,
    as_feedback,
    energy_swingup,
    make_controller,
    upright_state,
)
from .swingup.guess import Guess, energy_guess, linear_guess
from .swingup.problem import OBJECTIVES, SwingUpProblem
from .swingup.solve import GUESSES, SwingUpResult, swing_up
from .swingup.transcription import TRANSCRIPTIONS
from .tracking import TrackingController, tvlqr
from .tracking_sampled import TVLQRTracker, load_reference_csv, resample_reference, swingup_reference, tvlqr_tracker

__all__ = [
    "CONTROLLERS",
    "EnergySwingUp",
    "LinearStateFeedback",
    "SampledController",
    "TVLQRTracker",
    "TrackingController",
    "actuation_name",
    "as_feedback",
    "discrete_tvlqr",
    "energy_swingup",
    "load_reference_csv",
    "make_controller",
    "resample_reference",
    "swingup_reference",
    "tvlqr",
    "tvlqr_tracker",
    "zoh",
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
