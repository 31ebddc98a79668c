"""The one table of controllers the RealAIGym protocols accept by name, and how a name, object or factory becomes one.

Every protocol (leaderboard v2 :func:`~pendulab.evaluate.realai.realai_score`, robustness v2
:func:`~pendulab.evaluate.realai.robustness.robustness_v2`, v3 :func:`~pendulab.evaluate.realai.v3.v3_score`)
and ``pendulab score --protocol ...`` resolve controllers here, so a new controller plugs in with one entry.
Each factory takes the leaderboard task (``"pendubot"`` or ``"acrobot"``) and designs on pendulab's own model.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from ..._inputs import checked
from ...control.controllers import controller_for_task
from ...control.feedback import SampledController
from ...control.realai.adapter import REALAI_METHODS, check_realai_controller, from_realai, is_realai_controller
from ...control.realai.design import best_controller
from ...control.realai.spec import PLAN_VELOCITY_LIMIT_HW, leaderboard_task

__all__ = [
    "CONTROLLERS", "RATE_BOUNDED", "PLANT_DESIGNED", "LIBRARY_PLAYERS", "PLAN_VELOCITY_LIMIT_HW", "REPLAN_DELAY",
    "controller_name", "library_bound", "resolve_controller",
]  # fmt: skip

#: Prediction horizon of ``replan_delayed`` [s]: a background solver has this long (measured solves: 0.1-2 s).
REPLAN_DELAY: float = 0.5


def _task_controller(name: str) -> Callable[[str], SampledController]:
    def make(task: str) -> SampledController:
        ctrl, _ = controller_for_task(name, leaderboard_task(task))
        return ctrl

    make.__name__ = name
    return make


def _global(task: str) -> SampledController:
    from ...control.global_swingup import global_controller  # imported on use: builds on the swing-up solver

    return global_controller(task)


def _replan(task: str, velocity_limit: float | None = None) -> SampledController:
    from ...control.replanning import replanning_controller

    return replanning_controller(task, velocity_limit=velocity_limit)


def _rti(task: str) -> SampledController:
    from ...control.nmpc.rti import rti_for_task  # imported on use: compiles (once, cached) the 500 Hz RTI step

    return rti_for_task(leaderboard_task(task))[0]


def _mpc(task: str, plant: Any = None) -> SampledController:
    from ...control.realai.mpc import goal_mpc  # imported on use: compiles (once, cached) the 500 Hz RTI step

    return goal_mpc(task, plant)


def _mpc_library(task: str, velocity_limit: float | None = None, plant: Any = None) -> SampledController:
    from ...control.realai.guided_mpc import guided_mpc  # builds the bounded library first

    return guided_mpc(task, plant, velocity_limit=PLAN_VELOCITY_LIMIT_HW if velocity_limit is None else velocity_limit)


def _replan_delayed(task: str, velocity_limit: float | None = None) -> SampledController:
    from ...control.replanning import replanning_controller

    return replanning_controller(task, plan_delay=REPLAN_DELAY, velocity_limit=velocity_limit)


def _library(task: str, velocity_limit: float | None = None) -> SampledController:
    from ...control.plan_library import library_controller  # builds (or completes) ./pendulab-out/plan_library first

    return library_controller(task, velocity_limit=velocity_limit)


#: Controller names -> factory ``task -> SampledController`` (add an entry to plug a new name in).
CONTROLLERS: dict[str, Callable[[str], SampledController]] = {
    "best": best_controller,
    "tvlqr": _task_controller("tvlqr"),
    "lqr": _task_controller("lqr"),
    "swingup": _task_controller("swingup"),
    "nmpc": _task_controller("nmpc"),
    "rti": _rti,
    "mpc": _mpc,
    "mpc_library": _mpc_library,
    "robust": _task_controller("robust"),
    "global": _global,
    "replan": _replan,
    "replan_delayed": _replan_delayed,
    "library": _library,
}


#: Names whose factory plans swing-ups and takes ``velocity_limit`` (a bound on both joint rates of every plan
#: [rad/s]); the others (state feedback, pumping, fixed trajectories) have no plan to bound.
RATE_BOUNDED: frozenset[str] = frozenset({"replan", "replan_delayed", "library", "mpc_library"})

#: Names whose factory takes ``plant`` (the identified robot a protocol simulates) and designs on it; the others
#: design on pendulab's leaderboard model whatever the plant.
PLANT_DESIGNED: frozenset[str] = frozenset({"mpc", "mpc_library"})


#: Names whose controller plays the cached plan library: it is built (minutes of IPOPT at first use, with a progress
#: bar of its own) before their first run, and their results name it (:meth:`PlanLibrary.digest`).
LIBRARY_PLAYERS: frozenset[str] = frozenset({"library", "mpc_library"})


def library_bound(name: str, hardware: bool) -> float | None:
    """The rate bound [rad/s] of the plans controller ``name`` plays (None: unbounded), as it is built by
    :func:`resolve_controller` on a protocol (``hardware``: the v3-hardware protocol's bound is passed).

    Parameters
    ----------
    name : str
        A name of :data:`LIBRARY_PLAYERS`.
    hardware : bool
        The hardware protocol (which bounds the plans of every name in :data:`RATE_BOUNDED`).

    Returns
    -------
    float or None

    Raises
    ------
    ValueError
        ``name`` plays no plan library.
    """
    if name not in LIBRARY_PLAYERS:
        raise ValueError(f"controller {name!r} plays no plan library; those that do: {sorted(LIBRARY_PLAYERS)}")
    # mpc_library plays the rate-bounded library on every protocol (guided_mpc's default)
    return PLAN_VELOCITY_LIMIT_HW if hardware or name == "mpc_library" else None


def _is_controller(obj: Any) -> bool:
    return callable(obj) and hasattr(obj, "sample_time") and hasattr(obj, "input_names") and hasattr(obj, "reset")


@checked()
def resolve_controller(
    task: str,
    controller: str | SampledController | Callable[[str], Any],
    *,
    velocity_limit: float | None = None,
    plant: Any = None,
) -> tuple[str, SampledController]:
    """A controller for a leaderboard task from a name, an object or a factory.

    Parameters
    ----------
    task : {"pendubot", "acrobot"}
        Leaderboard task.
    controller : str, SampledController or callable
        A name of :data:`CONTROLLERS`; a :class:`~pendulab.control.feedback.SampledController`
        (``reset()``, ``__call__(t, x)``, ``sample_time``, ``input_names``); or a factory
        ``task -> SampledController`` (or ``-> (SampledController, x0)``, as the scorecard's); or a RealAIGym
        controller (``init``, ``get_control_output(x, t)``, ``reset``: upstream's ``AbstractController``), run
        through :func:`~pendulab.control.realai.adapter.from_realai` at 2 ms on the task's driven joint.
    velocity_limit : float, optional
        Bound on both joint rates of every plan [rad/s], given to the names of :data:`RATE_BOUNDED` (the others,
        objects and factories are built as they are); None: unbounded.
    plant : IdentifiedPlant, optional
        The robot the protocol simulates, given to the names of :data:`PLANT_DESIGNED` (they design on it).

    Returns
    -------
    name : str
        The name (the factory's or the class's ``__name__`` for objects).
    controller : SampledController
        Built for ``task``.

    Raises
    ------
    ValueError
        Unknown name.
    InputError
        ``velocity_limit`` not a finite positive rate (its declaration in :data:`pendulab._inputs.INPUTS`).
    TypeError
        Neither a name, a controller nor a factory, or a factory returning something else.
    """
    name = controller_name(controller)
    if isinstance(controller, str):
        extra: dict[str, Any] = {}
        if velocity_limit is not None and controller in RATE_BOUNDED:
            extra["velocity_limit"] = velocity_limit
        if plant is not None and controller in PLANT_DESIGNED:
            extra["plant"] = plant
        return name, CONTROLLERS[controller](task, **extra)
    if _is_controller(controller):
        return name, controller  # type: ignore[return-value]
    if is_realai_controller(controller):
        return name, from_realai(controller, task=task)
    made = controller(task)  # type: ignore[operator]
    if isinstance(made, tuple) and len(made) == 2:
        made = made[0]
    if not _is_controller(made):
        raise TypeError(f"a controller factory must return a SampledController, got {type(made).__name__}")
    return name, made


def controller_name(controller: str | SampledController | Callable[[str], Any]) -> str:
    """The name :func:`resolve_controller` gives ``controller``, without building it (journals are checked first).

    Parameters
    ----------
    controller : str, SampledController or callable
        As for :func:`resolve_controller`.

    Returns
    -------
    str
        The name; the factory's or the class's ``__name__`` for objects.

    Raises
    ------
    ValueError
        Unknown name.
    TypeError
        Neither a name, a controller nor a factory.
    """
    if isinstance(controller, str):
        if controller not in CONTROLLERS:
            raise ValueError(f"controller must be one of {list(CONTROLLERS)} or a SampledController, got {controller!r}")
        return controller
    if _is_controller(controller) or is_realai_controller(controller):
        return type(controller).__name__
    if callable(controller):
        return getattr(controller, "__name__", type(controller).__name__)
    if any(hasattr(controller, m) for m in REALAI_METHODS):
        check_realai_controller(controller)  # part of upstream's interface: name what is missing
    raise TypeError(f"controller must be a name, a SampledController or a factory task -> controller, got {type(controller)}")
