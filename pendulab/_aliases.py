"""Deprecated names, kept for one release: the one table of moved and renamed public names.

Old names keep working with a ``DeprecationWarning`` that names the new place.
This module sits above every layer and is installed by ``pendulab/__init__.py``
as an import hook (:class:`_AliasFinder`), so no package reaches up to a
higher layer to keep an old name alive (``pendulab.fmu.cosim`` used to load
``pendulab.cosim`` through ``importlib`` from inside ``fmu/``):

* :data:`MOVED_MODULES`: a module that moved; the old path is a module whose
  every attribute forwards to the new one (names renamed on the way are in
  :data:`RENAMED`);
* :data:`RENAMED`: ``(module, old name) -> "new.module:new_name"``, served by a
  module ``__getattr__`` that the hook adds to ``module`` when it is imported.

The package's architecture test lists this module as the top layer, with the CLI.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import importlib.util
import sys
import types
import warnings
from collections.abc import Callable, Sequence
from typing import Any

__all__ = ["MOVED_MODULES", "RENAMED", "install"]

#: Old module -> new module.
MOVED_MODULES: dict[str, str] = {
    "pendulab.control.tasks": "pendulab.control.swingup.tasks",
    "pendulab.control.scorecard": "pendulab.evaluate.scorecard",
    "pendulab.control.perturb": "pendulab.evaluate.perturb",
    "pendulab.control.realai.criteria": "pendulab.evaluate.realai.criteria",
    "pendulab.control.realai.simulate": "pendulab.evaluate.realai.simulate",
}

_EVAL = "pendulab.evaluate"
_REALAI = "pendulab.evaluate.realai"
#: (module, old name) -> "new.module:new_name".
RENAMED: dict[tuple[str, str], str] = {
    # fmu -> cosim (the co-simulation master moved up a layer)
    ("pendulab.fmu", "cosim"): "pendulab.cosim:cosim",
    ("pendulab.fmu", "cosim_many"): "pendulab.cosim:cosim_many",
    ("pendulab.fmu", "StepRejectedError"): "pendulab.cosim:StepRejectedError",
    # control -> evaluate (evaluation is its own layer above control)
    **{("pendulab.control", n): f"{_EVAL}:{n}" for n in ("CATEGORIES", "Scorecard", "Perturbation", "rerun", "score")},
    ("pendulab.control", "RealAIResult"): f"{_REALAI}:RealAIResult",
    ("pendulab.control", "realai_score"): f"{_REALAI}:realai_score",
    **{
        ("pendulab.control.realai", n): f"{_REALAI}:{n}"
        for n in ("CONTROLLER_NAMES", "CRITERIA", "PUBLISHED", "RealAIResult", "realai_score", "to_relative")
    },
    ("pendulab.control.perturb", "run_episode"): f"{_EVAL}.perturb:run_perturbed_episode",
    ("pendulab.control.realai", "run"): f"{_REALAI}:run_leaderboard",
    ("pendulab.control.realai.simulate", "run"): f"{_REALAI}.simulate:run_leaderboard",
    ("pendulab.control.realai.criteria", "score"): f"{_REALAI}.criteria:score_v2",
    ("pendulab.control.realai.simulate", "leaderboard_model"): "pendulab.control.realai.spec:leaderboard_model",
    ("pendulab.control.realai.simulate", "leaderboard_task"): "pendulab.control.realai.spec:leaderboard_task",
    # modules split in two
    ("pendulab.native.library", "native_library"): "pendulab.native.loader:native_library",
    ("pendulab.native.library", "loaded_libraries"): "pendulab.native.loader:loaded_libraries",
    # one name per concept
    ("pendulab.control.realai", "Plan"): "pendulab.control.realai.design:LeaderboardPlan",
    ("pendulab.control.realai.design", "Plan"): "pendulab.control.realai.design:LeaderboardPlan",
    ("pendulab.control.swingup.errors", "Plan"): "pendulab.control.swingup.errors:PlanTrajectory",
    ("pendulab.control.swingup.guess", "rigid_counterpart"): "pendulab.control.swingup.guess:rigid_counterpart_problem",
    ("pendulab.control.swingup.solve", "swing_up"): "pendulab.control.swingup.solve:solve_transcription",
    ("pendulab.bench.fmu_methods", "fmu_runner"): "pendulab.bench.fmu_methods:fmu_bench_runner",
    ("pendulab.bench.hierarchy", "choose_model"): "pendulab.bench.hierarchy:measure_model_choice",
    ("pendulab.integrate.compiled", "unavailable_reason"): "pendulab.integrate.compiled:compiled_unavailable_reason",
    ("pendulab.integrate.taylor.availability", "unavailable_reason"): (
        "pendulab.integrate.taylor.availability:taylor_unavailable_reason"
    ),
}


def _target(where: str) -> Any:
    module, name = where.split(":")
    return getattr(importlib.import_module(module), name)


def _warn(old: str, new: str) -> None:
    warnings.warn(f"{old} is deprecated; use {new}", DeprecationWarning, stacklevel=3)


def _module_getattr(module: str, fallback: Callable[[str], Any] | None) -> Callable[[str], Any]:
    renamed = {old: new for (mod, old), new in RENAMED.items() if mod == module}

    def forward(name: str) -> Any:
        if name in renamed:
            _warn(f"{module}.{name}", renamed[name].replace(":", "."))
            return _target(renamed[name])
        if fallback is not None:
            return fallback(name)
        raise AttributeError(f"module {module!r} has no attribute {name!r}")

    return forward


def _patch(module: types.ModuleType) -> None:
    if any(mod == module.__name__ for mod, _ in RENAMED) and not getattr(module, "_pendulab_aliases", False):
        module.__getattr__ = _module_getattr(module.__name__, module.__dict__.get("__getattr__"))  # type: ignore[method-assign]
        module._pendulab_aliases = True  # type: ignore[attr-defined]


class _MovedModuleLoader(importlib.abc.Loader):
    """Creates the old module: every attribute forwards to the new module, with a warning."""

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> types.ModuleType | None:
        return None

    def exec_module(self, module: types.ModuleType) -> None:
        old, new = module.__name__, MOVED_MODULES[module.__name__]
        renamed = _module_getattr(old, None)
        module.__doc__ = f"Deprecated alias of :mod:`{new}` (kept for one release)."

        def forward(name: str) -> Any:
            if name.startswith("__"):
                raise AttributeError(name)
            if (old, name) in RENAMED:
                return renamed(name)
            target = importlib.import_module(new)
            if not hasattr(target, name):
                raise AttributeError(f"module {old!r} has no attribute {name!r}")
            _warn(f"{old}.{name}", f"{new}.{name}")
            return getattr(target, name)

        module.__getattr__ = forward  # type: ignore[method-assign]
        module.__dir__ = lambda: dir(importlib.import_module(new))  # type: ignore[method-assign]


class _PatchingLoader(importlib.abc.Loader):
    """The module's own loader, then the module ``__getattr__`` of its renamed names."""

    def __init__(self, loader: Any) -> None:
        self._loader = loader

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> types.ModuleType | None:
        return self._loader.create_module(spec)

    def exec_module(self, module: types.ModuleType) -> None:
        self._loader.exec_module(module)
        _patch(module)

    def __getattr__(self, name: str) -> Any:  # get_source, get_resource_reader, is_package, ...
        return getattr(self._loader, name)


class _AliasFinder(importlib.abc.MetaPathFinder):
    def find_spec(
        self, fullname: str, path: Sequence[str] | None, target: types.ModuleType | None = None
    ) -> importlib.machinery.ModuleSpec | None:
        if fullname in MOVED_MODULES:
            return importlib.util.spec_from_loader(fullname, _MovedModuleLoader())
        if any(mod == fullname for mod, _ in RENAMED):
            spec = importlib.machinery.PathFinder.find_spec(fullname, path)
            if spec is not None and spec.loader is not None:
                spec.loader = _PatchingLoader(spec.loader)
            return spec
        return None


def install() -> None:
    """Install the hook (once) and patch the modules with renamed names that are already imported."""
    if not any(isinstance(f, _AliasFinder) for f in sys.meta_path):
        sys.meta_path.insert(0, _AliasFinder())
    for mod, _ in RENAMED:
        if mod in sys.modules:
            _patch(sys.modules[mod])
