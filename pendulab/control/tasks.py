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
    N = 100
    method = "radau"             # radau | legendre | shooting
    degree = 3
    success_fraction = 0.9

``[simulation] t_final`` is the episode length, ``[simulation] dt`` the
controller sample time, ``[initial]`` the start state by name and an optional
``[task.goal]`` the goal state by name (default: upright at rest).
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..model.model import Model, make_model
from .problem import SwingUpProblem, upright_state

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib

__all__ = ["Task", "load_task", "task_names", "SCENE_DIR"]

SCENE_DIR = Path(__file__).resolve().parent.parent / "scenes"
_PREFIX = "swingup_"
_TASK_KEYS = {
    "actuation", "torque_limit", "velocity_limit", "stretch_limits", "horizon", "free_horizon", "horizon_bounds",
    "objective", "time_weight", "N", "method", "degree", "success_fraction", "goal",
}  # fmt: skip


@dataclass(frozen=True)
class Task:
    """A swing-up task: the problem plus episode and solver settings.

    Attributes
    ----------
    name, description : str
    problem : SwingUpProblem
    t_final : float
        Episode length [s] (swing-up plus hold).
    dt : float
        Controller sample time [s].
    N : int
    method : str
    degree : int
    success_fraction : float
        End effector must stay above this fraction of L1 + L2.
    path : Path or None
    """

    name: str
    description: str
    problem: SwingUpProblem
    t_final: float
    dt: float
    N: int
    method: str
    degree: int
    success_fraction: float
    path: Path | None = None

    @property
    def model(self) -> Model:
        return self.problem.model

    @property
    def rest_lengths(self) -> tuple[float, float]:
        return (self.model.params.L1, self.model.params.L2)


def task_names() -> tuple[str, ...]:
    """Names of the shipped tasks (``pendulab/scenes/swingup_<name>.toml``)."""
    return tuple(sorted(p.stem[len(_PREFIX) :] for p in SCENE_DIR.glob(_PREFIX + "*.toml")))


def load_task(name_or_path: str | Path) -> Task:
    """Load a shipped task by name (see :func:`task_names`) or a scene file with a ``[task]`` section.

    Raises
    ------
    FileNotFoundError
        Unknown name and no such file.
    ValueError
        Missing or malformed sections/keys.
    """
    path = Path(name_or_path)
    if not path.suffix:
        shipped = SCENE_DIR / f"{_PREFIX}{name_or_path}.toml"
        if not shipped.exists():
            raise FileNotFoundError(f"unknown task {str(name_or_path)!r}; shipped tasks: {list(task_names())}")
        path = shipped
    if not path.exists():
        raise FileNotFoundError(f"scene file {str(path)!r} does not exist")
    with path.open("rb") as fh:
        try:
            data = tomllib.load(fh)
        except tomllib.TOMLDecodeError as exc:
            raise ValueError(f"scene file {str(path)!r} is not valid TOML: {exc}") from exc
    return _task_from_dict(data, path)


def _section(data: dict[str, Any], key: str, path: Path, required: bool = True) -> dict[str, Any]:
    sec = data.get(key, {})
    if required and key not in data:
        raise ValueError(f"scene {str(path)!r} has no [{key}] section (needed for a swing-up task)")
    if not isinstance(sec, dict):
        raise ValueError(f"[{key}] in {str(path)!r} must be a table, got {sec!r}")
    return sec


def _task_from_dict(data: dict[str, Any], path: Path) -> Task:
    scene = _section(data, "scene", path, required=False)
    model_sec = _section(data, "model", path)
    task = _section(data, "task", path)
    sim = _section(data, "simulation", path, required=False)
    unknown = sorted(set(task) - _TASK_KEYS)
    if unknown:
        raise ValueError(f"unknown key(s) {unknown} in [task] of {str(path)!r}; expected some of {sorted(_TASK_KEYS)}")
    if "actuation" not in task:
        raise ValueError(f"[task] of {str(path)!r} must set actuation (pendubot, acrobot or full)")
    model = make_model(model_sec.get("kind", "rigid"), **dict(model_sec.get("params", {})))
    x0 = model.state(**dict(data.get("initial", {})))
    goal = upright_state(model)
    for name, value in dict(task.get("goal", {})).items():
        if name not in model.state_names:
            raise ValueError(f"unknown state {name!r} in [task.goal]; expected one of {list(model.state_names)}")
        goal[model.state_names.index(name)] = float(value)
    kw = {
        k: task[k] for k in ("torque_limit", "velocity_limit", "horizon", "free_horizon", "objective", "time_weight") if k in task
    }
    for k in ("stretch_limits", "horizon_bounds"):
        if k in task:
            kw[k] = tuple(task[k])
    name = str(scene.get("name", path.stem))
    problem = SwingUpProblem(model=model, actuation=task["actuation"], x0=x0, goal=goal, name=name, **kw)
    return Task(
        name=name,
        description=str(scene.get("description", "")),
        problem=problem,
        t_final=float(sim.get("t_final", 10.0)),
        dt=float(sim.get("dt", 0.01)),
        N=int(task.get("N", 100)),
        method=str(task.get("method", "radau")),
        degree=int(task.get("degree", 3)),
        success_fraction=float(task.get("success_fraction", 0.9)),
        path=path,
    )
