"""NMPC for a swing-up task or a model: plan the swing-up offline, then track it and balance with one NMPC.

The plan is the optimal swing-up of :func:`pendulab.control.swingup.swing_up`
on the task's rigid model, or on the rigid counterpart of an elastic one (a few
seconds instead of minutes, and it always solves; the NMPC lifts it to
quasi-static spring lengths: see :mod:`.controller`), with the task's actuation,
torque limit and horizon. It is computed once, before the run.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np

from ..._inputs import checked
from ...model.counterpart import rigid_counterpart
from ...model.model import Model
from ..lqr import actuation_name
from ..swingup.transcription import MAX_INTERVALS
from .build import nmpc_controller
from .controller import NMPCController, NMPCOptions

if TYPE_CHECKING:
    from ..swingup.problem import SwingUpProblem
    from ..swingup.tasks import Task

__all__ = ["nmpc_for_task", "nmpc_swingup", "plan_swingup", "check_options"]


def check_options(**options: Any) -> NMPCOptions:
    """Check NMPC option values (names, types, bounds) without building anything.

    Parameters
    ----------
    **options
        :class:`NMPCOptions` fields.

    Returns
    -------
    NMPCOptions
        The checked options.

    Raises
    ------
    TypeError
        Unknown option names.
    ValueError
        Bad values (the message names the option).
    """
    unknown = sorted(set(options) - set(NMPCOptions.__dataclass_fields__))
    if unknown:
        raise TypeError(f"unknown NMPC option(s) {unknown}; expected some of {sorted(NMPCOptions.__dataclass_fields__)}")
    return NMPCOptions(**options)


@checked()
def plan_swingup(problem: SwingUpProblem, *, method: str = "radau", N: int | None = None, degree: int = 3) -> Any:
    """Optimal swing-up of ``problem`` on its rigid model (the rigid counterpart of an elastic model).

    Parameters
    ----------
    problem : SwingUpProblem
        Swing-up problem (its start and goal are replaced by the planning model's
        hanging rest and upright states when the model is elastic).
    method : str
        Transcription of :func:`pendulab.control.swingup.swing_up`.
    N : int, optional
        Intervals (default: the problem's ``intervals``).
    degree : int
        Collocation degree.

    Returns
    -------
    SwingUpResult
        A successful swing-up of the planning model.

    Raises
    ------
    ValueError
        The trajectory optimizer did not solve the swing-up.
    """
    from ..swingup.planning import swing_up

    plan = rigid_counterpart(problem.model)
    if plan is not problem.model:
        problem = replace(problem, model=plan, x0=None, goal=None, stretch_limits=None)
    res = swing_up(problem, method, N, degree=degree)
    if not res.success:
        raise ValueError(f"nmpc: the swing-up plan of {problem.name!r} did not solve: {res.message}")
    return res


@checked(NMPCOptions)
def nmpc_for_task(
    task: Task, *, sample_time: float = 0.02, solver: str = "sqp", **options: Any
) -> tuple[NMPCController, np.ndarray]:
    """NMPC that tracks the task's optimized swing-up and then balances; and the task's start state.

    Parameters
    ----------
    task : Task or str
        Swing-up task (model, actuation, torque and velocity limits, start, horizon), or its name
        (``pendubot``; ``swingup_pendubot`` is an alias).
    sample_time : float
        Controller sample time [s] (interval of the NMPC problem).
    solver : {"sqp", "ipopt", "fatrop"}
        NLP solver (see :class:`NMPCOptions`).
    **options
        Other :class:`NMPCOptions` fields (``horizon``, ``substeps``, weights...).

    Returns
    -------
    controller : NMPCController
        Saturated at the task's torque limit; soft velocity bound at the task's limit, if any.
    x0 : ndarray, shape (nx,)
        The task's start state (plant model).

    Raises
    ------
    ValueError
        The swing-up plan failed, or bad options (checked before planning).
    TypeError
        ``task`` is neither a Task nor a name; unknown option names.
    FileNotFoundError
        Unknown task name.

    Examples
    --------
    >>> import pendulab as pl
    >>> from pendulab.control import as_feedback, nmpc_for_task
    >>> from pendulab.control.swingup.check import height_success
    >>> from pendulab.control.swingup.tasks import load_task
    >>> task = load_task("pendubot")
    >>> ctrl, x0 = nmpc_for_task(task)  # plans the swing-up once, then tracks it at 50 Hz
    >>> traj = pl.simulate(task.model, x0, 4.0, dt=ctrl.sample_time, u=as_feedback(ctrl, task.model))
    >>> check = height_success(traj, task.rest_lengths)
    >>> check.success, round(check.t_up, 2), ctrl.stats()["failures"]
    (True, 1.62, 0)
    """
    from ..swingup.tasks import resolve_task

    task = resolve_task(task)
    check_options(sample_time=sample_time, solver=solver, **options)  # before the (costly) plan
    pb = task.problem
    res = plan_swingup(pb, method=task.method, N=task.N, degree=task.degree)
    options.setdefault("velocity_limit", pb.velocity_limit)
    ctrl = nmpc_controller(
        task.model, actuation=pb.actuation, u_max=pb.torque_limit, reference=(res.t, res.x, res.u),
        sample_time=sample_time, solver=solver, **options,
    )  # fmt: skip
    return ctrl, np.asarray(pb.start, dtype=float)


@checked()
def nmpc_swingup(
    model: Model,
    sample_time: float = 0.02,
    *,
    actuation: str | Sequence[str] = "full",
    u_max: float = 20.0,
    reference: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
    horizon: float = 3.0,
    solver: str = "sqp",
    **options: Any,
) -> tuple[NMPCController, np.ndarray]:
    """NMPC swing-up and balance of ``model`` from hanging at rest (the ``nmpc`` entry of ``make_controller``).

    Parameters
    ----------
    model : Model
        Plant model (e.g. an FMU's parameters).
    sample_time : float
        Controller sample time [s].
    actuation : {"full", "pendubot", "acrobot"} or sequence of input names
        Driven torques.
    u_max : float
        Torque limit [N.m].
    reference : (t, x, u), optional
        Reference to track instead of planning one (start: its first state).
    horizon : float
        Swing-up time of the plan [s] when no reference is given.
    solver : {"sqp", "ipopt", "fatrop"}
        NLP solver.
    **options
        Other :class:`NMPCOptions` fields.

    Returns
    -------
    controller : NMPCController
    x0 : ndarray, shape (nx,)
        Hanging at rest (:meth:`Model.rest_state`); with a ``reference`` of the
        plant model's states, its first state.

    Raises
    ------
    ValueError
        The plan failed, or bad arguments.
    """
    from ..swingup.problem import SwingUpProblem

    check_options(sample_time=sample_time, solver=solver, **options)  # before the (costly) plan
    if reference is None:
        horizon = float(horizon)
        if round(horizon / 0.03) > MAX_INTERVALS:
            raise ValueError(
                f"horizon must be at most {MAX_INTERVALS * 0.03:g} s (the plan has one interval per 30 ms, "
                f"at most {MAX_INTERVALS}), got {horizon!r}"
            )
        pb = SwingUpProblem(model=model, actuation=actuation_name(actuation), torque_limit=u_max, horizon=horizon, name="nmpc")
        res = plan_swingup(pb, N=max(20, round(horizon / 0.03)))
        reference, x0 = (res.t, res.x, res.u), model.rest_state()
    else:
        x_first = np.asarray(reference[1], dtype=float)[0]
        x0 = x_first.copy() if x_first.shape == (model.nx,) else model.rest_state()
    ctrl = nmpc_controller(
        model, actuation=actuation, u_max=u_max, reference=reference, sample_time=sample_time, solver=solver, **options
    )
    return ctrl, x0
