"""One case of each RealAIGym protocol for the leaderboard (:mod:`.leaderboard`): run it, time it, journal it."""

from __future__ import annotations

import json
import statistics
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from ..._io import atomic_write_text
from ...control.realai.spec import DT
from .controllers import resolve_controller

__all__: list[str] = []


def _read(path: Path, settings: Mapping[str, Any]) -> dict[str, Any] | None:
    """A recorded case, or None when there is none; ValueError for a record of other settings."""
    if not path.is_file():
        return None
    try:
        data = json.loads(path.read_text())
        stored, summary = data["settings"], data["summary"]
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise ValueError(f"journal {path} is not a leaderboard record ({exc}); delete it or run without resume") from None
    if stored != dict(settings):
        raise ValueError(f"journal {path} was written with other settings ({stored} there, {dict(settings)} now); "
                         "use another journal directory or resume=False")  # fmt: skip
    return summary


def _write(path: Path, settings: Mapping[str, Any], summary: Mapping[str, Any]) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic_write_text(path, json.dumps({"settings": dict(settings), "summary": dict(summary)}) + "\n")


class _Timed:
    """A sampled controller whose calls are timed (wall clock) in :attr:`times`."""

    def __init__(self, ctrl: Any) -> None:
        self._ctrl = ctrl
        self.times: list[float] = []

    def __getattr__(self, name: str) -> Any:
        return getattr(self._ctrl, name)

    def reset(self) -> None:
        self._ctrl.reset()

    def __call__(self, t: float, x: Any) -> Any:
        t0 = time.perf_counter()
        u = self._ctrl(t, x)
        self.times.append(time.perf_counter() - t0)
        return u


def _run_v2(task: str, name: str, progress: Callable[[int, int], None] | None, plant: Any = None) -> dict[str, Any]:
    from .simulate import run_leaderboard

    w0 = time.perf_counter()
    _, ctrl = resolve_controller(task, name)
    timed = _Timed(ctrl)
    res = run_leaderboard(task, timed, name, progress=progress, plant=plant)
    d = res.to_dict()
    d["wall_time"] = time.perf_counter() - w0
    d["controller_time"] = {
        "median_per_call": float(statistics.median(timed.times)) if timed.times else 0.0,
        "max_per_call": float(max(timed.times)) if timed.times else 0.0,
        "calls": len(timed.times),
        "sample_time": float(ctrl.sample_time),
    }
    return d


def _run_robustness(
    task: str, name: str, journal: Path, reduced: Mapping[str, Any], resume: bool, workers: int,
    progress: Callable[[int, int], None] | None,
) -> tuple[dict[str, Any], int, int]:  # fmt: skip
    from .robustness import robustness_v2

    before = 0
    if resume and journal.is_file():
        try:
            before = len(json.loads(journal.read_text()).get("records", []))
        except (OSError, ValueError, AttributeError):
            before = 0  # robustness_v2 reports the broken journal itself
    res = robustness_v2(task, name, seed=0, workers=workers, progress=progress, journal=journal, resume=resume, **reduced)
    d = res.to_dict()
    d["wall_total"] = float(sum(r.get("wall", 0.0) for r in res.records))
    act = 0 if task == "pendubot" else 1
    pert = [r for r in res.records if r["category"] == "perturbation"]
    d["perturbation_amplitude"] = [float(max(abs(a) for a in r["amplitude"][act])) for r in pert]
    d["model_level_indices"] = sorted({int(r["level_index"]) for r in res.records if r["category"] == "model"})
    n = len(res.records)
    return d, n - before, before


def _run_v3(
    task: str, name: str, seed: int, steps: int, progress: Callable[[int, int], None] | None, plant: Any = None
) -> dict[str, Any]:
    from .v3 import run_v3

    w0 = time.perf_counter()
    _, ctrl = resolve_controller(task, name)
    res = run_v3(task, ctrl, name, seed=seed, n_steps=steps, progress=progress, plant=plant)
    d = res.to_dict()
    d["duration"] = steps * DT
    d["uptime_fraction"] = res.uptime / (steps * DT)
    d["wall_time_s"] = time.perf_counter() - w0  # with the controller's design (plans, ROA)
    return d
