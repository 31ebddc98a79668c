"""Control design: python-control bridge, controllability, LQR, sampled controllers, tracking, swing-up, NMPC, estimation.

One definition per concept: :mod:`.lqr` holds the LQR design (continuous or
discrete), the TVLQR Riccati recursion, the ZOH discretization and the angle
wrapping; :mod:`.feedback` holds the controller protocol
(:class:`SampledController`) and the controllers that keep it (state
feedback, energy swing-up, the TVLQR tracker); :mod:`.tracking` designs the
TVLQR gains; :mod:`.controllers` names them for the CLI; :mod:`.swingup`
solves swing-up optimal control; :mod:`.nmpc` is receding-horizon control on
the same model; :mod:`.realai` designs a swing-up for RealAIGym's leaderboard
score. Evaluating controllers (robustness scorecard, leaderboard runs) is the
layer above: :mod:`pendulab.evaluate`.

Inside this package ``import control as ct`` is python-control (absolute
imports); never add a top-level module named ``control``.
"""

from .balance import ROAResult, balanced, format_roa, region_of_attraction, simulate_balance
from .bridge import to_nlsys, to_statespace
from .controllability import ReportRow, controllability_report, controllable_subspace, finite_gramian, format_report
from .controllers import CONTROLLERS, TASK_CONTROLLERS, controller_for_task, make_controller
from .estimation import ExtendedKalmanFilter, MultipleModelEstimator, StateEstimator
from .feedback import (
    EnergySwingUp,
    LinearStateFeedback,
    SampledController,
    actuated_inputs,
    as_feedback,
    balance_controller,
    energy_swingup,
    upright_state,
)
from .global_swingup import GlobalSwingUp, global_controller
from .lqr import LQRDesign, UncontrollableError, actuation_name, discrete_tvlqr, lqr_balance, wrap_state_error, zoh
from .nmpc import NMPCController, NMPCOptions, nmpc_controller, nmpc_for_task
from .replanning import ReplanningSwingUp, replanning_controller
from .robust import EstimatedController, robust_controller
from .swingup import GUESSES, OBJECTIVES, TRANSCRIPTIONS, SwingUpProblem, SwingUpResult, solve_transcription, swing_up
from .swingup.episode import SuccessRate, closed_loop_success_rate
from .swingup.errors import ErrorEstimate, estimate_error, estimate_error_arrays
from .swingup.guess import Guess, energy_guess, linear_guess
from .swingup.planning import PlanningDecision, plan, planning_rule
from .tracking import (
    TVLQRTracker,
    default_weights,
    load_reference_csv,
    resample_reference,
    swingup_reference,
    tvlqr,
    tvlqr_tracker,
)

__all__ = [
    "CONTROLLERS",
    "EstimatedController",
    "ExtendedKalmanFilter",
    "GlobalSwingUp",
    "MultipleModelEstimator",
    "ReplanningSwingUp",
    "StateEstimator",
    "global_controller",
    "replanning_controller",
    "robust_controller",
    "TASK_CONTROLLERS",
    "ErrorEstimate",
    "NMPCController",
    "NMPCOptions",
    "PlanningDecision",
    "SuccessRate",
    "closed_loop_success_rate",
    "controller_for_task",
    "estimate_error",
    "estimate_error_arrays",
    "nmpc_controller",
    "nmpc_for_task",
    "plan",
    "planning_rule",
    "GUESSES",
    "OBJECTIVES",
    "TRANSCRIPTIONS",
    "EnergySwingUp",
    "Guess",
    "LQRDesign",
    "LinearStateFeedback",
    "ROAResult",
    "ReportRow",
    "SampledController",
    "SwingUpProblem",
    "SwingUpResult",
    "TVLQRTracker",
    "UncontrollableError",
    "actuated_inputs",
    "actuation_name",
    "as_feedback",
    "balance_controller",
    "balanced",
    "controllability_report",
    "controllable_subspace",
    "default_weights",
    "discrete_tvlqr",
    "energy_guess",
    "energy_swingup",
    "finite_gramian",
    "format_report",
    "format_roa",
    "linear_guess",
    "load_reference_csv",
    "lqr_balance",
    "make_controller",
    "region_of_attraction",
    "resample_reference",
    "simulate_balance",
    "solve_transcription",
    "swing_up",
    "swingup_reference",
    "tvlqr",
    "tvlqr_tracker",
    "to_nlsys",
    "to_statespace",
    "upright_state",
    "wrap_state_error",
    "zoh",
]


def __getattr__(name: str):
    # Deprecated names, kept for one release.
    if name == "TrackingController":
        import warnings

        warnings.warn(
            "pendulab.control.TrackingController is deprecated; tvlqr() returns a TVLQRTracker", DeprecationWarning, stacklevel=2
        )
        return TVLQRTracker
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
