"""One case of each RealAIGym protocol for the leaderboard (:mod:`.leaderboard`): run it, time it, journal it."""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from ..._journal import Journal
from ...control.realai.spec import DT
from .controllers import resolve_controller

__all__: list[str] = []


#: Kind of the journal of one v2 run or one v3 seed of the leaderboard (one record, ``"summary"``).
CASE_KIND = "leaderboard-case"
#: Fields of a case's summary that the leaderboard's tables and figures read (v2 run, v3 seed).
_SUMMARY_FIELDS = {
    "v2": ("success", "score", "criteria", "wall_time", "controller_time"),
    "v3": ("uptime_fraction", "n_swingups", "wall_time_s", "controller_time"),
}


def _summary_check(protocol: str) -> Callable[[str, Any], None]:
    need = _SUMMARY_FIELDS["v3" if protocol.startswith("v3") else "v2"]

    def check(key: str, summary: Any) -> None:
        if key != "summary" or not isinstance(summary, Mapping):
            raise ValueError(f"a case journal holds one summary object, got {key!r}")
        for name in need:
            if name not in summary:
                raise KeyError(name)

    return check


def _read(path: Path, settings: Mapping[str, Any]) -> dict[str, Any] | None:
    """The journaled summary of a case that validates, else None (a JournalWarning says why it is run again).

    A journal of this pendulab version with other settings raises :class:`~pendulab._journal.JournalError`.
    """
    if not path.is_file():
        return None
    log = Journal(path, CASE_KIND, settings, resume=True, check=_summary_check(str(settings["protocol"])))
    summary = log.get("summary")
    return None if summary is None else dict(summary)


def _write(path: Path, settings: Mapping[str, Any], summary: Mapping[str, Any]) -> None:
    Journal(path, CASE_KIND, settings).record("summary", dict(summary))


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

    counted: list[int] = []

    def report(done: int, total: int) -> None:
        if not counted:
            counted.append(done)  # the first report: the runs taken from the journal (validated)
        if progress is not None:
            progress(done, total)

    res = robustness_v2(task, name, seed=0, workers=workers, progress=report, journal=journal, resume=resume, **reduced)
    before = counted[0] if counted else 0
    d = res.to_dict()
    d["wall_total"] = float(sum(r.get("wall", 0.0) for r in res.records))
    act = 0 if task == "pendubot" else 1
    pert = [r for r in res.records if r["category"] == "perturbation"]
    d["perturbation_amplitude"] = [float(max(abs(a) for a in r["amplitude"][act])) for r in pert]
    d["model_level_indices"] = sorted({int(r["level_index"]) for r in res.records if r["category"] == "model"})
    n = len(res.records)
    return d, n - before, before


def _run_v3(
    task: str, name: str, seed: int, steps: int, progress: Callable[[int, int], None] | None, plant: Any = None,
    passive_allowance: float | None = None,
) -> dict[str, Any]:  # fmt: skip
    """One v3 episode; with ``passive_allowance`` (not None) the v3-hardware episode of ``steps * 2 ms``."""
    w0 = time.perf_counter()
    if passive_allowance is None:
        from .v3 import run_v3

        _, ctrl = resolve_controller(task, name)
        res = run_v3(task, ctrl, name, seed=seed, n_steps=steps, progress=progress, plant=plant)
    else:
        from .v3_hardware import hardware_entry, run_v3_hardware

        # The same entry as ``score --protocol v3-hardware``: bounded plans, friction compensation with an allowance.
        _, ctrl, _, _ = hardware_entry(task, name, passive_allowance, plant)

        res = run_v3_hardware(
            task, ctrl, name, seed=seed, passive_allowance=passive_allowance, duration=steps * DT, progress=progress,
            plant=plant,
        )  # fmt: skip
    d = res.to_dict()
    d["duration"] = steps * DT
    d["uptime_fraction"] = res.uptime / (steps * DT)
    d["wall_time_s"] = time.perf_counter() - w0  # with the controller's design (plans, ROA)
    return d
