"""The RealAIGym simulation leaderboard v2 as a task: plant, step, horizon, torque limit, success line and norms.

What a controller is designed *for* (the score-designed swing-up of
:mod:`.design` optimizes against these numbers) and what the evaluation
(:mod:`pendulab.evaluate.realai`) runs and scores with, so it lives with the
design, below the evaluation. Sources: ``leaderboard/{pendubot,acrobot}/simulation_v2/sim_parameters.py``
and ``create_leaderboard.py`` (commit 699c934) of github.com/dfki-ric-underactuated-lab/double_pendulum:
design C.1, model 1.0, torque limit ``[6, 0]`` (pendubot) or ``[0, 6]`` (acrobot),
damping and friction zero, RK4 at 2 ms, 10 s, norms 20 s, 60 J, 20 N^2 m^2 s,
0.1 N.m and 400 rad^2/s.
"""

from __future__ import annotations

from collections.abc import Mapping

from ...model.model import Model
from ..swingup.tasks import Task, load_task

__all__ = [
    "DT",
    "T_FINAL",
    "N_STEPS",
    "TORQUE_LIMIT",
    "PLAN_VELOCITY_LIMIT_HW",
    "TASKS",
    "NORMS",
    "HEIGHT_FRACTION",
    "check_task",
    "leaderboard_task",
    "leaderboard_model",
]

#: Leaderboard step [s].
DT: float = 0.002
#: Episode length [s].
T_FINAL: float = 10.0
#: Number of RK4 steps (= rows of the scored CSV): 500 frames of 10 steps.
N_STEPS: int = int(T_FINAL / 0.02) * int(0.02 / DT)
#: Torque limit of the actuated joint [N.m].
TORQUE_LIMIT: float = 6.0
#: Bound on both joint rates (``omega1``, ``omega2 - omega1``) of the plans pendulab's planning controllers play on
#: the ICRA 2025 hardware protocol [rad/s]: 2 rad/s (20 times the measured rate noise) below its 20 rad/s limit
#: reset. It was 16 (the hardware winner's ``vmax``) on the *link* rates until 2026-11-29; bounding the joints at 16
#: slowed the acrobot's plans (``mpc_library`` 0.622 on its training seeds 30-45 against 0.639), at 18 0.637.
PLAN_VELOCITY_LIMIT_HW: float = 18.0
#: Leaderboard tasks and the joint each drives (index into (tau1, tau2)).
TASKS: dict[str, int] = {"pendubot": 0, "acrobot": 1}
#: Normalisations n_i of the v2 score (simulation leaderboard): s, J, N^2 m^2 s, N.m, rad^2/s.
NORMS: Mapping[str, float] = {
    "swingup_time": 20.0,
    "energy": 60.0,
    "torque_cost": 20.0,
    "torque_smoothness": 0.1,
    "velocity_cost": 400.0,
}
#: Success line: the end effector must stay above this fraction of L1 + L2.
HEIGHT_FRACTION: float = 0.9


def check_task(task: str) -> str:
    """A leaderboard task name, checked.

    Parameters
    ----------
    task : str
        ``"pendubot"`` or ``"acrobot"``.

    Returns
    -------
    str
        ``task``.

    Raises
    ------
    ValueError
        Unknown ``task``.
    """
    if task not in TASKS:
        raise ValueError(f"task must be one of {list(TASKS)}, got {task!r}")
    return task


def leaderboard_task(task: str) -> Task:
    """The pendulab swing-up task of a leaderboard task (``swingup_pendubot`` / ``swingup_acrobot``; design C.1, model 1.0).

    Parameters
    ----------
    task : {"pendubot", "acrobot"}
        Leaderboard task.

    Returns
    -------
    Task
        As shipped (joint damping 0.001 N.m.s/rad, controller sample time 10 ms).

    Raises
    ------
    ValueError
        Unknown ``task``.
    """
    return load_task(f"swingup_{check_task(task)}")


def leaderboard_model(task: str) -> Model:
    """The leaderboard plant: the task's rigid model with zero damping (Coulomb friction, rotor inertia: not modelled).

    Parameters
    ----------
    task : {"pendubot", "acrobot"}
        Leaderboard task.

    Returns
    -------
    Model
        Rigid model, ``b1 = b2 = 0``.

    Raises
    ------
    ValueError
        Unknown ``task``.
    """
    return leaderboard_task(task).model.with_params(b1=0.0, b2=0.0)
