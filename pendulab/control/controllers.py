"""Named controllers: the factory behind ``pendulab cosim --controller NAME``.

A new controller plugs in here: add its name to :data:`CONTROLLERS` and a
branch to :func:`make_controller` returning an object that keeps the
:class:`~pendulab.control.feedback.SampledController` protocol.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from .._checks import check_model, positive_float
from .._inputs import checked
from ..analysis.linearize import linearize
from ..model.model import INPUT_NAMES, Model
from .feedback import SampledController, actuated_inputs, balance_controller, energy_swingup, upright_state
from .tracking import swingup_reference, tvlqr, tvlqr_tracker

if TYPE_CHECKING:
    from .estimation import StateEstimator
    from .swingup.tasks import Task

__all__ = ["CONTROLLERS", "TASK_CONTROLLERS", "make_controller", "controller_for_task"]


#: Most samples of a default ``tvlqr`` reference (one gain matrix per sample).
MAX_REFERENCE_SAMPLES = 1_000_000
#: Names accepted by :func:`make_controller`.
CONTROLLERS: tuple[str, ...] = ("lqr", "swingup", "tvlqr", "nmpc")


@checked(t_ref="t_final")
def make_controller(
    name: str,
    model: Model,
    sample_time: float,
    *,
    u_max: float = 20.0,
    t_ref: float = 6.0,
    reference: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
    actuation: str = "full",
    nmpc_solver: str = "sqp",
    estimator: str | StateEstimator | None = None,
) -> tuple[SampledController, np.ndarray]:
    """A named controller for ``model`` and its natural start state.

    Parameters
    ----------
    name : {"lqr", "swingup", "tvlqr", "nmpc"}
        ``lqr``: continuous LQR balance (start 0.1 rad off upright);
        ``swingup``: energy pumping + LQR catch (start hanging, theta1 = 0.1);
        ``tvlqr``: discrete TVLQR tracking of ``reference`` (default: the native
        energy swing-up, :func:`swingup_reference`, ``t_ref`` seconds) then
        discrete LQR balance; starts at the reference's first state;
        ``nmpc``: tracking NMPC (:func:`pendulab.control.nmpc.nmpc_swingup`) of
        ``reference`` or of a swing-up planned for ``model``, ``actuation`` and
        ``u_max`` (3 s), then regulation upright; starts hanging at rest.
    model : Model
        Design model (e.g. ``FmuInfo.model()`` for an FMU's parameters).
    sample_time : float
        [s].
    u_max : float
        Torque limit [N.m] (swing-up and tracking).
    t_ref : float
        Horizon [s] of the default ``tvlqr`` reference.
    reference : (t, x, u), optional
        Reference to track with ``tvlqr`` (any grid; e.g. an optimized swing-up or
        :func:`load_reference_csv`).
    actuation : {"full", "pendubot", "acrobot"}
        Driven torques of ``lqr``, ``tvlqr`` and ``nmpc`` (``swingup`` needs both).
    nmpc_solver : {"sqp", "ipopt", "fatrop"}
        NLP solver of ``nmpc``.
    estimator : {"ekf", "mmae"} or StateEstimator, optional
        Feed the controller a state estimate instead of the measurement
        (:class:`~pendulab.control.robust.EstimatedController`; names built by
        :func:`~pendulab.control.robust.build_estimator` at ``sample_time`` from the start state).

    Returns
    -------
    controller : SampledController
        The sampled-data controller.
    x0 : ndarray, shape (nx,)
        Start state for ``model`` (see ``name``).

    Raises
    ------
    ValueError
        Unknown ``name``, non-positive ``sample_time`` (or ``t_ref``), or
        ``swingup`` with an actuation other than ``"full"``; an ``nmpc`` plan
        that did not solve.
    TypeError
        ``model`` is not a Model, ``name`` not a string.

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.control import as_feedback, make_controller
    >>> model = pl.rigid()
    >>> ctrl, x0 = make_controller("swingup", model, 0.01, u_max=20.0)  # energy pumping + LQR catch
    >>> x0  # its natural start: hanging, theta1 = 0.1 rad
    array([0.1, 0. , 0. , 0. ])
    >>> traj = pl.simulate(model, x0, 5.0, dt=ctrl.sample_time, u=as_feedback(ctrl, model))
    >>> np.round(np.cos(traj.x[-1, :2]), 3)  # both links upright
    array([-1., -1.])
    """
    check_model(model)
    if not isinstance(name, str):
        raise TypeError(f"name must be a controller name (one of {list(CONTROLLERS)}), got {type(name).__name__}")
    h = check_sample_time(model, sample_time)
    if u_max is not None:
        u_max = float(u_max)
    ctrl, x0 = _make_plain(name, model, h, u_max, t_ref, reference, actuation, nmpc_solver)
    return _with_estimator(ctrl, x0, model, estimator, u_max), x0


#: Shortest controller sample time [s]: 1e5 calls per simulated second (a budget, not physics).
MIN_SAMPLE_TIME: float = 1e-5
#: Longest sample time, as ``sample_time`` x the fastest unstable rate of the upright equilibrium: held for
#: longer, a sample lets the unstable mode grow e^2 = 7.4-fold before the controller can answer.
MAX_UNSTABLE_GROWTH: float = 2.0


def check_sample_time(model: Model, sample_time: Any) -> float:
    """A controller sample time that can control ``model``: at least :data:`MIN_SAMPLE_TIME`, at most
    :data:`MAX_UNSTABLE_GROWTH` / (fastest unstable rate at the upright equilibrium).

    Parameters
    ----------
    model : Model
        The plant the controller is designed for.
    sample_time : float
        [s].

    Returns
    -------
    float
        The sample time.

    Raises
    ------
    ValueError
        Not a positive finite number, or outside that range (the message gives the range).
    """
    h = positive_float("sample_time", sample_time, "[s]")
    A = linearize(model, upright_state(model)).A
    rate = float(max(np.max(np.linalg.eigvals(A).real), 0.0))
    longest = MAX_UNSTABLE_GROWTH / rate if rate > 0.0 else np.inf
    if not MIN_SAMPLE_TIME <= h <= longest:
        raise ValueError(
            f"sample_time must be in [{MIN_SAMPLE_TIME:g}, {longest:.3g}] s for this model (at least {MIN_SAMPLE_TIME:g} s: "
            f"a budget of 1e5 calls per second; at most {MAX_UNSTABLE_GROWTH:g} / {rate:.4g} 1/s, the fastest unstable rate "
            f"upright), got {h!r}"
        )
    return h


def _with_estimator(
    ctrl: SampledController, x0: np.ndarray, model: Model, estimator: Any, u_max: float | None
) -> SampledController:
    """``ctrl`` itself, or wrapped to see the estimate of ``estimator`` (a name or an object)."""
    if estimator is None:
        return ctrl
    from .robust import EstimatedController, build_estimator

    limit = np.array([np.inf if u_max is None else float(u_max) if n in ctrl.input_names else 0.0 for n in INPUT_NAMES])
    est = build_estimator(estimator, model, float(ctrl.sample_time), x0=x0, torque_limit=limit)
    return EstimatedController(ctrl, est)


def _make_plain(
    name: str,
    model: Model,
    h: float,
    u_max: float,
    t_ref: float,
    reference: tuple[np.ndarray, np.ndarray, np.ndarray] | None,
    actuation: str,
    nmpc_solver: str,
) -> tuple[SampledController, np.ndarray]:
    """The named controller without an estimator (see :func:`make_controller`)."""
    if name == "lqr":
        x0 = upright_state(model)
        x0[0] += 0.1
        return balance_controller(model, h, actuation=actuation), x0
    if name == "swingup":
        if actuated_inputs(actuation) != INPUT_NAMES:
            raise ValueError(f"the energy swing-up drives both torques; actuation must be 'full', got {actuation!r}")
        return energy_swingup(model, h, u_max=u_max), model.state(theta1=0.1)
    if name == "tvlqr":
        if reference is None:
            n_ref = round(positive_float("t_ref", t_ref, "[s]") / h)
            if n_ref > MAX_REFERENCE_SAMPLES:
                raise ValueError(
                    f"t_ref must be at most {MAX_REFERENCE_SAMPLES} samples of {h:g} s "
                    f"(the TVLQR gains are one matrix per sample), got {t_ref!r}"
                )
            reference = swingup_reference(model, h, max(n_ref, 1) * h, u_max=u_max)
        tracker = tvlqr_tracker(model, *reference, h, u_max=u_max, actuation=actuation)
        return tracker, tracker.x_ref[0].copy()
    if name == "nmpc":
        from .nmpc import nmpc_swingup

        return nmpc_swingup(model, h, actuation=actuation, u_max=u_max, reference=reference, solver=nmpc_solver)
    raise ValueError(f"controller must be one of {list(CONTROLLERS)}, got {name!r}")


#: Names accepted by :func:`controller_for_task`.
TASK_CONTROLLERS: tuple[str, ...] = ("lqr", "tvlqr", "swingup", "nmpc", "robust")


@checked()
def controller_for_task(
    name: str,
    task: Task | str,
    *,
    sample_time: float | None = None,
    nmpc_solver: str = "sqp",
    estimator: str | StateEstimator | None = None,
) -> tuple[SampledController, np.ndarray]:
    """A named controller designed for a swing-up task, and the task's start state.

    Every controller uses the task's model, actuation and torque limit, so the
    same task compares controllers on equal terms (scorecard, leaderboard).

    Parameters
    ----------
    name : {"lqr", "tvlqr", "swingup", "nmpc", "robust"}
        ``lqr``: discrete LQR balance about upright (no swing-up: from hanging it
        is expected to fail; it is the baseline); ``robust`` (the leaderboard tasks
        ``swingup_pendubot`` / ``swingup_acrobot`` only, 2 ms): the score-designed plan's TVLQR fed by
        a delay-identifying EKF (:func:`pendulab.control.robust.robust_controller`); ``tvlqr``: TVLQR along the
        task's plan (:meth:`~pendulab.control.swingup.tasks.Task.plan`, computed
        once per task), handing over to LQR balance; ``swingup``: energy pumping with the
        task's driven torques, then LQR balance; ``nmpc``: tracking NMPC of the
        task's optimized swing-up, then regulation upright
        (:func:`pendulab.control.nmpc.nmpc_for_task`).
    task : Task or str
        Swing-up task (model, actuation, torque limit, start), or its name (``pendubot``;
        ``swingup_pendubot`` is an alias).
    sample_time : float, optional
        Controller sample time [s]; default the task's ``dt`` (``nmpc``: 0.02 s).
    nmpc_solver : {"sqp", "ipopt", "fatrop"}
        NLP solver of ``nmpc``.
    estimator : {"ekf", "mmae"} or StateEstimator, optional
        Feed the controller a state estimate (see :func:`make_controller`); for ``robust``
        it replaces the default delay-identifying estimator.

    Returns
    -------
    controller : SampledController
        Saturated at the task's torque limit.
    x0 : ndarray, shape (nx,)
        The task's start state.

    Raises
    ------
    ValueError
        Unknown ``name``, a non-positive ``sample_time``, or a task whose
        plan failed (``tvlqr``).
    TypeError
        ``name`` is not a string, ``task`` neither a Task nor a name.
    FileNotFoundError
        Unknown task name.

    Examples
    --------
    >>> import pendulab as pl
    >>> from pendulab.control import as_feedback, controller_for_task
    >>> from pendulab.control.swingup.check import height_success
    >>> from pendulab.control.swingup.tasks import load_task
    >>> task = load_task("acrobot")  # RealAIGym acrobot: tau2 only, 6 N.m, 10 s
    >>> for name in ("lqr", "tvlqr"):
    ...     ctrl, x0 = controller_for_task(name, task)
    ...     traj = pl.simulate(task.model, x0, task.t_final, dt=ctrl.sample_time, u=as_feedback(ctrl, task.model))
    ...     print(name, height_success(traj, task.rest_lengths).success)
    lqr False
    tvlqr True
    """
    from .swingup.tasks import resolve_task

    if not isinstance(name, str):
        raise TypeError(f"name must be a controller name (one of {list(TASK_CONTROLLERS)}), got {type(name).__name__}")
    if name not in TASK_CONTROLLERS:
        raise ValueError(f"controller must be one of {list(TASK_CONTROLLERS)}, got {name!r}")
    task = resolve_task(task)
    pb, model = task.problem, task.model
    if name == "robust":
        from .realai.spec import DT
        from .robust import robust_controller

        lb = task.name
        if lb not in ("pendubot", "acrobot"):
            raise ValueError(
                f"robust is designed for the leaderboard tasks swingup_pendubot and swingup_acrobot, got task {task.name!r}"
            )
        if sample_time is not None and abs(float(sample_time) - DT) > 1e-12:
            raise ValueError(f"robust runs at the leaderboard's {DT} s; sample_time must be {DT} or None, got {sample_time!r}")
        est = None
        if estimator is not None:
            from .realai.spec import leaderboard_model
            from .robust import build_estimator

            limit = np.array([pb.torque_limit if n in actuated_inputs(pb.actuation) else 0.0 for n in INPUT_NAMES])
            est = build_estimator(estimator, leaderboard_model(lb), DT, x0=pb.start, torque_limit=limit)
        return robust_controller(lb, estimator=est), pb.start
    if name == "nmpc":
        from .nmpc import nmpc_for_task

        h = check_sample_time(model, 0.02 if sample_time is None else sample_time)
        ctrl0, x0 = nmpc_for_task(task, sample_time=h, solver=nmpc_solver)
        return _with_estimator(ctrl0, x0, model, estimator, pb.torque_limit), x0
    h = check_sample_time(model, task.dt if sample_time is None else sample_time)
    if name == "lqr":
        ctrl: SampledController = balance_controller(model, h, design="discrete", actuation=pb.actuation, u_max=pb.torque_limit)
    elif name == "tvlqr":
        res = task.plan().result
        if not res.success:
            raise ValueError(f"tvlqr: the swing-up plan of task {task.name!r} did not solve: {res.message}")
        ctrl = tvlqr(res, dt=h)
    elif name == "swingup":
        ctrl = energy_swingup(model, h, u_max=pb.torque_limit, actuation=pb.actuation)
    else:
        raise ValueError(f"controller must be one of {list(TASK_CONTROLLERS)}, got {name!r}")
    return _with_estimator(ctrl, pb.start, model, estimator, pb.torque_limit), pb.start
