"""Swing-up tasks: scenes (TOML, the shared scene format) with a ``[task]`` section.

Shipped tasks live in ``pendulab/scenes/swingup_<name>.toml``. The ``[task]``
section holds what the scene format itself does not (all optional except
``actuation``)::

    [task]
    actuation = "pendubot"       # pendubot | acrobot | full
    torque_limit = 6.0           # N.m
    velocity_limit = 20.0        # rad/s (optional)
    stretch_limits = [-0.05, 0.05]   # m, elastic only (optional)
    horizon = 3.0                # s (guess of T when free_horizon)
    free_horizon = false
    horizon_bounds = [0.5, 10.0]
    objective = "effort"         # effort | time | mix
    time_weight = 1.0
    torque_margin = 0.9          # plan within this fraction of torque_limit (default: 0.9 time/mix, 1.0 effort)
    tolerance = 1e-3             # relative defect the plan must meet on the task's dynamics
    planning = "auto"            # auto | rigid | quasi-static | elastic (planning model of elastic tasks)
    N = 100                      # intervals of the first mesh (default 100), carried by the problem as `intervals`
    method = "radau"             # radau | legendre | shooting
    degree = 3
    success_fraction = 0.9

``[simulation] t_final`` is the episode length, ``[simulation] dt`` the
controller sample time, ``[initial]`` the start state by name and an optional
``[task.goal]`` the goal state by name (default: upright at rest).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ...model.model import Model
from ...scene import SCENE_DIR, Scene, load_scene
from ..feedback import upright_state
from .problem import SwingUpProblem
from .rule import PLANNING

if TYPE_CHECKING:
    from .planning import Plan

__all__ = ["Task", "load_task", "task_names", "resolve_task", "short_name"]

_PREFIX = "swingup_"
_TASK_KEYS = {
    "actuation", "torque_limit", "velocity_limit", "stretch_limits", "horizon", "free_horizon", "horizon_bounds",
    "objective", "time_weight", "N", "method", "degree", "success_fraction", "goal",
    "torque_margin", "tolerance", "planning",
}  # fmt: skip


@dataclass(frozen=True)
class Task:
    """A swing-up task: a scene, the optimal-control problem its ``[task]`` section states, and solver settings.

    Attributes
    ----------
    scene : Scene
        The scene (model, start, episode length ``t_final``, controller sample time ``dt``).
    problem : SwingUpProblem
        The swing-up problem.
    N : int
        Intervals of the first mesh (``problem.intervals``: the same N for the CLI and ``swing_up(task.problem)``).
    method : str
        Transcription (``radau``, ``legendre``, ``shooting``).
    degree : int
        Collocation degree.
    success_fraction : float
        End effector must stay above this fraction of L1 + L2.
    tolerance : float
        Relative defect the plan must meet on the task's own dynamics (error estimate).
    planning : str
        Planning model of an elastic task (``auto``, ``rigid``, ``quasi-static``,
        ``elastic``; see :mod:`pendulab.control.swingup.planning`).
    """

    scene: Scene
    problem: SwingUpProblem
    N: int
    method: str
    degree: int
    success_fraction: float
    tolerance: float = 1e-3
    planning: str = "auto"
    _plans: dict[str, Any] = field(default_factory=dict, init=False, repr=False, compare=False)

    def plan(self) -> Plan:
        """The task's swing-up plan, computed once per task and kept (what controllers of the task track).

        :func:`pendulab.control.swingup.planning.plan` with the task's settings
        (``planning``, ``tolerance``, ``method``, ``N``, ``degree``): the planning
        rule for an elastic task, the transcription for a rigid one. A failed plan
        is kept too (``plan().success`` is False; solving again would fail again).

        Returns
        -------
        Plan
            The plan, its decision and its error estimate on the task's dynamics.
        """
        if "plan" not in self._plans:
            from .planning import plan

            self._plans["plan"] = plan(
                self.problem, planning=self.planning, tolerance=self.tolerance, method=self.method, N=self.N, degree=self.degree
            )
        return self._plans["plan"]

    @property
    def name(self) -> str:
        """Task name: the short form (``pendubot``) of a shipped task's scene ``swingup_pendubot``; else the scene's name."""
        return short_name(self.scene.name)

    @property
    def description(self) -> str:
        """The scene's description."""
        return self.scene.description

    @property
    def t_final(self) -> float:
        """Episode length [s] (swing-up plus hold)."""
        return self.scene.t_final

    @property
    def dt(self) -> float:
        """Controller sample time [s]."""
        return self.scene.dt

    @property
    def path(self) -> Path | None:
        """The scene file."""
        return self.scene.path

    @property
    def model(self) -> Model:
        """The problem's model (the scene's, with the problem's parameters)."""
        return self.problem.model

    def with_model(self, model: Model) -> Task:
        """The same task on another model of the same kind, e.g. an identified robot (``pl.rigid(plant=FILE)``).

        Parameters
        ----------
        model : Model
            The new model (start, limits, horizon and solver settings stay the task's).

        Returns
        -------
        Task
            A new task (its plan is computed afresh, on ``model``).

        Raises
        ------
        TypeError
            ``model`` is not a Model.
        ValueError
            ``model`` is of another kind than the task's.
        """
        if not isinstance(model, Model):
            raise TypeError(f"model must be a pendulab Model, got {type(model).__name__}")
        if model.kind != self.model.kind:
            raise ValueError(f"task {self.name!r} is {self.model.kind}; a {model.kind} model cannot replace its model")
        return dataclasses.replace(self, problem=dataclasses.replace(self.problem, model=model))

    @property
    def rest_lengths(self) -> tuple[float, float]:
        """Link lengths L1, L2 [m] (spring rest lengths) that the success height refers to."""
        return (self.model.params.L1, self.model.params.L2)


def short_name(name: str) -> str:
    """The one task-name scheme: ``swingup_pendubot`` -> ``pendubot`` (names without the prefix pass unchanged).

    Parameters
    ----------
    name : str
        A task name, short or long (the shipped scene's name).

    Returns
    -------
    str
        The short name when ``swingup_<short>`` is a shipped task, else ``name``.
    """
    if name.startswith(_PREFIX) and (SCENE_DIR / f"{name}.toml").is_file():
        return name[len(_PREFIX) :]
    return name


def resolve_task(task: Any, name: str = "task") -> Task:
    """A :class:`Task` from a task or a task name: the one rule of every public function that takes a task.

    Parameters
    ----------
    task : Task, str or Path
        A task, a shipped task name (``pendubot``; the long form ``swingup_pendubot``
        is an alias) or the path of a scene file with a ``[task]`` section.
    name : str
        Argument name used in the message.

    Returns
    -------
    Task
        ``task`` itself, or the loaded task.

    Raises
    ------
    TypeError
        ``task`` is neither a Task nor a name/path.
    FileNotFoundError
        Unknown task name.
    """
    if isinstance(task, Task):
        return task
    if isinstance(task, (str, Path)):
        return load_task(task)
    raise TypeError(f"{name} must be a swing-up Task or a task name (one of {list(task_names())}), got {type(task).__name__}")


def task_names() -> tuple[str, ...]:
    """Names of the shipped tasks (``pendulab/scenes/swingup_<name>.toml``).

    Returns
    -------
    tuple of str
        Sorted task names, without the ``swingup_`` prefix.
    """
    return tuple(sorted(p.stem[len(_PREFIX) :] for p in SCENE_DIR.glob(_PREFIX + "*.toml")))


def load_task(name_or_path: str | Path) -> Task:
    """Load a shipped task by name (see :func:`task_names`) or a scene file with a ``[task]`` section.

    The scene itself is read by :func:`pendulab.scene.load_scene` (validated there);
    this function interprets its ``[task]`` section.

    Parameters
    ----------
    name_or_path : str or Path
        A shipped task name (``swingup_<name>.toml`` in the scene directory),
        or the path of a scene file with a ``[task]`` section.

    Returns
    -------
    Task
        The scene, its :class:`SwingUpProblem` (goal default upright at rest,
        overridden by ``[task.goal]``) and the solver settings (defaults
        ``N = 100``, ``method = "radau"``, ``degree = 3``,
        ``success_fraction = 0.9``, ``tolerance = 1e-3``, ``planning = "auto"``).

    Raises
    ------
    FileNotFoundError
        Unknown name and no such file.
    ValueError
        Missing or malformed sections/keys.
    """
    if not isinstance(name_or_path, (str, Path)):
        raise TypeError(f"task must be a task name or a scene path, got {type(name_or_path).__name__}")
    text = str(name_or_path)
    if not Path(text).is_file() and (SCENE_DIR / f"{_PREFIX}{text}.toml").is_file():
        name_or_path = SCENE_DIR / f"{_PREFIX}{text}.toml"
    elif not Path(text).is_file() and not (SCENE_DIR / f"{text}.toml").is_file():
        raise FileNotFoundError(f"unknown task {text!r}; shipped tasks: {list(task_names())}")
    scene = load_scene(name_or_path)
    task = scene.extra.get("task")
    if not isinstance(task, dict):
        raise ValueError(f"scene {str(scene.path)!r} has no [task] table (needed for a swing-up task)")
    unknown = sorted(set(task) - _TASK_KEYS)
    if unknown:
        raise ValueError(f"unknown key(s) {unknown} in [task] of {str(scene.path)!r}; expected some of {sorted(_TASK_KEYS)}")
    if "actuation" not in task:
        raise ValueError(f"[task] of {str(scene.path)!r} must set actuation (pendubot, acrobot or full)")
    model = scene.model
    goal = upright_state(model)
    for name, value in dict(task.get("goal", {})).items():
        if name not in model.state_names:
            raise ValueError(f"unknown state {name!r} in [task.goal]; expected one of {list(model.state_names)}")
        goal[model.state_names.index(name)] = float(value)
    scalar_keys = ("torque_limit", "velocity_limit", "horizon", "free_horizon", "objective", "time_weight", "torque_margin")
    kw = {k: task[k] for k in scalar_keys if k in task}
    for k in ("stretch_limits", "horizon_bounds"):
        if k in task:
            kw[k] = tuple(task[k])
    if "N" in task:
        kw["intervals"] = task["N"]
    problem = SwingUpProblem(model=model, actuation=task["actuation"], x0=scene.x0, goal=goal, name=scene.name, **kw)
    planning = str(task.get("planning", "auto"))
    if planning not in PLANNING:
        raise ValueError(f"planning in [task] of {str(scene.path)!r} must be one of {list(PLANNING)}, got {planning!r}")
    tolerance = task.get("tolerance", 1e-3)
    if isinstance(tolerance, bool) or not isinstance(tolerance, (int, float)) or not 0.0 < tolerance < 1.0:
        raise ValueError(f"tolerance in [task] of {str(scene.path)!r} must be a relative defect in (0, 1), got {tolerance!r}")
    return Task(
        scene=scene,
        problem=problem,
        N=problem.intervals,
        method=str(task.get("method", "radau")),
        degree=int(task.get("degree", 3)),
        success_fraction=float(task.get("success_fraction", 0.9)),
        tolerance=float(tolerance),
        planning=planning,
    )
