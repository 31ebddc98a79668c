"""Scenes: a pendulum, an initial state, a horizon and what the user cares about, as TOML.

A scene file has the sections ``[scene]``, ``[model]`` (with ``[model.params]``),
``[initial]`` (state values by name, and ``start``: how unstated spring
lengths are set), ``[simulation]``, ``[outputs]`` and ``[input]`` (constant
torques, plus an optional ``[input.sine]``); any other
top-level section (e.g. ``[task]``) is kept verbatim in ``Scene.extra`` for the
feature that uses it. Every key of the known sections is validated: a typo is
an error naming the file, the section, the key, the value and what was
expected, never a silently ignored setting. See ``docs/scenes.md``.

Shipped scenes live in ``pendulab/scenes/*.toml`` and are loaded by name:
``load_scene("seed_paper")``. Two groups sit in subdirectories: the cases of
the work-precision study (``"bench/rigid_chaotic_10s"``) and the FMU
validation scenes (``"validation/rigid_forced"``); ``list_scenes("bench")``
lists a group. Every scene of the project -- user scenes, benchmark cases,
validation scenes and swing-up tasks -- is this one type.
"""

from .choice import ModelChoice, choose_model
from .core import GROUPS, SCENE_DIR, STARTS, Scene, default_scene, initial_state, list_scenes, scene_path
from .reader import load_scene

__all__ = [
    "Scene",
    "load_scene",
    "choose_model",
    "ModelChoice",
    "list_scenes",
    "default_scene",
    "scene_path",
    "initial_state",
    "SCENE_DIR",
    "STARTS",
    "GROUPS",
]
