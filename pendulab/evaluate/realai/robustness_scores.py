"""Robustness v2's scores: per-level successes, category rates (majority rule for noise levels), the mean score, the result."""

from __future__ import annotations

import math
import statistics
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .robustness_grid import CATEGORIES, PUBLISHED_ROBUSTNESS

__all__ = [
    "RobustnessResult",
    "category_rates",
    "level_successes",
    "robustness_score",
]


# -- scores ---------------------------------------------------------------------------------------------------------


def robustness_score(rates: Mapping[str, float]) -> float:
    """The overall score: the mean of the six category rates (``create_leaderboard.py``).

    Parameters
    ----------
    rates : mapping of str to float
        Rate in [0, 1] of every category of :data:`CATEGORIES`.

    Returns
    -------
    float
        ``1/6 * model + 1/6 * measurement_noise + ... + 1/6 * perturbation``.

    Raises
    ------
    KeyError
        A category is missing.
    """
    return (
        1.0 / 6.0 * rates["model"]
        + 1.0 / 6.0 * rates["measurement_noise"]
        + 1.0 / 6.0 * rates["u_noise"]
        + 1.0 / 6.0 * rates["u_responsiveness"]
        + 1.0 / 6.0 * rates["delay"]
        + 1.0 / 6.0 * rates["perturbation"]
    )


def level_successes(records: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """Successes per category and level from run records.

    Parameters
    ----------
    records : sequence of mapping
        Run records (:func:`run_protocol_episode`), any order.

    Returns
    -------
    dict
        ``"model"``: parameter -> [bool per level]; noise categories: [[bool per repetition] per level];
        the others: [bool per level or run] (the input of :func:`category_rates`).
    """
    out: dict[str, Any] = {c: {} for c in CATEGORIES}
    for r in sorted(records, key=lambda r: r["index"]):
        cat = r["category"]
        if cat == "model":
            out["model"].setdefault(r["param"], []).append(bool(r["success"]))
        elif cat in ("measurement_noise", "u_noise"):
            out[cat].setdefault(r["level_index"], []).append(bool(r["success"]))
        else:
            out[cat][r["level_index"]] = bool(r["success"])
    for cat in ("measurement_noise", "u_noise"):
        out[cat] = [out[cat][k] for k in sorted(out[cat])]
    for cat in ("u_responsiveness", "delay", "perturbation"):
        out[cat] = [out[cat][k] for k in sorted(out[cat])]
    return out


def category_rates(successes: Mapping[str, Any]) -> dict[str, float]:
    """Category rates from successes, as ``benchmark_scores.get_scores`` computes them.

    Parameters
    ----------
    successes : mapping
        ``"model"``: mapping parameter -> sequence of bool (one per value);
        ``"measurement_noise"``, ``"u_noise"``: sequence (levels) of sequences (repetitions) of bool;
        ``"u_responsiveness"``, ``"delay"``, ``"perturbation"``: sequence of bool.

    Returns
    -------
    dict of str to float
        Rate of each category present: model = all successes / all runs; noise: fraction of
        levels whose mean success exceeds 0.5; the others: successes / runs.
    """
    rates: dict[str, float] = {}
    if successes.get("model"):
        n = sum(len(v) for v in successes["model"].values())
        s = sum(int(np.sum(v)) for v in successes["model"].values())
        rates["model"] = float(s / n)
    for cat in ("measurement_noise", "u_noise"):
        if len(successes.get(cat, ())):
            lv = np.where(np.average(np.asarray(successes[cat], dtype=float), axis=1) > 0.5, True, False)
            rates[cat] = float(np.sum(lv) / len(lv))
    for cat in ("u_responsiveness", "delay", "perturbation"):
        if len(successes.get(cat, ())):
            rates[cat] = float(np.sum(successes[cat]) / len(successes[cat]))
    return rates


@dataclass
class RobustnessResult:
    """A robustness-v2 run of one controller on one task.

    Attributes
    ----------
    task, controller : str
        Leaderboard task and controller name.
    seed : int
        Seed of the legacy generator (upstream's ``np.random.seed``).
    rates : dict of str to float
        Category rates in [0, 1] (:data:`CATEGORIES`).
    score : float
        Mean of the six rates.
    successes : dict
        Per category and level (see :func:`category_rates`).
    levels : dict
        Levels of the runs (model: parameter -> values; perturbation: run numbers).
    records : list of dict
        Every run (:func:`run_protocol_episode` without trajectories), in the benchmark's order.
    wall_time : float
        Wall time of this call [s] (resumed runs not included).
    sample_time : float
        Controller sample time [s].
    plant : str
        The simulated plant (:func:`~pendulab.evaluate.realai.plant.plant_label`); the model
        variations are relative to it.
    complete : bool
        The full protocol (21 levels, 10 repetitions, 50 perturbation runs) was run.
    """

    task: str
    controller: str
    seed: int
    rates: dict[str, float]
    score: float
    successes: dict[str, Any] = field(repr=False)
    levels: dict[str, Any] = field(repr=False)
    records: list[dict[str, Any]] = field(repr=False)
    wall_time: float
    sample_time: float
    complete: bool
    plant: str = "nominal"

    @property
    def ctrl_time_median(self) -> float:
        """Median over runs of each run's median time per controller call [s]."""
        return float(statistics.median(r["ctrl_median"] for r in self.records)) if self.records else 0.0

    @property
    def ctrl_time_max(self) -> float:
        """Longest controller call of all runs [s]."""
        return float(max(r["ctrl_max"] for r in self.records)) if self.records else 0.0

    def level_rates(self) -> dict[str, Any]:
        """Success fraction per level, for figures.

        Returns
        -------
        dict
            ``"model"``: parameter -> list of 0/1; noise categories: mean over repetitions per
            level; others: 0/1 per level (perturbation: per run).
        """
        out: dict[str, Any] = {"model": {k: [float(b) for b in v] for k, v in self.successes["model"].items()}}
        for cat in ("measurement_noise", "u_noise"):
            out[cat] = [float(np.mean(v)) for v in self.successes.get(cat, [])]
        for cat in ("u_responsiveness", "delay", "perturbation"):
            out[cat] = [float(b) for b in self.successes.get(cat, [])]
        return out

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary.

        Returns
        -------
        dict
            protocol, task, controller, seed, score, rates, per-level successes and levels,
            wall time, controller timing (median/max per call, sample time, real-time flag),
            the published rows of the task and the best of them.
        """
        pub = PUBLISHED_ROBUSTNESS[self.task]
        best_name, (_, best) = max(pub.items(), key=lambda kv: kv[1][1])
        return {
            "protocol": "robustness-v2",
            "task": self.task,
            "controller": self.controller,
            "seed": self.seed,
            "complete": self.complete,
            "plant": self.plant,
            "score": None if math.isnan(self.score) else float(self.score),
            "rates": {k: float(v) for k, v in self.rates.items()},
            "successes": self.successes,
            "level_rates": self.level_rates(),
            "levels": self.levels,
            "runs": len(self.records),
            "wall_time": float(self.wall_time),
            "controller_time": {
                "median_per_call": self.ctrl_time_median,
                "max_per_call": self.ctrl_time_max,
                "sample_time": self.sample_time,
                "real_time": self.ctrl_time_max <= self.sample_time,
            },
            "published": {k: {"rates": [v / 100 for v in r], "score": s} for k, (r, s) in pub.items()},
            "published_best": {"name": best_name, "score": best},
            "beats_published": bool(self.complete and self.score > best),
        }
