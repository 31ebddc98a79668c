"""The RealAIGym leaderboard as a design target: its task (:mod:`.spec`) and the swing-up designed for its score.

* :mod:`.spec`: the leaderboard's plant, step, horizon, torque limit, success line and score norms;
* :mod:`.design`: the score-designed swing-up (multiple shooting on the leaderboard's RK4, TVLQR at 2 ms),
  with plans cached in ``plans/<task>.npz``;
* :mod:`.adapter`: the community's controllers (upstream ``AbstractController``) run as pendulab controllers.

Running and scoring controllers on the leaderboard is evaluation: :mod:`pendulab.evaluate.realai`.
"""

from __future__ import annotations

from .adapter import RealAIGymController, from_realai, is_realai_controller, to_joint
from .design import LeaderboardPlan, best_controller, design_plan, load_plan, save_plan, tracker_for_plan
from .spec import DT, HEIGHT_FRACTION, N_STEPS, NORMS, T_FINAL, TASKS, TORQUE_LIMIT, leaderboard_model, leaderboard_task

__all__ = [
    "DT",
    "HEIGHT_FRACTION",
    "NORMS",
    "N_STEPS",
    "T_FINAL",
    "TASKS",
    "TORQUE_LIMIT",
    "LeaderboardPlan",
    "RealAIGymController",
    "best_controller",
    "design_plan",
    "from_realai",
    "is_realai_controller",
    "leaderboard_model",
    "leaderboard_task",
    "load_plan",
    "save_plan",
    "to_joint",
    "tracker_for_plan",
]
