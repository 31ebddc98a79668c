"""RealAIGym simulation leaderboard v2: the faithful simulation and the criteria.

* :mod:`.criteria`: the five criteria, the v2 score (:func:`~.criteria.score_v2`) and the published entries (:data:`PUBLISHED`);
* :mod:`.simulate`: the leaderboard run (RK4 at 2 ms, 10 s, 6 N.m, zero damping) and :class:`RealAIResult`.

The leaderboard's numbers (step, horizon, torque limit, norms) are the task a
controller is designed for: :mod:`pendulab.control.realai.spec`; the
score-designed swing-up is design too (:mod:`pendulab.control.realai.design`).
:func:`realai_score` is what ``pendulab score --realai`` calls.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from ...control.controllers import TASK_CONTROLLERS, controller_for_task
from ...control.feedback import SampledController
from ...control.realai.design import best_controller
from ...control.realai.spec import TASKS, leaderboard_task
from ...control.swingup.tasks import short_name
from .criteria import CRITERIA, PUBLISHED, score_v2, to_relative
from .simulate import RealAIResult, rk4_rollout, run_leaderboard

__all__ = [
    "CONTROLLER_NAMES",
    "CRITERIA",
    "PUBLISHED",
    "RealAIResult",
    "realai_score",
    "rk4_rollout",
    "run_leaderboard",
    "score_v2",
    "to_relative",
]

#: Controller names :func:`realai_score` accepts: "best" and the task controllers.
CONTROLLER_NAMES: tuple[str, ...] = ("best", *TASK_CONTROLLERS)


def realai_score(
    task: str,
    controller: str | SampledController = "best",
    *,
    csv_path: str | Path | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> RealAIResult:
    """Score a controller on the RealAIGym simulation leaderboard v2.

    Parameters
    ----------
    task : {"pendubot", "acrobot"}
        Leaderboard task (``swingup_pendubot``, ``swingup_acrobot`` are aliases).
    controller : str or SampledController
        ``"best"`` (the project's best swing-up: TVLQR at 2 ms along the shipped
        score-designed plan), a name of
        :data:`pendulab.control.controllers.TASK_CONTROLLERS` (built by
        :func:`~pendulab.control.controllers.controller_for_task` on the task
        ``swingup_<task>`` at its 10 ms sample time; designed on the damped task
        model, run on the undamped leaderboard plant), or a controller object.
    csv_path : str or Path, optional
        Also write the run (t, theta1, theta2, omega1, omega2, tau1, tau2; absolute angles; every 2 ms).
    progress : callable, optional
        ``progress(done, total)`` in 2 ms steps of the leaderboard run.

    Returns
    -------
    RealAIResult
        Criteria, score, success and the trajectory.

    Raises
    ------
    ValueError
        Unknown task or controller name, or a controller that cannot be built or run.
    TypeError
        ``task`` is not a string, ``controller`` neither a name nor a sampled controller.
    """
    if not isinstance(task, str):
        raise TypeError(f"task must be a leaderboard task name (one of {list(TASKS)}), got {type(task).__name__}")
    task = short_name(task)
    if task not in TASKS:
        raise ValueError(f"task must be one of {list(TASKS)} (or swingup_pendubot, swingup_acrobot), got {task!r}")
    if isinstance(controller, str):
        name = controller
        if name == "best":
            ctrl: SampledController = best_controller(task)
        elif name in TASK_CONTROLLERS:
            ctrl, _ = controller_for_task(name, leaderboard_task(task))
        else:
            raise ValueError(f"controller must be one of {list(CONTROLLER_NAMES)} or a SampledController, got {name!r}")
    else:
        ctrl, name = controller, type(controller).__name__
    result = run_leaderboard(task, ctrl, name, progress=progress)
    if csv_path is not None:
        result.write_csv(csv_path)
    return result
