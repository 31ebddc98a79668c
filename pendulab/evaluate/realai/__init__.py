"""RealAIGym's three simulation protocols, reproduced faithfully: leaderboard v2, robustness v2 and v3.

* :mod:`.criteria`: the five criteria, the v2 score (:func:`~.criteria.score_v2`) and the published entries (:data:`PUBLISHED`);
* :mod:`.simulate`: the leaderboard run (RK4 at 2 ms, 10 s, 6 N.m, zero damping) and :class:`RealAIResult`;
* :mod:`.robustness` (with the protocol plant :mod:`.plant`): robustness v2, :func:`robustness_v2`;
* :mod:`.v3`: the v3 global protocol (60 s, 15 random resets), :func:`v3_score`;
* :mod:`.controllers`: the one table of controller names every protocol accepts.

The leaderboard's numbers (step, horizon, torque limit, norms) are the task a
controller is designed for: :mod:`pendulab.control.realai.spec`; the
score-designed swing-up is design too (:mod:`pendulab.control.realai.design`).
:func:`realai_score` is what ``pendulab score --realai`` calls.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from ...control.feedback import SampledController
from ...control.realai.spec import TASKS
from ...control.swingup.tasks import short_name
from ...model.plant_file import IdentifiedPlant
from .controllers import CONTROLLERS, resolve_controller
from .criteria import CRITERIA, PUBLISHED, score_v2, to_relative
from .robustness import RobustnessResult, robustness_v2
from .simulate import RealAIResult, rk4_rollout, run_leaderboard
from .v3 import V3Result, v3_score

__all__ = [
    "CONTROLLER_NAMES",
    "CONTROLLERS",
    "CRITERIA",
    "PUBLISHED",
    "RealAIResult",
    "RobustnessResult",
    "V3Result",
    "realai_score",
    "resolve_controller",
    "rk4_rollout",
    "robustness_v2",
    "run_leaderboard",
    "score_v2",
    "to_relative",
    "v3_score",
]

#: Controller names every protocol accepts (the keys of :data:`CONTROLLERS`).
CONTROLLER_NAMES: tuple[str, ...] = tuple(CONTROLLERS)


def realai_score(
    task: str,
    controller: str | SampledController = "best",
    *,
    csv_path: str | Path | None = None,
    progress: Callable[[int, int], None] | None = None,
    plant: IdentifiedPlant | None = None,
) -> RealAIResult:
    """Score a controller on the RealAIGym simulation leaderboard v2.

    Parameters
    ----------
    task : {"pendubot", "acrobot"}
        Leaderboard task (``swingup_pendubot``, ``swingup_acrobot`` are aliases).
    controller : str, SampledController or callable
        A name of :data:`CONTROLLERS` (``"best"``: TVLQR at 2 ms along the shipped score-designed plan;
        ``"robust"``: ``best`` fed by the delay-identifying estimator; the task controllers of
        :func:`~pendulab.control.controllers.controller_for_task`, designed on the damped task model and run
        on the undamped leaderboard plant; ``"global"``, ``"replan"``), a controller object or a factory
        (:func:`~.controllers.resolve_controller`).
    csv_path : str or Path, optional
        Also write the run (t, theta1, theta2, omega1, omega2, tau1, tau2; absolute angles; every 2 ms).
    progress : callable, optional
        ``progress(done, total)`` in 2 ms steps of the leaderboard run.
    plant : IdentifiedPlant, optional
        Simulate an identified robot (``pendulab identify``) instead of the nominal plant
        (:func:`~pendulab.evaluate.realai.plant.protocol_params`); the controller keeps its design model.

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

    Examples
    --------
    >>> from pendulab.evaluate import realai_score
    >>> res = realai_score("pendubot", "best")  # TVLQR at 2 ms along the shipped score-designed plan
    >>> res.success, round(res.score, 3), round(res.swingup_time, 3)  # score v2 in [0, 1]; swing-up time [s]
    (True, 0.696, 1.558)
    >>> res.to_dict()["beats_published"]  # above the best published pendubot entry
    True
    """
    if not isinstance(task, str):
        raise TypeError(f"task must be a leaderboard task name (one of {list(TASKS)}), got {type(task).__name__}")
    task = short_name(task)
    if task not in TASKS:
        raise ValueError(f"task must be one of {list(TASKS)} (or swingup_pendubot, swingup_acrobot), got {task!r}")
    name, ctrl = resolve_controller(task, controller)
    result = run_leaderboard(task, ctrl, name, progress=progress, plant=plant)
    if csv_path is not None:
        result.write_csv(csv_path)
    return result
